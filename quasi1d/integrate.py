"""Integration of the chamber equations over one lobe period.

Explicit embedded Runge-Kutta pairs with adaptive steps (per-component relative and
absolute tolerances, error norm RMS over components and max over a batch of states):

    "dopri5"  Dormand-Prince 5(4), FSAL
    "bs3"     Bogacki-Shampine 3(2), FSAL

a linearly implicit Rosenbrock method for stiff cases (nozzle ports, wide gaps on small
chambers), with a finite-difference Jacobian taken in one batched call per step:

    "ros23"   Shampine-Reichelt 2(3), L-stable (MATLAB's ode23s)

"auto" (the default) runs dopri5 and switches to ros23 when a period needs more than
AUTO_STIFF_STEPS steps, and back to dopri5 (with the whole step budget) when ros23 needs
more than AUTO_ROS23_STEPS; and scipy's stiff implicit "radau" and "bdf" (the reference).
Events sit at known
angles (birth, port closing and opening, death), so a period is integrated segment by
segment, each ending exactly at the next event.

A batch of states (B, n_state) is integrated with one shared step sequence: this is how
the cycle solver gets the Jacobian of the period map by finite differences in one pass.
``replay`` integrates with a given step sequence instead of choosing steps, so that the
period map is one fixed smooth function while Newton's method converges on it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import RunFailure

from . import stepping

#: A chamber mass below -NEGATIVE_MASS x (suction density x V_max) at the end of an
#: implicit solver's segment is a failed integration, not round-off.
NEGATIVE_MASS = 1e-9


class IntegrationError(RunFailure):
    """The chamber equations could not be integrated (too stiff, or states left the range)."""


class OverTime(IntegrationError):
    """The wall-clock budget ran out inside a period (``deadline`` of integrate_period)."""


#: Steps an adaptive segment takes between looks at the clock: a stiff segment can take
#: its whole step budget (minutes) before the cycle solver's own check between periods.
CLOCK_STEPS = 2000


@dataclass(frozen=True)
class Tableau:
    c: np.ndarray
    A: np.ndarray  # the Runge-Kutta matrix (stages, stages), zero on and above the diagonal
    b: np.ndarray
    e: np.ndarray  # b - b_hat: error estimate weights (length stages + 1 for FSAL)
    order: int  # order of the error estimator + 1 (exponent of the step control)


def _lower(rows) -> np.ndarray:
    A = np.zeros((len(rows), len(rows)))
    for i, row in enumerate(rows):
        A[i, :len(row)] = row
    return A


DOPRI5 = Tableau(
    c=np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0]),
    A=_lower((
        (),
        (1 / 5,),
        (3 / 40, 9 / 40),
        (44 / 45, -56 / 15, 32 / 9),
        (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
        (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
    )),
    b=np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]),
    e=np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40]),
    order=5,
)

BS3 = Tableau(
    c=np.array([0.0, 1 / 2, 3 / 4]),
    A=_lower(((), (1 / 2,), (0.0, 3 / 4))),
    b=np.array([2 / 9, 1 / 3, 4 / 9]),
    e=np.array([5 / 72, -1 / 12, -1 / 9, 1 / 8]),
    order=3,
)

TABLEAUS = {"dopri5": DOPRI5, "bs3": BS3}

# A replayed step whose error estimate exceeds the tolerance by this factor makes the
# integration fall back to choosing its own steps.
REPLAY_SLACK = 4.0


# "auto": explicit dopri5 until a period needs more than this many steps (the mark of a
# stiff problem: large ports or gaps on small chambers), then the Rosenbrock method.
AUTO_STIFF_STEPS = 1500
# ... unless the Rosenbrock method needs more than this: then the steps were not limited
# by stiffness but by a right-hand side that is not smooth, which a Jacobian taken by
# finite differences across the kink makes worse.  A wet pentane chamber discharging on
# the bubble line, where the pressure's slope in density jumps ~1e4-fold: ros23 needs
# 4453 steps for a period dopri5 does in 70; the stiff test cases (nozzle ports) need
# 450-620 steps of ros23.
AUTO_ROS23_STEPS = 3000


class _Stiff(Exception):
    pass


@dataclass
class PeriodRun:
    y: np.ndarray  # (B, n_state) at the period's end
    steps: list  # accepted step ends per segment (for replay)
    n_rhs: int
    n_rejected: int
    method: str = ""
    trace_theta: list = field(default_factory=list)
    trace_y: list = field(default_factory=list)
    # f(theta, y) at the trace's points where the integrator had it (the explicit and
    # Rosenbrock steps), for the dense traces; shorter than trace_y when it has not
    trace_f: list = field(default_factory=list)
    replayed: bool = False


def integrate_period(model, y0: np.ndarray, method: str, rtol: float, atol: np.ndarray,
                     replay=None, record=False, max_steps=200_000, h0=None,
                     force_replay=False, deadline=None) -> PeriodRun:
    """Integrate one lobe period from y0 (B, n_state), applying the events.

    ``method`` "auto" runs dopri5 and falls back to "ros23" when the period turns out stiff,
    and to dopri5 with the whole budget when ros23 needs even more steps; the method used
    is in the result's ``method``.  ``replay`` (step ends per segment)
    replaces the step-size choice; a replayed step that misses the tolerance by more
    than REPLAY_SLACK re-adapts its segment unless ``force_replay`` (the cycle solver's
    choice once the state hardly changes between periods, so that the map stays fixed).
    ``deadline`` (time.perf_counter()) stops an adaptive segment with :class:`OverTime`
    (scipy's "radau" and "bdf" are not watched).
    """
    with np.errstate(all="ignore"):  # non-finite stages are rejected by the error norm
        if method == "auto":
            try:
                return _period(model, y0, "dopri5", rtol, atol, replay, record,
                               AUTO_STIFF_STEPS, h0, True, force_replay, deadline)
            except _Stiff:
                replay = None
            try:
                return _period(model, y0, "ros23", rtol, atol, None, record, AUTO_ROS23_STEPS,
                               h0, True, force_replay, deadline)
            except _Stiff:
                method = "dopri5"
        return _period(model, y0, method, rtol, atol, replay, record, max_steps, h0, False,
                       force_replay, deadline)


def _period(model, y0, method, rtol, atol, replay, record, max_steps, h0, stiff_error,
            force_replay, deadline):
    y = np.array(y0, dtype=float, copy=True)
    run = PeriodRun(y, [], 0, 0, method)
    use_replay = replay is not None
    h = h0
    budget = [max_steps]
    for i, seg in enumerate(model.segments):
        if deadline is not None and time.perf_counter() > deadline:
            raise OverTime(f"the time budget ran out inside a period, at angle "
                           f"{seg.start:.4f} rad, after {run.n_rhs} right-hand sides")
        for kind, k in seg.events:
            model.apply_event(kind, k, seg.start, y)
            if not np.all(np.isfinite(y)):
                # (a state the fluid cannot evaluate: a chamber that dies at negative
                # mass, as scipy's Radau once left a wet pentane pump's, has no pressure)
                raise IntegrationError(f"the {kind} of slot {k} at {seg.start:.4f} rad "
                                       f"left a state that is not finite")
        if record:
            run.trace_theta.append(seg.start)
            run.trace_y.append(y[0].copy())
        if seg.end <= seg.start:
            if record and len(run.trace_f) == len(run.trace_y) - 1:
                run.trace_f.append(np.full(y.shape[1], np.nan))  # (never interpolated)
            run.steps.append([])
            continue
        if method in ("radau", "bdf"):
            y, ends = _scipy(model, seg, y, method, rtol, atol, run, record)
        else:
            step, stages, order = _stepper(model, seg, method, atol, y.shape[1])
            ok = False
            if replay is not None:
                # the previous period's steps, so that the period map stays one function;
                # a segment whose replayed steps miss the tolerance chooses its own
                slack = 1e30 if force_replay else REPLAY_SLACK  # never accept a non-finite step
                ok, y_new, ends = _replay(model, seg, y, step, stages, rtol, atol, replay[i],
                                          run, record, slack)
                if ok:
                    y = y_new
                else:
                    use_replay = False
            if not ok:
                y, ends, h = _adaptive(model, seg, y, step, stages, order, rtol, atol, h, run,
                                       record, budget, stiff_error, deadline)
        run.steps.append(ends)
    run.y = y
    run.replayed = use_replay
    return run


def _stepper(model, seg, method, atol, S):
    """step(t, y, h, k1, args) of ``method`` in ``seg`` with its arguments, the right-hand
    sides a step evaluates (ros23: three and a Jacobian) and its order: the compiled
    fused step where the model holds the compiled kernel and the segment is fusable,
    else Python.  ``atol``: the absolute tolerance (the Jacobian's steps), S the state's
    size."""
    fast = getattr(model, "fast", {}).get("kernel")
    geo = model.fused_geometry(seg) if fast is not None else None

    def rhs(t, y, _):
        return model.rhs(t, y, seg)

    if method == "ros23":
        # the Jacobian's columns: the chamber states of the active slots
        cols = model.state_columns(seg) if hasattr(model, "state_columns") else np.arange(S)
        if geo is not None:
            return (fast.ros23_step, ((atol, cols), geo, model._fused_args(seg))), 4, 3

        def step(t, y, h, k1, _):
            return stepping.ros23_step(rhs, None, t, y, h, k1, atol, cols)

        return (step, None), 4, 3
    tab = TABLEAUS[method]
    if geo is not None:
        return (fast.rk_step, ((tab.c, tab.A, tab.b, tab.e), geo, model._fused_args(seg))), \
            len(tab.c), tab.order

    def step(t, y, h, k1, _):
        return stepping.rk_step(rhs, None, tab.c, tab.A, tab.b, tab.e, t, y, h, k1)

    return (step, None), len(tab.c), tab.order


def _run_segment(model, seg, step, ends, y, k1, h, rtol, atol, order, budget, slack,
                 record, start=None):
    """stepping.segment as Python, or its compiled twin for the compiled step; from
    ``start`` (default the segment's) to the segment's end."""
    fast = getattr(model, "fast", {}).get("kernel")
    rest = (seg.start if start is None else start, seg.end, ends, np.ascontiguousarray(y),
            k1, h, rtol, atol, order, budget, slack, record)
    if fast is not None and step[0] is fast.rk_step:
        return fast.segment(step[1], *rest)
    if fast is not None and step[0] is fast.ros23_step:
        return fast.segment_ros23(step[1], *rest)
    return stepping.segment(step[0], step[1], *rest)


def _first_rhs(model, seg, step, y, t=None):
    """f(t, y) in the segment, t by default its start: compiled where its step is (a
    numpy right-hand side costs ~80 us, four times the compiled batch; issue 19's
    per-point overheads)."""
    t = seg.start if t is None else t
    fast = getattr(model, "fast", {}).get("kernel")
    if fast is not None and step[0] in (fast.rk_step, fast.ros23_step):
        return fast.rhs_segment(t, np.ascontiguousarray(y), step[1])
    return model.rhs(t, y, seg)


def _adaptive(model, seg, y, step, stages, order, rtol, atol, h, run, record, budget,
              stiff_error, deadline):
    """The segment in chunks of CLOCK_STEPS steps, the clock read between them."""
    k1 = k_start = _first_rhs(model, seg, step, y)
    t, h = seg.start, np.nan if h is None else float(h)
    parts = []
    while True:
        chunk = budget[0] if deadline is None else min(budget[0], CLOCK_STEPS)
        status, t, y, h, ends, trace, tried, rejected = _run_segment(
            model, seg, step, np.empty(0), y, k1, h, rtol, atol, order, chunk, 0.0,
            record, start=t)
        budget[0] -= tried
        run.n_rhs += 1 + stages * tried
        run.n_rejected += rejected
        parts.append((ends, trace))
        if status != stepping.OVER_BUDGET or budget[0] <= 0:
            break
        if time.perf_counter() > deadline:
            raise OverTime(f"the time budget ran out inside a period, near angle {t:.4f} "
                           f"rad, after {run.n_rhs} right-hand sides")
        k1 = _first_rhs(model, seg, step, y, t)  # (counted with the chunk's steps)
    ends = np.concatenate([e for e, _ in parts])
    trace = np.concatenate([tr for _, tr in parts])
    if status == stepping.OVER_BUDGET:
        if stiff_error:
            raise _Stiff
        others = ", ".join(f'"{m}"' for m in ("ros23", "bdf") if m != run.method)
        raise IntegrationError(
            f"step limit reached near angle {t:.4f} rad: the chamber equations are too "
            f'stiff for integrator "{run.method}"; try {others}, or a larger [numerics] '
            "max_steps")
    if status == stepping.UNDERFLOW:
        if stiff_error:
            raise _Stiff
        raise IntegrationError(f"step size underflow near angle {t:.6f} rad (state "
                               "not finite or tolerance unreachable)")
    _record(run, ends, trace, record, k_start)
    return y, list(ends), h


def _replay(model, seg, y, step, stages, rtol, atol, ends, run, record, slack):
    ends = np.asarray(ends, dtype=float)
    k1 = _first_rhs(model, seg, step, y)
    status, _, y, _, _, trace, taken, _ = _run_segment(
        model, seg, step, ends, y, k1, np.nan, rtol, atol, 0, 0, slack, record)
    run.n_rhs += 1 + stages * taken
    if status != stepping.DONE:
        return False, None, None
    _record(run, ends, trace, record, k1)
    return True, y, list(ends)


def _record(run, ends, trace, record, k1):
    """Add a segment's steps to the trace; f at its start (k1) beside the start's state,
    which the period recorded before the segment ran."""
    if record:
        S = trace.shape[1] // 2
        run.trace_theta.extend(ends.tolist())
        run.trace_y.extend(trace[:, :S])
        if len(run.trace_f) == len(run.trace_y) - len(ends) - 1:
            run.trace_f.append(k1[0].copy())
            run.trace_f.extend(trace[:, S:])


def _scipy(model, seg, y, method, rtol, atol, run, record):
    from scipy.integrate import solve_ivp
    from scipy.sparse import block_diag, csr_matrix

    B, S = y.shape

    def fun(t, yy):
        run.n_rhs += 1
        # trial states of the implicit solvers can be unphysical (negative mass): keep
        # their Newton iterations going with finite values; accepted steps are checked
        return np.nan_to_num(model.rhs(t, yy.reshape(B, S), seg).ravel(), nan=0.0,
                             posinf=1e300, neginf=-1e300)

    sparsity = block_diag([csr_matrix(np.ones((S, S)))] * B) if B > 1 else None
    sol = solve_ivp(fun, (seg.start, seg.end), y.ravel(), method=method.upper() if method ==
                    "bdf" else method.capitalize(), rtol=rtol, atol=np.tile(atol, B),
                    jac_sparsity=sparsity)
    if not sol.success or not np.all(np.isfinite(sol.y[:, -1])):
        raise IntegrationError(f"{method} failed between {seg.start:.4f} and {seg.end:.4f} rad: "
                               f"{sol.message}")
    # Its trial states may be unphysical, its accepted ones not (a wet pentane pump's
    # chamber came out at -3 kg): the state itself (row 0; Newton's perturbed rows are
    # judged by the cycle), beyond what its own mass tolerance allows a nearly empty slot.
    floor = np.maximum(NEGATIVE_MASS * model.m_ref, 10.0 * np.asarray(atol)[:model.n])
    if np.any(sol.y[:model.n, -1] < -floor):
        raise IntegrationError(f"{method} left a chamber with negative mass between "
                               f"{seg.start:.4f} and {seg.end:.4f} rad")
    if record:
        for t, yy in zip(sol.t[1:], sol.y.T[1:], strict=True):
            run.trace_theta.append(t)
            run.trace_y.append(yy.reshape(B, S)[0].copy())
    return sol.y[:, -1].reshape(B, S), list(sol.t[1:])
