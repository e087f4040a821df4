"""The chamber equations: every chamber present in the machine, coupled, over one lobe period.

Slots.  At outer-rotor angle ``theta`` (within one lobe period starting at the birth
angle) slot k holds the chamber of age ``theta + k * period``; slot 0 is born at the
period's start, the last slot dies inside the period.  After one period slot k has
become slot k+1 of the next, so integrating one period and shifting the slots is one
cycle of the machine (seed 000: chambers are the same chamber shifted by 2 pi / N1).

State per slot: mass m and internal energy U of the gas (and, with oil injection, the
oil mass and its enthalpy).  With the volume V these give rho and u, from which every
fluid gives p and T without inner iteration; with (m, U) as state, mass and energy are
linear invariants, which an explicit Runge-Kutta method conserves to round-off.

    dm/dt = sum of mass flows in
    dU/dt = sum of (mass flow in * enthalpy of its upstream side) + Q - p dV/dt

(seed 003 Eqs. 6-7; seed 001 Eqs. 1-2 written for U).  The model integrates in angle:
d/dtheta = (1/omega) d/dt.

Flow paths: leakage along the sealing lines to the next (older) and previous (younger)
chamber, across the end faces to the suction (low-pressure face) and discharge plenum
(high-pressure face); the youngest chamber's previous neighbour is the suction plenum,
the oldest's next is the discharge plenum.  With moving walls (Leakage.wall_motion) the
interlobe lines also carry the gas the rotor surface drags from the older into the
younger chamber: a Couette term of its own, or, with the "cfd-calibrated" model and a fit
that has a wall term, the fit's drag term, the wall speed passed to the correlation
(ChamberModel.drag_in_fit).  Ports: suction open from birth to suction_close through
area_lp, discharge open from discharge_open to death through area_hp; "nozzle" ports are
flows like the others, "ideal" ports hold the chamber at the plenum pressure (the port
flow is solved from dp/dt = 0 with a weak drift correction).

Accumulators ride along the state (quadratures of the same flows): mass and enthalpy
from suction and to discharge, work done on the gas, heat, gross leakage per path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import flows
from .chamber import ChamberGeometry
from .settings import Leakage, Operating, Ports

# Accumulator columns (per unit of a lobe period's integration)
ACC_M_SUC, ACC_H_SUC, ACC_M_DIS, ACC_H_DIS, ACC_W, ACC_Q = range(6)
ACC_L_INT, ACC_L_LP, ACC_L_HP = 6, 7, 8
ACC_OIL_M_IN, ACC_OIL_H_IN, ACC_OIL_M_OUT, ACC_OIL_H_OUT = 9, 10, 11, 12
N_ACC = 13

# Drift correction of the ideal-port constraint: a pressure offset from the plenum decays
# over this outer-rotor angle.  0.2 rad keeps it well below any step an explicit method
# takes for stability (its eigenvalue -1/0.2 per rad) while removing offsets within a
# fraction of a period.
IDEAL_PORT_RELAXATION_RAD = 0.2

# Wall area of a chamber for heat transfer: that of a cube of the same volume, 6 V^(2/3).
WALL_AREA_FACTOR = 6.0


@dataclass(frozen=True)
class Plenum:
    p: float
    T: float
    rho: float
    u: float
    h: float
    kappa: float


@dataclass(frozen=True)
class Segment:
    """Part of a lobe period between two events; the topology is constant inside.

    Nodes: 0 the suction plenum, 1..n_act the active slots, n_act+1 the discharge plenum.
    Flow f goes from node ia[f] to node ib[f] through area = area_map @ geometry, where the
    geometry vector is ChamberGeometry.evaluate's ``lin`` raveled (rows area_lp, area_hp,
    seal_next, seal_prev, seal_lp_face, seal_hp_face, then the lines to chambers two or
    more periods away, over the active slots).  The matrices
    mm, me, mg map mass flows, enthalpy flows and |mass flows| straight into dy/dtheta
    (slot balances and accumulators); mx, mxe do the same for the ideal-port flows.
    """

    index: int
    start: float
    end: float
    events: tuple  # (kind, slot) applied at ``start``, in order
    n_act: int  # active slots 0..n_act-1
    k_sc: int  # slots 0..k_sc-1 open to suction
    k_do: int  # slots k_do..n_act-1 open to discharge
    kP: np.ndarray = field(repr=False)  # k * period for the active slots
    ia: np.ndarray = field(repr=False)
    ib: np.ndarray = field(repr=False)
    n_leak: int  # flows 0..n_leak-1 are leakage, the rest nozzle ports
    area: np.ndarray = field(repr=False)  # (n_flows, rows*n_act)
    link_len: np.ndarray = field(repr=False)  # (n_act+1, rows*n_act): chain line lengths
    mm: np.ndarray = field(repr=False)  # (n_flows, n_state)
    me: np.ndarray = field(repr=False)
    mg: np.ndarray = field(repr=False)
    ideal: np.ndarray = field(repr=False)  # slots held at a plenum pressure
    ideal_p: np.ndarray = field(repr=False)  # their plenum pressure
    ideal_h: np.ndarray = field(repr=False)  # and plenum enthalpy
    ideal_is_dis: np.ndarray = field(repr=False)  # True where the plenum is discharge
    mx: np.ndarray = field(repr=False)  # (n_ideal, n_state)
    mxe: np.ndarray = field(repr=False)
    dis_port: np.ndarray = field(repr=False)  # flows that are nozzle discharge ports


@dataclass(frozen=True)
class ChamberModel:
    geo: ChamberGeometry
    fluid: object
    op: Operating
    leak: Leakage
    ports: Ports
    suc: Plenum
    dis: Plenum
    n: int  # slots
    nv: int  # state variables per slot: 2 (m, U) or 4 (with oil mass and enthalpy)
    segments: tuple
    m_ref: float  # suction density * V_max
    e_ref: float  # p_suction * V_max
    x_choke: float  # Fanno choking ratio
    ideal_gas: bool
    inv_omega: float
    cache: dict = field(default_factory=dict, repr=False, compare=False)
    work: dict = field(default_factory=dict, repr=False, compare=False)

    # -- layout --------------------------------------------------------------------
    @property
    def n_state(self) -> int:
        return self.nv * self.n + N_ACC

    @property
    def oil(self) -> bool:
        return self.nv == 4

    def acc(self, y):
        return y[..., self.nv * self.n:]

    def state_columns(self, seg: Segment) -> np.ndarray:
        """Columns of y the right-hand side depends on in ``seg`` (active slots' states)."""
        n, na = self.n, seg.n_act
        return np.concatenate([np.arange(b * n, b * n + na) for b in range(self.nv)])

    def scales(self) -> np.ndarray:
        """Reference magnitudes per state component (for the absolute tolerance)."""
        s = np.empty(self.n_state)
        n = self.n
        s[:n] = self.m_ref
        s[n:2 * n] = self.e_ref + self.m_ref * abs(self.suc.u)
        if self.oil:
            s[2 * n:3 * n] = self.m_ref * max(self.op.oil_mass_ratio, 1e-3)
            s[3 * n:4 * n] = s[2 * n:3 * n] * self.op.oil_cp_J_kgK * self.op.oil_temperature_K
        a = s[self.nv * n:]
        a[:] = self.m_ref
        a[[ACC_H_SUC, ACC_H_DIS]] = self.m_ref * abs(self.suc.h) + self.e_ref
        a[[ACC_W, ACC_Q]] = self.e_ref
        a[[ACC_OIL_H_IN, ACC_OIL_H_OUT]] = s[3 * n] if self.oil else self.e_ref
        return s

    def atol_scales(self) -> np.ndarray:
        """Scales of the absolute tolerance: chamber states at the size of a chamber at
        birth (so that a young or dying chamber is still integrated to rtol, not drowned by
        an absolute tolerance made for a full one), accumulators at a cycle's totals."""
        s = self.scales()
        s[:self.nv * self.n] *= float(self.geo.volume(self.geo.birth)) / self.geo.v_max
        return s

    # -- right-hand side ---------------------------------------------------------------
    def _geometry(self, theta: float, seg: Segment):
        """Geometry of the active slots at ``theta`` (cached: replayed steps repeat angles)."""
        key = (seg.index, theta)
        g = self.cache.get(key)
        if g is None:
            if len(self.cache) > 20_000:
                self.cache.clear()
            V, dV, lin = self.geo.evaluate(theta + seg.kP)
            flat = lin.ravel()
            area = seg.area @ flat
            cou = None
            if self.leak.wall_motion and seg.n_leak and not self.drag_in_fit:
                cou = (self.wall_speed * self.leak.gap_m) * (seg.link_len @ flat)
            wall = None
            if self.op.heat_transfer_W_m2K > 0.0:
                wall = self.op.heat_transfer_W_m2K * WALL_AREA_FACTOR * V ** (2.0 / 3.0)
            g = (V, 1.0 / V, dV, self.geo.omega_outer * dV, area, cou, wall)
            self.cache[key] = g
        return g

    def _nodes(self, B: int, na: int):
        """Work arrays of node values (B, na+2) with the plenum columns filled in."""
        key = (B, na)
        w = self.work.get(key)
        if w is None:
            w = np.empty((4, B, na + 2))
            for i, (s, d) in enumerate(((self.suc.p, self.dis.p), (self.suc.rho, self.dis.rho),
                                         (self.suc.h, self.dis.h),
                                         (self.suc.kappa, self.dis.kappa))):
                w[i, :, 0] = s
                w[i, :, -1] = d
            self.work[key] = w
        return w

    @property
    def wall_speed(self) -> float:
        """U = half the outer rotor's tip speed: the mean wall speed along an interlobe
        line, dragging gas from the older chamber into the younger one."""
        return 0.5 * self.geo.omega_outer * self.geo.radius

    @property
    def drag_in_fit(self) -> bool:
        """The wall drag of the interlobe lines is the "cfd-calibrated" fit's own (its wall
        term w, with the wall speed passed to it) rather than the separate Couette term.
        A fit without a wall term (w = 0: fitted to static walls, or saved before the term
        existed) says nothing about moving walls; it keeps the Couette term."""
        leak = self.leak
        return bool(leak.wall_motion and leak.model == "cfd-calibrated"
                    and leak.correlation is not None and leak.correlation.wall != 0.0)

    def _calibrated_flux(self, S, x, psi, v, rr):
        """Mass flux over sqrt(p_up rho_up) of each leakage path from the CFD fit: Cd psi
        in the fit's form that is finite through x -> 1 (FlowCoefficientFit.reduced_flux):
        PR = p_up / p_down, K = 24 L mu / (h^2 S) with L the land and S = sqrt(p_up
        rho_up), ``v`` the wall speed ratios along the flow (None: static walls), ``rr``
        the downstream over the upstream density (for flows the walls drive backwards;
        None: static walls).  With static walls this is Cd(Re, PR, L/h) psi with Re from
        the ideal nozzle flow per unit sealing-line length (the fit's definition), and no
        flow without a pressure difference."""
        leak = self.leak
        k = (24.0 * leak.land_m * leak.viscosity_Pa_s / leak.gap_m**2) / S
        return leak.correlation.reduced_flux(psi, 1.0 / x, k, v, rr)

    def path_flows(self, theta: float, y: np.ndarray, seg: Segment, enthalpy: bool = False):
        """Mass flow (kg/s) along every flow path of ``seg`` (from node ia to node ib) for
        a state y (n_state,) or a batch (B, n_state); the leakage paths come first.  With
        ``enthalpy``: (mass flows, enthalpy flows in W)."""
        y = np.asarray(y, dtype=float)
        F, E = self._flows(theta, np.atleast_2d(y), seg)[:2]
        if y.ndim == 1:
            F, E = F[0], E[0]
        return (F, E) if enthalpy else F

    def _flows(self, theta: float, y: np.ndarray, seg: Segment):
        """Mass and enthalpy flows of every path, with the slot states they came from."""
        na, fl = seg.n_act, self.fluid
        n = self.n
        B = y.shape[0]
        g = self._geometry(theta, seg)
        iV, area, cou = g[1], g[4], g[5]
        m = y[:, :na]
        U = y[:, n:n + na]
        rho = m * iV
        u = U / m
        p, T, kap = fl.props(rho, u)
        h = u * fl.gamma if self.ideal_gas else u + p / rho
        W = self._nodes(B, na)
        W[0, :, 1:na + 1] = p
        W[1, :, 1:na + 1] = rho
        W[2, :, 1:na + 1] = h
        scalar_k = not np.ndim(kap)
        if not scalar_k:
            W[3, :, 1:na + 1] = kap
        R = W[1]
        ia, nl = seg.ia, seg.n_leak
        Wa = W[:, :, ia]  # (4, B, n_flows): both ends of every flow path in two gathers
        Wb = W[:, :, seg.ib]
        pa, pb = Wa[0], Wb[0]
        fwd = pa >= pb
        p1 = np.maximum(pa, pb)
        x = np.minimum(pa, pb) / p1
        r1 = np.where(fwd, Wa[1], Wb[1])
        drag = self.drag_in_fit and nl
        k1 = kap if scalar_k else np.where(fwd, Wa[3], Wb[3])
        if self.leak.model == "fanno" and nl:
            f = np.empty_like(x)
            f[:, :nl] = flows.fanno_f(x[:, :nl], self.leak.zeta, self.x_choke)
            if f.shape[1] > nl:
                f[:, nl:] = flows.nozzle_f(x[:, nl:], k1 if scalar_k else k1[:, nl:])
        else:
            f = flows.nozzle_f(x, k1)
        S = np.sqrt(p1 * r1)
        if self.leak.model == "cfd-calibrated" and nl:
            v = rr = None
            if drag:
                # Interlobe lines (the chain, flows 0..na): the drag runs from the older
                # chamber (node j+1, side b) into the younger (node j, side a), so the wall
                # speed along the flow is positive when b is upstream; 0 on the end faces
                # and the farther lines.  rr: downstream over upstream density, for the
                # gas that enters the gap where the walls win against the pressure.
                c = slice(0, na + 1)
                v = np.zeros_like(x[:, :nl])
                v[:, c] = np.where(fwd[:, c], -self.wall_speed, self.wall_speed) * np.sqrt(
                    r1[:, c] / p1[:, c])
                rr = np.ones_like(v)
                ra, rb = Wa[1][:, c], Wb[1][:, c]
                rr[:, c] = np.where(fwd[:, c], rb / ra, ra / rb)
            f[:, :nl] = self._calibrated_flux(S[:, :nl], x[:, :nl], f[:, :nl], v, rr)
        F = S * f * area
        F = np.where(fwd, F, -F)
        if cou is not None:
            # Couette flow: half the tip speed times the gap along each interlobe line,
            # carried from the older (node j+1) into the younger chamber (node j).
            F[:, :na + 1] -= cou * R[:, 1:na + 2]
        if cou is not None or drag:
            fwd = F > 0.0  # the walls may carry the flow against the pressure difference
        E = F * np.where(fwd, Wa[2], Wb[2])
        return F, E, g, m, rho, u, p, T, h

    def rhs(self, theta: float, y: np.ndarray, seg: Segment) -> np.ndarray:
        """dy/dtheta for a batch of states y (B, n_state) inside segment ``seg``."""
        n, na, fl = self.n, seg.n_act, self.fluid
        F, E, g, m, rho, u, p, T, h = self._flows(theta, y, seg)
        V, dV, Vt, wall = g[0], g[2], g[3], g[6]
        dy = F @ seg.mm + E @ seg.me + np.abs(F) @ seg.mg
        pdV = p * dV
        dy[:, n:n + na] -= pdV
        w = self.inv_omega
        acc0 = self.nv * n
        dy[:, acc0 + ACC_W] = -pdV.sum(axis=1)
        q = None
        if wall is not None:
            q = wall * (self.op.wall_temperature_K - T)
            dy[:, acc0 + ACC_Q] = q.sum(axis=1) * w
        if self.oil:
            mo = y[:, 2 * n:2 * n + na]
            Ho = y[:, 3 * n:3 * n + na]
            q_oil = (Ho - mo * self.op.oil_cp_J_kgK * T) / self.op.oil_time_constant_s
            q = q_oil if q is None else q + q_oil
        if q is not None:
            dy[:, n:n + na] += q * w
        xs = None
        if seg.ideal.size:
            c = seg.ideal
            A = dy[:, c] * self.geo.omega_outer  # other mass flows in (kg/s)
            Bh = (dy[:, n + c] + pdV[:, c]) * self.geo.omega_outer  # other enthalpy + heat (W)
            rc, uc, pc, hc = rho[:, c], u[:, c], p[:, c], h[:, c]
            hpl = seg.ideal_h
            tgt = (seg.ideal_p - pc) * (self.geo.omega_outer / IDEAL_PORT_RELAXATION_RAD)
            Vc, Vtc = V[c], Vt[c]
            if self.ideal_gas:
                g1 = fl.gamma - 1.0
                num = Vc * tgt / g1 - Bh + rc * hc * Vtc
                x = num / np.where(num > 0.0, hpl, hc)
            else:
                pr, pu = fl.dp(rc, uc)
                num = Vc * tgt - pr * (A - rc * Vtc) - pu * (Bh - pc * Vtc - uc * A) / rc
                x_in = num / (pr + pu * (hpl - uc) / rc)
                x_out = num / (pr + pu * (hc - uc) / rc)
                x = np.where(x_in > 0.0, x_in, np.minimum(x_out, 0.0))
            hx = np.where(x > 0.0, hpl, hc)
            dy += x @ seg.mx + (x * hx) @ seg.mxe
            xs = x
        if self.oil:
            # oil leaves with the gas that flows out through the discharge port
            out = np.zeros_like(p)
            if xs is not None:
                sel = seg.ideal_is_dis
                out[:, seg.ideal[sel]] = np.maximum(-xs[:, sel], 0.0)
            if seg.dis_port.size:
                out[:, seg.ia[seg.dis_port] - 1] += np.maximum(F[:, seg.dis_port], 0.0)
            frac = out / m
            dy[:, 2 * n:2 * n + na] = -mo * frac * w
            dy[:, 3 * n:3 * n + na] = (-q_oil - Ho * frac) * w
            dy[:, acc0 + ACC_OIL_M_OUT] = (mo * frac).sum(axis=1) * w
            dy[:, acc0 + ACC_OIL_H_OUT] = (Ho * frac).sum(axis=1) * w
        return dy

    # -- observation -----------------------------------------------------------------
    def observe(self, theta: float, y: np.ndarray):
        """Volume, p, T, m of every slot for one state y (n_state,); NaN where inactive."""
        n = self.n
        ages = theta + self.geo.period * np.arange(n)
        V = self.geo.volume(np.minimum(ages, self.geo.death))
        m = y[:n].copy()
        U = y[n:2 * n]
        live = (ages <= self.geo.death * (1 + 1e-12)) & (m > 0)
        m[~live] = np.nan
        with np.errstate(invalid="ignore", divide="ignore"):
            p, T, _ = self.fluid.props(m / V, U / m)
        return ages, V, np.asarray(p, float), np.asarray(T, float), m

    # -- events ----------------------------------------------------------------------
    def apply_event(self, kind: str, k: int, theta: float, y: np.ndarray) -> None:
        """Apply one event to a batch of states in place."""
        n, geo = self.n, self.geo
        acc = y[:, self.nv * n:]
        age = theta + k * geo.period
        V = float(geo.volume(age))
        if kind == "birth":
            m = self.suc.rho * V
            y[:, k] = m
            y[:, n + k] = m * self.suc.u
            acc[:, ACC_M_SUC] += m
            acc[:, ACC_H_SUC] += m * self.suc.h
            acc[:, ACC_W] -= self.suc.p * V
            if self.oil:
                y[:, 2 * n + k] = 0.0
                y[:, 3 * n + k] = 0.0
        elif kind == "death":
            m = y[:, k].copy()
            U = y[:, n + k].copy()
            p, _, _ = self.fluid.props(m / V, U / m)
            acc[:, ACC_M_DIS] += m
            acc[:, ACC_H_DIS] += U + p * V
            acc[:, ACC_W] += p * V
            y[:, k] = 0.0
            y[:, n + k] = 0.0
            if self.oil:
                acc[:, ACC_OIL_M_OUT] += y[:, 2 * n + k]
                acc[:, ACC_OIL_H_OUT] += y[:, 3 * n + k]
                y[:, 2 * n + k] = 0.0
                y[:, 3 * n + k] = 0.0
        elif kind == "close" and self.oil:
            mo = self.op.oil_mass_ratio * y[:, k]
            ho = mo * self.op.oil_cp_J_kgK * self.op.oil_temperature_K
            y[:, 2 * n + k] += mo
            y[:, 3 * n + k] += ho
            acc[:, ACC_OIL_M_IN] += mo
            acc[:, ACC_OIL_H_IN] += ho
        elif kind == "open" and self.ports.model == "ideal":
            self._equalise(k, V, y, acc)

    def _equalise(self, k, V, y, acc):
        """Ideal discharge port opening: bring the chamber to the discharge pressure at once."""
        n, fl, pd = self.n, self.fluid, self.dis.p
        m = y[:, k].copy()
        U = y[:, n + k].copy()
        rho = m / V
        u = U / m
        p, _, _ = fl.props(rho, u)
        m2 = m.copy()
        U2 = U.copy()
        over = p > pd * (1 + 1e-12)
        under = p < pd * (1 - 1e-12)
        if np.any(over):
            r2, u2 = fl.isentropic(rho[over], u[over], pd)
            m2[over] = r2 * V
            U2[over] = m2[over] * u2
        if np.any(under):
            m2[under], U2[under] = fl.fill(m[under], U[under], V, self.dis.h, pd)
        y[:, k] = m2
        y[:, n + k] = U2
        acc[:, ACC_M_DIS] += m - m2
        acc[:, ACC_H_DIS] += U - U2

    # -- initial state ---------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        """Start of a period with the no-leakage adiabatic cycle as the guess (slot 0 empty)."""
        n, geo, fl = self.n, self.geo, self.fluid
        y = np.zeros(self.n_state)
        kap = self.suc.kappa
        m_trap = self.suc.rho * geo.v_trapped
        for k in range(1, n):
            age = geo.birth + k * geo.period
            if age > geo.death:
                continue
            V = float(geo.volume(age))
            if age < geo.suction_close:
                rho, p = self.suc.rho, self.suc.p
            elif age < geo.discharge_open:
                rho = m_trap / V
                p = self.suc.p * (rho / self.suc.rho) ** kap
            else:  # any working port keeps the chamber near the discharge pressure
                p = self.dis.p
                rho = self.suc.rho * (p / self.suc.p) ** (1.0 / kap)
            u = fl.u_from_rho_p(rho, p)
            y[k] = rho * V
            y[n + k] = rho * V * u
            if self.oil and age >= geo.suction_close:
                mo = self.op.oil_mass_ratio * m_trap
                y[2 * n + k] = mo
                y[3 * n + k] = mo * self.op.oil_cp_J_kgK * self.op.T_suction_K
        return y

    def shift(self, y_end: np.ndarray) -> np.ndarray:
        """State at the start of the next period: slot k -> k+1, slot 0 empty, sums reset."""
        y = np.zeros_like(y_end)
        n = self.n
        for b in range(self.nv):
            y[..., b * n + 1:(b + 1) * n] = y_end[..., b * n:(b + 1) * n - 1]
        return y


def _cols(k, nl, leak):
    if not np.ndim(k):
        return k
    return k[:, :nl] if leak else k[:, nl:]


# ---------------------------------------------------------------------------------------
def build(geo: ChamberGeometry, fluid, op: Operating, leak: Leakage, ports: Ports) -> ChamberModel:
    def plenum(p, T):
        rho, u, h = fluid.state_pT(p, T)
        k = fluid.props(np.array([rho]), np.array([u]))[2]
        return Plenum(p, T, rho, u, h, float(np.ravel(k)[0]) if np.ndim(k) else float(k))

    suc = plenum(op.p_suction_Pa, op.T_suction_K)
    # Discharge plenum gas (what flows back) at the isentropic end temperature of the
    # pressure ratio: the temperature of gas compressed from suction without losses.
    if hasattr(fluid, "gamma"):
        g = fluid.gamma
        Td = op.T_suction_K * op.pressure_ratio ** ((g - 1.0) / g)
    else:
        h_is = suc.h + fluid.work_isentropic(op.p_suction_Pa, op.T_suction_K, op.p_discharge_Pa)
        Td = fluid.T_ph(op.p_discharge_Pa, h_is)
    dis = plenum(op.p_discharge_Pa, Td)
    n = geo.slots
    nv = 4 if op.oil_mass_ratio > 0 else 2
    x_choke = flows.fanno_choke_ratio(leak.zeta) if leak.model == "fanno" else 0.0
    segments = tuple(_segments(geo, n, nv, leak, ports, suc, dis))
    return ChamberModel(geo, fluid, op, leak, ports, suc, dis, n, nv, segments,
                        suc.rho * geo.v_max, op.p_suction_Pa * geo.v_max, x_choke,
                        hasattr(fluid, "gamma"), 1.0 / geo.omega_outer)


def _segments(geo: ChamberGeometry, n: int, nv: int, leak: Leakage, ports: Ports, suc, dis):
    P, t0 = geo.period, geo.birth
    tol = 1e-10 * P
    events = [(t0, 0, "birth", 0)]
    order = {"birth": 0, "death": 1, "close": 2, "open": 3}
    for kind, age in (("close", geo.suction_close), ("open", geo.discharge_open),
                      ("death", geo.death)):
        k = int(math.floor((age - t0 + tol) / P))
        if 0 <= k < n:
            th = max(age - k * P, t0)
            events.append((th, order[kind], kind, k))
    events.sort()
    marks = sorted({e[0] for e in events} | {t0 + P})
    index = 0
    for a, b in zip(marks[:-1], marks[1:], strict=True):
        evs = tuple((kind, k) for th, _, kind, k in events if abs(th - a) <= tol)
        if b - a <= tol and not evs:
            continue
        mid = 0.5 * (a + b)
        ages = mid + P * np.arange(n)
        n_act = int(np.sum(ages <= geo.death))
        k_sc = int(np.sum(ages[:n_act] < geo.suction_close))
        k_do = int(np.sum(ages[:n_act] < geo.discharge_open))
        yield _topology(index, a, max(a, b), evs, n, nv, n_act, k_sc, k_do, P, leak, ports,
                        suc, dis, 1.0 / geo.omega_outer, geo.far_offsets)
        index += 1


def _topology(index, a, b, evs, n, nv, na, k_sc, k_do, period, leak: Leakage, ports: Ports,
              suc, dis, w, far_offsets=()) -> Segment:
    """Flow paths and their maps into dy/dtheta for one segment (see Segment)."""
    def gi(row, k):
        return row * na + k

    ia, ib, rows, grp = [], [], [], []
    n_rows = 6 + len(far_offsets)
    ncol = n_rows * na
    link_len = np.zeros((na + 1, ncol))
    if leak.model != "none":
        cl = leak.gap_m * leak.coefficient
        for j in range(na + 1):  # chain links node j -> node j+1
            r = np.zeros(ncol)
            if j == 0:
                r[gi(3, 0)] = 1.0  # youngest chamber's previous side -> suction
            elif j == na:
                r[gi(2, na - 1)] = 1.0  # oldest chamber's next side -> discharge
            else:  # both chambers see the same line; average their two views of it
                r[gi(2, j - 1)] = 0.5
                r[gi(3, j)] = 0.5
            link_len[j] = r
            ia.append(j)
            ib.append(j + 1)
            rows.append(cl * r)
            grp.append(ACC_L_INT)
        for k in range(na):  # end faces
            for node, row, gr in ((0, 4, ACC_L_LP), (na + 1, 5, ACC_L_HP)):
                r = np.zeros(ncol)
                r[gi(row, k)] = cl
                ia.append(k + 1)
                ib.append(node)
                rows.append(r)
                grp.append(gr)
        # Lines to chambers d >= 2 periods older: slot j to slot j + d; a slot below 0 is
        # a chamber not yet born (the space is open to suction), one past the last a
        # chamber already discharged.
        for d in sorted({abs(x) for x in far_offsets}):
            up = 6 + far_offsets.index(d) if d in far_offsets else None
            down = 6 + far_offsets.index(-d) if -d in far_offsets else None
            for j in range(-d, na):
                old = j + d
                if j < 0 and old >= na:
                    continue
                r = np.zeros(ncol)
                views = [(up, j), (down, old)]
                seen = [(row, k) for row, k in views if row is not None and 0 <= k < na]
                if not seen:
                    continue
                for row, k in seen:
                    r[gi(row, k)] = cl / len(seen)
                ia.append(min(max(j + 1, 0), na + 1))
                ib.append(min(old + 1, na + 1))
                rows.append(r)
                grp.append(ACC_L_INT)
    n_leak = len(ia)
    dis_port = []
    ideal = []
    if ports.model == "nozzle":
        cp = ports.coefficient
        for k in range(na):
            for node, row, open_ in ((0, 0, k < k_sc), (na + 1, 1, k >= k_do)):
                if open_:
                    r = np.zeros(ncol)
                    r[gi(row, k)] = cp
                    if node == na + 1:
                        dis_port.append(len(ia))
                    ia.append(k + 1)
                    ib.append(node)
                    rows.append(r)
                    grp.append(None)
    else:
        ideal = list(range(k_sc)) + list(range(k_do, na))
    nf = len(ia)
    S = nv * n + N_ACC
    acc0 = nv * n

    def node_map(node_a, node_b, unit_m, unit_e):
        """Row of dy for a unit flow from node_a to node_b."""
        rm = np.zeros(S)
        re = np.zeros(S)
        for node, sgn in ((node_a, -1.0), (node_b, 1.0)):
            if node == 0:
                rm[acc0 + ACC_M_SUC] -= sgn * w * unit_m
                re[acc0 + ACC_H_SUC] -= sgn * w * unit_e
            elif node == na + 1:
                rm[acc0 + ACC_M_DIS] += sgn * w * unit_m
                re[acc0 + ACC_H_DIS] += sgn * w * unit_e
            else:
                rm[node - 1] += sgn * w * unit_m
                re[n + node - 1] += sgn * w * unit_e
        return rm, re

    mm = np.zeros((nf, S))
    me = np.zeros((nf, S))
    mg = np.zeros((nf, S))
    for f in range(nf):
        rm, _ = node_map(ia[f], ib[f], 1.0, 0.0)
        _, re = node_map(ia[f], ib[f], 0.0, 1.0)
        mm[f], me[f] = rm, re
        if grp[f] is not None:
            mg[f, acc0 + grp[f]] = w
    ni = len(ideal)
    mx = np.zeros((ni, S))
    mxe = np.zeros((ni, S))
    is_dis = np.array([k >= k_do for k in ideal], dtype=bool)
    for i, k in enumerate(ideal):
        plen = na + 1 if is_dis[i] else 0
        rm, _ = node_map(plen, k + 1, 1.0, 0.0)
        _, re = node_map(plen, k + 1, 0.0, 1.0)
        mx[i], mxe[i] = rm, re
    area = np.array(rows).reshape(nf, ncol) if nf else np.zeros((0, ncol))
    ip = np.where(is_dis, dis.p, suc.p)
    ih = np.where(is_dis, dis.h, suc.h)
    return Segment(index, a, b, evs, na, k_sc, k_do, period * np.arange(na),
                   np.array(ia, dtype=np.intp), np.array(ib, dtype=np.intp), n_leak, area,
                   link_len, mm, me, mg, np.array(ideal, dtype=np.intp), ip, ih, is_dis, mx, mxe,
                   np.array(dis_port, dtype=np.intp))
