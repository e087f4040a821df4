"""The chamber model's side of a volatile liquid (:mod:`.vapour`): the vapour's state,
flows, evaporation and events.

The vapour rides in a fifth state block, its mass mv per slot (columns 4n..); the gas's
mass m and energy U (blocks 0 and 1) hold carrier and vapour together, the liquid's
(blocks 2 and 3) the liquid alone.  Every gas flow carries vapour at its upstream node's
fraction w: a slot's mv / m, the suction plenum's (its relative humidity), the discharge
plenum's (:func:`humid_plenums`).  The accumulators count the vapour drawn in, delivered
and evaporated (:class:`.network.AccColumns`), so that each of gas, liquid and vapour
closes its own balance over a cycle (:func:`.cycle.balances`):

    gas     drawn in - delivered + evaporated = stored change
    liquid  in - out - evaporated             = stored change
    vapour  drawn in - delivered + evaporated = stored change

and the energy's balance is the one without vapour: evaporation moves energy between
the liquid and the gas, it creates none.  The ideal ports hold the pressure with the
composition's share of dp/dt (p depends on w at fixed rho and u).
"""

from __future__ import annotations

import numpy as np

from . import kernel, liquid
from .network import ACC_H_DIS, ACC_M_DIS, ACC_M_SUC
from .oil import flooded_discharge_T
from .plenums import Plenum, liquid_ratio

BLOCK = 4  # the vapour's state block


def humid_plenums(fluid, op) -> tuple[Plenum, Plenum]:
    """(suction, discharge): the suction gas at its relative humidity (fluid.w_ref); the
    discharge plenum's gas at the flooded compression's end temperature
    (:func:`.oil.flooded_discharge_T`, gas and liquid in equilibrium from the moment they
    mix), saturated there as a discharge line full of liquid holds it, or holding all
    the liquid evaporated, whichever is less.  It enters the chambers only as gas that
    flows back from the discharge; a drier plenum would be saturated anew in the
    chamber and raise the vapour delivered (on the multiphase pump at 4 bar with water
    at 330 K: 0.034 with the suction's composition against 0.027 saturated)."""
    def plenum(p, T, w):
        rho, u, h = fluid.state_pT(p, T, w)
        return Plenum(p, T, rho, u, h, float(fluid.props(rho, u, w)[2]), float(w))

    suc = plenum(op.p_suction_Pa, op.T_suction_K, fluid.w_ref)
    ratio = liquid_ratio(op, suc)
    Td = flooded_discharge_T(fluid, suc, op, ratio)
    w_all = (fluid.w_ref + ratio) / (1.0 + ratio)
    w_d = min(float(fluid.saturated_fraction(op.p_discharge_Pa, Td)), w_all)
    return suc, plenum(op.p_discharge_Pa, Td, w_d)


def _map(model, seg, name: str) -> np.ndarray:
    """The segment's map ``name`` of gas mass flows (mm, mx) turned into the vapour's:
    slot masses to the vapour block, the suction's and discharge's mass sums to the
    vapour's."""
    key = ("vapour", seg.index, name)
    if key not in model.fast:
        M = getattr(seg, name)
        n, acc0, c = model.n, model.nv * model.n, model.acc_cols
        out = np.zeros_like(M)
        out[:, BLOCK * n:(BLOCK + 1) * n] = M[:, :n]
        out[:, acc0 + c.vap_in] = M[:, acc0 + ACC_M_SUC]
        out[:, acc0 + c.vap_out] = M[:, acc0 + ACC_M_DIS]
        model.fast[key] = out
    return model.fast[key]


def fractions(model, y, m, na):
    """Every active slot's vapour fraction w = mv / m."""
    n = model.n
    return y[:, BLOCK * n:BLOCK * n + na] / m


def flows_and_evaporation(model, seg, dy, F, y, m, rho, w, p) -> None:
    """Add in place the vapour that the gas flows F carry (each at its upstream node's
    fraction) and the evaporation (:meth:`.vapour.HumidGas.evaporation`)."""
    n, na, op, c, fl = model.n, seg.n_act, model.op, model.acc_cols, model.fluid
    wo, acc0 = model.inv_omega, model.nv * model.n
    W = kernel.nodes(w, model.suc.w, model.dis.w)
    dy += (F * np.where(F > 0.0, W[:, seg.ia], W[:, seg.ib])) @ _map(model, seg, "mm")
    mo, Ho = y[:, 2 * n:2 * n + na], y[:, 3 * n:3 * n + na]
    J, T_l = fl.evaporation(mo, Ho, op.oil_cp_J_kgK, op.oil_time_constant_s, rho, w, fl.cp(w))
    # the vapour leaves the liquid at its temperature; the liquid's p / rho_l goes with
    # its volume (liquid.volume_work moves it back)
    e = J * (fl.vapour.h(T_l) + p * model.inv_rho_liquid) * wo
    Jw = J * wo
    dy[:, :na] += Jw
    dy[:, BLOCK * n:BLOCK * n + na] += Jw
    dy[:, n:n + na] += e
    dy[:, 2 * n:2 * n + na] -= Jw
    dy[:, 3 * n:3 * n + na] -= e
    dy[:, acc0 + c.evaporated] += Jw.sum(axis=1)


def ideal_ports(model, seg, dy, pdV, g, y, m, rho, u, p, h, w, relax):
    """The ideal ports' flows (kg/s into the slots) with the vapour they carry, added to
    dy in place (:func:`.kernel.ideal_flow` with the composition's share of dp/dt).

    dp/dt gains p_w dw/dt, dw/dt = (Av + x w_x - w (A + x)) / m: its part without x,
    p_w (Av - w A) / m, is taken off the drift target (as a plenum pressure lower by
    relax / omega times it), its part per kg flowing in, p_w (w_x - w) / m, joins the
    inflow's p_u (h_x - u) / rho term (as an enthalpy higher by p_w (w_x - w) / p_u);
    an outflow leaves w unchanged."""
    n, na, c, om = model.n, seg.n_act, seg.ideal, model.geo.omega_outer
    V, Vt = g[0], g[3]
    kl = 0.0
    if model.inv_rho_liquid:
        V, Vt, kl = liquid.port_volumes(model, y, dy, V, Vt, m, na)
        kl = kl[:, c]
    pr, pu, pw = model.fluid.dp(rho, u, w)
    A, Av = dy[:, c] * om, dy[:, BLOCK * n + c] * om
    wc, mc = w[:, c], m[:, c]
    w_pl = np.where(seg.ideal_is_dis, model.dis.w, model.suc.w)
    p_pl = seg.ideal_p - relax / om * pw[:, c] * (Av - wc * A) / mc
    h_pl = seg.ideal_h + pw[:, c] * (w_pl - wc) / pu[:, c]
    x, _ = kernel.ideal_flow(A, (dy[:, n + c] + pdV[:, c]) * om, rho[:, c], u[:, c], p[:, c],
                             h[:, c], pr[:, c], pu[:, c], V[..., c], Vt[..., c], p_pl, h_pl,
                             om, relax, 0.0, kl)
    inflow = x > 0.0
    dy += x @ seg.mx + (x * np.where(inflow, seg.ideal_h, h[:, c])) @ seg.mxe
    dy += (x * np.where(inflow, w_pl, wc)) @ _map(model, seg, "mx")
    return x


def born(model, k, m, y, acc) -> None:
    """A chamber born full of suction gas holds its vapour."""
    y[:, BLOCK * model.n + k] = model.suc.w * m
    acc[:, model.acc_cols.vap_in] += model.suc.w * m


def delivered(model, k, y, acc) -> None:
    """A dying chamber's vapour goes to the discharge."""
    col = BLOCK * model.n + k
    acc[:, model.acc_cols.vap_out] += y[:, col]
    y[:, col] = 0.0


def equalise(model, k, V, y, acc) -> None:
    """:func:`.events._equalise` with the vapour: expanded at its own composition, or
    filled with the discharge plenum's gas."""
    n, fl, pd, dis = model.n, model.fluid, model.dis.p, model.dis
    m, U, mv = (y[:, b * n + k].copy() for b in (0, 1, BLOCK))
    w = mv / m
    rho, u = m / V, U / m
    p = fl.props(rho, u, w)[0]
    m2, U2, mv2 = m.copy(), U.copy(), mv.copy()
    over, under = p > pd * (1 + 1e-12), p < pd * (1 - 1e-12)
    if np.any(over):
        r2, u2 = fl.isentropic(rho[over], u[over], pd, w[over])
        m2[over] = r2 * V
        U2[over] = m2[over] * u2
        mv2[over] = w[over] * m2[over]
    if np.any(under):
        m2[under], U2[under], mv2[under] = fl.fill(m[under], U[under], mv[under], V, dis.h,
                                                  dis.w, pd)
    y[:, k], y[:, n + k], y[:, BLOCK * n + k] = m2, U2, mv2
    c = model.acc_cols
    acc[:, ACC_M_DIS] += m - m2
    acc[:, ACC_H_DIS] += U - U2
    acc[:, c.vap_out] += mv - mv2
