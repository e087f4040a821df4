"""Integration of the chamber equations over one lobe period.

Explicit embedded Runge-Kutta pairs with adaptive steps (per-component relative and
absolute tolerances, error norm RMS over components and max over a batch of states):

    "dopri5"  Dormand-Prince 5(4), FSAL
    "bs3"     Bogacki-Shampine 3(2), FSAL

a linearly implicit Rosenbrock method for stiff cases (nozzle ports, wide gaps on small
chambers), with a finite-difference Jacobian taken in one batched call per step:

    "ros23"   Shampine-Reichelt 2(3), L-stable (MATLAB's ode23s)

"auto" (the default) runs dopri5 and switches to ros23 when a period needs more than
AUTO_STIFF_STEPS steps; and scipy's stiff implicit "radau" and "bdf" (the reference).
Events sit at known
angles (birth, port closing and opening, death), so a period is integrated segment by
segment, each ending exactly at the next event.

A batch of states (B, n_state) is integrated with one shared step sequence: this is how
the cycle solver gets the Jacobian of the period map by finite differences in one pass.
``replay`` integrates with a given step sequence instead of choosing steps, so that the
period map is one fixed smooth function while Newton's method converges on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import RotorflowError


class IntegrationError(RotorflowError, RuntimeError):
    """The chamber equations could not be integrated (too stiff, or states left the range)."""


@dataclass(frozen=True)
class Tableau:
    c: np.ndarray
    a: tuple  # rows of the Runge-Kutta matrix
    b: np.ndarray
    e: np.ndarray  # b - b_hat: error estimate weights (length stages + 1 for FSAL)
    order: int  # order of the error estimator + 1 (exponent of the step control)


DOPRI5 = Tableau(
    c=np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0]),
    a=(
        np.array([]),
        np.array([1 / 5]),
        np.array([3 / 40, 9 / 40]),
        np.array([44 / 45, -56 / 15, 32 / 9]),
        np.array([19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729]),
        np.array([9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656]),
    ),
    b=np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]),
    e=np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40]),
    order=5,
)

BS3 = Tableau(
    c=np.array([0.0, 1 / 2, 3 / 4]),
    a=(np.array([]), np.array([1 / 2]), np.array([0.0, 3 / 4])),
    b=np.array([2 / 9, 1 / 3, 4 / 9]),
    e=np.array([5 / 72, -1 / 12, -1 / 9, 1 / 8]),
    order=3,
)

TABLEAUS = {"dopri5": DOPRI5, "bs3": BS3}

# Step-size controller: safety factor and the bounds of the change per step.
SAFETY, GROW_MAX, SHRINK_MIN = 0.9, 5.0, 0.2
# A replayed step whose error estimate exceeds the tolerance by this factor makes the
# integration fall back to choosing its own steps.
REPLAY_SLACK = 4.0


# "auto": explicit dopri5 until a period needs more than this many steps (the mark of a
# stiff problem: large ports or gaps on small chambers), then the Rosenbrock method.
AUTO_STIFF_STEPS = 1500


class _Stiff(Exception):
    pass


@dataclass
class PeriodRun:
    y: np.ndarray  # (B, n_state) at the period's end
    steps: list  # accepted step ends per segment (for replay)
    n_rhs: int
    n_rejected: int
    method: str = ""
    atol: np.ndarray = None
    jac: list = None  # ros23: [segment, uses, J, dfdt]
    trace_theta: list = field(default_factory=list)
    trace_y: list = field(default_factory=list)
    replayed: bool = False


def integrate_period(model, y0: np.ndarray, method: str, rtol: float, atol: np.ndarray,
                     replay=None, record=False, max_steps=200_000, h0=None,
                     force_replay=False) -> PeriodRun:
    """Integrate one lobe period from y0 (B, n_state), applying the events.

    ``method`` "auto" runs dopri5 and falls back to "ros23" when the period turns out stiff;
    the method used is in the result's ``method``.  ``replay`` (step ends per segment)
    replaces the step-size choice; a replayed step that misses the tolerance by more
    than REPLAY_SLACK re-adapts its segment unless ``force_replay`` (the cycle solver's
    choice once the state hardly changes between periods, so that the map stays fixed).
    """
    with np.errstate(all="ignore"):  # non-finite stages are rejected by the error norm
        if method == "auto":
            try:
                return _period(model, y0, "dopri5", rtol, atol, replay, record,
                               AUTO_STIFF_STEPS, h0, True, force_replay)
            except _Stiff:
                method = "ros23"
                replay = None
        return _period(model, y0, method, rtol, atol, replay, record, max_steps, h0, False,
                       force_replay)


def _period(model, y0, method, rtol, atol, replay, record, max_steps, h0, stiff_error,
            force_replay):
    y = np.array(y0, dtype=float, copy=True)
    run = PeriodRun(y, [], 0, 0, method)
    use_replay = replay is not None
    h = h0
    budget = [max_steps]
    for i, seg in enumerate(model.segments):
        for kind, k in seg.events:
            model.apply_event(kind, k, seg.start, y)
        if record:
            run.trace_theta.append(seg.start)
            run.trace_y.append(y[0].copy())
        if seg.end <= seg.start:
            run.steps.append([])
            continue
        if method in ("radau", "bdf"):
            y, ends = _scipy(model, seg, y, method, rtol, atol, run, record)
        else:
            stepper = _ros23_step if method == "ros23" else _rk_stepper(TABLEAUS[method])
            order = 3 if method == "ros23" else TABLEAUS[method].order
            ok = False
            if replay is not None:
                # the previous period's steps, so that the period map stays one function;
                # a segment whose replayed steps miss the tolerance chooses its own
                slack = 1e30 if force_replay else REPLAY_SLACK  # never accept a non-finite step
                ok, y_new, ends = _replay(model, seg, y, stepper, rtol, atol, replay[i], run,
                                          record, slack)
                if ok:
                    y = y_new
                else:
                    use_replay = False
            if not ok:
                y, ends, h = _adaptive(model, seg, y, stepper, order, rtol, atol, h, run, record,
                                       budget, stiff_error)
        run.steps.append(ends)
    run.y = y
    run.replayed = use_replay
    return run


def _err_norm(err, y, y_new, rtol, atol):
    # The largest component error, not the RMS: an RMS over all slots and accumulators
    # lets one chamber's pressure oscillate by 7-13 % of p_discharge at rtol 5e-4-1e-3
    # while the other components dilute its error (issue 19, nozzle ports near balance).
    sc = atol + rtol * np.maximum(np.abs(y), np.abs(y_new))
    e = np.max(np.abs(err / sc), axis=1)
    m = float(np.max(e))
    return m if np.isfinite(m) else np.inf


def _rk_stepper(tab: Tableau):
    s = len(tab.c)

    def step(model, seg, t, y, h, k1, run):
        shape = y.shape
        K = np.empty((s + 1, y.size))  # stages as rows: one matmul per stage combination
        K[0] = k1.ravel()
        yf = y.ravel()
        for i in range(1, s):
            yi = yf + h * (tab.a[i] @ K[:i])
            K[i] = model.rhs(t + tab.c[i] * h, yi.reshape(shape), seg).ravel()
        y_new = (yf + h * (tab.b @ K[:s])).reshape(shape)
        k_new = model.rhs(t + h, y_new, seg)
        K[s] = k_new.ravel()
        run.n_rhs += s
        return y_new, k_new, (h * (tab.e @ K)).reshape(shape)

    return step


# Rosenbrock method of Shampine & Reichelt (MATLAB ode23s): L-stable, order 2 with a
# third-order error estimate, three right-hand sides and one Jacobian per step.
_D = 1.0 / (2.0 + math.sqrt(2.0))
_E32 = 6.0 + math.sqrt(2.0)
# finite-difference steps of the Jacobian (relative to the tolerance scale) and of df/dt
JAC_STEP = 1.0e-7
JAC_T_STEP = 1.0e-7
# Steps one Jacobian serves (renewed at every segment start and after a rejection).  The
# formula is a W-method, so reuse keeps its order, but measured on nozzle-port cycles a
# stale Jacobian cost more steps and cycles than it saved: a fresh one every step.
JAC_REUSE = 1


def _jacobian(model, seg, t, y, f0, atol):
    """df/dy and df/dt of every batch member by finite differences, in two batched calls.

    Only the columns the right-hand side depends on are perturbed (the chamber states of
    the active slots; nothing depends on the accumulators or on inactive slots).  Each
    member gets its own Jacobian, so that a batch of perturbed states (the cycle
    solver's finite-difference Jacobian of the period map) sees the same method as an
    unperturbed one."""
    B, S = y.shape
    cols = model.state_columns(seg) if hasattr(model, "state_columns") else np.arange(S)
    nc = cols.size
    delta = JAC_STEP * (np.abs(y[:, cols]) + atol[cols])  # (B, nc)
    Y = np.repeat(y[:, None, :], nc, axis=1)  # (B, nc, S)
    Y[:, np.arange(nc), cols] += delta
    F = model.rhs(t, Y.reshape(B * nc, S), seg).reshape(B, nc, S)
    ft = model.rhs(t + JAC_T_STEP, y, seg)
    if not (np.all(np.isfinite(F)) and np.all(np.isfinite(ft))):
        return None, None
    J = np.zeros((B, S, S))
    J[:, :, cols] = np.swapaxes((F - f0[:, None, :]) / delta[:, :, None], 1, 2)
    return J, (ft - f0) / JAC_T_STEP


def _ros23_step(model, seg, t, y, h, F0, run):
    jac = run.jac
    if jac is None or jac[0] is not seg or jac[1] >= JAC_REUSE or jac[2].shape[0] != y.shape[0]:
        J, T = _jacobian(model, seg, t, y, F0, run.atol)
        run.jac = None if J is None else [seg, 0, J, T]
    else:
        J, T = jac[2], jac[3]
    if run.jac is not None:
        run.jac[1] += 1
    if J is None or not np.all(np.isfinite(F0)):
        return y, F0, np.full_like(y, np.inf)
    try:
        Wi = np.linalg.inv(np.eye(y.shape[1]) - (h * _D) * J)  # (B, S, S)
    except np.linalg.LinAlgError:
        return y, F0, np.full_like(y, np.inf)

    def solve(R):
        return np.einsum("bij,bj->bi", Wi, R)

    hdT = (h * _D) * T
    k1 = solve(F0 + hdT)
    F1 = model.rhs(t + 0.5 * h, y + 0.5 * h * k1, seg)
    if not np.all(np.isfinite(F1)):
        return y, F0, np.full_like(y, np.inf)
    k2 = solve(F1 - k1) + k1
    y_new = y + h * k2
    F2 = model.rhs(t + h, y_new, seg)
    if not np.all(np.isfinite(F2)):
        return y, F0, np.full_like(y, np.inf)
    k3 = solve(F2 - _E32 * (k2 - F1) - 2.0 * (k1 - F0) + hdT)
    run.n_rhs += 4
    return y_new, F2, (h / 6.0) * (k1 - 2.0 * k2 + k3)


def _adaptive(model, seg, y, stepper, order, rtol, atol, h, run, record, budget, stiff_error):
    t, t_end = seg.start, seg.end
    span = t_end - t
    run.atol = atol
    k1 = model.rhs(t, y, seg)
    run.n_rhs += 1
    if h is None or not np.isfinite(h) or h <= 0:
        # initial step: a small fraction of what the derivative scale allows
        d0 = np.max(np.abs(y) / (atol + rtol * np.abs(y)))
        d1 = np.max(np.abs(k1) / (atol + rtol * np.abs(y)))
        h = 0.01 * d0 / d1 if d1 > 0 else 0.01 * span
    h = min(h, span)
    ends = []
    while t < t_end:
        budget[0] -= 1
        if budget[0] < 0:
            if stiff_error:
                raise _Stiff
            raise IntegrationError(
                f"step limit reached near angle {t:.4f} rad: the chamber equations are too "
                'stiff for this integrator; use integrator "auto", "ros23" or "bdf"')
        last = t + h >= t_end - 1e-12 * span
        hh = t_end - t if last else h
        y_new, k_new, err = stepper(model, seg, t, y, hh, k1, run)
        en = _err_norm(err, y, y_new, rtol, atol)
        if en <= 1.0:
            t = t_end if last else t + hh
            y, k1 = y_new, k_new
            ends.append(t)
            if record:
                run.trace_theta.append(t)
                run.trace_y.append(y[0].copy())
            fac = GROW_MAX if en == 0 else min(GROW_MAX, SAFETY * en ** (-1.0 / order))
            h = hh * fac if not last else max(h, hh)
        else:
            run.n_rejected += 1
            run.jac = None
            fac = SHRINK_MIN if not np.isfinite(en) else max(SHRINK_MIN,
                                                             SAFETY * en ** (-1.0 / order))
            h = hh * fac
            if h < 1e-14 * max(span, 1.0):
                if stiff_error:
                    raise _Stiff
                raise IntegrationError(f"step size underflow near angle {t:.6f} rad (state "
                                       "not finite or tolerance unreachable)")
    return y, ends, h


def _replay(model, seg, y, stepper, rtol, atol, ends, run, record, slack):
    t = seg.start
    run.atol = atol
    n_trace = len(run.trace_theta)
    k1 = model.rhs(t, y, seg)
    run.n_rhs += 1
    for t_next in ends:
        y_new, k1, err = stepper(model, seg, t, y, t_next - t, k1, run)
        if not _err_norm(err, y, y_new, rtol, atol) <= slack:
            del run.trace_theta[n_trace:], run.trace_y[n_trace:]
            return False, None, None
        y, t = y_new, t_next
        if record:
            run.trace_theta.append(t)
            run.trace_y.append(y[0].copy())
    return True, y, list(ends)


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
    if record:
        for t, yy in zip(sol.t[1:], sol.y.T[1:], strict=True):
            run.trace_theta.append(t)
            run.trace_y.append(yy.reshape(B, S)[0].copy())
    return sol.y[:, -1].reshape(B, S), list(sol.t[1:])
