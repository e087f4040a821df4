"""The chamber equations' right-hand side on flat arrays: the pieces
:meth:`.model.ChamberModel.rhs` is made of, and :func:`rhs_fused`, all of them in one
function for the segments that need nothing else (see :func:`fusable`).

Every function here is plain numpy on arrays of the batch (B, ...) and also compiles
with numba (:mod:`.compiled`): the model calls these functions uncompiled, piece by
piece, with its other terms (calibrated or rarefied leakage, moving walls, oil) in
between; where a segment has none of those, the compiled :func:`rhs_fused` evaluates
the same pieces in one call.  So each piece of physics is written once.

Measured on the default case (8 slots, 52 flows of which ~24 open): 31 us a call
against ~120 us in numpy for the cycle solver's batch of 15 states; 16 against 55 us
with nozzle ports and no leakage (7 flows); no faster than numpy for the 240 states of a
Rosenbrock Jacobian, where numpy's vectorised power function outruns numba's scalar one.
The rest of a compiled call is the numba versions of the gathers (~1.4 ns an element),
the powers of the nozzle formula (~10 ns) and five small matrix products (~1.5 us each).
"""

from __future__ import annotations

import numpy as np

from . import flows, stepping
from .chamber import spline_at
from .coolprop_fluid import table_interp as table_2d
from .dry_air import table_interp as table_1d

# Fluid kinds of fluid_state (the fluids' kernel_params)
PERFECT, TABLE_1D, TABLE_2D = 0, 1, 2


def fluid_state(kind, par, tab, rho, u):
    """p, T, kappa, (dp/drho)_u and (dp/du)_rho at arrays rho, u of one of the three
    fluids (:mod:`.fluids`): the perfect gas (par: gamma - 1, 1 / cv, gamma), dry air's
    table in u (par: u0, du, R), a CoolProp table in (ln rho, u) (par: x0, dx, u0, du,
    nodes in u)."""
    if kind == PERFECT:
        g1 = par[0]
        return g1 * rho * u, u * par[1], np.full_like(rho, par[2]), g1 * u, g1 * rho
    if kind == TABLE_1D:
        v = table_1d(u, par[0], par[1], tab)
        R = par[2]
        return R * rho * v[0], v[0], v[1], R * v[0], R * rho * v[2]
    v = table_2d(rho, u, par[0], par[1], par[2], par[3], int(par[4]), tab, 0, 5)
    return np.exp(v[0]), v[1], v[2], v[3], v[4]


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
                relax, n, gamma):
    """Add the ideal ports' flows to dy in place (those that hold the open slots c at
    their plenum's pressure p_pl, gas of enthalpy h_pl flowing in); returns them (kg/s).

    The flow x into slot c makes dp/dt = (p_pl - p) omega / relax (the drift correction):
    with dm/dt = A + x and dU/dt = Bh + x h_x - p dV/dt, dp/dt = pr drho/dt + pu du/dt.
    ``gamma`` > 0: a perfect gas of that gamma (then pr, pu are not read)."""
    A = dy[:, c] * omega  # other mass flows in (kg/s)
    Bh = (dy[:, n + c] + pdV[:, c]) * omega  # other enthalpy + heat (W)
    rc, uc, pc, hc = rho[:, c], u[:, c], p[:, c], h[:, c]
    tgt = (p_pl - pc) * (omega / relax)
    Vc, Vtc = V[..., c], Vt[..., c]
    if gamma > 0.0:
        g1 = gamma - 1.0
        num = Vc * tgt / g1 - Bh + rc * hc * Vtc
        x = num / np.where(num > 0.0, h_pl + 0.0 * hc, hc)
    else:
        prc, puc = pr[:, c], pu[:, c]
        num = Vc * tgt - prc * (A - rc * Vtc) - puc * (Bh - pc * Vtc - uc * A) / rc
        x_in = num / (prc + puc * (h_pl - uc) / rc)
        x_out = num / (prc + puc * (hc - uc) / rc)
        x = np.where(x_in > 0.0, x_in, np.minimum(x_out, 0.0))
    hx = np.where(x > 0.0, h_pl + 0.0 * hc, hc)
    dy += x @ mx + (x * hx) @ mxe
    return x


def fusable(model, seg) -> bool:
    """The segment needs nothing but what :func:`rhs_fused` evaluates: nozzle or Fanno
    leakage on static walls, gas only, a fluid with kernel parameters."""
    return (not model.oil and seg.oil is None and not seg.walls and not seg.cou_gap.size
            and all(g.model in ("nozzle", "fanno") for g in seg.groups)
            and hasattr(model.fluid, "kernel_params"))


def rhs_fused(y, n, na, V, iV, dV, Vt, area, wall, T_wall, w, omega, relax, ia, ib,
              fanno, zeta, x_choke, mm, me, mg, acc_w, acc_q, c, p_pl, h_pl, mx, mxe, plen,
              kind, par, tab, gamma):
    """dy/dtheta of a fusable segment (see :meth:`.model.ChamberModel.rhs`): y (B, S);
    the geometry of the active slots at the angle (V, 1/V, dV/dtheta, dV/dt, the flows'
    areas, heat transfer coefficient times area or an empty array); the flows' nodes and
    laws (Fanno where ``fanno``); the maps; the ideal ports (slots c); the plenums' p,
    rho, h, kappa (plen (4, 2)); the fluid (kind, par, tab; gamma > 0 a perfect gas)."""
    m = y[:, :na]
    rho = m * iV
    u = y[:, n:n + na] / m
    p, T, kap, pr, pu = fluid_state(kind, par, tab, rho, u)
    h = u * gamma if gamma > 0.0 else u + p / rho
    P = nodes(p, plen[0, 0], plen[0, 1])
    R = nodes(rho, plen[1, 0], plen[1, 1])
    H = nodes(h, plen[2, 0], plen[2, 1])
    xc, cc, ik = flows.nozzle_constants(nodes(kap, plen[3, 0], plen[3, 1]))
    # only the flows of non-zero area (about half: lines that do not exist at the angle)
    live = np.nonzero(area > 0.0)[0]
    a, b = ia[live], ib[live]
    fwd, x, p1, r1 = upstream(P, R, a, b)
    f = flows.nozzle_f_c(x, np.where(fwd, xc[:, a], xc[:, b]), np.where(fwd, cc[:, a], cc[:, b]),
                         np.where(fwd, ik[:, a], ik[:, b]))
    fl = fanno[live]
    if fl.any():
        f = np.where(fl, flows.fanno_f(x, zeta[live], x_choke[live]), f)
    F = np.zeros((y.shape[0], ia.size))
    E = np.zeros((y.shape[0], ia.size))
    F[:, live] = mass_flows(fwd, p1, r1, f, area[live])
    E[:, live] = enthalpy_flows(F[:, live], H[:, a], H[:, b])
    dy, pdV = balances(F, E, mm, me, mg, p, dV, n, acc_w)
    if wall.size:
        q = wall * (T_wall - T)
        dy[:, acc_q] = q.sum(axis=1) * w
        dy[:, n:n + na] += q * w
    if c.size:
        ideal_ports(dy, pdV, V, Vt, rho, u, p, h, pr, pu, c, p_pl, h_pl, mx, mxe, omega,
                    relax, n, gamma)
    return dy


# -- one segment in one compiled call (issue 19) ---------------------------------------
# args = (tableau (c, A, b, e), geometry (ChamberModel.fused_geometry), the arguments of
# rhs_fused after its geometry (ChamberModel._fused_args)).

def rhs_segment(theta, y, args):
    """:func:`rhs_fused` at angle ``theta`` with the segment's geometry evaluated here:
    what :meth:`.model.ChamberModel.rhs` computes for a fusable segment."""
    nodes_, coef, kP, area_m, heat, omega, n, na, T_wall, w, relax = args[1]
    V, dV, lin = spline_at(nodes_, coef, theta + kP)
    area = area_m @ lin.reshape(lin.size)
    wall = heat * V ** (2.0 / 3.0) if heat > 0.0 else np.empty(0)
    return rhs_fused(y, n, na, V, 1.0 / V, dV, omega * dV, area, wall, T_wall, w, omega,
                     relax, *args[2])


def rk_step_fused(t, y, h, k1, args):
    c, A, b, e = args[0]
    return stepping.rk_step(rhs_segment, args, c, A, b, e, t, y, h, k1)


def segment_fused(args, t, t_end, ends, y, k1, h, rtol, atol, order, budget, slack, record):
    return stepping.segment(rk_step_fused, args, t, t_end, ends, y, k1, h, rtol, atol, order,
                            budget, slack, record)
