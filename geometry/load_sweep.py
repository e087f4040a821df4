"""Section loads swept along the rotors at fourth order, split where they jump.

The 3D load of a chamber is ``int_0^wrap f(phi - theta) W(theta) d theta`` (:meth:`.Sweep
.hat_kernel`: theta = twist(z), W = scale^power / twist') of its section load f, tabulated
on a uniform grid of angle.  Integrated as the linear interpolant of the nodes, that errs
by O(h^2) where f is smooth and by O(h) in every cell where f jumps; a twin-screw
section's loads jump where its sealing changes hands (a tip passing a cusp, a contact
crossing the cusp line, a band), at angles between the nodes.  Here:

* away from the jumps, f is the local cubic through the four nearest nodes (the cardinal
  cubic of every cell, integrated against W once: a convolution kernel, as the hat's);
* in the cells next to a jump (:class:`LoadEvents`), f is, on either side of it, the
  cubic through the nearest trusted data of that side only (its nodes, and samples the
  family cut between close events), and the difference from the kernel's cubic is
  integrated with Gauss nodes on the pieces, against W, for every output angle.

Both parts are linear in the node values and the same for chambers a lobe period apart
(the family gives every event and sample in every period), so the loads of all chambers
at uniform pressure still sum exactly as their sections do (to zero).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Gauss-Legendre nodes per cell (or piece of a cell): the pieces are cubics and W is
#: smooth and the cells short, so four integrate them to rounding (as hat_kernel's).
GAUSS_NODES = 4
#: Data points of a piece's local polynomial (a cubic: fourth order).
STENCIL = 4
#: Zero nodes either side of the table (the chamber is not there) beyond the shadows:
#: a stencil near the table's ends sees the same data as one a lobe period inside it.
PAD = STENCIL + 2
#: A node this close to an event (per step) is on it: it shows one side or neither.
ON_EVENT = 1e-6


@dataclass(frozen=True)
class LoadEvents:
    """Where a section table's loads do not vary smoothly, in absolute angle (every
    occurrence over the table's span, a lobe period either side included).

    ``at`` (sorted): the angles where the loads jump or kink, among them the chamber's
    birth and death unless its loads vanish smoothly there (a piece reaching past the
    table's ends would carry its last nodes' polynomial beyond them).  ``before`` and
    ``after``: per event, the angles before and after it over which the table's nodes are
    not trusted (the section resolves the event only to a lens of its polygons: its
    nodes there may show either side).  ``sample_psi`` (sorted) with ``sample_force``
    (k, rotors, 2) and ``sample_torque`` (k, rotors): the loads at further angles, cut
    where two events leave no trusted node between them."""

    at: np.ndarray
    before: np.ndarray
    after: np.ndarray
    sample_psi: np.ndarray
    sample_force: np.ndarray
    sample_torque: np.ndarray
    #: The data a piece's polynomial goes through lie at least this far apart (rad): on a
    #: fine grid the nearest nodes to a shadow would carry the polynomial across it from
    #: a span as narrow as the lens's own features next to the shadow.
    spread: float = 0.0


def cardinal_cubic(x):
    """The node-0 weight of the four-point cubic of each cell (cells [k, k + 1] in units
    of the step, through nodes k - 1 .. k + 2): zero beyond two steps."""
    ax = np.abs(np.asarray(x, dtype=float))
    out = np.zeros_like(ax)
    near, far = ax <= 1.0, (ax > 1.0) & (ax < 2.0)
    t = ax[near]
    out[near] = 0.5 * (t + 1.0) * (t - 1.0) * (t - 2.0)
    t = ax[far]
    out[far] = -(t - 1.0) * (t - 2.0) * (t - 3.0) / 6.0
    return out


def _weight(sweep, theta, power: int):
    z = sweep.z_of_twist(theta)
    return sweep.scale(z) ** power / sweep.dtwist(z)


def cubic_kernel(sweep, h: float, power: int) -> np.ndarray:
    """K[i], i = m + 1 for node offsets m = -1 .. M + 2: the sweep integral of f tabulated
    every ``h`` and read as the cubic of each cell is ``sum_m K[m] f[j - m]`` at phi_j
    (the cubic analogue of :meth:`.Sweep.hat_kernel`; cells split at the wrap)."""
    x, w = np.polynomial.legendre.leggauss(GAUSS_NODES)
    cells = int(math.ceil(sweep.wrap / h))
    a = h * np.arange(cells)
    b = np.minimum(a + h, sweep.wrap)
    theta = 0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * x[None, :]
    ww = 0.5 * (b - a)[:, None] * w[None, :] * _weight(sweep, theta, power)
    kernel = np.zeros(cells + 3)
    for offset in (-1, 0, 1, 2):  # cell c's cubic goes through nodes c - 1 .. c + 2
        m = np.arange(cells) + offset
        kernel[m + 1] += np.sum(cardinal_cubic(theta / h - m[:, None]) * ww, axis=1)
    return kernel


def sweep_loads(psi: np.ndarray, values: np.ndarray, sweep, powers, n_out: int,
                events: LoadEvents | None = None, samples: np.ndarray | None = None
                ) -> np.ndarray:
    """The sweep integral of section loads ``values`` ((n, c) on the uniform grid
    ``psi``, column k weighted by scale^powers[k]; ``samples``: (s, c), the same loads at
    ``events.sample_psi``) at phi_j = psi[0] + j h, j < n_out (module docstring)."""
    h = psi[1] - psi[0]
    powers = np.broadcast_to(np.asarray(powers, dtype=int), (values.shape[1],))
    out = np.zeros((n_out, values.shape[1]))
    if sweep.wrap == 0.0:  # every section alike: no sweep, no events
        z, wz = sweep.nodes()
        for c, power in enumerate(powers):
            out[:min(n_out, len(psi)), c] = (values[:n_out, c]
                                             * float(np.sum(wz * sweep.scale(z) ** power)))
        return out
    kernels = {int(p): cubic_kernel(sweep, h, int(p)) for p in set(powers.tolist())}
    for c, power in enumerate(powers):
        full = _convolve(values[:, c], kernels[int(power)])  # [t] = sum_m K[m] f[t - 1 - m]
        got = full[1:1 + n_out]
        out[:len(got), c] = got
    if events is not None and len(events.at):
        extra = np.zeros((0, values.shape[1])) if samples is None else np.asarray(samples)
        out += _corrections(psi, values, sweep, powers, n_out, events,
                            extra.reshape(len(extra), values.shape[1]))
    return out


def _corrections(psi, flat, sweep, powers, n_out, ev: LoadEvents, svals) -> np.ndarray:
    """The event-aware pieces less the kernel's cubics, in the cells next to events."""
    h = psi[1] - psi[0]
    n = len(psi)
    # The table padded with the zero nodes beyond its ends (index k <-> node k - pad),
    # far enough that the pieces next to the ends are all zero data, as they are.
    shadow = max(float(np.max(ev.before, initial=0.0)), float(np.max(ev.after, initial=0.0)))
    pad = PAD + int(math.ceil(shadow / h))
    grid = psi[0] + h * np.arange(-pad, n + pad)
    data = np.concatenate([np.zeros((pad, flat.shape[1])), flat,
                           np.zeros((pad, flat.shape[1]))])
    at = np.asarray(ev.at, dtype=float)
    tol = ON_EVENT * h
    trusted = np.ones(len(grid), bool)
    for e, lo, hi in zip(at, ev.before, ev.after, strict=True):
        trusted &= ~((grid >= e - lo - tol) & (grid <= e + hi + tol))
    piece_of_node = np.searchsorted(at, grid, side="right")
    samples = np.asarray(ev.sample_psi, dtype=float)
    piece_of_sample = np.searchsorted(at, samples, side="right")
    # a spread no wider than the step binds nothing: the nodes lie a step apart
    spread = ev.spread if ev.spread > h * (1.0 + 1e-9) else 0.0
    # Dirty cells: the kernel's stencil (nodes k - 1 .. k + 2 of cell [k, k + 1]) holds
    # an untrusted node or spans an event.
    k = np.arange(1, len(grid) - 2)
    bad = ~trusted
    dirty = bad[k - 1] | bad[k] | bad[k + 1] | bad[k + 2]
    lo_i = np.searchsorted(at, grid[k - 1] - tol, side="left")
    hi_i = np.searchsorted(at, grid[k + 2] + tol, side="right")
    dirty |= hi_i > lo_i
    gx, gw = np.polynomial.legendre.leggauss(GAUSS_NODES)
    phi = psi[0] + h * np.arange(n_out)
    out = np.zeros((n_out, flat.shape[1]))
    kinds = [(int(p), powers == p) for p in set(powers.tolist())]

    def add(rows, theta, d):
        for power, cols in kinds:
            out[rows, cols] += _weight(sweep, theta, power) @ d[:, cols]

    for cell in k[dirty]:
        a, b = grid[cell], grid[cell + 1]
        stencil = np.arange(cell - 1, cell + 3)
        cuts = np.concatenate([[a], at[(at > a + tol) & (at < b - tol)], [b]])
        for s0, s1 in zip(cuts[:-1], cuts[1:], strict=True):
            p = int(np.searchsorted(at, 0.5 * (s0 + s1), side="right"))
            xs, ys = _piece_data(grid, data, trusted & (piece_of_node == p), samples,
                                 svals, piece_of_sample == p, 0.5 * (s0 + s1), spread)
            if not len(xs):
                continue  # no data on this side (the family gives samples): keep the kernel's

            def diff(t, xs=xs, ys=ys, stencil=stencil):
                return _poly(xs, ys, t) - _poly(grid[stencil], data[stencil], t)

            # Outputs phi_j with the piece inside [phi_j - wrap, phi_j] take it whole;
            # the one or two whose wrap ends inside it take the part beyond that end.
            t = 0.5 * (s0 + s1) + 0.5 * (s1 - s0) * gx
            d = diff(t) * (0.5 * (s1 - s0) * gw)[:, None]
            j0 = max(int(math.ceil((s1 - psi[0]) / h - ON_EVENT)), 0)
            j1 = min(int(math.floor((s0 + sweep.wrap - psi[0]) / h + ON_EVENT)), n_out - 1)
            if j1 >= j0:
                add(slice(j0, j1 + 1), phi[j0:j1 + 1, None] - t[None, :], d)
            for j in range(max(j1 + 1, 0), min(int(math.ceil((s1 + sweep.wrap - psi[0]) / h)),
                                               n_out)):
                start = phi[j] - sweep.wrap
                if not s0 < start < s1:
                    continue
                u = 0.5 * (start + s1) + 0.5 * (s1 - start) * gx
                part = diff(u) * (0.5 * (s1 - start) * gw)[:, None]
                add(slice(j, j + 1), (phi[j] - u)[None, :], part)
    return out


def _piece_data(grid, data, nodes, samples, svals, in_piece, mid, spread=0.0):
    """(angles, values) of the STENCIL data points of one piece nearest ``mid``: its
    samples (cut where it has too few nodes) and its nodes, no two of those nearer than
    ``spread`` (the nearest first)."""
    xs = np.concatenate([samples[in_piece], grid[nodes]])
    ys = np.concatenate([svals[in_piece], data[nodes]])
    order = np.argsort(np.abs(xs - mid), kind="stable")
    if spread > 0.0:
        cut = int(np.count_nonzero(in_piece))
        kept = []
        for i in order:
            if i < cut or all(k < cut or abs(xs[i] - xs[k]) >= spread * (1.0 - 1e-9)
                              for k in kept):
                kept.append(i)
                if len(kept) == STENCIL:
                    break
        order = np.array(kept, dtype=int)
    order = order[:STENCIL]
    return xs[order], ys[order]


def _poly(xs, ys, t):
    """The polynomial through (xs, ys) (rows) at t, by Lagrange's formula."""
    w = np.ones((len(t), len(xs)))
    with np.errstate(divide="ignore", invalid="ignore"):
        for m in range(len(xs)):
            factor = (t[:, None] - xs[m]) / (xs[None, :] - xs[m])
            factor[:, m] = 1.0
            w *= factor
    return w @ ys


def _convolve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Full linear convolution by FFT (numpy's own: scipy.signal's import alone costs
    half a second of every command)."""
    n = a.size + b.size - 1
    size = 1 << (n - 1).bit_length()
    return np.fft.irfft(np.fft.rfft(a, size) * np.fft.rfft(b, size), size)[:n]

