"""Leakage of a rarefied gas: clearance gaps from continuum through slip and transition to
free-molecular flow (``[leakage] model = "rarefied"``), for vacuum pumps (seed 003: large
clearances at pressures where the mean free path is no longer small against the gap).

A sealing line is a plane slot: gap h, length l along the line (the table's column), land
L in the flow direction.  Mean free path and Knudsen number (hard-sphere definition of
Karniadakis, Beskok & Aluru, *Microflows and Nanoflows*, Springer 2005, Sec. 1.2):

    lambda = mu / p * sqrt(pi R T / 2),        Kn = lambda / h.

Viscous, slip and transition flow: the unified flow model of Beskok & Karniadakis (1999),
"A model for flows in channels, pipes and ducts at micro and nano scales", Microscale
Thermophys. Eng. 3, 43-77 (Karniadakis et al. 2005, Sec. 4.2): the local flow rate is
Poiseuille's times

    R(Kn) = (1 + alpha(Kn) Kn) (1 + 6 s Kn / (1 + Kn)),  s = (2 - sigma) / sigma,
    alpha(Kn) = alpha_inf (2/pi) atan(alpha1 Kn^beta),   alpha1 = 4, beta = 0.4,

sigma the tangential momentum accommodation coefficient (1: diffuse walls).  The flow is
isothermal at the upstream temperature and fully developed along the land; integrated
along it with the local Kn = c / p (c = lambda p is constant), the mass flow is

    m_v = h^3 l / (12 mu R T L) * int_{p2}^{p1} p R(c / p) dp,

which is the compressible Poiseuille flow h^3 l (p1^2 - p2^2) / (24 mu R T L) for Kn -> 0,
its first-order slip correction (1 + 6 s Kn) at the mean pressure for small Kn, and for
Kn -> oo tends to 7 alpha_inf c h^3 l (p1 - p2) / (12 mu R T L): a free-molecular flow
proportional to the pressure difference.  Its integrand is positive, so m_v rises with p1
and falls with p2 everywhere (no Knudsen minimum can make the flow run backwards), and it
changes sign with (p1, p2).

Free-molecular limit.  Beskok & Karniadakis fix alpha_inf = 64 / (15 pi) for a channel
without ends, whose free-molecular flow in truth grows without bound (as ln Kn); a land of
finite L / h has a finite one, the transmission probability W(L/h) of the slot times the
effusion flux (Clausing 1932, Ann. Phys. 12, 961; Berman 1965, J. Appl. Phys. 36, 3356):

    m_fm = W h l (p1 - p2) / sqrt(2 pi R T).

Here alpha_inf = 12 W L / (7 pi h) makes the model's limit exactly that (for diffuse
walls; with sigma < 1 it scales by (1 + 6 s) / 7 as in Beskok & Karniadakis).  W comes
from Clausing's integral equation for the slot between two diffuse plates, solved by
Nystrom's method (:func:`slot_transmission`; checked in the tests by a test-particle
Monte Carlo simulation).

Inertia.  At higher pressures and pressure ratios the gas accelerates into the gap and the
flow is limited by inertia, the isentropic nozzle flux m_i of the same gap
(:mod:`.flows`).  The two resistances act in series, the pressure drop split into a
viscous part linear in the flow and an inertial part quadratic in it (the laminar channel
with entry and exit losses):  m / m_v + w (m / m_i)^2 = 1, so

    m = 2 m_v / (1 + sqrt(1 + 4 w (m_v / m_i)^2)),

smooth and below both m_v and m_i; m -> m_v at low Reynolds number, m -> m_i at high.  The
inertial term is a continuum effect: it is weighted by w = 1 / (1 + Kn) at the mean
pressure, the fraction of a molecule's collisions that are with other molecules rather
than the walls (Karniadakis et al. 2005, Eq. 4.21), so that it vanishes in free-molecular
flow, where the transmission probability already holds all the slot's resistance.  A case
from 0.01 bar to 1 bar thus runs through one continuous, monotone law.

Orifices (paths whose column is an area, such as blow-holes): the continuum nozzle and the
free-molecular effusion (W = 1) through the same area, weighted by the same w with Kn at
the upstream pressure (Sharipov's rarefaction parameter of an orifice is the upstream
one) and the path's gap as the size that sets Kn: f = w f_nozzle + (1 - w) (1 - x) /
sqrt(2 pi).  Give the hole's size as its gap ([leakage.blow-hole] gap_um).

Everything is written, as in :mod:`.flows`, as the flux over sqrt(p1 rho1) per unit flow
area (h l for a sealing line, the area for an orifice), R T = p1 / rho1 of the upstream
state.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

# Beskok & Karniadakis (1999): alpha(Kn) = alpha_inf (2/pi) atan(ALPHA1 Kn^BETA) for a channel
ALPHA1 = 4.0
BETA = 0.4
# Gauss-Legendre nodes of the integral over the land, in ln p: 16 hold it to 1e-11 for
# pressure ratios down to 1e-4 against adaptive quadrature (tests).  Flows whose pressure
# ratio is at least X_FEW take N_FEW: 4e-13 against 128 nodes over Kn 1e-6 to 1e4 (the
# interval in ln p is short), at half the cost of the law's evaluation, which is most of a
# multiphase pump's right-hand side (it runs in numpy).
N_GAUSS = 16
N_FEW = 8
X_FEW = 0.1
_NODES = {n: (1.0 - g, w) for n, (g, w) in
          ((n, np.polynomial.legendre.leggauss(n)) for n in (N_GAUSS, N_FEW))}
# (the same nodes as plain arrays, which the compiled kernel reads as constants)
_OMG_WIDE, _GW_WIDE = _NODES[N_GAUSS]
_OMG_FEW, _GW_FEW = _NODES[N_FEW]
# Pressure ratios below this are taken as this: none occurs between the chambers of a
# machine, and the flux changes by less than 1e-9 of itself (it is linear in 1 - x or in
# 1 - x^2 there), while ln x stays finite for the quadrature.
X_FLOOR = 1.0e-9
# Clausing's equation is solved directly up to this L/h (1,200 nodes, 0.4 s once per
# distinct path); beyond it W = (ln(L/h) + C) / (L/h), the diffusive form of a long slot,
# with C from the solution at this length (C drifts by ~0.02 per doubling of L/h, so
# about 0.3 % of W at twice this length).
L_DIRECT_MAX = 200.0
# Nystrom panels per gap height and Gauss nodes per panel: 1e-7 of W against 8 x 8.
_PANELS_PER_H = 1
_NODES_PER_PANEL = 6


def mean_free_path(viscosity_Pa_s, p, RT):
    """lambda = mu / p sqrt(pi R T / 2) (the hard-sphere mean free path; RT = p / rho)."""
    return viscosity_Pa_s / p * np.sqrt(0.5 * math.pi * RT)


def _clausing(l: float) -> float:
    """Transmission probability of a slot of length l (in gap heights) between diffuse
    plates: Clausing's integral equation for the wall emission J(x) per unit entering flux,
    J(x) = G(x) + int_0^l K(x - x') J(x') dx' with the view factors of infinitely long
    strips (Hottel's crossed strings): K(s) = 1 / (2 (1 + s^2)^(3/2)) from the opposite
    plate, G(x) = (1 - x / sqrt(1 + x^2)) / 2 from the inlet; then
    W = sqrt(1 + l^2) - l (inlet straight to outlet) + 2 int_0^l J F_out dx."""
    n_pan = max(1, math.ceil(l * _PANELS_PER_H))
    g, gw = np.polynomial.legendre.leggauss(_NODES_PER_PANEL)
    edges = np.linspace(0.0, l, n_pan + 1)
    a, b = edges[:-1, None], edges[1:, None]
    x = (0.5 * (a + b) + 0.5 * (b - a) * g).ravel()
    w = (0.5 * (b - a) * gw).ravel()
    s = x[:, None] - x[None, :]
    K = 0.5 / (1.0 + s * s) ** 1.5 * w[None, :]
    G = 0.5 * (1.0 - x / np.sqrt(1.0 + x * x))
    J = np.linalg.solve(np.eye(x.size) - K, G)
    F_out = 0.5 * (1.0 - (l - x) / np.sqrt(1.0 + (l - x) ** 2))
    return float(math.sqrt(1.0 + l * l) - l + 2.0 * np.sum(w * J * F_out))


def _rarefaction(kn, alpha_inf, slip, kn_beta=None):
    """R(Kn) of :meth:`RarefiedLaw.rarefaction`, with the law's alpha_inf and s
    (``kn_beta``: Kn**BETA where the caller has it cheaper than the power)."""
    kn_beta = kn**BETA if kn_beta is None else kn_beta
    alpha = alpha_inf * (2.0 / math.pi) * np.arctan(ALPHA1 * kn_beta)
    return (1.0 + alpha * kn) * (1.0 + 6.0 * slip * kn / (1.0 + kn))


def flow_flux(f_nozzle, x, p1, rho1, gap, land, viscosity, alpha_inf, slip, orifice):
    """:meth:`RarefiedLaw.reduced_flux` of one flow (scalars; one flow at a time, as
    :func:`.kernel.rhs_fused` calls it): the same law, its land integral summed node by
    node instead of over an array axis (the two agree to round-off, tested)."""
    kn1 = viscosity / p1 * math.sqrt(0.5 * math.pi * p1 / rho1) / gap
    if orifice:
        w = 1.0 / (1.0 + kn1)
        return w * f_nozzle + (1.0 - w) * (1.0 - x) / math.sqrt(2.0 * math.pi)
    xf = max(x, X_FLOOR)
    half = -0.5 * math.log1p(xf - 1.0)
    one_minus_g, gw = (_OMG_WIDE, _GW_WIDE) if xf < X_FEW else (_OMG_FEW, _GW_FEW)
    kn_beta = kn1**BETA
    total = 0.0
    for j in range(gw.size):
        z = half * one_minus_g[j]
        e = math.exp(z)
        r = _rarefaction(kn1 * e, alpha_inf, slip, kn_beta * math.exp(BETA * z))
        total += gw[j] * r / (e * e)
    f_v = (gap / land) * math.sqrt(0.5 * math.pi) / (12.0 * kn1) * (half * total)
    if not f_nozzle > 0.0:  # (as reduced_flux: no inertial resistance at x = 1)
        return f_v
    w = 1.0 / (1.0 + 2.0 * kn1 / (1.0 + x))
    return 2.0 * f_v / (1.0 + math.hypot(1.0, 2.0 * math.sqrt(w) * (f_v / f_nozzle)))


def _per_node(v):
    """A per-flow parameter against the quadrature's nodes (a trailing axis)."""
    return v[..., None] if np.ndim(v) else v


@functools.lru_cache(maxsize=128)
def slot_transmission(l: float) -> float:
    """Free-molecular transmission probability W of a slot of land l = L / h (diffuse
    walls): 1 for l = 0, ~ (ln l + 0.1) / l for a long slot."""
    if l < 0:
        raise ValueError(f"slot length over gap must not be negative, got {l}")
    if l == 0.0:
        return 1.0
    if l <= L_DIRECT_MAX:
        return _clausing(l)
    c = L_DIRECT_MAX * slot_transmission(L_DIRECT_MAX) - math.log(L_DIRECT_MAX)
    return (math.log(l) + c) / l


@dataclass(frozen=True, eq=False)
class RarefiedLaw:
    """The rarefied flow law of one kind of gap (see the module docstring), or of a group
    of leakage flows (:meth:`of_flows`: the gaps' parameters arrays over the flows, the
    last axis of the states; one call for a segment's sealing lines)."""

    gap_m: float | np.ndarray
    land_m: float | np.ndarray
    viscosity_Pa_s: float | np.ndarray
    accommodation: float | np.ndarray = 1.0  # sigma, tangential momentum accommodation
    orifice: bool = False  # the path's column is an area (blow-hole): no land

    @classmethod
    def of_flows(cls, laws, orifice: bool) -> RarefiedLaw:
        """One law over flows each flowing by one of ``laws`` (anything with this class's
        gap_m, land_m, viscosity_Pa_s and accommodation): scalars where they agree."""
        def column(name):
            v = np.array([getattr(law, name) for law in laws], dtype=float)
            return float(v[0]) if np.all(v == v[0]) else v

        return cls(column("gap_m"), column("land_m"), column("viscosity_Pa_s"),
                   column("accommodation"), orifice)

    @property
    def slip(self):
        """s = (2 - sigma) / sigma of the slip term."""
        return (2.0 - self.accommodation) / self.accommodation

    @functools.cached_property
    def alpha_inf(self):
        """alpha_inf = 12 W L / (7 pi h): the free-molecular limit is the slot's W."""
        lh = self.land_m / self.gap_m
        w = np.vectorize(slot_transmission, otypes=[float])(lh) if np.ndim(lh) else \
            slot_transmission(lh)
        return 12.0 * w * lh / (7.0 * math.pi)

    def per_flow(self, count: int) -> np.ndarray:
        """The law's parameters per flow for :func:`flow_flux` (the compiled kernel's):
        rows orifice (0 or 1), gap, land, viscosity, alpha_inf, s over ``count`` flows."""
        return np.array([np.broadcast_to(np.asarray(v, dtype=float), (count,))
                         for v in (float(self.orifice), self.gap_m, self.land_m,
                                   self.viscosity_Pa_s, self.alpha_inf, self.slip)])

    def knudsen(self, p, RT):
        return mean_free_path(self.viscosity_Pa_s, p, RT) / self.gap_m

    def rarefaction(self, kn):
        """R(Kn) = (1 + alpha(Kn) Kn) (1 + 6 s Kn / (1 + Kn)) of the unified model."""
        return _rarefaction(kn, self.alpha_inf, self.slip)

    def viscous_flux(self, x, kn1):
        """Flux of the unified model over sqrt(p1 rho1) per unit of h l, for x = p2/p1
        and Kn1 = Kn at p1: (h/L) sqrt(pi/2) / (12 Kn1) int_x^1 xi R(Kn1 / xi) dxi,
        the integral by Gauss-Legendre in ln xi."""
        x = np.maximum(x, X_FLOOR)
        kn1 = np.asarray(kn1, dtype=float)
        half = -0.5 * np.log1p(x - 1.0)  # (ln 1 - ln x) / 2, exact near x = 1
        integral = self._land_integral(half, kn1, N_FEW)
        wide = x < X_FEW
        if np.any(wide):  # (the few flows across a large pressure ratio: all the nodes)
            shape = np.broadcast_shapes(half.shape, kn1.shape, np.shape(self.alpha_inf))
            sel = np.broadcast_to(wide, shape)
            integral = np.array(np.broadcast_to(integral, shape))
            integral[sel] = self._land_integral(
                np.broadcast_to(half, shape)[sel], np.broadcast_to(kn1, shape)[sel], N_GAUSS,
                *(np.broadcast_to(v, shape)[sel] if np.ndim(v) else v
                  for v in (self.alpha_inf, self.slip)))
        return (self.gap_m / self.land_m) * math.sqrt(0.5 * math.pi) / (12.0 * kn1) * integral

    def _land_integral(self, half, kn1, nodes, alpha_inf=None, slip=None):
        """int_x^1 xi R(Kn1 / xi) dxi by ``nodes`` Gauss-Legendre nodes in ln xi, for
        half = -ln(x) / 2 (per flow: the law's alpha_inf and slip, or the given ones)."""
        one_minus_g, gw = _NODES[nodes]
        alpha_inf = self.alpha_inf if alpha_inf is None else alpha_inf
        slip = self.slip if slip is None else slip
        z = half[..., None] * one_minus_g
        e = np.exp(z)  # 1 / xi at the nodes in [x, 1]
        # (Kn**BETA at the nodes by an exponential: numpy's power costs three of them)
        kn_beta = (kn1**BETA)[..., None] * np.exp(BETA * z)
        r = _rarefaction(kn1[..., None] * e, _per_node(alpha_inf), _per_node(slip), kn_beta)
        return half * np.sum(gw * r / (e * e), axis=-1)

    def reduced_flux(self, f_nozzle, x, p1, rho1):
        """Flux over sqrt(p1 rho1) per unit flow area, given the nozzle's f_nozzle of
        the same flows (x = p2 / p1 <= 1, upstream p1 and rho1)."""
        RT = p1 / rho1
        kn1 = self.knudsen(p1, RT)
        if self.orifice:
            w = 1.0 / (1.0 + kn1)
            return w * f_nozzle + (1.0 - w) * (1.0 - x) / math.sqrt(2.0 * math.pi)
        f_v = self.viscous_flux(x, kn1)
        w = 1.0 / (1.0 + 2.0 * kn1 / (1.0 + x))  # Kn at the mean pressure
        # f_nozzle is 0 at x = 1 (and where round-off takes 1 - x below ~1e-16): there
        # the inertial resistance is nil against the viscous one, f = f_v
        live = f_nozzle > 0.0
        q = np.where(live, f_v / np.where(live, f_nozzle, 1.0), 0.0)
        return 2.0 * f_v / (1.0 + np.hypot(1.0, 2.0 * np.sqrt(w) * q))

    def mass_flux(self, pa, ra, pb, rb, gamma: float):
        """Mass flux (kg/s per m^2 of flow area) from state a to state b, negative from b
        to a: the law as the chamber model applies it (:meth:`.model.ChamberModel._flows`)."""
        from .flows import nozzle_f

        pa, ra, pb, rb = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                               for v in (pa, ra, pb, rb)))
        fwd = pa >= pb
        p1 = np.where(fwd, pa, pb)
        r1 = np.where(fwd, ra, rb)
        x = np.where(fwd, pb, pa) / p1
        f = self.reduced_flux(nozzle_f(x, gamma), x, p1, r1)
        g = np.sqrt(p1 * r1) * f
        return np.where(fwd, g, -g)
