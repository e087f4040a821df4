"""What happens to the slot states at the events of a lobe period, and the states that
start and continue the cycle.

Birth: the chamber appears with the suction gas filling its volume (mass, enthalpy and
the suction's p V booked); death: it is handed over to the discharge plenum with its
mass, energy and p V; suction close: with oil injection the oil enters with the trapped
gas; discharge open with ideal ports: the chamber is brought to the discharge pressure at
once.  A period's end state becomes the next period's start by shifting the slots.
"""

from __future__ import annotations

import numpy as np

from rotorflow.errors import CaseError

from . import humid, liquid
from .network import ACC_H_DIS, ACC_H_SUC, ACC_M_DIS, ACC_M_SUC, ACC_W


def apply_event(model, kind: str, k: int, theta: float, y: np.ndarray) -> None:
    """Apply one event to a batch of states (B, n_state) in place."""
    n, geo, c = model.n, model.geo, model.acc_cols
    acc = y[:, model.nv * n:]
    age = theta + k * geo.period
    V = float(geo.volume(age))
    if kind == "birth":
        m = model.suc.rho * V
        y[:, k] = m
        y[:, n + k] = m * model.suc.u
        acc[:, ACC_M_SUC] += m
        acc[:, ACC_H_SUC] += m * model.suc.h
        acc[:, ACC_W] -= model.suc.p * V
        if model.oil:
            y[:, 2 * n + k] = 0.0
            y[:, 3 * n + k] = 0.0
        if model.vapour:
            humid.born(model, k, m, y, acc)
    elif kind == "death":
        m = y[:, k].copy()
        U = y[:, n + k].copy()
        Vg = _gas_volume(model, V, y, k)
        p, _, _ = model.fluid.props(m / Vg, U / m, *_fraction(model, y, k, m))
        if model.vapour:
            humid.delivered(model, k, y, acc)
        acc[:, ACC_M_DIS] += m
        acc[:, ACC_H_DIS] += U + p * Vg
        acc[:, ACC_W] += p * V
        y[:, k] = 0.0
        y[:, n + k] = 0.0
        if model.oil:  # the liquid leaves with its enthalpy, p V_l with it
            acc[:, c.oil_m_out] += y[:, 2 * n + k]
            acc[:, c.oil_h_out] += y[:, 3 * n + k] + p * (V - Vg)
            y[:, 2 * n + k] = 0.0
            y[:, 3 * n + k] = 0.0
    elif kind == "close" and model.op.gas_volume_fraction < 1.0:
        liquid.fill_at_close(model, k, V, y, acc)
    elif kind == "close" and model.oil:
        # the oil enters at its injection temperature, its energy's datum: mass only
        mo = model.op.oil_mass_ratio * y[:, k]
        y[:, 2 * n + k] += mo
        acc[:, c.oil_m_in] += mo
    elif kind == "open" and model.ports.model == "ideal":
        equalise = humid.equalise if model.vapour else _equalise
        equalise(model, k, _gas_volume(model, V, y, k), y, acc)


def _fraction(model, y, k, m) -> tuple:
    """(w,) of slot k's gas with a volatile liquid's vapour (:mod:`.humid`), else ()."""
    return (y[:, humid.BLOCK * model.n + k] / m,) if model.vapour else ()


def _gas_volume(model, V, y, k):
    """The gas's volume in slot k: V less the liquid's (:mod:`.liquid`)."""
    if not model.inv_rho_liquid:
        return V
    return liquid.gas_volume(V, y[:, 2 * model.n + k], model.inv_rho_liquid)


def _equalise(model, k, V, y, acc):
    """Ideal discharge port opening: bring the chamber's gas (volume V) to the discharge
    pressure at once (the liquid, incompressible, keeps its volume)."""
    n, fl, pd = model.n, model.fluid, model.dis.p
    m = y[:, k].copy()
    U = y[:, n + k].copy()
    V = np.broadcast_to(V, m.shape)  # (per state where a liquid holds some of it)
    rho = m / V
    u = U / m
    p, _, _ = fl.props(rho, u)
    m2 = m.copy()
    U2 = U.copy()
    over = p > pd * (1 + 1e-12)
    under = p < pd * (1 - 1e-12)
    if np.any(over):
        r2, u2 = fl.isentropic(rho[over], u[over], pd)
        m2[over] = r2 * V[over]
        U2[over] = m2[over] * u2
    if np.any(under):
        m2[under], U2[under] = fl.fill(m[under], U[under], V[under], model.dis.h, pd)
    y[:, k] = m2
    y[:, n + k] = U2
    acc[:, ACC_M_DIS] += m - m2
    acc[:, ACC_H_DIS] += U - U2


def initial_state(model) -> np.ndarray:
    """Start of a period with the no-leakage adiabatic cycle as the guess (slot 0 empty);
    a liquid (:mod:`.liquid`) takes its inlet share of the trapped volume and keeps it."""
    n, geo, fl, op = model.n, model.geo, model.fluid, model.op
    y = np.zeros(model.n_state)
    # A wet suction's kappa (rho a^2 / p of the equilibrium mixture) is far below 1: its
    # p ~ rho^kappa would guess liquid-dense states the fluid has not got.  A guess only
    # has to be a state; 1 (isothermal) is one for a gas or a wet mixture.
    kap = max(model.suc.kappa, 1.0)
    _refuse_lock(model)
    beta = op.gas_volume_fraction if model.inv_rho_liquid else 1.0
    m_trap = beta * model.suc.rho * geo.v_trapped  # the gas trapped
    ml_trap = trapped_liquid(model)
    for k in range(1, n):
        age = geo.birth + k * geo.period
        if age > geo.death:
            continue
        V = Vg = float(geo.volume(age))
        if model.oil and age >= geo.suction_close:
            ml = ml_trap
            if age >= geo.discharge_open:
                # gas and liquid leave together: a discharging chamber keeps its share of
                # liquid (its whole trapped liquid would lock a small chamber near death)
                ml *= V / float(geo.volume(geo.discharge_open))
            y[2 * n + k] = ml
            y[3 * n + k] = 0.0  # at the inlet temperature, the liquid's energy datum
            Vg = V - ml * model.inv_rho_liquid
            if Vg <= 0:
                raise CaseError(f"the liquid fills the chamber before the discharge opens "
                                f"(hydraulic lock at {age:.3f} rad of its life): lower the "
                                f"volume ratio or raise the gas volume fraction")
        if age < geo.suction_close:
            rho, p = model.suc.rho, model.suc.p
        elif age < geo.discharge_open:
            rho = m_trap / Vg
            p = model.suc.p * (rho / model.suc.rho) ** kap
        else:  # any working port keeps the chamber near the discharge pressure
            p = model.dis.p
            rho = model.suc.rho * (p / model.suc.p) ** (1.0 / kap)
        w = (model.suc.w,) if model.vapour else ()
        try:
            u = fl.u_from_rho_p(rho, p, *w)
        except ValueError:
            # (a state the fluid has not got, e.g. R134a squeezed to 800 bar at the
            # isothermal guess's density: the flash cannot bracket it)
            rho, u = (model.dis.rho, model.dis.u) if age >= geo.discharge_open else \
                (rho, model.suc.u)
        y[k] = rho * Vg
        y[n + k] = rho * Vg * u
        if model.vapour:
            y[humid.BLOCK * n + k] = rho * Vg * model.suc.w
    return y


def trapped_liquid(model) -> float:
    """The liquid (or oil) mass a chamber holds at suction closing: its inlet share of
    the gas trapped (0 without one)."""
    if not model.oil:
        return 0.0
    beta = model.op.gas_volume_fraction if model.inv_rho_liquid else 1.0
    return model.liquid_ratio * beta * model.suc.rho * model.geo.v_trapped


#: Gas room left at the discharge's opening (of the room the chamber has then) below
#: which a liquid's share counts as filling it: the share 1 - beta and the room
#: V_do / V_trapped are equal at beta = 1 - 1 / vi, up to the port angle's round-off.
LOCK_ROOM = 1e-9


def _refuse_lock(model) -> None:
    """A liquid drawn in that alone needs as much room as the chamber has left when its
    discharge opens locks it: refused.  A wet suction's liquid, compressed, hardly
    shrinks and evaporates only as the vapour heats it (the model ran such points to
    pressures of hundreds of bar read off the property table's liquid side beyond its
    range, and called them converged); an incompressible one (gas_volume_fraction <
    1, its share 1 - beta of the trapped volume) squeezes the gas to nothing (a
    multiphase pump at beta 0.5 and volume ratio 2 ran until its step size underflowed
    or its time budget ran out, exit 1, instead of naming the input)."""
    q = model.op.suction_quality
    geo, suc = model.geo, model.suc
    if model.inv_rho_liquid:
        beta = model.op.gas_volume_fraction
        share, what = 1.0 - beta, f"gas_volume_fraction {beta:g}"
        fix = "raise gas_volume_fraction"
    elif q is not None and q < 1.0:
        rho_liquid = model.fluid.state_pT(suc.p, suc.T, q=0.0)[0]
        share = (1.0 - q) * suc.rho / rho_liquid
        what, fix = f"suction_quality {q:g}", "raise suction_quality"
    else:
        return
    room = float(geo.volume(geo.discharge_open)) / geo.v_trapped
    if share >= room * (1.0 - LOCK_ROOM):
        raise CaseError(f"hydraulic lock: the liquid drawn in ({what}) fills {share:.1%} of "
                        f"the trapped volume, no less than the {room:.1%} left when the "
                        f"discharge opens; {fix} or lower volume_ratio")


def shift(model, y_end: np.ndarray) -> np.ndarray:
    """State at the start of the next period: slot k -> k+1, slot 0 empty, sums reset."""
    y = np.zeros_like(y_end)
    n = model.n
    for b in range(model.nv):
        y[..., b * n + 1:(b + 1) * n] = y_end[..., b * n:(b + 1) * n - 1]
    return y
