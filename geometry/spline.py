"""Interpolating cubic splines (not-a-knot or periodic) in numpy alone.

Why not scipy.interpolate.CubicSpline: importing scipy.interpolate costs about 0.3 s
(it pulls in scipy.special and its array-API layer), more than the whole geometry of a
case takes to compute, and every ``rotorflow geometry`` process pays it. The splines here
are the textbook ones (second-derivative form, de Boor, "A Practical Guide to Splines",
ch. IV), checked against scipy's to round-off in tests/test_spline.py.

Values may carry trailing axes (``y`` of shape (n, ...)); evaluation at ``x`` of any shape
returns ``x.shape + y.shape[1:]``.
"""

from __future__ import annotations

import numpy as np

# Below this many knots the spline's system is solved densely: the reduced tridiagonal
# form of the not-a-knot ends needs at least two interior unknowns, and a 2-interval
# periodic spline's "cyclic tridiagonal" matrix is not tridiagonal at all.
DENSE_KNOTS = 5


class CubicSpline:
    """C2 cubic spline through (x[i], y[i]); ``bc_type`` "not-a-knot" or "periodic".

    ``extrapolate``: True (continue the end pieces), False (NaN outside [x0, x_end]) or
    "periodic" (wrap into the period; the default for periodic splines, as scipy's).
    """

    def __init__(self, x, y, bc_type: str = "not-a-knot", extrapolate=None):
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        if x.ndim != 1 or len(x) < 2 or len(y) != len(x):
            raise ValueError("a spline needs matching 1-D x and y of at least 2 points")
        h = np.diff(x)
        if not np.all(h > 0.0):
            raise ValueError("spline knots must increase strictly")
        if bc_type not in ("not-a-knot", "periodic"):
            raise ValueError(f"unknown spline end condition {bc_type!r}")
        if bc_type == "periodic" and not np.allclose(
                y[0], y[-1], rtol=0.0, atol=1e-12 * (np.abs(y).max() + 1e-300)):
            raise ValueError("a periodic spline needs y[0] == y[-1]")
        self.x, self.y, self.h = x, y, h
        self.periodic = bc_type == "periodic"
        self.extrapolate = ("periodic" if self.periodic else True) if extrapolate is None \
            else extrapolate
        self.m = _second_derivatives(x, y, h, self.periodic)

    def __call__(self, xq, nu: int = 0):
        x, y, h, m = self.x, self.y, self.h, self.m
        xq = np.asarray(xq, dtype=float)
        flat = xq.ravel()
        if self.extrapolate == "periodic":
            flat = x[0] + np.mod(flat - x[0], x[-1] - x[0])
        i = np.clip(np.searchsorted(x, flat, side="right") - 1, 0, len(x) - 2)
        trail = (slice(None),) + (None,) * (y.ndim - 1)
        t = (flat - x[i])[trail]
        hi = h[i][trail]
        m0, m1 = m[i], m[i + 1]
        b = (y[i + 1] - y[i]) / hi - hi * (2.0 * m0 + m1) / 6.0
        c3 = (m1 - m0) / (6.0 * hi)
        if nu == 0:
            out = y[i] + t * (b + t * (0.5 * m0 + t * c3))
        elif nu == 1:
            out = b + t * (m0 + 3.0 * t * c3)
        elif nu == 2:
            out = m0 + 6.0 * t * c3
        elif nu == 3:
            out = 6.0 * c3 + 0.0 * t
        else:
            raise ValueError(f"derivative order {nu} not available (0..3)")
        if self.extrapolate is False:
            outside = (flat < x[0]) | (flat > x[-1])
            out = np.where(outside[trail], np.nan, out)
        return out.reshape(xq.shape + y.shape[1:])

    def integrate(self, a: float, b: float):
        """The spline's integral from ``a`` to ``b``, both within the knots."""
        lo, hi = self.x[0], self.x[-1]
        if not (lo <= a <= hi and lo <= b <= hi):
            raise ValueError(f"integration bounds [{a}, {b}] outside the knots [{lo}, {hi}]")
        return _integral_to(self, b) - _integral_to(self, a)


def _integral_to(spline: CubicSpline, xq: float):
    """Integral of the spline from its first knot to ``xq`` (inside the knots)."""
    x, y, h, m = spline.x, spline.y, spline.h, spline.m
    hc = _col(h, y)
    whole = hc * 0.5 * (y[:-1] + y[1:]) - hc ** 3 * (m[:-1] + m[1:]) / 24.0
    cum = np.concatenate([np.zeros((1,) + y.shape[1:]), np.cumsum(whole, axis=0)])
    i = int(np.clip(np.searchsorted(x, xq, side="right") - 1, 0, len(x) - 2))
    t, hi = xq - x[i], h[i]
    m0, m1 = m[i], m[i + 1]
    b = (y[i + 1] - y[i]) / hi - hi * (2.0 * m0 + m1) / 6.0
    c3 = (m1 - m0) / (6.0 * hi)
    return cum[i] + t * (y[i] + t * (b / 2.0 + t * (m0 / 6.0 + t * c3 / 4.0)))


def _second_derivatives(x, y, h, periodic: bool) -> np.ndarray:
    """Knot second derivatives M from continuity of the slope (and the end conditions)."""
    n = len(x)
    d = np.diff(y, axis=0) / _col(h, y)
    if n == 2 and not periodic:
        return np.zeros_like(y)
    if n < DENSE_KNOTS:
        return _dense(h, d, periodic)
    if periodic:
        return _periodic(h, d)
    # Interior rows: h0 M0 + 2 (h0 + h1) M1 + h1 M2 = 6 (d1 - d0). Not-a-knot (third
    # derivative continuous at x1 and x_{n-2}) gives M0 and M_{n-1} from their neighbours;
    # substituting them leaves a tridiagonal system in M1..M_{n-2}.
    h0, h1, hb, ha = h[0], h[1], h[-1], h[-2]
    lower = np.concatenate([[0.0], h[1:-1]])
    diag = 2.0 * (h[:-1] + h[1:])
    upper = np.concatenate([h[1:-1], [0.0]])
    rhs = 6.0 * np.diff(d, axis=0)
    diag[0] = 2.0 * (h0 + h1) + h0 * (1.0 + h0 / h1)
    upper[0] = h1 - h0 * h0 / h1
    diag[-1] = 2.0 * (ha + hb) + hb * (1.0 + hb / ha)
    lower[-1] = ha - hb * hb / ha
    inner = _tridiagonal(lower, diag, upper, rhs)
    first = inner[0] + h0 / h1 * (inner[0] - inner[1])
    last = inner[-1] + hb / ha * (inner[-1] - inner[-2])
    return np.concatenate([first[None], inner, last[None]])


def _periodic(h, d) -> np.ndarray:
    """Cyclic system in M_0..M_{N-1} (M_N = M_0), solved by Sherman-Morrison: the corner
    entries h_{N-1} are one rank-one correction of a tridiagonal matrix."""
    hm = np.roll(h, 1)  # h_{k-1}, wrapping
    lower, upper = hm.copy(), h.copy()
    diag = 2.0 * (hm + h)
    rhs = 6.0 * (d - np.roll(d, 1, axis=0))
    corner = h[-1]  # A[0, N-1] = A[N-1, 0]
    gamma = -diag[0]
    lower[0] = upper[-1] = 0.0
    diag = diag.copy()
    diag[0] -= gamma
    diag[-1] -= corner * corner / gamma
    u = np.zeros(len(h))
    u[0], u[-1] = gamma, corner
    sol = _tridiagonal(lower, diag, upper, np.column_stack([rhs.reshape(len(h), -1), u]))
    x, z = sol[:, :-1], sol[:, -1:]
    factor = (x[0] + corner * x[-1] / gamma) / (1.0 + z[0] + corner * z[-1] / gamma)
    m = (x - z * factor).reshape(rhs.shape)
    return np.concatenate([m, m[:1]])


def _dense(h, d, periodic: bool) -> np.ndarray:
    """The full system for a few knots, where the banded forms do not apply."""
    n = len(h) + 1
    a = np.zeros((n, n))
    rhs = np.zeros((n,) + d.shape[1:])
    for k in range(1, n - 1):
        a[k, k - 1:k + 2] = h[k - 1], 2.0 * (h[k - 1] + h[k]), h[k]
        rhs[k] = 6.0 * (d[k] - d[k - 1])
    if periodic:
        # Slope continuity across the seam, and M_end = M_0.
        a[0, 0] = 2.0 * (h[0] + h[-1])
        a[0, 1] += h[0]
        a[0, n - 2] += h[-1]
        rhs[0] = 6.0 * (d[0] - d[-1])
        a[n - 1, 0], a[n - 1, n - 1] = 1.0, -1.0
    elif n == 3:
        # Not-a-knot with one interior knot: the single parabola through the 3 points.
        a[0, 0], a[0, 1] = 1.0, -1.0
        a[2, 1], a[2, 2] = 1.0, -1.0
    else:
        a[0, 0], a[0, 1], a[0, 2] = h[1], -(h[0] + h[1]), h[0]
        a[n - 1, n - 3], a[n - 1, n - 2], a[n - 1, n - 1] = h[-1], -(h[-2] + h[-1]), h[-2]
    return np.linalg.solve(a, rhs.reshape(n, -1)).reshape(rhs.shape)


def _tridiagonal(lower, diag, upper, rhs) -> np.ndarray:
    """Solve a diagonally dominant tridiagonal system by parallel cyclic reduction.

    Row i: lower[i] x[i-1] + diag[i] x[i] + upper[i] x[i+1] = rhs[i] (lower[0] and
    upper[-1] are 0). Each pass folds rows i -/+ s into row i, doubling s, so log2(n)
    vectorised passes replace the n-step Python loop of the Thomas algorithm (0.1 ms
    against 0.3 s at the 10^5 knots of an inner-rotor table). No pivoting: the spline's
    rows are diagonally dominant.
    """
    n = len(diag)
    a, b, c = lower.astype(float), diag.astype(float), upper.astype(float)
    r = np.array(rhs, dtype=float)
    shape = (-1,) + (1,) * (r.ndim - 1)
    s = 1
    while s < n:
        # Couplings below round-off against their diagonal are dropped, and the passes
        # stop once none is left: they shrink geometrically, so the spline's rows
        # decouple after a few passes of the log2(n) (10^5 knots: 39 ms against 91 ms).
        tiny = 1e-17 * np.abs(b)
        a = np.where(np.abs(a) <= tiny, 0.0, a)
        c = np.where(np.abs(c) <= tiny, 0.0, c)
        if not (a.any() or c.any()):
            break
        bm = np.concatenate([np.ones(s), b[:-s]])  # b[i - s]; rows outside are x = 0
        bp = np.concatenate([b[s:], np.ones(s)])
        am = np.concatenate([np.zeros(s), a[:-s]])
        ap = np.concatenate([a[s:], np.zeros(s)])
        cm = np.concatenate([np.zeros(s), c[:-s]])
        cp = np.concatenate([c[s:], np.zeros(s)])
        pad = np.zeros((s,) + r.shape[1:])
        rm = np.concatenate([pad, r[:-s]])
        rp = np.concatenate([r[s:], pad])
        alpha, gamma = -a / bm, -c / bp
        b = b + alpha * cm + gamma * ap
        r = r + alpha.reshape(shape) * rm + gamma.reshape(shape) * rp
        a, c = alpha * am, gamma * cp
        s *= 2
    return r / b.reshape(shape)
def _col(h, y):
    return h.reshape((-1,) + (1,) * (y.ndim - 1))
