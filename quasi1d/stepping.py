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

import math

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


# Rosenbrock method of Shampine & Reichelt (MATLAB ode23s): L-stable, order 2 with a
# third-order error estimate, three right-hand sides and one Jacobian per step.
_D = 1.0 / (2.0 + math.sqrt(2.0))
_E32 = 6.0 + math.sqrt(2.0)
# finite-difference steps of the Jacobian (relative to the tolerance scale) and of df/dt
JAC_STEP = 1.0e-7
JAC_T_STEP = 1.0e-7


def ros23_step(rhs, args, t, y, h, F0, atol, cols):
    """One Rosenbrock step from (t, y) with f(t, y) = F0: (y_new, f(t + h, y_new), error
    estimate), an infinite error where a stage is not finite.  The formula is a W-method,
    so a Jacobian could serve several steps, but measured on nozzle-port cycles a stale
    one cost more steps and cycles than it saved: a fresh one every step.

    df/dy is non-zero in the columns ``cols`` only (the chamber states of the active
    slots; nothing depends on the accumulators or on idle slots), so W = I - h d J is
    inverted in that (nc, nc) block only: W k = R gives (I - h d J_cc) k_c = R_c and then
    k = R + h d J[:, c] k_c (rows c included)."""
    fail = (y, F0, np.full_like(y, np.inf))
    Jc, T = jacobian(rhs, args, t, y, F0, atol, cols)
    if not (np.all(np.isfinite(Jc)) and np.all(np.isfinite(T)) and np.all(np.isfinite(F0))):
        return fail
    hd = h * _D
    Wi = w_inverse(Jc, cols, hd)
    if not np.all(np.isfinite(Wi)):
        return fail
    hdT = hd * T
    k1 = _w_solve(Wi, Jc, cols, hd, F0 + hdT)
    F1 = rhs(t + 0.5 * h, y + 0.5 * h * k1, args)
    if not np.all(np.isfinite(F1)):
        return fail
    k2 = _w_solve(Wi, Jc, cols, hd, F1 - k1) + k1
    y_new = y + h * k2
    F2 = rhs(t + h, y_new, args)
    if not np.all(np.isfinite(F2)):
        return fail
    k3 = _w_solve(Wi, Jc, cols, hd, F2 - _E32 * (k2 - F1) - 2.0 * (k1 - F0) + hdT)
    return y_new, F2, (h / 6.0) * (k1 - 2.0 * k2 + k3)


def jacobian(rhs, args, t, y, f0, atol, cols):
    """The columns ``cols`` of df/dy (B, S, nc) and df/dt (B, S) of every batch member by
    finite differences, in two batched calls.  Each member gets its own Jacobian, so that
    a batch of perturbed states (the cycle solver's finite-difference Jacobian of the
    period map) sees the same method as an unperturbed one."""
    B, S = y.shape
    nc = cols.size
    delta = JAC_STEP * (np.abs(y[:, cols]) + atol[cols])  # (B, nc)
    Y = np.empty((B, nc, S))
    for j in range(nc):
        Y[:, j, :] = y
        Y[:, j, cols[j]] += delta[:, j]
    F = rhs(t, Y.reshape(B * nc, S), args).reshape(B, nc, S)
    ft = rhs(t + JAC_T_STEP, y, args)
    return np.transpose((F - f0[:, None, :]) / delta[:, :, None], (0, 2, 1)), \
        (ft - f0) / JAC_T_STEP


def _w_solve(Wi, Jc, cols, hd, R):
    return R + hd * batch_mv(Jc, batch_mv(Wi, R[:, cols]))


def batch_mv(A, x):
    """A[b] @ x[b] for every b (compiled: loops, :mod:`.compiled`)."""
    return np.einsum("bij,bj->bi", A, x)


def w_inverse(Jc, cols, hd):
    """(I - hd J_cc)^-1 of every batch member, NaN where singular (compiled: loops)."""
    try:
        return np.linalg.inv(np.eye(cols.size) - hd * Jc[:, cols, :])
    except np.linalg.LinAlgError:
        return np.full((Jc.shape[0], cols.size, cols.size), np.nan)


def segment(step, args, t, t_end, replay, y, k1, h, rtol, atol, order, budget, slack,
            record):
    """Integrate from t to t_end: through the step ends ``replay`` where it has any, else
    choosing the steps.  Returns (status, t reached, y, h for the next segment, step
    ends, trace of y[0] and f(t, y)[0] side by side at them (empty unless ``record``: the
    derivative, which every step has at its end, serves the dense traces), steps tried,
    steps rejected);
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
    S = y.shape[1]
    trace = np.empty((ends.size if record else 0, 2 * S))
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
                trace[n, :S] = y[0]
                trace[n, S:] = k1[0]
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
