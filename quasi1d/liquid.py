"""A liquid that takes up chamber volume: the multiphase pump's gas-liquid mixture
(seed 003: "sludge flow ... incompressible ... interacting with the gas flow only through
internal heat transfer").

The liquid rides in the oil's state columns (mass mo and internal energy Ho per slot,
:mod:`.oil`); with ``liquid_density_kg_m3`` given it also fills volume mo / rho_l, so
the gas lives in V_g = V - mo / rho_l.  Without a density the liquid's volume is
neglected (the injected oil of a compressor, :mod:`.oil`), and everything here reduces
to what :mod:`.oil` does.

Energy, the liquid incompressible (u_l = c T_l, its enthalpy u_l + p / rho_l):

    gas     dU  = sum m_g h_g - p dV_g + Q_wall + Q_liquid,   dV_g = dV - dmo / rho_l
    liquid  dHo = sum m_l (u_l + p_up / rho_l) - p dmo / rho_l - Q_liquid

so the two together take -p dV, the shaft's work on the whole chamber (the liquid's
push-out work (p_d - p_s) V_l is in the indicated power), and a liquid flowing from
p_up into a chamber at p dissipates (p_up - p) / rho_l per kg into the liquid.

Leakage (``[leakage] mixture``): "homogeneous", the gap passes the mixture (no slip,
:mod:`.oil`), its flux by
Leung's omega method (J. C. Leung, "A generalized correlation for one-component
homogeneous equilibrium flashing choked flow", AIChE J. 32 (1986) 1743; the frozen,
non-flashing form, as API 520 Part I Annex C gives it): the mixture's specific volume
v = v_1 [omega (p_1 / p - 1) + 1] with omega = alpha_1 / kappa, alpha_1 the upstream
gas volume fraction, so

    G / sqrt(p_1 rho_m1) = G*(eta, omega)
        = sqrt(-2 [omega ln eta + (omega - 1)(1 - eta)]) / (omega (1 / eta - 1) + 1),

choked below the critical ratio eta_c(omega) (G* = eta_c / sqrt(omega)).  omega = 0 is a
liquid, G* = sqrt(2 (1 - eta)): the orifice's A sqrt(2 rho_l dp).  Each path keeps its own
law (nozzle, Fanno, rarefied, calibrated) for the gas alone, f(x); the mixture's is that
law times G*(x, omega) / G*(x, 1 / kappa): the law's departure from an ideal gas nozzle
(friction, rarefaction) is carried over to the mixture.  The gas is kappa's gas in the
gap (as in :mod:`.oil`: the liquid's heat capacity would pull the expansion towards the
isothermal one, omega = alpha_1); not modelled: slip, flashing of a volatile liquid.
"centrifuged": the liquid flung onto the bores fills the gaps there, the others are
shared by volume, each phase by its own law (:func:`centrifuged_leakage`).
"""

from __future__ import annotations

import numpy as np

from rotorflow.errors import CaseError

from . import flows
from .keys import _number
from .network import ACC_H_SUC, ACC_M_SUC

# eta_c(omega) of the omega method, tabulated once in log omega: the root of
# eta^2 + (omega^2 - 2 omega)(1 - eta)^2 + 2 omega^2 ln eta + 2 omega^2 (1 - eta) = 0
# (Leung 1986, Eq. 19), positive at eta -> 1 and -inf at eta -> 0.
_LOG_OMEGA = np.linspace(np.log(1e-8), np.log(1e4), 601)


def _critical_ratio(omega: np.ndarray) -> np.ndarray:
    lo, hi = np.full_like(omega, 1e-12), np.ones_like(omega)
    w2 = omega * omega
    for _ in range(60):
        eta = 0.5 * (lo + hi)
        f = eta * eta + (w2 - 2 * omega) * (1 - eta) ** 2 + 2 * w2 * np.log(eta) \
            + 2 * w2 * (1 - eta)
        neg = f < 0.0
        lo = np.where(neg, eta, lo)
        hi = np.where(neg, hi, eta)
    return 0.5 * (lo + hi)


_ETA_C = _critical_ratio(np.exp(_LOG_OMEGA))


def critical_ratio(omega):
    """eta_c(omega): the pressure ratio below which the omega method's flux chokes."""
    return np.interp(np.log(np.maximum(omega, 1e-300)), _LOG_OMEGA, _ETA_C)


def omega_flux(eta, omega):
    """G*(eta, omega) = G / sqrt(p_1 rho_1) of the omega method, choked below eta_c."""
    e = np.maximum(eta, critical_ratio(omega))
    num = -2.0 * (omega * np.log(e) + (omega - 1.0) * (1.0 - e))
    return np.sqrt(np.maximum(num, 0.0)) / (omega * (1.0 / e - 1.0) + 1.0)


def mixture_factor(x, kappa, rho_g, X, inv_rho_l):
    """What the mixture's gas flow is as a share of the gas-only flow F of the same gap
    at the same upstream pressure and gas density, times sqrt(1 + X) (:mod:`.oil`'s
    homogeneous split has divided by it already): sqrt(alpha) G*(x, alpha / kappa) /
    G*(x, 1 / kappa).  x = p_low / p_high, X = liquid mass per gas mass upstream."""
    alpha = 1.0 / (1.0 + np.maximum(X, 0.0) * rho_g * inv_rho_l)
    ik = 1.0 / kappa
    g0 = omega_flux(x, ik)
    live = g0 > 0.0  # (flows.select: compiled, one flow at a time, by .kernel.rhs_fused)
    ratio = flows.select(live, omega_flux(x, alpha * ik) / flows.select(live, g0, 1.0), 1.0)
    return np.sqrt(alpha) * ratio


def gas_volume(V, mo, inv_rho_l):
    """The gas's volume: the chamber's less the liquid's."""
    return V - mo * inv_rho_l


def volume_work(dy, p, n: int, na: int, inv_rho_l: float) -> None:
    """Move the work p dV_l between the liquid and the gas in place: the gas, which took
    -p dV, gets back p dmo / rho_l; the liquid gives it (see the module's balance)."""
    pdVl = p * dy[:, 2 * n:2 * n + na] * inv_rho_l
    dy[:, n:n + na] += pdVl
    dy[:, 3 * n:3 * n + na] -= pdVl


def fill_at_close(model, k: int, V: float, y: np.ndarray, acc: np.ndarray) -> None:
    """Suction close with a gas volume fraction beta < 1 at the inlet: the mixture drawn
    in fills the chamber's gas space V_g with gas (beta V_g, at its state) and liquid
    ((1 - beta) V_g at the inlet temperature).  The suction port held the gas at the
    plenum's pressure, so the liquid is booked as entering with its enthalpy
    u_l + p / rho_l and the gas it displaces as never drawn in (mass and enthalpy
    taken back from the suction's books); the chamber's work is unchanged: the volume
    was swept at the same pressure."""
    n, c, op, inv = model.n, model.acc_cols, model.op, model.inv_rho_liquid
    beta = op.gas_volume_fraction
    m, U, mo = y[:, k].copy(), y[:, n + k].copy(), y[:, 2 * n + k]
    Vg = gas_volume(V, mo, inv)
    if model.vapour:  # the gas displaced takes its vapour with it (.humid)
        mv = y[:, 4 * n + k].copy()
        p = model.fluid.props(m / Vg, U / m, mv / m)[0]
        y[:, 4 * n + k] = beta * mv
        acc[:, c.vap_in] -= (1.0 - beta) * mv
    else:
        p = model.fluid.props(m / Vg, U / m)[0]
    y[:, k] = beta * m
    y[:, n + k] = beta * U
    acc[:, ACC_M_SUC] -= (1.0 - beta) * m
    acc[:, ACC_H_SUC] -= (1.0 - beta) * (U + p * Vg)
    ml = (1.0 - beta) * Vg / inv
    # its energy is 0 at the inlet temperature (the datum): only its flow work is booked
    y[:, 2 * n + k] += ml
    acc[:, c.oil_m_in] += ml
    acc[:, c.oil_h_in] += p * (1.0 - beta) * Vg


def inlet_mass_ratio(op, rho_g_suction: float) -> float:
    """Liquid mass per gas mass of the inlet mixture: rho_l (1 - beta) / (rho_g beta)."""
    beta = op.gas_volume_fraction
    return op.liquid_density_kg_m3 * (1.0 - beta) / (rho_g_suction * beta)


def parse_keys(d: dict, s: str, where: str) -> dict:
    """The liquid keys of [operating] (see Operating): a gas volume fraction in (0, 1]
    (the liquid fraction 1 - beta in [0, 1)), below 1 only with the liquid's density and
    not beside injected oil; liquid_cp_J_kgK names the liquid's heat capacity (the oil's
    field: one liquid per case)."""
    out = {}
    if "liquid_density_kg_m3" in d:
        out["liquid_density_kg_m3"] = _number(d, "liquid_density_kg_m3", s, where, positive=True)
    beta = _number(d, "gas_volume_fraction", s, where, 1.0, positive=True)
    if beta > 1.0:
        raise CaseError(f"key 'gas_volume_fraction' in [{s}] of {where} must be in (0, 1] "
                        f"(the liquid fraction 1 - beta in [0, 1)), got {beta}")
    if beta < 1.0:
        if "liquid_density_kg_m3" not in d:
            raise CaseError(f"gas_volume_fraction < 1 in [{s}] of {where} needs the liquid's "
                            "liquid_density_kg_m3")
        if d.get("oil_mass_ratio", 0.0):
            raise CaseError(f"give gas_volume_fraction or oil_mass_ratio in [{s}] of {where}, "
                            "not both (one liquid per case)")
    out["gas_volume_fraction"] = beta
    if "liquid_viscosity_Pa_s" in d:
        out["liquid_viscosity_Pa_s"] = _number(d, "liquid_viscosity_Pa_s", s, where,
                                               positive=True)
    out.update(_volatile_keys(d, s, where, beta))
    if "liquid_cp_J_kgK" in d:
        if "oil_cp_J_kgK" in d:
            raise CaseError(f"give liquid_cp_J_kgK or oil_cp_J_kgK in [{s}] of {where}, "
                            "not both (one liquid per case)")
        out["cp"] = _number(d, "liquid_cp_J_kgK", s, where, positive=True)
    return out


def _volatile_keys(d: dict, s: str, where: str, beta: float) -> dict:
    """liquid_volatile (the liquid's CoolProp name: its vapour in the gas, :mod:`.vapour`),
    the suction gas's relative humidity in [0, 1] and the Lewis number; a volatile liquid
    is drawn in (gas_volume_fraction < 1) or injected (oil_mass_ratio)."""
    out = {}
    name = d.get("liquid_volatile")
    if name is None:
        extra = [k for k in ("suction_relative_humidity", "lewis_number") if k in d]
        if extra:
            raise CaseError(f"key '{extra[0]}' in [{s}] of {where} needs liquid_volatile")
        return out
    if not isinstance(name, str) or not name:
        raise CaseError(f"key 'liquid_volatile' in [{s}] of {where} must name a CoolProp "
                        f"fluid, got {name!r}")
    if beta == 1.0 and not d.get("oil_mass_ratio", 0.0):
        raise CaseError(f"liquid_volatile in [{s}] of {where} needs a liquid: "
                        "gas_volume_fraction < 1 or oil_mass_ratio > 0")
    rh = _number(d, "suction_relative_humidity", s, where, 1.0, nonnegative=True)
    if rh > 1.0:
        raise CaseError(f"key 'suction_relative_humidity' in [{s}] of {where} must be in "
                        f"[0, 1], got {rh}")
    out["liquid_volatile"] = name
    out["suction_relative_humidity"] = rh
    out["lewis_number"] = _number(d, "lewis_number", s, where, 1.0, positive=True)
    return out


def leak_mix(model, seg, X, fwd, x, p1, r1, k1):
    """The mixture's factor on each leakage flow and the liquid's p / rho_l upstream
    (:func:`.oil.leakage`'s ``mix``); k1 the gas's kappa, a scalar or per flow."""
    nl, inv = seg.n_leak, model.inv_rho_liquid
    Xu = np.where(fwd[:, :nl], X[:, seg.ia[:nl]], X[:, seg.ib[:nl]])
    kl = k1 if not np.ndim(k1) else k1[:, :nl]
    return mixture_factor(x[:, :nl], kl, r1[:, :nl], Xu, inv), p1[:, :nl] * inv


def port_volumes(model, y, dy, V, Vt, m, na):
    """The ideal ports' view of the gas (:func:`.kernel.ideal_ports`): its volume, its
    rate without the port's liquid (dy holds the liquid's leakage) and the liquid
    volume leaving per kg of gas."""
    n, inv = model.n, model.inv_rho_liquid
    mo = y[:, 2 * n:2 * n + na]
    Vt_g = Vt - dy[:, 2 * n:2 * n + na] * (inv / model.inv_omega)
    return gas_volume(V, mo, inv), Vt_g, mo * inv / m


#: Path kinds whose gap lies on the bores (see :func:`centrifuged_leakage`).
CASING_KINDS = ("tip", "blow-hole")
#: The liquid volume share above which the layer on the bore fills a casing gap.  Below
#: it the gap's liquid share falls linearly to zero, so that a chamber the casing gaps
#: drain dries smoothly instead of switching from liquid to gas (with the switch sharp,
#: the step size underflowed in the first period).  Seed 003's multiphase pump's chambers
#: hold 29 % of liquid at suction close, more as the gas is squeezed: its eta_v moves by
#: < 1e-7 between 5e-4 and 1e-2.
LAYER_FILL = 0.01


def _gaps(model, seg):
    """Per leakage flow of the segment (cached): whether its gap lies on the bores,
    whether it is a sealing line (or an orifice), its gap and its land (m)."""
    key = ("centrifuged", seg.index)
    if key not in model.fast:
        laws = {law.path.name: law for law in model.laws}
        own = [laws[nm] for nm in seg.names[:seg.n_leak]]
        model.fast[key] = (np.array([w.path.kind in CASING_KINDS for w in own], dtype=bool),
                           np.array([w.path.measure == "length" for w in own], dtype=bool),
                           np.array([w.gap_m for w in own]), np.array([w.land_m for w in own]))
    return model.fast[key]


def liquid_flux(dp, dp_eff, line, h, L, rho_l, mu_l):
    """The liquid's mass flux (kg/s per m2 of gap) through a sealing line (``line``) or
    an orifice at the pressure difference dp: the orifice's sqrt(2 rho_l dp_eff) (dp_eff
    the nozzle's smoothed difference, :func:`.flows._x_eff`), on a sealing line in series
    with plane Poiseuille flow along the land, rho_l h^2 dp / (12 mu_l L), the laminar
    channel with entry and exit losses, m / m_v + (m / m_i)^2 = 1, as the rarefied law's
    continuum limit joins the gas's (:mod:`.rarefied`).  The path's coefficient scales
    the whole flow (through the area), as it does the gas's laws.  Laminar along the
    land is assumed: water at 3-13 bar through 100 um reaches Re(2h) ~ 5e3-1e4, where
    turbulent friction over a 2 mm land would add ~0.4 velocity heads to the orifice's
    one (a few % of the flow, which the orifice governs there)."""
    gi = np.sqrt(2.0 * rho_l * dp_eff)
    gv = rho_l * h * h * dp / (12.0 * mu_l * L)
    r = np.where(gi > 0.0, gv / np.where(gi > 0.0, gi, 1.0), 0.0)
    series = 2.0 * gv / (1.0 + np.sqrt(1.0 + 4.0 * r * r))
    return np.where(line, series, gi)


def centrifuged_leakage(model, seg, F, X, Y, fwd, x, p1, r1, area):
    """``[leakage] mixture = "centrifuged"``: gas and liquid through separate parts of each
    gap, the liquid where the rotors have flung it.  Splits the leakage columns of the
    gas-only flows F (B, n_flows) through the flow areas ``area`` in place into the
    gas's and returns the liquid's mass and enthalpy flows (B, n_leak), as
    :func:`.oil.leakage` does.

    The grooves turn the liquid with the rotors at omega^2 r, ~280 g on seed 003's pump
    (155 mm at 1801 rpm), and the liquid is 60-800 times denser than the gas: it lies as a
    layer on the bore side of each groove, the gas in the groove's inner part (the
    stratified picture behind twin-screw multiphase pump models, e.g. Vetter & Wincek,
    ASME FED 154, 1993).  Hence:

    - a gap on the bores (tip lines; the blow-hole at the bores' cusp: CASING_KINDS)
      passes liquid only while the upstream chamber holds more than LAYER_FILL of it;
    - a gap across the groove's depth (interlobe line, end faces) is shared: the gas
      through the part of it the gas's volume share alpha covers, by the path's own
      gas law, the liquid through the rest.

    The liquid flows by its own law (:func:`liquid_flux`: orifice, and on a sealing line
    Poiseuille flow along the land with the liquid's viscosity), not the gas's; no slip
    within a phase.  Flows the walls drive against the pressure are refused with this
    mixture (:func:`.model.build`)."""
    nl, inv = seg.n_leak, model.inv_rho_liquid
    casing, line, h, L = _gaps(model, seg)
    Fl = F[:, :nl]
    up = fwd[:, :nl]
    Xu = np.where(up, X[:, seg.ia[:nl]], X[:, seg.ib[:nl]])
    Yu = np.where(up, Y[:, seg.ia[:nl]], Y[:, seg.ib[:nl]])
    pu, xl = p1[:, :nl], x[:, :nl]
    alpha = 1.0 / (1.0 + np.maximum(Xu, 0.0) * r1[:, :nl] * inv)
    layer = np.minimum((1.0 - alpha) / LAYER_FILL, 1.0)
    gas_share = np.where(casing, alpha * (1.0 - layer), alpha)
    G = liquid_flux(pu * (1.0 - xl), pu * (1.0 - flows._x_eff(xl)), line, h, L,
                    1.0 / inv, model.op.liquid_viscosity_Pa_s)
    Fo = np.where(up, 1.0, -1.0) * area[..., :nl] * (1.0 - gas_share) * G
    F[:, :nl] = Fl * gas_share
    wet = Xu > 0.0
    per_kg = np.where(wet, Yu / np.where(wet, Xu, 1.0), 0.0) + pu * inv
    return Fo, Fo * per_kg
