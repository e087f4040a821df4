"""The property table of a CoolProp fluid: which states a run can reach, and the table's
nodes over them, two-phase states included.

Nodes are evaluated with CoolProp's (rho, u) flash (``DmassUmass_INPUTS``, HEOS backend),
which returns the equilibrium state on either side of the saturation dome: inside it a
homogeneous equilibrium mixture (HEM: both phases at one p and T, one velocity), whose
p and T are the saturation values.  Per node the table holds

    ln p, T, kappa = rho a^2 / p, (dp/drho)_u, (dp/du)_rho

with the sound speed of the equilibrium mixture,

    a^2 = (dp/drho)_s = (dp/drho)_u + (p / rho^2) (dp/du)_rho        (du = T ds + p/rho^2 drho),

which is the ordinary sound speed in one phase and the HEM (equilibrium) sound speed in
two (Wallis 1969, *One-dimensional two-phase flow*, ch. 2).  CoolProp's speed_sound()
raises inside the dome and its first_partial_deriv there returns the single-phase
Helmholtz derivatives at the mixture's density (measured for R134a at 3 bar, quality
0.95: dp/du 1.96 against the mixture's 1.65 Pa kg/J), so inside the dome both pressure
derivatives are difference quotients of the flash (on the side that stays inside the dome
when a node lies next to the saturation line).

CoolProp's tabular backends (``BICUBIC&HEOS``, ``TTSE&HEOS``) would be faster per call but
do not accept (rho, u) inputs (CoolProp 6/7: "this set of inputs is not supported for
Tabular backend"), which the chamber equations need without inner iteration; the flash
here costs ~10 us a node (40 000 nodes: well under a second).
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError

# Step of the difference quotients inside the dome: relative 1e-6 in density, 1e-6 of the
# table's u-span in u.  The flash returns p to ~1e-12, so the quotients carry ~1e-6 relative
# noise, below the table's interpolation error (see TabulatedFluid).
FD_STEP = 1.0e-6

# Margins of the reachable range (see reachable_box).
P_LOW_FRACTION = 0.01  # deep under-pressure: a leaking vacuum chamber, a throttled suction
# ... but not below the triple point: CO2's (5.2 bar) lies above 1 % of a 35 bar suction,
# and below it the fluid would freeze, which the equation of state does not describe.
# 1 % above it so that the expanded suction isentrope stays in the fluid region.
P_TRIPLE_MARGIN = 1.01
P_HIGH_FACTOR = 3.0  # over-compression and throttled discharge above max(pd, built-in end)
HOT_RISE_FACTOR = 2.0  # recompressed leakage: up to 3x the isentropic rise above suction
# CoolProp's (rho, u) flash fails above ~1.5 x the equation of state's Tmax (R134a: 682 K
# for Tmax 455 K); the table stops below it and a hotter state is reported.
T_MAX_FACTOR = 1.4


def _state(name: str):
    import CoolProp.CoolProp as CP

    try:
        return CP.AbstractState("HEOS", name)
    except ValueError as exc:
        raise CaseError(f"CoolProp does not know the fluid {name!r}: {exc}") from None


def suction_state(name: str, ps: float, Ts: float, qs: float | None):
    """(rho, u, h, s, T) of the suction gas: at (p, T), or at (p, quality) for a wet
    suction (PT inputs are singular inside the dome)."""
    import CoolProp.CoolProp as CP

    st = _state(name)
    if qs is None:
        st.update(CP.PT_INPUTS, ps, Ts)
    else:
        st.update(CP.PQ_INPUTS, ps, qs)
    return st.rhomass(), st.umass(), st.hmass(), st.smass(), st.T()


def dew_temperature(name: str, p: float) -> float | None:
    """The saturated vapour's temperature at p (the dew point of a pseudo-pure blend),
    None at or above the critical pressure (no dome to fall into)."""
    import CoolProp.CoolProp as CP

    st = _state(name)
    if p >= st.p_critical():
        return None
    st.update(CP.PQ_INPUTS, p, 1.0)
    return st.T()


def reachable_box(name, ps, pd, Ts, qs, Tw, To, vr):
    """(rho_lo, rho_hi, u_lo, u_hi) of the table for suction (ps, Ts or quality qs),
    discharge pressure pd, wall and oil temperatures Tw, To and volume ratio vr.

    Pressures from P_LOW_FRACTION x ps (at least P_TRIPLE_MARGIN x the triple-point
    pressure) to P_HIGH_FACTOR x the larger of pd and the end
    pressure of the built-in compression (the suction isentrope at vr x the suction
    density).  Internal energy from the coldest of: the suction isentrope expanded to the
    lowest pressure, the coldest boundary temperature at the highest density (inside the
    dome if the wall or oil is below saturation there); to the hottest gas: the hottest
    boundary or isentropic end temperature plus HOT_RISE_FACTOR x the isentropic rise,
    at the lowest density.  Density from the hottest gas at the lowest pressure to the
    suction isentrope at the highest pressure (or the saturated vapour there, if denser).
    """
    import CoolProp.CoolProp as CP

    st = _state(name)
    rho_s, u_s, _, s_s, T_s = suction_state(name, ps, Ts, qs)
    st.update(CP.DmassSmass_INPUTS, rho_s * vr, s_s)
    p_end = st.p()
    p_hi = P_HIGH_FACTOR * max(pd, p_end)
    p_lo = max(P_LOW_FRACTION * ps, P_TRIPLE_MARGIN * st.trivial_keyed_output(CP.iP_triple))
    st.update(CP.PSmass_INPUTS, max(pd, p_end), s_s)
    T_end = st.T()
    T_hi = min(max(T_end, Tw, To) + HOT_RISE_FACTOR * (T_end - T_s),
               T_MAX_FACTOR * st.Tmax())
    st.update(CP.PSmass_INPUTS, p_lo, s_s)
    u_exp = st.umass()
    st.update(CP.PSmass_INPUTS, p_hi, s_s)
    rho_hi = st.rhomass()
    if p_hi < st.p_critical():
        st.update(CP.PQ_INPUTS, p_hi, 1.0)
        rho_hi = max(rho_hi, st.rhomass())
    st.update(CP.PT_INPUTS, p_lo, T_hi)
    rho_lo, u_hi = st.rhomass(), st.umass()
    st.update(CP.DmassT_INPUTS, rho_hi, min(T_s, Tw, To))
    u_lo = min(u_exp, u_s, st.umass())
    return rho_lo, rho_hi, u_lo, u_hi


def build_nodes(name: str, x: np.ndarray, ug: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The table (5, nx, nu) on ln rho = x and u = ug, NaN where CoolProp cannot evaluate
    (below the triple point, beyond the equation of state); and which nodes lie inside
    the dome (nx, nu)."""
    import CoolProp.CoolProp as CP

    st = _state(name)
    two = CP.iphase_twophase
    du_fd = FD_STEP * (ug[-1] - ug[0])
    tab = np.full((5, x.size, ug.size), np.nan)
    dome = np.zeros((x.size, ug.size), dtype=bool)

    def p_at(r, u):
        st.update(CP.DmassUmass_INPUTS, r, u)
        return st.p(), st.phase() == two

    for i, rho in enumerate(np.exp(x)):
        for j, u in enumerate(ug):
            try:
                st.update(CP.DmassUmass_INPUTS, rho, u)
                p, T = st.p(), st.T()
                dome[i, j] = st.phase() == two
                if not dome[i, j]:
                    pr = st.first_partial_deriv(CP.iP, CP.iDmass, CP.iUmass)
                    pu = st.first_partial_deriv(CP.iP, CP.iUmass, CP.iDmass)
                else:
                    pr = _quotient(p, p_at, rho, u, rho * FD_STEP, 0.0)
                    pu = _quotient(p, p_at, rho, u, 0.0, du_fd)
            except ValueError:
                continue
            a2 = pr + p / (rho * rho) * pu
            tab[:, i, j] = (math.log(p), T, rho * a2 / p, pr, pu) if p > 0 and a2 > 0 else np.nan
    return tab, dome


def _quotient(p0, p_at, rho, u, dr, du):
    """Forward difference quotient of p inside the dome along (dr, du), backward where
    the forward neighbour has left the dome (a node next to the saturation line).  One
    side is enough: its O(step) error, ~1e-6 relative, is below the table's own."""
    h = dr + du
    pp, inside = p_at(rho + dr, u + du)
    if inside:
        return (pp - p0) / h
    pm, inside = p_at(rho - dr, u - du)
    if inside:
        return (p0 - pm) / h
    raise ValueError("a two-phase node without two-phase neighbours")


#: Nodes inside a pseudo-pure blend's dome continued from its vapour, per row of density.
VAPOUR_GHOSTS = 1


def continue_vapour_side(name: str, tab: np.ndarray) -> None:
    """Fill, in place, the first VAPOUR_GHOSTS nodes inside the dome of a pseudo-pure
    blend (R404A, R410A, ...) in each row of density of the table (5, nx, nu) with the
    vapour's continuation, linear in u through the two vapour nodes above them.

    CoolProp's (rho, u) flash fails inside a blend's dome (no equilibrium mixture of one
    pseudo-pure fluid across its glide), so those nodes were NaN, and every cell the dew
    line cuts with them: a suction within a cell of the dew line (R404A at 4 bar, 0.6 K
    of superheat) left the table at the first compression step (step size underflow),
    and one a cell closer was refused as not superheated.  The continuation is the
    metastable vapour's p, T and derivatives, which meet the dome's at the dew line
    (continuous p and T, the kink at the line); deeper nodes stay NaN, out of the table.
    A pure fluid's dome nodes are CoolProp's own (untouched)."""
    import CoolProp.CoolProp as CP

    if CP.get_fluid_param_string(name, "pure") != "false":
        return
    finite = np.all(np.isfinite(tab), axis=0)
    for i in range(tab.shape[1]):
        vap = np.nonzero(finite[i])[0]
        if vap.size < 2 or vap[0] == 0 or vap[1] != vap[0] + 1:
            continue
        k = vap[0]
        top, above = tab[:, i, k], tab[:, i, k + 1]
        for g in range(1, min(VAPOUR_GHOSTS, k) + 1):
            ghost = top - g * (above - top)
            if np.isfinite(tab[0, i, k - g]) or not np.all(ghost[2:] > 0.0):
                break
            tab[:, i, k - g] = ghost
