"""Rotor profiles as closed analytic curves: evaluation, sampling to a
chordal tolerance, clearance offsets, closest points and a self-intersection check.

A profile is a chain of analytic pieces traversed counter-clockwise; a global parameter
``u`` in ``[0, n_pieces)`` runs along it, piece ``floor(u)`` at local ``t = u - floor(u)``.

Every family's profiles are such chains (:class:`PieceCurve`, e.g. the pin-generated
pair's in :mod:`.internal_gear.profiles`); what follows works on any of them, and on
any object with the same methods.

A clearance is a true normal offset ``q(u) = p(u) + d c(u) n(u)`` (``n`` the outward
unit normal, ``d = +1`` grows the region, ``-1`` shrinks it) with ``c`` uniform or a
smooth periodic distribution along each lobe.  It is valid when ``1 + d c kappa > 0``
everywhere (no fold) and the offset polygon is simple.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rotorflow.errors import CaseError

from .offset_corners import corner_trims
from .planar import cross
from .spline import CubicSpline

#: Pre-grid per piece on which curvature is tabulated to place samples.
PREGRID = 513
#: Gauss-Legendre nodes per sub-interval and sub-intervals per piece for arc-length
#: integrals (analytic integrands: 1e-12 relative).
GAUSS_NODES = 16
GAUSS_PANELS = 32
#: Bisection rounds after equidistribution before sampling gives up (2^-40 of a piece).
MAX_REFINE = 40



class PieceCurve:
    """A closed counter-clockwise chain of analytic pieces (lengths in metres).

    Families subclass it with ``_eval(u, order)`` (the point, order 0, or d/du, order 1,
    at global parameters u) and the attributes ``name``, ``n`` (pieces), ``lobes`` and
    ``material_inside``; everything else here (normals, curvature, arc length, the
    enclosed area, lobe fractions) follows from ``_eval``.
    """

    name: str
    lobes: int
    material_inside: bool

    @property
    def n(self) -> int:
        raise NotImplementedError

    def _eval(self, u, order: int):
        raise NotImplementedError

    def _split(self, u):
        u = np.mod(np.asarray(u, dtype=float), self.n)
        j = np.minimum(np.floor(u).astype(int), self.n - 1)
        return j, u - j

    def _lobe_start(self, ut, st) -> float:
        """Arc length from u = 0 to lobe 0's reference point (see lobe_fraction)."""
        return 0.0

    def point(self, u):
        return self._eval(u, 0)

    def derivative(self, u):
        return self._eval(u, 1)

    def second_derivative(self, u):
        """d2/du2 by a central difference of the (analytic) first derivative, in-piece."""
        j, t = self._split(u)
        h = 1e-5
        lo = j + np.clip(t - h, 0.0, 1.0 - 1e-12)
        hi = j + np.clip(t + h, 0.0, 1.0 - 1e-12)
        return (self.derivative(hi) - self.derivative(lo)) / (hi - lo)[..., None]

    def normal(self, u):
        """Outward unit normal (right of the counter-clockwise tangent)."""
        d = self.derivative(u)
        n = np.stack([d[..., 1], -d[..., 0]], -1)
        return n / np.linalg.norm(n, axis=-1)[..., None]

    def curvature(self, u):
        """Signed curvature, positive where the region inside is convex."""
        d1, d2 = self.derivative(u), self.second_derivative(u)
        return cross(d1, d2) / np.linalg.norm(d1, axis=-1) ** 3

    def turning_rate(self, u):
        """kappa |dp/du| (finite even where the speed vanishes at sigma_bar = 1)."""
        d1, d2 = self.derivative(u), self.second_derivative(u)
        return cross(d1, d2) / np.sum(d1 * d1, -1)

    # -------------------------------------------------------------- integrals
    @cached_property
    def _gauss(self):
        x, w = np.polynomial.legendre.leggauss(GAUSS_NODES)
        edges = np.linspace(0.0, 1.0, GAUSS_PANELS + 1)
        h = np.diff(edges)
        t = (edges[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
        wt = (0.5 * h[:, None] * w[None, :]).ravel()
        u = (np.arange(self.n)[:, None] + t[None, :]).ravel()
        return u, np.tile(wt, self.n)

    def integrate(self, f) -> float:
        """\\oint f(u) du by Gauss-Legendre panels on every piece."""
        u, w = self._gauss
        return float(np.sum(f(u) * w))

    @cached_property
    def length(self) -> float:
        return self.integrate(lambda u: np.linalg.norm(self.derivative(u), axis=-1))

    @cached_property
    def _arc_table(self):
        u = (np.arange(self.n)[:, None] + np.linspace(0.0, 1.0, PREGRID)[None, :-1]).ravel()
        u = np.append(u, self.n)
        p = self.point(u)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=-1))])
        return u, s

    def lobe_fraction(self, u):
        """Fraction of the lobe (by arc length) from the lobe's reference point, [0, 1).

        The reference point is the family's (:meth:`_lobe_start`); u = 0 by default.
        """
        ut, st = self._arc_table
        s = np.interp(np.mod(np.asarray(u, dtype=float), self.n), ut, st)
        lobe_len = st[-1] / self.lobes
        return np.mod((s - self._lobe_start(ut, st)) / lobe_len, 1.0)

    # -------------------------------------------------------------- area
    @cached_property
    def area(self) -> float:
        """Enclosed area, 1/2 of the integral of p x p' (Green's theorem, Gauss panels).

        Families with closed forms override it."""
        return 0.5 * self.integrate(lambda u: cross(self.point(u), self.derivative(u)))

    @cached_property
    def radius_max(self) -> float:
        ut, _ = self._arc_table
        return float(np.linalg.norm(self.point(ut), axis=-1).max())


# ------------------------------------------------------------------ clearance offsets
@dataclass(frozen=True)
class Clearance:
    """A clearance distribution along each lobe of a profile (metres).

    ``values`` at equally spaced lobe fractions (by arc length, from the lobe's
    reference point), joined by a periodic cubic spline; one value is uniform.
    """

    values: tuple[float, ...]

    @property
    def uniform(self) -> bool:
        return len(self.values) == 1 or len(set(self.values)) == 1

    @property
    def largest(self) -> float:
        return max(self.values)

    @cached_property
    def _spline(self):
        v = np.asarray(self.values, dtype=float)
        x = np.linspace(0.0, 1.0, len(v) + 1)
        return CubicSpline(x, np.append(v, v[0]), bc_type="periodic")

    def __call__(self, fraction):
        if self.uniform:
            return np.full(np.shape(fraction), float(self.values[0]))
        return self._spline(np.mod(fraction, 1.0))


@dataclass(frozen=True)
class OffsetProfile:
    """``base`` moved along its outward normal by ``direction * c(u)``.  With ``trims``
    (per piece, the base's local range (lo, hi) kept: cut at sharp corners,
    :mod:`.offset_corners`) its own u = j + t runs over piece j's, t -> lo + (hi - lo) t."""

    base: PieceCurve
    clearance: Clearance
    direction: int  # +1 grows the enclosed region, -1 shrinks it
    trims: tuple[tuple[float, float], ...] | None = None

    def base_param(self, u):
        """(the base's parameter at the offset's u, d(base u) / du: the trimmed range)."""
        if self.trims is None:
            return np.asarray(u, dtype=float), 1.0
        j, t = self.base._split(u)
        lo, hi = np.asarray(self.trims).T
        return j + lo[j] + (hi[j] - lo[j]) * t, hi[j] - lo[j]

    @property
    def name(self):
        return self.base.name

    @property
    def n(self):
        return self.base.n

    @property
    def lobes(self):
        return self.base.lobes

    @property
    def material_inside(self):
        return self.base.material_inside

    def offset(self, u):
        return self.direction * self.clearance(self.lobe_fraction(u))

    def point(self, u):
        bu, _ = self.base_param(u)
        return self.base.point(bu) + self.offset(u)[..., None] * self.base.normal(bu)

    def derivative(self, u):
        if self.clearance.uniform:
            # d/du (c n) = c kappa p' = c (kappa |p'|) t: finite where |p'| vanishes.
            bu, k = self.base_param(u)
            d = self.base.derivative(bu)
            t = d / np.maximum(np.linalg.norm(d, axis=-1), 1e-300)[..., None]
            out = d + (self.offset(u) * self.base.turning_rate(bu))[..., None] * t
            return out * np.asarray(k)[..., None]
        j, t = self.base._split(u)
        h = 1e-6
        lo = j + np.clip(t - h, 0.0, 1.0 - 1e-12)
        hi = j + np.clip(t + h, 0.0, 1.0 - 1e-12)
        return (self.point(hi) - self.point(lo)) / (hi - lo)[..., None]

    def normal(self, u):
        return self.base.normal(self.base_param(u)[0])

    def second_derivative(self, u):
        j, t = self.base._split(u)
        h = 1e-5
        lo = j + np.clip(t - h, 0.0, 1.0 - 1e-12)
        hi = j + np.clip(t + h, 0.0, 1.0 - 1e-12)
        return (self.derivative(hi) - self.derivative(lo)) / (hi - lo)[..., None]

    def curvature(self, u):
        d1, d2 = self.derivative(u), self.second_derivative(u)
        return cross(d1, d2) / np.linalg.norm(d1, axis=-1) ** 3

    def integrate(self, f) -> float:
        return self.base.integrate(f)

    @cached_property
    def moments(self) -> tuple[float, float]:
        """(\\oint c ds, 1/2 \\oint c^2 kappa ds) along the base profile.

        The offset of ``s p`` (the base scaled by s, the offset not) encloses
        ``s^2 A + d s M1 + M2``: exact for a regular offset (uniform c: c P, pi c^2).
        Trimmed at corners, M2 is what makes the sum the trimmed curve's own area (Green's
        theorem along it): each corner's c^2 tan(turn / 2) replaces the regular formula's
        share, exact at s = 1 and to O(c^3 kappa) on a scaled section.
        """
        b = self.base
        if self.trims is not None:
            m1 = self._first_moment()
            own = 0.5 * b.integrate(lambda u: cross(self.point(u), self.derivative(u)))
            return m1, own - b.area - self.direction * m1
        if self.clearance.uniform:
            c = self.clearance.values[0]
            return c * b.length, math.pi * c * c

        def second(u):
            return self.clearance(b.lobe_fraction(u)) ** 2 * b.turning_rate(u)

        return self._first_moment(), 0.5 * b.integrate(second)

    def _first_moment(self) -> float:
        """\\oint c ds along the whole base profile."""
        b = self.base
        if self.clearance.uniform:
            return self.clearance.values[0] * b.length
        return b.integrate(lambda u: self.clearance(b.lobe_fraction(u))
                           * np.linalg.norm(b.derivative(u), axis=-1))

    @cached_property
    def area(self) -> float:
        """A + d \\oint c ds + 1/2 \\oint c^2 kappa ds (exact for a regular offset)."""
        m1, m2 = self.moments
        return self.base.area + self.direction * m1 + m2

    @cached_property
    def length(self) -> float:
        return self.base.integrate(lambda u: np.linalg.norm(self.derivative(u), axis=-1))

    def lobe_fraction(self, u):
        return self.base.lobe_fraction(self.base_param(u)[0])

    @cached_property
    def radius_max(self) -> float:
        return self.base.radius_max + max(0.0, self.direction * self.clearance.largest)


def region_volume(curve, sweep) -> float:
    """Volume enclosed by the swept ``curve`` between z = 0 and L (analytic)."""
    i2 = sweep.scale_squared_integral
    if not isinstance(curve, OffsetProfile):
        return curve.area * i2
    i1 = 0.5 * sweep.length * (1.0 + sweep.scale_end)
    m1, m2 = curve.moments
    return curve.base.area * i2 + curve.direction * m1 * i1 + m2 * sweep.length


def offset_profile(base: PieceCurve, clearance: Clearance, direction: int):
    """The clearance offset of ``base``, checked for folds; ``base`` if c = 0."""
    if clearance.largest == 0.0 and min(clearance.values) == 0.0:
        return base
    if min(clearance.values) < 0.0:
        raise CaseError(f"clearance on the {base.name} rotor must not be negative")
    off = OffsetProfile(base, clearance, direction)
    # A fold appears where 1 + d c kappa <= 0: check on every piece's dense pre-grid and
    # around the sharpest point found (the inner profile at sigma_bar = 1 has a point of
    # infinite curvature that no grid lands on exactly).
    u = (np.arange(base.n)[:, None] + np.linspace(0.0, 1.0, 4 * PREGRID)[None, :]).ravel()
    u = np.minimum(u, base.n - 1e-12)
    kappa = base.curvature(u)
    worst = int(np.argmin(1.0 + off.offset(u) * kappa))
    h = 1.0 / (4 * PREGRID)
    fine = np.clip(u[worst] + np.linspace(-h, h, 2001), 0.0, base.n - 1e-12)
    kf = base.curvature(fine)
    fold = 1.0 + off.offset(fine) * kf
    i = int(np.argmin(fold))
    if not fold[i] > 0.0:
        radius = 1.0 / abs(kf[i]) if kf[i] != 0 else math.inf
        p = base.point(fine[i])
        raise CaseError(
            f"a clearance of {abs(off.offset(fine[i])) * 1e6:.3g} um on the {base.name} rotor "
            f"folds its profile: its radius of curvature there is {radius * 1e6:.3g} um, at "
            f"({p[0] * 1e3:.3f}, {p[1] * 1e3:.3f}) mm"
            + ("; apply the clearance to the outer rotor" if base.material_inside else "")
        )
    trims = corner_trims(off)
    return off if trims is None else dataclasses.replace(off, trims=trims)


# ------------------------------------------------------------------ sampling
def _chord_error(curve, ua, ub):
    """Largest distance of the curve between ua and ub from the chord (3 interior points)."""
    a, b = curve.point(ua), curve.point(ub)
    ab = b - a
    lab = np.maximum(np.linalg.norm(ab, axis=-1), 1e-300)
    worst = np.zeros(len(ua))
    for q in (0.25, 0.5, 0.75):
        p = curve.point(ua + q * (ub - ua))
        worst = np.maximum(worst, np.abs(cross(ab, p - a)) / lab)
    return worst, lab


def sample(curve, tol: float, max_step: float = math.inf) -> np.ndarray:
    """Parameters u of a closed polyline through the curve with chord error <= tol.

    Samples are first spread so that each chord carries about the same sagitta
    (density sqrt(|kappa| / (8 tol)) per unit length, and at least 1 / max_step), then
    every chord is checked against the curve at three interior points and bisected
    until it passes; piece ends are always samples.  Returns sorted u in [0, n).
    """
    if not tol > 0.0:
        raise CaseError(f"the sampling tolerance must be positive, got {tol}")
    # Every piece's curve evaluations in one call (a call costs the same whatever its
    # length: 0.1 s of the twin screw's 1.5 s went to sampling its profiles piece by
    # piece); each piece's grid and bisections are its own, as before.
    t = np.linspace(0.0, 1.0, PREGRID)
    n = curve.n
    u = np.arange(n)[:, None] + t[None, :]
    u[:, -1] = np.arange(n) + 1.0 - 1e-13
    d1 = curve.derivative(u.ravel()).reshape(n, PREGRID, 2)
    kappa = curve.curvature(u.ravel()).reshape(n, PREGRID)
    pieces = []
    for j in range(n):
        speed = np.linalg.norm(d1[j], axis=-1)
        kap = np.abs(kappa[j])
        kap = np.where(np.isfinite(kap), kap, 0.0)
        dens = np.maximum(np.sqrt(kap / (8.0 * tol)), 1.0 / max_step) * speed
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(u[j]))])
        if not cum[-1] > 0.0:  # a straight piece and no max_step: spread by parameter
            cum = t.copy()
        m = max(int(math.ceil(cum[-1] * 1.05)), 1)
        us = np.interp(np.linspace(0.0, cum[-1], m + 1), cum, j + t)
        us[-1] = j + 1.0
        pieces.append(us)
    todo = list(range(n))
    for _ in range(MAX_REFINE):
        err, lab = _chord_error(curve, np.concatenate([pieces[j][:-1] for j in todo]),
                                np.concatenate([pieces[j][1:] for j in todo]))
        bad = np.split((err > tol) | (lab > max_step),
                       np.cumsum([len(pieces[j]) - 1 for j in todo])[:-1])
        for j, b in zip(todo, bad, strict=True):
            if b.any():
                us = pieces[j]
                pieces[j] = np.sort(np.concatenate([us, 0.5 * (us[:-1] + us[1:])[b]]))
        todo = [j for j, b in zip(todo, bad, strict=True) if b.any()]
        if not todo:
            break
    else:
        raise CaseError(f"the {curve.name} profile cannot be sampled to {tol * 1e6:.3g} um")
    return np.concatenate([us[:-1] for us in pieces])


def sample_polygon(curve, tol: float) -> np.ndarray:
    """A closed polyline (vertices on the curve, first not repeated) to chord error tol."""
    return curve.point(sample(curve, tol))


# ------------------------------------------------------------------ closest points
def closest(curve, x, u0, iterations: int = 8):
    """Foot points on the curve of points x (m, 2), starting from parameters u0.

    Newton on (p(u) - x) . p'(u) = 0 with the Gauss-Newton slope |p'|^2; every iterate
    is a point of the curve, so the distance returned is an upper bound of the true
    one and tight once converged.  Returns (u, distance, signed distance) with the sign
    positive outside the enclosed region.
    """
    u = np.array(u0, dtype=float)
    p = curve.point(u)
    dist = np.linalg.norm(p - x, axis=-1)
    for _ in range(iterations):
        d = curve.derivative(u)
        step = np.sum((p - x) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300)
        step = np.clip(step, -0.05, 0.05)  # never more than 1/20 of a piece at once
        # Backtrack: keep a step only where it brings the point closer (the slope
        # vanishes at the sigma_bar = 1 point, where a full step overshoots).
        for _ in range(6):
            un = u - step
            pn = curve.point(un)
            dn = np.linalg.norm(pn - x, axis=-1)
            better = dn <= dist
            u = np.where(better, un, u)
            p = np.where(better[..., None], pn, p)
            dist = np.where(better, dn, dist)
            step = np.where(better, 0.0, 0.5 * step)
            if not step.any():
                break
    r = x - p
    dist = np.linalg.norm(r, axis=-1)
    sign = np.sign(np.sum(r * curve.normal(u), -1))
    return np.mod(u, curve.n), dist, np.where(sign == 0, 1.0, sign) * dist
