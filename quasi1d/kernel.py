"""The chamber equations' right-hand side on flat arrays: the pieces
:meth:`.model.ChamberModel.rhs` is made of, and :func:`rhs_fused`, all of them in one
compiled function for the segments that need nothing else (see :func:`fusable`).

The physics is written once, element-wise (the fluid's state :func:`fluid_state`, the
nozzle and Fanno fluxes of :mod:`.flows`, the ideal port's flow :func:`ideal_flow`):
numpy calls it on whole arrays of the batch (B, ...) in the model's piecewise
right-hand side, with its other terms (calibrated or rarefied leakage, moving walls,
oil, liquids) in between; :func:`rhs_fused`, compiled by numba (:mod:`.compiled`), calls it one
element at a time inside loops over the batch, the slots and the flows.  Written in
numpy style, the compiled function was bound by its ~60 temporaries a call and by
dense products with the flow maps; the loops have none and add each flow to the five
entries of dy it touches.

Measured on the default case (8 slots, 47 flows of which ~25 open) on a loaded
machine: ~20 us a call for the cycle solver's batch of 15 states (31 us numpy-style
compiled, ~120 us numpy), 1.8 us for one state; with nozzle ports and no leakage (6
flows) ~9 us for 15 states and ~140 us for the 240 of a Rosenbrock Jacobian (~180 us
numpy-style).  What is left is the arithmetic: the nozzle formula's power (~12 ns) and
square roots per flow, the fluid table per slot.
"""

from __future__ import annotations

import numpy as np

from . import flows, stepping
from .chamber import spline_at
from .coolprop_fluid import table_state
from .dry_air import table_interp as table_1d
from .liquid import mixture_factor
from .oil import heat_to_gas, homogeneous_split
from .rarefied import flow_flux

# Fluid kinds of fluid_state (the fluids' kernel_params)
PERFECT, TABLE_1D, TABLE_2D = 0, 1, 2


def fluid_state(kind, par, tab, rho, u):
    """p, T, kappa, (dp/drho)_u and (dp/du)_rho at rho, u (scalars or arrays) of one of
    the three fluids (:mod:`.fluids`): the perfect gas (par: gamma - 1, 1 / cv, gamma),
    dry air's table in u (par: u0, du, R), a CoolProp table in (ln rho, u) (par: x0, dx,
    u0, du, nodes in u)."""
    if kind == PERFECT:
        g1 = par[0]
        return g1 * rho * u, u * par[1], par[2] + 0.0 * rho, g1 * u, g1 * rho
    if kind == TABLE_1D:
        T, kap, icv = table_1d(u, par[0], par[1], tab)
        R = par[2]
        return R * rho * T, T, kap, R * T, R * rho * icv
    nu = int(par[4])
    return table_state(rho, u, par[0], par[1], par[2], par[3], nu, tab)


def nodes(x, suction, discharge):
    """Node values (B, na + 2): the suction plenum, the slots' x (B, na), the discharge."""
    B, na = x.shape
    out = np.empty((B, na + 2))
    out[:, 0] = suction
    out[:, 1:na + 1] = x
    out[:, na + 1] = discharge
    return out


def upstream(P, R, ia, ib):
    """Direction (a to b), pressure ratio x = p_low / p_high <= 1, upstream pressure and
    density of the paths from node ia to node ib, from node pressures P and densities R."""
    pa, pb = P[:, ia], P[:, ib]
    fwd = pa >= pb
    p1 = np.maximum(pa, pb)
    x = np.minimum(pa, pb) / p1
    r1 = np.where(fwd, R[:, ia], R[:, ib])
    return fwd, x, p1, r1


def mass_flows(fwd, p1, r1, f, area):
    """Signed mass flows (kg/s, positive from a to b): sqrt(p1 rho1) f(x) times the area."""
    F = np.sqrt(p1 * r1) * f * area
    return np.where(fwd, F, -F)


def enthalpy_flows(F, Ha, Hb):
    """Enthalpy flows (W) of the mass flows F, at the enthalpy of the node they leave."""
    return F * np.where(F > 0.0, Ha, Hb)


def balances(F, E, mm, me, mg, p, dV, n, acc_w):
    """dy/dtheta of the flows (slot balances and accumulators, through the segment's
    maps), with -p dV in every slot's energy and the p dV work accumulated; also p dV."""
    na = p.shape[1]
    dy = F @ mm + E @ me + np.abs(F) @ mg
    pdV = p * dV
    dy[:, n:n + na] -= pdV
    dy[:, acc_w] = -pdV.sum(axis=1)
    return dy, pdV


def ideal_ports(dy, pdV, V, Vt, rho, u, p, h, pr, pu, c, p_pl, h_pl, mx, mxe, omega,
                relax, n, gamma, kl=0.0):
    """Add the ideal ports' flows to dy in place (those that hold the open slots c at
    their plenum's pressure p_pl, gas of enthalpy h_pl flowing in); returns them (kg/s).
    ``gamma`` > 0: a perfect gas of that gamma (then pr, pu are not read).  With a liquid
    of finite density (:mod:`.liquid`): V, Vt the gas's volume and its rate without the
    port's liquid, kl (B, na) the liquid volume that leaves per kg of gas."""
    kl = kl[:, c] if np.ndim(kl) else kl
    x, hx = ideal_flow(dy[:, c] * omega, (dy[:, n + c] + pdV[:, c]) * omega, rho[:, c],
                       u[:, c], p[:, c], h[:, c], pr[:, c], pu[:, c], V[..., c], Vt[..., c],
                       p_pl, h_pl, omega, relax, gamma, kl)
    dy += x @ mx + (x * hx) @ mxe
    return x


def ideal_flow(A, Bh, rc, uc, pc, hc, prc, puc, Vc, Vtc, p_pl, h_pl, omega, relax, gamma,
               kl):
    """The flow x (kg/s) into a slot held at its plenum's pressure p_pl by an ideal port,
    and the enthalpy it carries (arrays or scalars, :func:`.flows.select`): A the other
    mass flows in (kg/s), Bh the other enthalpy flows and heat (W).

    The flow makes dp/dt = (p_pl - p) omega / relax (the drift correction): with
    dm/dt = A + x and dU/dt = Bh + x h_x - p dV/dt, dp/dt = pr drho/dt + pu du/dt.
    A liquid leaving with the gas (kl m3 per kg of gas out, :mod:`.liquid`) makes the
    gas's volume rate Vtc - kl x for x < 0: the outflow's denominator gains
    kl (rho h) (perfect gas) or kl (pr rho + pu p / rho)."""
    tgt = (p_pl - pc) * (omega / relax)
    if gamma > 0.0:
        g1 = gamma - 1.0
        num = Vc * tgt / g1 - Bh + rc * hc * Vtc
        x = num / flows.select(num > 0.0, h_pl + 0.0 * hc, hc * (1.0 + rc * kl))
    else:
        num = Vc * tgt - prc * (A - rc * Vtc) - puc * (Bh - pc * Vtc - uc * A) / rc
        x_in = num / (prc + puc * (h_pl - uc) / rc)
        x_out = num / (prc + puc * (hc - uc) / rc + kl * (prc * rc + puc * pc / rc))
        x = flows.select(x_in > 0.0, x_in, np.minimum(x_out, 0.0))
    return x, flows.select(x > 0.0, h_pl + 0.0 * hc, hc)


def fusable(model, seg) -> bool:
    """The segment needs nothing but what :func:`rhs_fused` evaluates: nozzle, Fanno or
    rarefied leakage on static walls, gas, gas with injected oil (:mod:`.oil`) or with a
    liquid that fills volume and leaks with it as a homogeneous mixture (:mod:`.liquid`;
    no vapour), a fluid with kernel parameters."""
    return (not model.vapour and not seg.walls and not seg.cou_gap.size
            and not (model.inv_rho_liquid and model.leak.mixture == "centrifuged")
            and all(g.model in ("nozzle", "fanno", "rarefied") for g in seg.groups)
            and hasattr(model.fluid, "kernel_params"))


def flow_laws(seg):
    """The segment's flow laws as :func:`rhs_fused` takes them: Fanno's flags, zeta and
    choking ratio, and the rarefied law's rows (a flag, then
    :meth:`.rarefied.RarefiedLaw.per_flow`'s) per flow."""
    nf = seg.ia.size
    fanno, zeta, x_choke = np.zeros(nf, bool), np.zeros(nf), np.zeros(nf)
    rar = np.zeros((7, nf))
    for grp in seg.groups:
        if grp.model == "fanno":
            fanno[grp.flows], zeta[grp.flows] = True, grp.zeta
            x_choke[grp.flows] = grp.x_choke
        elif grp.model == "rarefied":
            rar[0, grp.flows] = 1.0
            rar[1:, grp.flows] = grp.rarefied.per_flow(rar[0, grp.flows].size)
    return fanno, zeta, x_choke, rar


def scatter(m):
    """The rows of a map (rows, cols) as sparse rows for the compiled loops: row i's
    non-zero columns col[ptr[i]:ptr[i + 1]] and their weights w (a flow touches two
    nodes: its rows of mm and me hold two entries of the state's ~25, of mg one)."""
    rows, col = np.nonzero(m)
    ptr = np.searchsorted(rows, np.arange(m.shape[0] + 1))
    return ptr.astype(np.intp), col.astype(np.intp), np.ascontiguousarray(m[rows, col])


def _add(dy, b, sparse, i, v):
    """dy[b] += v times row i of the map ``sparse`` (:func:`scatter`)."""
    ptr, col, w = sparse
    for q in range(ptr[i], ptr[i + 1]):
        dy[b, col[q]] += w[q] * v


# Rows of rhs_fused's node values (suction plenum, the slots, the discharge plenum):
# the state, the nozzle constants of its kappa (critical ratio, 2k / (k - 1), 1 / k) and
# sqrt(p rho), the slots' T and pressure derivatives; with oil (.oil) its mass and
# enthalpy per gas mass, its heat to the gas and the gas leaving through a discharge port;
# kappa itself (a liquid's mixture factor, .liquid).
_P, _R, _H, _U, _XC, _CC, _IK, _S, _T, _PR, _PU, _X, _Y, _QO, _OUT, _K = range(16)


def _node(W, j, p, rho, h, kap):
    W[_P, j], W[_R, j], W[_H, j], W[_S, j], W[_K, j] = p, rho, h, np.sqrt(p * rho), kap
    xc, cc, ik = flows.nozzle_constants(kap)
    W[_XC, j], W[_CC, j], W[_IK, j] = xc, cc, ik


def rhs_fused(y, n, na, V, iV, dV, Vt, area, wall, T_wall, w, omega, relax, ia, ib,
              fanno, zeta, x_choke, rar, maps, acc_w, acc_q, c, p_pl, h_pl, ideal_maps, plen,
              kind, par, tab, gamma, oil):
    """dy/dtheta of a fusable segment (see :meth:`.model.ChamberModel.rhs`): y (B, S);
    the geometry of the active slots at the angle (V, 1/V, dV/dtheta, dV/dt, the flows'
    areas, heat transfer coefficient times area or an empty array); the flows' nodes and
    laws (Fanno where ``fanno``, rarefied where ``rar[0]`` > 0: its rows those of
    :meth:`.rarefied.RarefiedLaw.per_flow` shifted by one); the flows' and the ideal
    ports' maps into dy
    (:func:`scatter` of mm, me, mg and of mx, mxe); the ideal ports (slots c); the
    plenums' p, rho, h, kappa (plen (4, 2)); the fluid (kind, par, tab; gamma > 0 a
    perfect gas); the injected oil or a liquid (:func:`.oil.fused_args`: its leakage
    with the gas, its heat to the gas, its exit through the discharge port, and a
    liquid's 1 / rho_l, which takes its volume from the gas's, :mod:`.liquid`).

    Loops over the batch, the slots and the flows, calling the physics one element at a
    time (:func:`fluid_state`, :func:`.flows.nozzle_f_c`, :func:`.flows.fanno_f`,
    :func:`ideal_flow`): compiled, no temporaries; each flow adds to the few entries of
    dy its maps name instead of dense products with them.  What depends on one node
    only (sqrt(p rho), the nozzle's constants) is evaluated per node, not per flow."""
    B = y.shape[0]
    dy = np.zeros(y.shape)
    W = np.empty((16, na + 2))  # node values of one batch member
    _node(W, 0, plen[0, 0], plen[1, 0], plen[2, 0], plen[3, 0])
    _node(W, na + 1, plen[0, 1], plen[1, 1], plen[2, 1], plen[3, 1])
    x_id = np.empty(c.size)
    h_id = np.empty(c.size)
    on, split, nl, flags, inv = oil[0], oil[1], oil[2], oil[8], oil[11]
    nf = ia.size
    if on:
        W[_X, 0] = W[_Y, 0] = 0.0  # (the suction plenum's gas is dry)
        W[_X, na + 1], W[_Y, na + 1] = oil[6], oil[7]
    for b in range(B):
        _slots(W, y, b, n, na, V, iV, kind, par, tab, gamma, on, inv)
        for f in range(ia.size):
            if not area[f] > 0.0:  # a line that does not exist at this angle
                continue
            a, d = ia[f], ib[f]
            fwd = W[_P, a] >= W[_P, d]
            up, dn = (a, d) if fwd else (d, a)
            x = W[_P, dn] / W[_P, up]
            F = W[_S, up] * _flux_at(W, f, up, x, fanno, zeta, x_choke, rar) * area[f]
            F = F if fwd else -F
            if split and f < nl:  # a homogeneous gas-oil mixture leaks (.oil)
                F = _oil_leak(dy, b, maps, nf + f, F, W, ia[f] if F >= 0.0 else ib[f], x,
                              inv)
            elif on and flags[f]:  # (the oil leaves with the gas, _oil_exit)
                W[_OUT, a] += max(F, 0.0)
            _add(dy, b, maps[0], f, F)
            _add(dy, b, maps[1], f, F * (W[_H, a] if F > 0.0 else W[_H, d]))
            _add(dy, b, maps[2], f, abs(F))
        work = 0.0
        for k in range(na):
            pdv = W[_P, k + 1] * dV[k]
            dy[b, n + k] -= pdv
            work += pdv
        dy[b, acc_w] = -work
        if wall.size:
            heat = 0.0
            for k in range(na):
                q = wall[k] * (T_wall - W[_T, k + 1])
                dy[b, n + k] += q * w
                heat += q
            dy[b, acc_q] = heat * w
        if on:
            _oil_heat(dy, b, y, n, na, W, oil, w)
        for i in range(c.size):
            k = c[i]
            Vg, Vtg, kl = _port_gas(V, Vt, y, dy, b, n, k, inv, w)
            x_id[i], h_id[i] = ideal_flow(
                dy[b, k] * omega, (dy[b, n + k] + W[_P, k + 1] * dV[k]) * omega,
                W[_R, k + 1], W[_U, k + 1], W[_P, k + 1], W[_H, k + 1], W[_PR, k + 1],
                W[_PU, k + 1], Vg, Vtg, p_pl[i], h_pl[i], omega, relax, gamma, kl)
        for i in range(c.size):
            _add(dy, b, ideal_maps[0], i, x_id[i])
            _add(dy, b, ideal_maps[1], i, x_id[i] * h_id[i])
        if on:
            _oil_exit(dy, b, y, n, na, W, oil, x_id, c, nf, w)
    return dy


def _flux_at(W, f, up, x, fanno, zeta, x_choke, rar):
    """The gas's flux f(x) of flow f (upstream node ``up``): Fanno's, the nozzle's, or
    the rarefied law's, whose inertial limit is the nozzle's."""
    if fanno[f]:
        return flows.fanno_f(x, zeta[f], x_choke[f])
    fx = flows.nozzle_f_c(x, W[_XC, up], W[_CC, up], W[_IK, up])
    if rar[0, f] > 0.0:
        fx = flow_flux(fx, x, W[_P, up], W[_R, up], rar[2, f], rar[3, f], rar[4, f],
                       rar[5, f], rar[6, f], rar[1, f] > 0.0)
    return fx


def _port_gas(V, Vt, y, dy, b, n, k, inv, w):
    """Slot k's gas volume, its rate without the port's liquid and the liquid volume
    leaving per kg of gas, as the ideal port sees them (:func:`.liquid.port_volumes`;
    dy holds the liquid's leakage); V[k], Vt[k] and 0 without a liquid's volume."""
    if not inv > 0.0:
        return V[k], Vt[k], 0.0
    mo = y[b, 2 * n + k]
    return V[k] - mo * inv, Vt[k] - dy[b, 2 * n + k] * (inv / w), mo * inv / y[b, k]


def _slots(W, y, b, n, na, V, iV, kind, par, tab, gamma, on, inv):
    """The slots' node values (W's columns 1..na) of batch member b; a liquid (inv =
    1 / rho_l > 0) leaves the gas the volume V - mo / rho_l."""
    for k in range(na):
        m = y[b, k]
        rho = m / (V[k] - y[b, 2 * n + k] * inv) if inv > 0.0 else m * iV[k]
        u = y[b, n + k] / m
        p, T, kap, pr, pu = fluid_state(kind, par, tab, rho, u)
        _node(W, k + 1, p, rho, u * gamma if gamma > 0.0 else u + p / rho, kap)
        W[_U, k + 1], W[_T, k + 1], W[_PR, k + 1], W[_PU, k + 1] = u, T, pr, pu
        if on:
            W[_X, k + 1], W[_Y, k + 1] = y[b, 2 * n + k] / m, y[b, 3 * n + k] / m
            W[_OUT, k + 1] = 0.0


def _oil_leak(dy, b, maps, row, F, W, up, x, inv):
    """:func:`.oil.homogeneous_split` of a leakage flow (the gas-only flow F, from node
    ``up``, pressure ratio x): its oil added to dy through the maps' oil rows ``row``;
    returns the gas's part.  A liquid of finite density (inv = 1 / rho_l > 0) scales
    the three by :func:`.liquid.mixture_factor` and carries its p / rho_l
    (:func:`.oil.leakage`'s ``mix``)."""
    Fg, Fo, Eo = homogeneous_split(F, W[_X, up], W[_Y, up])
    if inv > 0.0:
        fac = mixture_factor(x, W[_K, up], W[_R, up], W[_X, up], inv)
        Fg, Fo, Eo = Fg * fac, Fo * fac, Eo * fac
        Eo += Fo * (W[_P, up] * inv)
    _add(dy, b, maps[0], row, Fo)
    _add(dy, b, maps[1], row, Eo)
    _add(dy, b, maps[2], row, abs(Fo))
    return Fg


def _oil_heat(dy, b, y, n, na, W, oil, w):
    """The oil's heat to the gas of every slot (W's _QO row), as the model's."""
    cp, datum, tau = oil[3], oil[4], oil[5]
    for k in range(na):
        q = heat_to_gas(y[b, 3 * n + k], y[b, 2 * n + k], W[_T, k + 1], cp, datum, tau)
        W[_QO, k + 1] = q
        dy[b, n + k] += q * w


def _oil_exit(dy, b, y, n, na, W, oil, x_id, c, nf, w):
    """:func:`.oil.slot_balances` for one batch member: the oil leaves each slot with the
    gas that flows out through a discharge port (the ideal ports' x_id; the nozzle
    ports' flows are in W's _OUT row already)."""
    flags, acc_mo, acc_ho, inv = oil[8], oil[9], oil[10], oil[11]
    for i in range(c.size):
        if flags[nf + i]:
            W[_OUT, c[i] + 1] += max(-x_id[i], 0.0)
    for k in range(na):
        mo, Ho = y[b, 2 * n + k], y[b, 3 * n + k]
        frac = W[_OUT, k + 1] / y[b, k]
        Hx = (Ho + W[_P, k + 1] * mo * inv) * frac
        dy[b, 2 * n + k] -= mo * frac * w
        dy[b, 3 * n + k] -= (W[_QO, k + 1] + Hx) * w
        dy[b, acc_mo] += mo * frac * w
        dy[b, acc_ho] += Hx * w
    if inv > 0.0:  # (.liquid.volume_work: the gas's p dV_l moved to the liquid)
        for k in range(na):
            pdvl = W[_P, k + 1] * dy[b, 2 * n + k] * inv
            dy[b, n + k] += pdvl
            dy[b, 3 * n + k] -= pdvl


# -- one segment in one compiled call (issue 19) ---------------------------------------
# args = (the step's own: the tableau (c, A, b, e) or ros23's (atol, Jacobian columns),
# geometry (ChamberModel.fused_geometry), the arguments of rhs_fused after its geometry
# (ChamberModel._fused_args)).

def rhs_segment(theta, y, args):
    """:func:`rhs_fused` at angle ``theta`` with the segment's geometry evaluated here:
    what :meth:`.model.ChamberModel.rhs` computes for a fusable segment."""
    nodes_, coef, kP, area_map, heat, omega, n, na, T_wall, w, relax = args[1]
    V, dV, lin = spline_at(nodes_, coef, theta + kP)
    flat = lin.reshape(lin.size)
    ptr, col, wts = area_map  # (:func:`scatter` of the segment's area matrix)
    area = np.zeros(ptr.size - 1)
    for f in range(area.size):
        for q in range(ptr[f], ptr[f + 1]):
            area[f] += wts[q] * flat[col[q]]
    wall = heat * V ** (2.0 / 3.0) if heat > 0.0 else np.empty(0)
    return rhs_fused(y, n, na, V, 1.0 / V, dV, omega * dV, area, wall, T_wall, w, omega,
                     relax, *args[2])


def rk_step_fused(t, y, h, k1, args):
    c, A, b, e = args[0]
    return stepping.rk_step(rhs_segment, args, c, A, b, e, t, y, h, k1)


def segment_fused(args, t, t_end, ends, y, k1, h, rtol, atol, order, budget, slack, record):
    return stepping.segment(rk_step_fused, args, t, t_end, ends, y, k1, h, rtol, atol, order,
                            budget, slack, record)


def ros23_step_fused(t, y, h, k1, args):
    atol, cols = args[0]  # (the step's own atol: the Jacobian's steps)
    return stepping.ros23_step(rhs_segment, args, t, y, h, k1, atol, cols)


def segment_ros23(args, t, t_end, ends, y, k1, h, rtol, atol, order, budget, slack, record):
    return stepping.segment(ros23_step_fused, args, t, t_end, ends, y, k1, h, rtol, atol,
                            order, budget, slack, record)
