"""The periodic state: integrate one lobe period, shift the slots, repeat until periodic.

The period map Phi takes the state of slots 1..n-1 at the start of a period (slot 0 is
born empty-handed at that angle) to the same slots one period later.  Its fixed point is
the machine's periodic state.  Plain iteration z <- Phi(z) converges slowly when leakage
couples the chambers (an error leaves only after a chamber's whole life); the solver
therefore applies Newton's method to Phi(z) - z, with the Jacobian of Phi taken by
finite differences over a batch of perturbed states integrated together with z in the
same pass (one shared step sequence; a batch costs little more than one state because
the work per step is dominated by fixed overhead, not by the array length).  Once the
step sequence has been found, later periods replay it, so that Phi is one fixed smooth
map and Newton converges on it instead of on integration noise.  Where Newton's steps
fail (kinks of reversing flows, a bubble line), the plain iteration is probed, and
Anderson's acceleration of it takes over when it contracts fast or Newton stalls
(PROBE_GAIN, NEWTON_PATIENCE).

Converged: p and T of every chamber at the period start change by less than
``cycle_rtol`` (relative) and the period's mass and energy balance close to
``balance_tol`` (mass relative to the period's throughput, energy relative to its
indicated work; each with a floor of the ideal displacement's mass and p_suction V so
that a pump delivering nothing is still judged).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from .cycle_states import plausible, rejected
from .integrate import OverTime, PeriodRun, integrate_period
from .model import ChamberModel
from .network import ACC_H_DIS, ACC_H_SUC, ACC_M_DIS, ACC_M_SUC, ACC_Q, ACC_W
from .settings import Numerics

# Once p, T and the balances change by less than this between periods, the period's step
# sequence is frozen (replayed whatever its error estimate says): the state moves so
# little that the steps stay as accurate as when they were chosen, and a fixed step
# sequence keeps the period map one smooth function for Newton's method.
FORCE_REPLAY_BELOW = 1.0e-3
# Times the tolerance is tightened tenfold when Newton's method stalls.
STALL_TIGHTEN = 2
# Periods Newton's method may go without halving its best residual before the solver
# switches to Anderson acceleration of the plain iteration: where flows reverse (a
# machine whose leakage exceeds its displacement) the period map has kinks, the
# finite-difference Jacobian points past them, and damped Newton steps cycle at a
# residual of ~1e-4 (a CO2 stress point: steps 3000 times the residual).
NEWTON_PATIENCE = 8
# Past iterates Anderson's least-squares extrapolation combines (Walker & Ni 2011: 3-10).
ANDERSON_MEMORY = 5
# Finite-difference step of the Jacobian, relative to each component's reference scale:
# large against round-off (1e-16 / 1e-6) and small against curvature.
FD_STEP = 1.0e-6
# Chord periods: once a Newton step is this small (relative to the scales), the next
# periods integrate the state alone (no perturbed batch, ~1/10 of the cost) and step with
# the last Jacobian, whose error is then of the order of the step times the residual.
# A chord period that does not cut the residual by CHORD_GAIN brings the batch back.
CHORD_BELOW = 1.0e-2
CHORD_GAIN = 0.1
# The first full Newton step that does not lower the residual is followed by periods of
# the plain iteration from the best iterate (integrated alone, ~1/10 of a batch period),
# kept up while each cuts the residual by PROBE_GAIN; when a later one does not,
# Anderson acceleration of that iteration takes over.  If the first does not, Newton
# resumes where it was, with the step sequence it replayed: one cheap period lost.  A
# wet pentane pump whose discharging chambers condense: the batch's Newton steps land
# across the bubble line (20-30 thousand right-hand sides a period instead of 1-2
# thousand) and never beat the first iterate, while the plain iteration converges by
# ~20x a period (9 batch periods, 60 s, before NEWTON_PATIENCE ran out; now 2).  Once a
# solve, and Anderson only after a plain period met the gain: where Newton's steps fail
# at kinks of reversing flows, plain periods started from every new best iterate and
# then stepped with a stale Jacobian took twice damped Newton's periods (a leaky machine
# whose map contracts by ~0.6 a period), and a first probe's cut of 3x sent two stress
# points to Anderson, which converged one (CO2) and not the other in 22 periods.
PROBE_GAIN = 0.25  # (0: no probe)


@dataclass
class CycleSolution:
    model: ChamberModel
    y_start: np.ndarray  # state at the start of the converged period (slot 0 empty)
    run: PeriodRun  # the converged period (with trace)
    cycles: int  # lobe periods integrated
    converged: bool
    message: str
    dp_rel: float
    dT_rel: float
    mass_closure: float
    energy_closure: float
    conservation_mass: float  # stored change vs boundary flows (round-off only)
    conservation_energy: float
    n_rhs: int


def balances(model: ChamberModel, y_start: np.ndarray, y_end: np.ndarray):
    """Mass and energy closure of one period and the conservation residuals."""
    n, nv = model.n, model.nv
    a = y_end[nv * n:]
    c = model.acc_cols
    m_ref = model.suc.rho * model.geo.v_trapped
    e_ref = model.suc.p * model.geo.v_trapped
    throughput = max(abs(a[ACC_M_SUC]), m_ref)
    work = max(abs(a[ACC_W]), e_ref)
    e_in = a[ACC_H_SUC] + a[ACC_W] + a[ACC_Q] + a[c.oil_h_in]
    e_out = a[ACC_H_DIS] + a[c.oil_h_out]
    stored_e0 = y_start[n:2 * n].sum() + (y_start[3 * n:4 * n].sum() if nv >= 4 else 0.0)
    stored_e1 = y_end[n:2 * n].sum() + (y_end[3 * n:4 * n].sum() if nv >= 4 else 0.0)
    # gas and oil (or liquid) are each conserved: each closes against its own throughput
    # (a multiphase pump carries ~100 times more liquid than gas by mass); a volatile
    # liquid's evaporation moves mass from the liquid to the gas and its vapour (.humid)
    evap = a[c.evaporated] if nv == 5 else 0.0
    gas = a[ACC_M_SUC] - a[ACC_M_DIS] + evap
    mass_closure = abs(gas) / throughput
    cons_m = abs(y_end[:n].sum() - y_start[:n].sum() - gas) / throughput
    if nv >= 4:
        liq = a[c.oil_m_in] - a[c.oil_m_out] - evap
        liq_through = max(abs(a[c.oil_m_in]), m_ref * 1e-3)
        mass_closure = max(mass_closure, abs(liq) / liq_through)
        cons_m = max(cons_m, abs(y_end[2 * n:3 * n].sum() - y_start[2 * n:3 * n].sum() - liq)
                     / liq_through)
    if nv == 5:
        vap = a[c.vap_in] - a[c.vap_out] + evap
        mass_closure = max(mass_closure, abs(vap) / throughput)
        cons_m = max(cons_m, abs(y_end[4 * n:5 * n].sum() - y_start[4 * n:5 * n].sum() - vap)
                     / throughput)
    energy_closure = abs(e_in - e_out) / work
    cons_e = abs((stored_e1 - stored_e0) - (e_in - e_out)) / work
    return mass_closure, energy_closure, cons_m, cons_e


def _pT(model, z):
    _, _, p, T, _ = model.observe(model.geo.birth, z)
    return p[1:], T[1:]


def _unknowns(model: ChamberModel) -> np.ndarray:
    """State entries the Newton iteration solves for: every slot's but the newborn's
    (slot 0 is born at the suction state) and those of slots already dead."""
    n, nv = model.n, model.nv
    idx = np.concatenate([np.arange(b * n + 1, (b + 1) * n) for b in range(nv)])
    alive = np.array([model.geo.birth + k * model.geo.period <= model.geo.death
                      for k in range(1, n)] * nv)
    return idx[alive]


def _update_best(model, run, z, z_next, idx, dz, norm, best, lam, figures, J=None):
    """Keep the iterate with the smallest residual and its Newton step (None when the
    Jacobian is singular or the step not finite); a worse iterate halves the damping.
    The Jacobian of Phi(z) - z is the batch's finite differences, or ``J`` (a chord
    period's: the state was integrated alone). Returns (best, damping, Jacobian)."""
    if not (best is None or norm < best[0]):  # (a NaN residual is never the best)
        return best, lam * 0.5, J
    if run.y.shape[0] > 1:
        Phi = np.stack([model.shift(yy)[idx] for yy in run.y[1:]])  # row i: input i
        J = ((Phi - z_next[idx]) / dz[:, None]).T - np.eye(idx.size)
    try:
        step = np.linalg.solve(J, -(z_next - z)[idx])
    except np.linalg.LinAlgError:
        step = None
    if step is not None and not np.all(np.isfinite(step)):
        step = None
    return (norm, z, run, step, z_next, figures), 1.0, J


def _damped(model, best, idx, lam):
    """(the damped Newton iterate from the best state, shrunk until it is physical; the
    damping it took).  The best iterate's successor where none is, with the smallest
    damping tried: the next failure halves from the damping that was run, not from
    one whose steps were never physical (a wet n-pentane pump's halvings from 0.5 to
    0.125 each ran the same successor, three batch periods to one result)."""
    for shrink in (1.0, 0.5, 0.25):
        cand = best[1].copy()
        cand[idx] += lam * shrink * best[3]
        if plausible(model, cand):
            return cand, lam * shrink
    return best[4], lam * 0.25


def solve(model: ChamberModel, num: Numerics, record: bool = True) -> CycleSolution:
    from . import compiled  # (not at import: `python -m rotorflow.quasi1d.compiled`)

    cpu = time.process_time()
    model.fast["kernel"] = compiled.kernel_for_point()  # None: numpy (see .compiled)
    try:
        # The flow maps' products are small (batch x flows x states, ~40 000 products):
        # OpenBLAS splits them over threads once they cross its size threshold, which
        # cost the multiphase pump with a volatile water twice its time (67 against 36
        # s) on 2 cores; one thread is as fast below it.
        with threadpool_limits(limits=1, user_api="blas"):
            return _solve(model, num, record)
    finally:
        compiled.note_work(time.process_time() - cpu)


def _solve(model: ChamberModel, num: Numerics, record: bool) -> CycleSolution:
    scales = model.scales()
    atol = num.atol * model.atol_scales()
    idx = _unknowns(model)
    d = idx.size
    newton = num.newton and d > 0
    dz = FD_STEP * scales[idx]
    z = model.initial_state()
    replay = newton_replay = None
    method = _first_method(model, num)
    cycles = n_rhs = 0
    message = ""
    converged = False
    dp = dT = mc = ec = np.inf
    nw = _NewtonState()
    rtol = num.rtol
    tightened = 0
    anderson = None  # the iterate history once Anderson acceleration has taken over
    deadline = time.perf_counter() + num.max_seconds
    for _ in range(num.max_cycles):
        batch = newton and nw.batch
        Y0 = np.repeat(z[None], d + 1 if batch else 1, axis=0)
        if batch:
            Y0[np.arange(1, d + 1), idx] += dz
        ran, message = _budgeted_period(model, Y0, method, rtol, atol, replay, record, num,
                                        max(dp, dT, mc, ec) < FORCE_REPLAY_BELOW, deadline,
                                        cycles, nw.took)
        if ran is None:
            break
        run = ran
        cycles += 1
        n_rhs += run.n_rhs
        method = run.method  # "auto" settles on the method the first period needed
        if method not in ("radau", "bdf"):
            replay = run.steps
        y_end = run.y[0]
        if rejected(model, y_end, anderson is None and newton and nw.best is not None):
            z_next = np.full_like(z, np.nan)  # (a residual that is never the best)
        else:
            z_next = model.shift(y_end)
            dp, dT = _changes(model, z, z_next)
            mc, ec, _, _ = balances(model, z, y_end)
            if max(dp, dT) < num.cycle_rtol and max(mc, ec) < num.balance_tol:
                converged = True
                break
        if anderson is not None:
            z = _anderson(model, anderson, z, z_next, idx, scales)
            continue
        if not newton:
            z = z_next
            continue
        kind, z_new = _newton_next(model, nw, run, z, z_next, idx, dz, scales, (dp, dT, mc, ec))
        if kind == "resume":  # (a plain period's steps are not Newton's map: PROBE_GAIN)
            kind, replay = "step", newton_replay
        newton_replay = replay
        if kind != "stalled":
            newton, anderson = (False, []) if kind == "anderson" else (newton, anderson)
            z = z_new
        elif tightened < STALL_TIGHTEN:
            # Newton stalled: at a coarse tolerance the period map has kinks (flows that
            # reverse inside a step); restart from the best state with a tighter one
            tightened += 1
            rtol *= 0.1
            atol = atol * 0.1
            replay = None
            z = nw.best[1]
            nw.best = None
            dp = dT = mc = ec = np.inf
        else:
            z = nw.best[4]
            nw.best = None
    if not converged:
        z, run, message = _unconverged(nw.best, z, z_next, run, idx, scales, message, num,
                                       (dp, dT, mc, ec))
    mc, ec, cm, ce = balances(model, z, run.y[0])
    model.cache.clear()  # the result keeps the model; not its geometry cache
    return CycleSolution(model, z, run, cycles, converged, message, dp, dT, mc, ec, cm, ce,
                         n_rhs)


def _unconverged(best, z, z_next, run, idx, scales, message, num, figures):
    """(state, its period, message) of a solve that did not converge: the best iterate
    where its residual is below the last's (or the last period was rejected)."""
    if best is not None and not float(np.max(np.abs(z_next - z)[idx] / scales[idx])) \
            <= best[0]:
        _, z, run, _, _, figures = best
    dp, dT, mc, ec = figures
    return z, run, (message or f"cycle not converged after {num.max_cycles} periods: ") + (
        f"relative change of p {dp:.2e}, T {dT:.2e}, mass balance {mc:.2e}, "
        f"energy balance {ec:.2e}")


def _budgeted_period(model, Y0, method, rtol, atol, replay, record, num, force_replay,
                     deadline, cycles, took):
    """(one period's run, "") or, once the time budget runs out inside a period after
    the first, (None, the budget's message); the first has no state to return: OverTime.
    Its seconds go to took[0] (a batch) or took[1] (the state alone)."""
    start = time.perf_counter()
    try:
        run = integrate_period(model, Y0, method, rtol, atol, replay=replay, record=record,
                               max_steps=num.max_steps, force_replay=force_replay,
                               deadline=deadline)
        took[Y0.shape[0] == 1] = time.perf_counter() - start
        return run, ""
    except OverTime as exc:
        budget = f"stopped at the time budget of {num.max_seconds:g} s ([numerics] max_seconds)"
        if not cycles:
            raise OverTime(f"{budget} in the first period: {exc}") from None
        return None, f"{budget} after {cycles} periods: "


@dataclass
class _NewtonState:
    #: the iterate with the smallest residual: (norm, z, run, step, z_next, figures)
    best: tuple | None = None
    lam: float = 1.0  # damping of the next step from the best iterate
    mark: float = np.inf  # the best residual when it last halved
    since_gain: int = 0  # periods since
    J: np.ndarray | None = None  # the last batch's Jacobian of Phi(z) - z
    chord: bool = False  # the next period integrates the state alone (CHORD_BELOW)
    last: float = np.inf  # the residual of the last period
    plain: float | None = None  # the last residual while plain periods run (PROBE_GAIN)
    probed: bool = False  # they have run (once a solve)
    plain_runs: int = 0  # plain periods that met PROBE_GAIN
    resume: np.ndarray | None = None  # Newton's next iterate, put off by them
    took: list = field(default_factory=lambda: [np.inf, np.inf])  # s: batch, chord

    @property
    def batch(self) -> bool:
        """The next period carries the perturbed states (the Jacobian)."""
        return not self.chord and self.plain is None


def _newton_next(model, nw: _NewtonState, run, z, z_next, idx, dz, scales, figures):
    """Damped Newton on Phi(z) - z: a full step from the best iterate so far; a step
    that does not lower the residual is halved (the map has kinks where flows reverse).
    Returns ("step", next iterate), ("stalled", None) after four halvings, or
    ("anderson", the best iterate's image) when the best residual has not halved in
    NEWTON_PATIENCE periods; around the first halving, plain periods (PROBE_GAIN)."""
    norm = float(np.max(np.abs(z_next - z)[idx] / scales[idx]))
    if nw.plain is not None:
        return _after_plain(model, nw, run, z, z_next, idx, dz, norm, figures)
    was_chord = run.y.shape[0] == 1
    lam = nw.lam
    nw.best, nw.lam, nw.J = _update_best(model, run, z, z_next, idx, dz, norm, nw.best,
                                         nw.lam, figures, nw.J)
    step = nw.best[3]
    nw.chord = (step is not None and nw.best[1] is z and nw.lam >= 1.0
                and float(np.max(np.abs(step) / scales[idx])) < CHORD_BELOW
                and not (was_chord and not _chord_pays(norm / nw.last, nw.took)))
    nw.last = norm
    if nw.best[0] < 0.5 * nw.mark:
        nw.mark, nw.since_gain = nw.best[0], 0
    else:
        nw.since_gain += 1
    if nw.since_gain >= NEWTON_PATIENCE:
        return "anderson", nw.best[4]
    if nw.best[3] is None or nw.lam < 1.0 / 16.0:
        return "stalled", None
    failed = nw.lam < lam
    z_new, nw.lam = _damped(model, nw.best, idx, nw.lam)
    if failed and not nw.probed and PROBE_GAIN > 0.0:  # the first that failed
        nw.plain, nw.probed, nw.resume = nw.best[0], True, z_new
        return "step", nw.best[4]
    return "step", z_new


def _chord_pays(gain: float, took) -> bool:
    """Whether the next period is a chord one after a chord period that cut the
    residual by ``gain``: it reached CHORD_GAIN, or chord periods at that gain would
    reach it in less time than a batch period took (``took``: the last batch and chord
    periods' seconds)."""
    if gain <= CHORD_GAIN:
        return True
    if not gain < 1.0:
        return False
    return took[1] * math.log(CHORD_GAIN) / math.log(gain) < took[0]


def _after_plain(model, nw: _NewtonState, run, z, z_next, idx, dz, norm, figures):
    """After a plain period (PROBE_GAIN): another, Anderson's acceleration of them, or
    ("resume", Newton's iterate it had put off) after a first one that did not gain."""
    if norm < PROBE_GAIN * nw.plain:
        nw.plain, nw.plain_runs = norm, nw.plain_runs + 1
        nw.best, nw.lam, nw.J = _update_best(model, run, z, z_next, idx, dz, norm, nw.best,
                                             nw.lam, figures, nw.J)
        return "step", z_next
    nw.plain = None
    return ("anderson", z_next) if nw.plain_runs else ("resume", nw.resume)


def _anderson(model, hist: list, z, z_next, idx, scales):
    """The next iterate by Anderson acceleration (type II) of z <- Phi(z): the
    combination of the last ANDERSON_MEMORY map images whose residuals, combined
    likewise, are least in the least-squares sense; the plain image where that state is
    not physical (the history then restarts)."""
    hist.append((z[idx] / scales[idx], z_next[idx] / scales[idx]))
    del hist[:-(ANDERSON_MEMORY + 1)]
    if len(hist) < 2:
        return z_next
    X = np.array([h[0] for h in hist])
    G = np.array([h[1] for h in hist])
    F = G - X
    dF, dG = np.diff(F, axis=0), np.diff(G, axis=0)
    gamma = np.linalg.lstsq(dF.T, F[-1], rcond=None)[0]
    cand = z_next.copy()
    cand[idx] = (G[-1] - dG.T @ gamma) * scales[idx]
    if np.all(np.isfinite(cand)) and plausible(model, cand):
        return cand
    hist.clear()
    return z_next


def _first_method(model: ChamberModel, num: Numerics) -> str:
    if num.integrator == "auto" and model.ports.model == "nozzle":
        # a nozzle port on a small chamber is stiff from the first step: go implicit at once
        return "ros23"
    return num.integrator


def _changes(model: ChamberModel, z: np.ndarray, z_next: np.ndarray) -> tuple[float, float]:
    """Largest relative change of p and of T over a period, from state z to z_next."""
    p0, T0 = _pT(model, z)
    p1, T1 = _pT(model, z_next)
    dp = float(np.nanmax(np.abs(p1 / p0 - 1.0))) if p0.size else 0.0
    dT = float(np.nanmax(np.abs(T1 / T0 - 1.0))) if T0.size else 0.0
    return dp, dT
