"""Injected oil in the chamber model: its leakage with the gas, its exit with the discharge
and the discharge plenum's temperature.

The oil rides in each slot as a mass mo and an enthalpy Ho (state columns 2n.. and 3n..),
counted from the oil's injection temperature (ChamberModel.liquid_datum_K).
It enters at suction closing (:mod:`.events`), exchanges heat with the gas, leaves with
the gas through the discharge port and, with ``[leakage] mixture = "homogeneous"`` (the
default), through every leakage path with the gas that leaks.

Leakage as a homogeneous mixture.  The homogeneous (no-slip) model of two-phase flow
(Wallis 1969, *One-dimensional two-phase flow*, ch. 2; Collier & Thome, *Convective
boiling and condensation*, ch. 2) lets both phases move at one velocity, so the mixture
flows as one fluid of density

    rho_m = (1 + X) / (1 / rho_g + X / rho_oil)  ~  rho_g (1 + X),

X the oil mass per gas mass of the upstream node.  The oil's own volume is neglected
against the gas's: its volume fraction X rho_g / rho_oil is 0.5 % at 1 bar and ~5 % at
11 bar for X = 4 (air at 360 K, oil 870 kg/m3), so the mixture flux is overestimated by
at most ~2.5 % (half of it, through the square root) where the pressure is highest.  A
gap's mass flux is the gas's formula with rho -> rho (1 + X): the factor sqrt(p1 rho1)
of :mod:`.flows`, and likewise seed 003 Eq. 9 with a^2 -> a^2 / (1 + X) (the oil loads
the gas without adding to its pressure).  Of that mixture flux the gas is 1 / (1 + X) and
the oil X / (1 + X): the gas leakage falls by 1 / sqrt(1 + X) against gas alone, and the
oil leaks X times the gas's mass.  Approximations kept:

- the dimensionless flux f(x) keeps the gas's exponent (the nozzle's kappa; in truth the
  oil's heat capacity pulls the expansion towards the isothermal one of Eq. 9) and,
  with "cfd-calibrated", the fit's Cd at the gas's Reynolds number and wall-speed ratio;
- the oil carries its own specific enthalpy, that of the upstream node's oil (Ho / mo of
  a slot, c_oil T of a plenum); the two phases need not share a temperature in the gap;
- the Couette (wall-drag) flow stays gas only: the drag of an oil film needs its
  thickness and viscosity, which the model does not know;
- nodes: a slot's X is mo / m; the suction plenum's 0 (its gas is dry); the discharge
  plenum's the injected ratio (``oil_mass_ratio``), its oil at the plenum's temperature.

Oil leaking between slots moves between their oil states; oil leaking to or from a plenum
is booked as the gas is, net: oil into the suction plenum lowers the oil drawn in
(``oil_m_in``, ``oil_h_in``), oil from the discharge plenum lowers the oil delivered
(``oil_m_out``, ``oil_h_out``), so that the cycle's balances (:mod:`.cycle`) and the
Runge-Kutta conservation of mass and energy hold with oil as they do without it.  The
gross oil leakage per report key rides along (:class:`.network.AccColumns`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OilMaps:
    """Maps of a segment's leakage flows of oil into dy/dtheta, as Segment's mm, me, mg
    are for the gas: oil mass flows (mm), oil enthalpy flows (me), |oil mass flows|
    (mg, the gross oil leakage per report key); each (n_leak, n_state)."""

    mm: np.ndarray
    me: np.ndarray
    mg: np.ndarray


def leak_maps(fr, na: int, ia, ib, laws) -> OilMaps:
    """OilMaps of the leakage flows ia[f] -> ib[f] (nodes as in :mod:`.network`) of a
    segment with ``na`` active slots; ``fr`` is the network's frame."""
    nf, S, n, w, c = len(ia), fr.n_state, fr.n, fr.w, fr.acc
    acc0 = fr.nv * n
    mm, me, mg = (np.zeros((nf, S)) for _ in range(3))
    for f in range(nf):
        for node, sgn in ((ia[f], -1.0), (ib[f], 1.0)):
            if node == 0:  # net oil drawn in from suction, as the gas's ACC_M_SUC
                mm[f, acc0 + c.oil_m_in] -= sgn * w
                me[f, acc0 + c.oil_h_in] -= sgn * w
            elif node == na + 1:  # net oil delivered, as the gas's ACC_M_DIS
                mm[f, acc0 + c.oil_m_out] += sgn * w
                me[f, acc0 + c.oil_h_out] += sgn * w
            else:
                mm[f, 2 * n + node - 1] += sgn * w
                me[f, 3 * n + node - 1] += sgn * w
        mg[f, acc0 + c.oil_leak(laws[f].path.report_key)] = w
    return OilMaps(mm, me, mg)


def node_loads(model, y: np.ndarray, m: np.ndarray, na: int):
    """Oil per gas mass X and oil enthalpy per gas mass Y of every node (B, na + 2) for a
    batch of states y: the slots' mo / m and Ho / m, the suction plenum's 0, the
    discharge plenum's injected ratio with its oil at the plenum's temperature."""
    n, op = model.n, model.op
    B = y.shape[0]
    X = np.zeros((B, na + 2))
    Y = np.zeros((B, na + 2))
    X[:, 1:na + 1] = y[:, 2 * n:2 * n + na] / m
    Y[:, 1:na + 1] = y[:, 3 * n:3 * n + na] / m
    X[:, -1] = model.liquid_ratio
    Y[:, -1] = model.liquid_ratio * op.oil_cp_J_kgK * (model.dis.T - model.liquid_datum_K)
    return X, Y


def homogeneous_split(F, X_up, Y_up):
    """Gas, oil and oil-enthalpy flows of a homogeneous gas-oil mixture through a gap
    whose gas-only flow at the same upstream state is F (signed, any shape), the
    upstream node's oil per gas mass X_up and oil enthalpy per gas mass Y_up.

    The mixture flux is F sqrt(1 + X) (rho -> rho (1 + X) under the square root), of which
    the gas carries 1 / (1 + X): F / sqrt(1 + X); the oil X times that.  A negative X
    (round-off of an emptied slot) counts as no oil in the density, so that the root
    stays real; its (tiny) oil flow is kept, which pushes the slot back to zero.
    """
    Fg = F / np.sqrt(1.0 + np.maximum(X_up, 0.0))
    return Fg, Fg * X_up, Fg * Y_up


def heat_to_gas(Ho, mo, T, cp, datum, tau):
    """The oil's heat to the gas per second (any shape): the oil's enthalpy Ho above what
    it would hold at the gas's temperature T (mass mo, c_oil cp, enthalpy zero at
    ``datum``), relaxed over the exchange time constant tau."""
    return (Ho - mo * cp * (T - datum)) / tau


def leakage(seg, F, X, Y, mix=None):
    """Split the leakage columns of the signed flows F (B, n_flows) in place into gas
    (F keeps the gas) and return the oil's mass and enthalpy flows (B, n_leak).  The
    upstream node is the one the flow leaves (with moving walls in a calibrated fit the
    flow may run against the pressure).  ``mix``: a liquid of finite density
    (:mod:`.liquid`), the mixture's factor on every flow and the liquid's p / rho_l at
    the upstream node, which its enthalpy flow carries."""
    nl = seg.n_leak
    Fl = F[:, :nl]
    a, b = seg.ia[:nl], seg.ib[:nl]
    out_of_a = Fl >= 0.0
    Xu = np.where(out_of_a, X[:, a], X[:, b])
    Yu = np.where(out_of_a, Y[:, a], Y[:, b])
    F[:, :nl], Fo, Eo = homogeneous_split(Fl, Xu, Yu)
    if mix is not None:
        fac, pv = mix
        F[:, :nl] *= fac
        Fo, Eo = Fo * fac, Eo * fac
        Eo += Fo * pv
    return Fo, Eo


def oil_leak_balances(seg, dy, Fo, Eo):
    """Add the oil's leakage (its mass and enthalpy flows Fo, Eo) to dy/dtheta in place."""
    dy += Fo @ seg.oil.mm + Eo @ seg.oil.me + np.abs(Fo) @ seg.oil.mg


def slot_balances(model, seg, dy, xs, F, y, m, p, q_oil, w):
    """Add the rest of the oil's part of dy/dtheta in place: its heat to the gas (q_oil)
    and its exit with the gas that flows out through the discharge port (xs: the ideal
    ports' flows, or None) at the slot's oil per gas mass, carrying its enthalpy
    (with a liquid of finite density also p / rho_l, :mod:`.liquid`)."""
    n, na, c = model.n, seg.n_act, model.acc_cols
    acc0 = model.nv * n
    mo = y[:, 2 * n:2 * n + na]
    Ho = y[:, 3 * n:3 * n + na]
    out = np.zeros_like(m)
    if xs is not None:
        sel = seg.ideal_is_dis
        out[:, seg.ideal[sel]] = np.maximum(-xs[:, sel], 0.0)
    if seg.dis_port.size:
        out[:, seg.ia[seg.dis_port] - 1] += np.maximum(F[:, seg.dis_port], 0.0)
    frac = out / m
    Hx = (Ho + p * mo * model.inv_rho_liquid) * frac
    dy[:, 2 * n:2 * n + na] -= mo * frac * w
    dy[:, 3 * n:3 * n + na] -= (q_oil + Hx) * w
    dy[:, acc0 + c.oil_m_out] += (mo * frac).sum(axis=1) * w
    dy[:, acc0 + c.oil_h_out] += Hx.sum(axis=1) * w


def flooded_discharge_T(fluid, suc, op, x: float) -> float:
    """The discharge plenum's temperature with oil injected: gas and oil compressed
    together without losses, in thermal equilibrium from the moment they mix.

    What flows back from the discharge is that mixture's gas, not gas compressed dry
    (which, at a pressure ratio of 11, would be ~300 K hotter than what the oil lets
    out).  With x kg of oil per kg of gas, (cp + x c_oil) dT = v dp gives
    T2 = T1 (p2 / p1)^(R / (cp + x c_oil)), T1 the adiabatic mixing temperature of
    gas at suction and oil at injection.
    """
    T1g, co = op.T_suction_K, op.oil_cp_J_kgK
    h_lo = fluid.state_pT(op.p_suction_Pa, T1g - 0.5)[2]
    h_hi = fluid.state_pT(op.p_suction_Pa, T1g + 0.5)[2]
    cp = float(h_hi - h_lo)
    R = op.p_suction_Pa / (suc.rho * T1g)
    T1 = (cp * T1g + x * co * op.oil_temperature_K) / (cp + x * co)
    return T1 * op.pressure_ratio ** (R / (cp + x * co))


def fused_args(model, seg) -> tuple:
    """The oil's arguments of the compiled right-hand side (:func:`.kernel.rhs_fused`):
    (oil injected, its leakage split off the gas's, leakage flows, c_oil, the enthalpy's
    datum temperature, the exchange time constant, the discharge plenum's X and Y,
    flags (per flow: a nozzle discharge port; then per ideal port: the discharge's), the
    delivered oil's accumulator columns, a liquid's 1 / rho_l or 0, :mod:`.liquid`),
    the same types without oil (one compiled
    specialisation, scalars but one array: each array argument costs a compiled call
    two atomic reference counts); and the oil's leakage maps (mm, me, mg), which
    :meth:`.model.ChamberModel._fused_args` appends to the gas's as rows n_flows + f
    (None without them)."""
    op, n, c = model.op, model.n, model.acc_cols
    on = bool(model.oil)
    split = on and seg.oil is not None
    acc0 = model.nv * n
    x_dis = model.liquid_ratio if on else 0.0
    y_dis = x_dis * op.oil_cp_J_kgK * (model.dis.T - model.liquid_datum_K) if on else 0.0
    nf = seg.ia.size
    flags = np.zeros(nf + seg.ideal.size, dtype=np.int8)
    flags[seg.dis_port] = 1
    flags[nf:][np.asarray(seg.ideal_is_dis, dtype=bool)] = 1
    args = (on, split, int(seg.n_leak), float(op.oil_cp_J_kgK), float(model.liquid_datum_K),
            float(op.oil_time_constant_s), float(x_dis), float(y_dis), flags,
            acc0 + c.oil_m_out if on else 0, acc0 + c.oil_h_out if on else 0,
            float(model.inv_rho_liquid))
    return args, ((seg.oil.mm, seg.oil.me, seg.oil.mg) if split else None)
