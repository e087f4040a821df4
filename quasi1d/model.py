"""The chamber equations: every chamber present in the machine, coupled, over one lobe period.

Slots.  At outer-rotor angle ``theta`` (within one lobe period starting at the birth
angle) slot k holds the chamber of age ``theta + k * period``; slot 0 is born at the
period's start, the last slot dies inside the period.  After one period slot k has
become slot k+1 of the next, so integrating one period and shifting the slots is one
cycle of the machine (seed 000: chambers are the same chamber shifted by 2 pi / N1).

State per slot: mass m and internal energy U of the gas (and the oil's or liquid's mass
and energy, :mod:`.oil`, :mod:`.liquid`, and a volatile liquid's vapour, :mod:`.humid`).
With the gas's volume they give rho and u, hence p and T without inner iteration; mass
and energy are linear invariants, which an explicit Runge-Kutta method conserves to
round-off.

    dm/dt = sum of mass flows in
    dU/dt = sum of (mass flow in * enthalpy of its upstream side) + Q - p dV/dt

(seed 003 Eqs. 6-7; seed 001 Eqs. 1-2 written for U).  The model integrates in angle:
d/dtheta = (1/omega) d/dt.

Flow paths: the leakage paths the chamber table declares (for the internal gear: the
sealing lines to the older and younger chambers, the end faces to the suction and the
discharge plenum), each with its own gap, coefficient and flow model (:mod:`.paths`),
joined into a network per segment of the period (:mod:`.network`).  Moving walls
(Leakage.wall_motion) drag gas from the older into the younger chamber: a Couette term,
or with "cfd-calibrated" and a fit that has a wall term, the fit's drag term.
With oil or a liquid the leakage is a homogeneous mixture (:mod:`.oil`, :mod:`.liquid`).
Ports: suction open from birth to suction_close through area_lp, discharge from
discharge_open to death through area_hp; "nozzle" ports are flows like the others,
"ideal" ports hold the chamber at the plenum pressure (the port flow solved from
dp/dt = 0 with a weak drift correction).

Accumulators ride along the state (quadratures of the same flows): mass and enthalpy
from suction and to discharge, work done on the gas, heat, gross leakage per report key
of the paths.  The events (birth, port closing and opening, death) are :mod:`.events`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import CaseError

from . import events, flows, humid, kernel, liquid, oil
from .chamber import ChamberGeometry
from .heat import WALL_AREA_FACTOR, WallHeat, wall_heat
from .network import ACC_H_DIS, ACC_H_SUC, ACC_Q, ACC_W, AccColumns, Segment, segments
from .oil import leakage as oil_leakage
from .oil import node_loads, oil_leak_balances, slot_balances
from .paths import resolve
from .plenums import Plenum, liquid_ratio, plenums
from .settings import Leakage, Operating, Ports

# Drift correction of the ideal-port constraint: a pressure offset from the plenum decays
# over this outer-rotor angle.  0.2 rad keeps it well below any step an explicit method
# takes for stability (its eigenvalue -1/0.2 per rad) while removing offsets within a
# fraction of a period.
IDEAL_PORT_RELAXATION_RAD = 0.2

_NO_WALL = np.empty(0)  # the compiled right-hand side's "no heat transfer"


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
    nv: int  # state variables per slot: 2 (m, U), 4 (with oil mass and enthalpy), 5 (vapour)
    laws: tuple  # paths.PathLaw of every declared leakage path
    acc_cols: AccColumns
    segments: tuple
    m_ref: float  # suction density * V_max
    e_ref: float  # p_suction * V_max
    ideal_gas: bool
    inv_omega: float
    # 1 / the liquid's density (0: no volume) and its mass per gas mass (.liquid)
    inv_rho_liquid: float = 0.0
    liquid_ratio: float = 0.0
    heat: WallHeat = WallHeat(0.0, "none", 0.0)  # the walls' heat-transfer law (.heat)
    cache: dict = field(default_factory=dict, repr=False, compare=False)
    # the compiled right-hand side ("kernel", set by the cycle solver) and its arguments
    fast: dict = field(default_factory=dict, repr=False, compare=False)

    # -- layout --------------------------------------------------------------------
    @property
    def n_state(self) -> int:
        return self.nv * self.n + self.acc_cols.size

    @property
    def oil(self) -> bool:
        return self.nv >= 4

    @property
    def vapour(self) -> bool:
        """A volatile liquid's vapour rides in a fifth block (:mod:`.humid`)."""
        return self.nv == 5

    @property
    def liquid_datum_K(self) -> float:
        """Ho = mo c (T_l - datum): from 0 K a pump's books would drown its work."""
        return self.op.oil_temperature_K

    def acc(self, y):
        return y[..., self.nv * self.n:]

    def state_columns(self, seg: Segment) -> np.ndarray:
        """Columns of y the right-hand side depends on in ``seg`` (active slots' states)."""
        key = ("columns", seg.index)
        if key not in self.fast:
            n, na = self.n, seg.n_act
            self.fast[key] = np.concatenate([np.arange(b * n, b * n + na)
                                             for b in range(self.nv)])
        return self.fast[key]

    def scales(self) -> np.ndarray:
        """Reference magnitudes per state component (for the absolute tolerance)."""
        s = np.empty(self.n_state)
        n, c = self.n, self.acc_cols
        s[:n] = self.m_ref
        s[n:2 * n] = self.e_ref + self.m_ref * abs(self.suc.u)
        if self.oil:
            s[2 * n:3 * n] = self.m_ref * max(self.liquid_ratio, 1e-3)
            s[3 * n:4 * n] = s[2 * n:3 * n] * self.op.oil_cp_J_kgK * self.op.oil_temperature_K
        if self.vapour:
            s[4 * n:5 * n] = self.m_ref * max(self.suc.w, 1e-3)
        a = s[self.nv * n:]
        a[:] = self.m_ref
        a[[ACC_H_SUC, ACC_H_DIS]] = self.m_ref * abs(self.suc.h) + self.e_ref
        a[[ACC_W, ACC_Q]] = self.e_ref
        a[[c.oil_h_in, c.oil_h_out]] = s[3 * n] if self.oil else self.e_ref
        if c.oil_leaks:
            a[[c.oil_leak(key) for key in c.leak_keys]] = s[2 * n]
        return s

    def atol_scales(self) -> np.ndarray:
        """Scales of the absolute tolerance: chamber states at the size of a chamber at
        birth (so that a young or dying chamber is still integrated to rtol, not drowned by
        an absolute tolerance made for a full one), accumulators at a cycle's totals."""
        s = self.scales()
        s[:self.nv * self.n] *= float(self.geo.volume(self.geo.birth)) / self.geo.v_max
        return s

    # -- right-hand side ---------------------------------------------------------------
    def _geometry(self, theta, seg: Segment):
        """Geometry of the active slots at ``theta`` (cached: replayed steps repeat angles);
        ``theta`` an array (B,): one angle per batch member, every entry (B, ...)."""
        multi = np.ndim(theta) > 0
        key = None if multi else (seg.index, theta)
        g = None if multi else self.cache.get(key)
        if g is None:
            if len(self.cache) > 20_000:
                self.cache.clear()
            V, dV, lin = self.geo.evaluate(np.add.outer(theta, seg.kP) if multi
                                           else theta + seg.kP)
            if multi:  # (rows, B, na) -> (B, rows * na), the rows' order of ravel()
                flat = np.swapaxes(lin, 0, 1).reshape(len(theta), -1)
                area = flat @ seg.area.T
                links = flat @ seg.link_len.T
            else:
                flat = lin.ravel()
                area = seg.area @ flat
                links = seg.link_len @ flat if seg.cou_gap.size else None
            cou = None
            if seg.cou_gap.size:
                # Couette flow: half the tip speed times the gap along each line
                cou = (self.wall_speed * seg.cou_gap) * links
            # h A of a constant h (None: no heat, or h from the gas's state, in rhs)
            wall = self.heat.conductance(V) if self.heat.on and self.heat.constant else None
            g = (V, 1.0 / V, dV, self.geo.omega_outer * dV, area, cou, wall)
            if not multi:
                self.cache[key] = g
        return g

    @property
    def wall_speed(self) -> float:
        """U = half the outer rotor's tip speed: the mean wall speed along an interlobe
        line, dragging gas from the older chamber into the younger one."""
        return 0.5 * self.geo.omega_outer * self.geo.radius

    @property
    def drag_in_fit(self) -> bool:
        """The wall drag of some path is the "cfd-calibrated" fit's own (its wall term w,
        with the wall speed passed to it) rather than the separate Couette term.  A fit
        without a wall term (w = 0: fitted to static walls, or saved before the term
        existed) says nothing about moving walls; it keeps the Couette term."""
        return any(law.drag_in_fit for law in self.laws)

    def path_flows(self, theta: float, y: np.ndarray, seg: Segment, enthalpy: bool = False,
                   oil_flows: bool = False):
        """Gas mass flow (kg/s) along every flow path of ``seg`` (from node ia to node ib;
        ``seg.names`` names the path of each) for a state y (n_state,) or a batch
        (B, n_state); the leakage paths come first.  With ``enthalpy``: (mass flows,
        enthalpy flows in W).  With ``oil_flows`` the oil's mass and enthalpy flows along
        the leakage paths follow (zeros where the leakage carries gas only)."""
        y = np.asarray(y, dtype=float)
        F, E, *_, Fo, Eo = self._flows(theta, np.atleast_2d(y), seg)
        if Fo is None:
            Fo = np.zeros_like(F[:, :seg.n_leak])
            Eo = np.zeros_like(Fo)
        out = (F, E) if enthalpy else (F,)
        out += (Fo, Eo) if oil_flows else ()
        if y.ndim == 1:
            out = tuple(o[0] for o in out)
        return out if len(out) > 1 else out[0]

    def _flows(self, theta: float, y: np.ndarray, seg: Segment):
        """Gas mass and enthalpy flows of every path, with the slot states they came
        from, then the leakage's oil mass and enthalpy flows (None, None: gas only)."""
        na, fl, n, suc, dis = seg.n_act, self.fluid, self.n, self.suc, self.dis
        g = self._geometry(theta, seg)
        iV, area, cou = g[1], g[4], g[5]
        m = y[:, :na]
        inv = self.inv_rho_liquid  # a liquid's volume leaves the gas V - mo / rho_l
        rho = m / liquid.gas_volume(g[0], y[:, 2 * n:2 * n + na], inv) if inv else m * iV
        u = y[:, n:n + na] / m
        w = humid.fractions(self, y, m, na) if self.vapour else None
        dps = None  # (dp/drho)_u, (dp/du)_rho where the ideal ports need them
        if w is not None:
            p, T, kap = fl.props(rho, u, w)
        elif seg.ideal.size and not self.ideal_gas:  # one table lookup for both
            p, T, kap, *dps = fl.state(rho, u)
        else:
            p, T, kap = fl.props(rho, u)
        h = u * fl.gamma if self.ideal_gas else u + p / rho
        R = kernel.nodes(rho, suc.rho, dis.rho)
        fwd, x, p1, r1 = kernel.upstream(kernel.nodes(p, suc.p, dis.p), R, seg.ia, seg.ib)
        scalar_k = not np.ndim(kap)
        k1 = kap
        if not scalar_k:
            K = kernel.nodes(kap, suc.kappa, dis.kappa)
            k1 = np.where(fwd, K[:, seg.ia], K[:, seg.ib])
        f = _flux(seg, x, k1, scalar_k)
        for grp in seg.groups:
            if grp.model == "cfd-calibrated":
                c = grp.flows
                ra, rb = R[:, seg.ia], R[:, seg.ib]
                v, rr = self._drag_ratios(grp, x, fwd, r1, p1, ra, rb)
                # Cd psi in the fit's form that is finite through x -> 1
                # (FlowCoefficientFit.reduced_flux): PR = 1/x, K = 24 L mu / (h^2 S) with
                # S = sqrt(p_up rho_up)
                f[:, c] = grp.correlation.reduced_flux(
                    f[:, c], 1.0 / x[:, c], grp.k_factor / np.sqrt(p1[:, c] * r1[:, c]), v, rr)
            elif grp.model == "rarefied":  # f holds the nozzle's: its inertial limit
                c = grp.flows
                f[:, c] = grp.rarefied.reduced_flux(f[:, c], x[:, c], p1[:, c], r1[:, c])
        F = kernel.mass_flows(fwd, p1, r1, f, area)
        oil_flows = (None, None)
        if seg.oil is not None:  # the oil or liquid leaks with the gas (.oil, .liquid)
            X, Y = node_loads(self, y, m, na)
            if self.leak.mixture == "centrifuged":
                oil_flows = liquid.centrifuged_leakage(self, seg, F, X, Y, fwd, x, p1, r1, area)
            else:
                mix = liquid.leak_mix(self, seg, X, fwd, x, p1, r1, k1) \
                    if self.inv_rho_liquid else None  # the liquid's volume (see .liquid)
                oil_flows = oil_leakage(seg, F, X, Y, mix)
        if cou is not None:
            # Couette flow: carried from the older (node ib) into the younger chamber (ia)
            F[:, seg.cou] -= cou * R[:, seg.cou_older]
        H = kernel.nodes(h, suc.h, dis.h)  # the walls may carry flow against the pressure
        E = kernel.enthalpy_flows(F, H[:, seg.ia], H[:, seg.ib])
        return F, E, g, m, rho, u, p, T, h, w, dps, *oil_flows

    def _drag_ratios(self, grp, x, fwd, r1, p1, ra, rb):
        """Wall speed ratios V = U sqrt(rho / p) along the flows of a calibrated group and
        the downstream over the upstream density (None, None: static walls).  On the
        paths with moving walls the drag runs from the older chamber (side b) into the
        younger (side a), so the wall speed along the flow is positive when b is
        upstream; 0 on the other paths of the group.  rr serves the gas that enters the
        gap where the walls win against the pressure."""
        if grp.drag is None:
            return None, None
        c, d = grp.drag, grp.drag_in_group
        v = np.zeros_like(x[:, grp.flows])
        v[:, d] = np.where(fwd[:, c], -self.wall_speed, self.wall_speed) * np.sqrt(
            r1[:, c] / p1[:, c])
        rr = np.ones_like(v)
        ra, rb = ra[:, c], rb[:, c]
        rr[:, d] = np.where(fwd[:, c], rb / ra, ra / rb)
        return v, rr

    def rhs(self, theta, y: np.ndarray, seg: Segment) -> np.ndarray:
        """dy/dtheta for a batch of states y (B, n_state) inside segment ``seg``, at one
        angle ``theta`` or at one per state (an array (B,))."""
        fused = self.fast.get("kernel")
        if fused is not None and not getattr(theta, "ndim", 0):
            args = self._fused_args(seg)
            if args is not None:
                g = self._geometry(theta, seg)
                wall = g[6] if g[6] is not None else _NO_WALL
                return fused.rhs(y, self.n, seg.n_act, g[0], g[1], g[2], g[3], g[4], wall,
                             self.op.wall_temperature_K, self.inv_omega,
                             self.geo.omega_outer, IDEAL_PORT_RELAXATION_RAD, *args)
        n, na = self.n, seg.n_act
        F, E, g, m, rho, u, p, T, h, w_v, dps, Fo, Eo = self._flows(theta, y, seg)
        V, dV, Vt, wall = g[0], g[2], g[3], g[6]
        w = self.inv_omega
        acc0 = self.nv * n
        dy, pdV = kernel.balances(F, E, seg.mm, seg.me, seg.mg, p, dV, n, acc0 + ACC_W)
        q = self.heat.rate(V, wall, rho, T)  # (seed 003 Eq. 6's Q; None: adiabatic)
        if q is not None:
            dy[:, acc0 + ACC_Q] = q.sum(axis=1) * w
        if self.oil:
            op, mo, Ho = self.op, y[:, 2 * n:2 * n + na], y[:, 3 * n:3 * n + na]
            q_oil = oil.heat_to_gas(Ho, mo, T, op.oil_cp_J_kgK, self.liquid_datum_K,
                                    op.oil_time_constant_s)
            q = q_oil if q is None else q + q_oil
        if q is not None:
            dy[:, n:n + na] += q * w
        if Fo is not None:
            oil_leak_balances(seg, dy, Fo, Eo)
        if self.vapour:
            humid.flows_and_evaporation(self, seg, dy, F, y, m, rho, w_v, p)
        xs = None
        if seg.ideal.size and self.vapour:
            xs = humid.ideal_ports(self, seg, dy, pdV, g, y, m, rho, u, p, h, w_v,
                                   IDEAL_PORT_RELAXATION_RAD)
        elif seg.ideal.size:
            gamma, pr, pu = (self.fluid.gamma, p, p) if self.ideal_gas else (0.0, *dps)
            V, Vt, kl = liquid.port_volumes(self, y, dy, V, Vt, m, na) \
                if self.inv_rho_liquid else (V, Vt, 0.0)
            xs = kernel.ideal_ports(dy, pdV, V, Vt, rho, u, p, h, pr, pu, seg.ideal,
                                    seg.ideal_p, seg.ideal_h, seg.mx, seg.mxe,
                                    self.geo.omega_outer, IDEAL_PORT_RELAXATION_RAD, n, gamma,
                                    kl)
        if self.oil:
            slot_balances(self, seg, dy, xs, F, y, m, p, q_oil, w)
            liquid.volume_work(dy, p, n, na, self.inv_rho_liquid)  # (0: nothing moves)
        return dy

    def _fused_args(self, seg: Segment):
        """The segment's arguments of the compiled right-hand side after the geometry
        (:func:`.kernel.rhs_fused`), None where it needs more (:func:`.kernel.fusable`)."""
        key = ("fused", seg.index)
        if key not in self.fast:
            args = None
            if kernel.fusable(self, seg) and self.heat.constant:  # (h from T: numpy only)
                s, d = self.suc, self.dis
                plen = np.array([[s.p, d.p], [s.rho, d.rho], [s.h, d.h], [s.kappa, d.kappa]])
                acc0 = self.nv * self.n
                oil_args, oil_maps = oil.fused_args(self, seg)
                maps = (seg.mm, seg.me, seg.mg)
                if oil_maps is not None:  # (rows n_flows + f: kernel._oil_leak)
                    maps = tuple(np.vstack(m) for m in zip(maps, oil_maps, strict=True))
                args = (seg.ia, seg.ib, *kernel.flow_laws(seg),
                        tuple(kernel.scatter(m) for m in maps),
                        acc0 + ACC_W, acc0 + ACC_Q, seg.ideal, seg.ideal_p, seg.ideal_h,
                        (kernel.scatter(seg.mx), kernel.scatter(seg.mxe)), plen,
                        *self.fluid.kernel_params(),
                        self.fluid.gamma if self.ideal_gas else 0.0, oil_args)
            self.fast[key] = args
        return self.fast[key]

    def fused_geometry(self, seg: Segment):
        """What the compiled segment step (:func:`.kernel.rhs_segment`) needs to evaluate
        the geometry of ``seg`` itself, None where the segment is not fusable."""
        if self._fused_args(seg) is None:
            return None
        key = ("geometry", seg.index)
        if key not in self.fast:
            heat = self.heat.coefficient * WALL_AREA_FACTOR
            self.fast[key] = (self.geo.nodes, self.geo.coef, seg.kP,
                              kernel.scatter(seg.area), heat, self.geo.omega_outer,
                              self.n, seg.n_act, self.op.wall_temperature_K,
                              self.inv_omega, IDEAL_PORT_RELAXATION_RAD)
        return self.fast[key]

    # -- observation -----------------------------------------------------------------
    def observe(self, theta, y: np.ndarray):
        """Ages, volume, p, T, m of every slot for one state y (n_state,) at theta, or for
        states y (N, n_state) at angles theta (N,) (then each (N, n)); NaN where inactive."""
        n = self.n
        ages = np.add.outer(theta, self.geo.period * np.arange(n))
        V = self.geo.volume(np.minimum(ages, self.geo.death))
        m = y[..., :n].copy()
        U = y[..., n:2 * n]
        live = (ages <= self.geo.death * (1 + 1e-12)) & (m > 0)
        m[~live] = np.nan
        inv = self.inv_rho_liquid
        Vg = liquid.gas_volume(V, y[..., 2 * n:3 * n], inv) if inv else V
        with np.errstate(invalid="ignore", divide="ignore"):
            p, T, _ = self.fluid.props(m / Vg, U / m, *(
                (y[..., humid.BLOCK * n:(humid.BLOCK + 1) * n] / m,) if self.vapour else ()))
        return ages, V, np.asarray(p, float), np.asarray(T, float), m

    # -- events and the cycle's states (see .events) -----------------------------------
    def apply_event(self, kind: str, k: int, theta: float, y: np.ndarray) -> None:
        events.apply_event(self, kind, k, theta, y)

    def initial_state(self) -> np.ndarray:
        return events.initial_state(self)

    def shift(self, y_end: np.ndarray) -> np.ndarray:
        return events.shift(self, y_end)


def _flux(seg: Segment, x, k1, scalar_k: bool):
    """Dimensionless flux f(x) of every flow: the nozzle's, and Fanno's on the leakage
    flows that flow by it."""
    if not any(grp.model == "fanno" for grp in seg.groups):
        return flows.nozzle_f(x, k1)
    f = np.empty_like(x)
    for grp in seg.groups:
        c = grp.flows
        if grp.model == "fanno":
            f[:, c] = flows.fanno_f(x[:, c], grp.zeta, grp.x_choke)
        else:
            f[:, c] = flows.nozzle_f(x[:, c], k1 if scalar_k else k1[:, c])
    nl = seg.n_leak
    if f.shape[1] > nl:
        f[:, nl:] = flows.nozzle_f(x[:, nl:], k1 if scalar_k else k1[:, nl:])
    return f


def build(geo: ChamberGeometry, fluid, op: Operating, leak: Leakage, ports: Ports) -> ChamberModel:
    suc, dis = plenums(fluid, op, ports.discharge_plenum_K)
    ratio = liquid_ratio(op, suc)
    if leak.mixture not in Leakage.MIXTURES:
        raise CaseError(f"leakage mixture {leak.mixture!r} is not one of "
                        f"{', '.join(Leakage.MIXTURES)}")
    if leak.mixture == "centrifuged" and not (ratio > 0 and op.liquid_density_kg_m3):
        raise CaseError('leakage mixture "centrifuged" needs a liquid that fills chamber '
                        "volume ([operating] liquid_density_kg_m3 and gas_volume_fraction < 1 "
                        "or oil_mass_ratio > 0)")
    n = geo.slots
    nv = (5 if op.liquid_volatile else 4) if ratio > 0 else 2
    laws = resolve(geo.paths, leak)
    acc = AccColumns.of(laws, oil_leaks=nv >= 4 and leak.mixture != "gas",
                        vapour=nv == 5)
    segs = tuple(segments(geo, laws, acc, nv, n, ports, suc, dis))
    if leak.mixture == "centrifuged" and any(seg.walls for seg in segs):
        raise CaseError('leakage mixture "centrifuged" takes flows driven by the pressure '
                        "only: drop wall_motion (the walls' drag would carry liquid against it)")
    inv_rho = 1.0 / op.liquid_density_kg_m3 if op.liquid_density_kg_m3 and ratio > 0 else 0.0
    return ChamberModel(geo, fluid, op, leak, ports, suc, dis, n, nv, laws, acc, segs,
                        suc.rho * geo.v_max, op.p_suction_Pa * geo.v_max,
                        hasattr(fluid, "gamma"), 1.0 / geo.omega_outer, inv_rho, ratio,
                        wall_heat(op, geo))
