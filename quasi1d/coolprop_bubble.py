"""The liquid side of the saturation dome in a CoolProp property table.

The table (:mod:`.coolprop_fluid`) is bilinear in (ln rho, u) on cells ~5 % wide in
density.  A wet mixture's pressure hardly changes with density (the dome's p is p_sat(T));
a liquid's rises by its bulk modulus, ~1e3-1e4 times faster: n-pentane at 4 bar gains 3 bar
over 0.1 % of density.  A cell the bubble line cuts therefore cannot hold both sides: its
bilinear p ran from the wet node's 4 bar to the liquid node's 134 bar, a median 8 % and up
to 7 x off the flash, and a chamber that condensed at the plenum's pressure sat at the
cell's edge, 2 % lighter than the saturated liquid.

So the table carries the bubble line itself, per u node (the saturated liquid of that
internal energy, from CoolProp's (T, quality 0) flash, T found by Newton's method on
u_l(T)): rho_b, p_b, T_b and the liquid's (dp/drho)_u and (dT/drho)_u there.  A state
denser than rho_b(u) is liquid,

    p = p_b(u) + (dp/drho)_u (rho - rho_b(u)),   T = T_b(u) + (dT/drho)_u (rho - rho_b(u)),

linear in rho (n-pentane at 356 K: 2.9 bar of compression within 0.7 %, 15 bar within
2.6 %), each coefficient linear in u between nodes; its derivatives are those of this p,
so that the ideal ports' constraint holds the p the chamber sees.  A state lighter than
rho_b(u) is read from the table, whose first two liquid nodes in each column of u are
replaced by the wet side's continuation (linear in ln rho from the two wet nodes below):
the cells the bubble line cuts then interpolate the wet mixture alone, smooth up to the
line, and the kink of p sits on the line, where it is.

Not done for the dew line (vapour and wet mixture differ by 2-35 % in the derivatives and
the cut cells' p is within 7.5e-4 of the flash), nor within 3 % of the critical
temperature (BUBBLE_T_MAX), where the liquid's bulk modulus vanishes and a linear law in
rho would not hold: there the table is as before.
"""

from __future__ import annotations

import numpy as np

#: Rows of the property table (after :mod:`.coolprop_fluid`'s five) that hold the bubble
#: line at the u nodes (the first nu entries of each row): rho_b, p_b, T_b, (dp/drho)_u,
#: (dT/drho)_u of the saturated liquid.
ROW_RHO, ROW_P, ROW_T, ROW_A, ROW_DT = 5, 6, 7, 8, 9
ROWS = 5
#: rho_b where a u node has no bubble line (above the hottest saturated liquid kept, or
#: below the triple point's): no state is denser, so none is taken as liquid.  With p_b
#: 1 Pa, T_b 1 K and zero slopes there, the liquid law's unused values stay finite (no
#: overflow or division by zero beside a node that has a bubble line).
NO_LIQUID = 1e30
#: The bubble line is kept up to this fraction of the critical temperature.
BUBBLE_T_MAX = 0.97
#: Samples of u_l(T) from the triple point to BUBBLE_T_MAX x T_critical (the start of
#: Newton's method on it); ~2 ms of flashes.
SAMPLES = 1000
#: Relative step into the liquid at which its derivatives are taken (the saturated
#: state's own derivatives are the wet mixture's).
INTO_LIQUID = 1e-7


def bubble_line(st, ug: np.ndarray) -> np.ndarray:
    """(ROWS, nu): the saturated liquid at each internal energy ug (CoolProp state st),
    NO_LIQUID density where there is none."""
    import CoolProp.CoolProp as CP

    T = np.linspace(st.Ttriple() * 1.001, BUBBLE_T_MAX * st.T_critical(), SAMPLES)
    ul = np.empty_like(T)
    for n, t in enumerate(T):
        st.update(CP.QT_INPUTS, 0.0, t)
        ul[n] = st.umass()
    out = np.zeros((ROWS, ug.size))
    out[:3] = np.array([[NO_LIQUID], [1.0], [1.0]])
    slope = np.gradient(ul, T)
    for j, u in enumerate(ug):
        if not (ul[0] <= u <= ul[-1]):
            continue
        t = float(np.interp(u, ul, T))
        dudT = float(np.interp(u, ul, slope))
        for _ in range(4):  # Newton on u_l(T) = u: the samples' error, 1e-5 K, to 1e-12
            st.update(CP.QT_INPUTS, 0.0, t)
            t -= (st.umass() - u) / dudT
        st.update(CP.QT_INPUTS, 0.0, t)
        rho, p = st.rhomass(), st.p()
        st.update(CP.DmassUmass_INPUTS, rho * (1.0 + INTO_LIQUID), u)
        out[:, j] = (rho, p, t, st.first_partial_deriv(CP.iP, CP.iDmass, CP.iUmass),
                     st.first_partial_deriv(CP.iT, CP.iDmass, CP.iUmass))
    return out


def continue_wet_side(tab: np.ndarray, dome: np.ndarray, x: np.ndarray,
                      rho_b: np.ndarray) -> None:
    """Replace, in place, the first two liquid nodes of each column of u of the table
    (5, nx, nu) by the wet mixture's continuation, linear in ln rho through the two wet
    nodes below them (``dome``: the nodes inside the dome).  A column without two wet
    nodes under its liquid keeps its nodes, and so does one whose continuation would
    reach a kappa or a pressure derivative that is not positive (a wet mixture's are)."""
    rho = np.exp(x)
    for j in range(tab.shape[2]):
        liquid = np.nonzero(~dome[:, j] & (rho > rho_b[j]))[0]
        wet = np.nonzero(dome[:, j])[0]
        if liquid.size == 0 or wet.size < 2:
            continue
        k = wet[wet < liquid[0]]
        if k.size < 2 or k[-1] - k[-2] != 1 or liquid[0] - k[-1] > 2:
            continue
        top, below = tab[:, k[-1], j], tab[:, k[-2], j]
        ghosts = [(i, top + (i - k[-1]) * (top - below)) for i in liquid[:2] if i - k[-1] <= 2]
        if all(np.all(g[2:] > 0.0) for _, g in ghosts):
            for i, g in ghosts:
                tab[:, i, j] = g


def liquid_state(table, j, tu, rho, du):
    """rho_b at the cells' u (j, tu: :func:`.coolprop_fluid.table_cell`) and the liquid
    state there at rho: (rho_b, p, T, kappa, (dp/drho)_u, (dp/du)_rho) (arrays or
    scalars; meaningful where rho >= rho_b)."""
    r0, r1 = table[ROW_RHO, j], table[ROW_RHO, j + 1]
    p0, p1 = table[ROW_P, j], table[ROW_P, j + 1]
    a0, a1 = table[ROW_A, j], table[ROW_A, j + 1]
    rb = r0 + tu * (r1 - r0)
    a = a0 + tu * (a1 - a0)
    d = rho - rb
    p = p0 + tu * (p1 - p0) + a * d
    T = table[ROW_T, j] + tu * (table[ROW_T, j + 1] - table[ROW_T, j]) + d * (
        table[ROW_DT, j] + tu * (table[ROW_DT, j + 1] - table[ROW_DT, j]))
    pu = ((p1 - p0) + (a1 - a0) * d - a * (r1 - r0)) / du
    kappa = rho * (a + p / (rho * rho) * pu) / p
    return rb, p, T, kappa, a, pu
