"""Step control of one segment and the explicit Runge-Kutta step, written once for two
callers: :mod:`.integrate` runs them as Python with the model's right-hand side (and the
Rosenbrock step), :mod:`.compiled` compiles them with numba around the fused
right-hand side, so that a whole segment is one compiled call (issue 19: the Python
loop around a compiled right-hand side cost three quarters of the default point).

Every function here is plain numpy that numba also compiles: no Python objects, status
codes instead of exceptions, arrays grown by doubling instead of lists.  ``step(t, y, h,
k1, args)`` returns (y_new, f(t + h, y_new), error estimate); y is (B, S), one shared
step sequence for the whole batch.
"""

from __future__ import annotations

import numpy as np

# Status of a segment's integration
DONE, OVER_BUDGET, UNDERFLOW, REPLAY_MISSED = 0, 1, 2, 3
# Step-size controller: safety factor and the bounds of the change per step.
SAFETY, GROW_MAX, SHRINK_MIN = 0.9, 5.0, 0.2


def err_norm(err, y, y_new, rtol, atol):
    """The largest component error over the batch, scaled by the tolerances.

    The largest, not the RMS: an RMS over all slots and accumulators lets one chamber's
    pressure oscillate by 7-13 % of p_discharge at rtol 5e-4-1e-3 while the other
    components dilute its error (issue 19, nozzle ports near balance)."""
    sc = atol + rtol * np.maximum(np.abs(y), np.abs(y_new))
    m = np.max(np.abs(err / sc))
    return m if np.isfinite(m) else np.inf


def rk_step(rhs, args, c, A, b, e, t, y, h, k1):
    """One step of the explicit pair (c, A, b, e) from (t, y) with f(t, y) = k1 (FSAL):
    (y_new, f(t + h, y_new), error estimate).  Stages are rows of K (stages, B * S) so that
    each stage's combination is one matrix-vector product; the new state's derivative is
    the last row, from the same call of ``rhs`` (one call site: numba compiles the
    right-hand side once per site)."""
    s = c.size
    B, S = y.shape
    K = np.empty((s + 1, B * S))
    K[0] = k1.reshape(B * S)
    yf = np.ascontiguousarray(y).reshape(B * S)
    y_new = yf
    for i in range(1, s + 1):
        if i < s:
            yi, ti = yf + h * (np.ascontiguousarray(A[i, :i]) @ K[:i]), t + c[i] * h
        else:
            yi, ti = yf + h * (b @ K[:s]), t + h
            y_new = yi
        K[i] = np.ascontiguousarray(rhs(ti, yi.reshape(B, S), args)).reshape(B * S)
    return y_new.reshape(B, S), K[s].reshape(B, S).copy(), (h * (e @ K)).reshape(B, S)


def segment(step, args, t, t_end, replay, y, k1, h, rtol, atol, order, budget, slack,
            record):
    """Integrate from t to t_end: through the step ends ``replay`` where it has any, else
    choosing the steps.  Returns (status, t reached, y, h for the next segment, step
    ends, trace of y[0] at them (empty unless ``record``), steps tried, steps rejected);
    status OVER_BUDGET once ``budget`` steps were tried, UNDERFLOW when the step shrinks
    to nothing, REPLAY_MISSED where a replayed step's error exceeds ``slack`` times the
    tolerance (the caller then chooses its own steps).  One loop and one call of
    ``step`` for both: numba compiles the right-hand side once per call site."""
    replaying = replay.size > 0
    span = t_end - t
    if not replaying and not (h > 0.0 and np.isfinite(h)):
        # initial step: a small fraction of what the derivative scale allows
        d0 = np.max(np.abs(y) / (atol + rtol * np.abs(y)))
        d1 = np.max(np.abs(k1) / (atol + rtol * np.abs(y)))
        h = 0.01 * d0 / d1 if d1 > 0.0 else 0.01 * span
    if not replaying:
        h = min(h, span)
    ends = np.empty(max(replay.size, 16))
    trace = np.empty((ends.size if record else 0, y.shape[1]))
    n = tried = rejected = 0
    status = DONE
    while n < replay.size if replaying else t < t_end:
        if tried >= budget and not replaying:
            status = OVER_BUDGET
            break
        tried += 1
        last = n == replay.size - 1 if replaying else t + h >= t_end - 1e-12 * span
        t_next = replay[n] if replaying else (t_end if last else t + h)
        hh = t_next - t
        y_new, k_new, err = step(t, y, hh, k1, args)
        en = err_norm(err, y, y_new, rtol, atol)
        if replaying and not en <= slack:
            status = REPLAY_MISSED
            break
        if en <= 1.0 or replaying:
            t, y, k1 = t_next, y_new, k_new
            ends, trace = _grow(ends, trace, n, record)
            ends[n] = t
            if record:
                trace[n] = y[0]
            n += 1
            if not replaying:
                fac = GROW_MAX if en == 0.0 else min(GROW_MAX, SAFETY * en ** (-1.0 / order))
                h = max(h, hh) if last else hh * fac
        else:
            rejected += 1
            fac = SHRINK_MIN if not np.isfinite(en) else max(SHRINK_MIN,
                                                             SAFETY * en ** (-1.0 / order))
            h = hh * fac
            if h < 1e-14 * max(span, 1.0):
                status = UNDERFLOW
                break
    return status, t, y, h, ends[:n], trace[:n], tried, rejected


def _grow(ends, trace, n, record):
    """The buffers with room for entry n (doubled when full)."""
    if n < ends.size:
        return ends, trace
    more = np.empty(2 * ends.size)
    more[:n] = ends[:n]
    if record:
        bigger = np.empty((2 * ends.size, trace.shape[1]))
        bigger[:n] = trace[:n]
        trace = bigger
    return more, trace
