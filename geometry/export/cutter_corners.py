"""Corners of a rotor profile inside a disc cutter's tooth space (:mod:`.cutter`).

At a piece boundary the profile's curve gives the next piece's slope.  Where the
profile turns there (the 4/6 pin-cycloid male: its flanks meet its root arc at right
angles, the cusps of the cycloids that the female's land corners trace), each flank's
end makes its own tool point, from its own slope.  A concave rotor corner is a convex
corner of the tool, and the two flanks' tool profiles run past each other there (a
swallowtail): the tool is the part under both, so each is cut at their crossing.
Without that the tool's point stood 10 um proud of the other flank's profile and cut
into it (the 4/6 pin-cycloid male's root; and its far tip, the tooth space's end, took
the next lobe's slope, so that no tool circle met it).
"""

from __future__ import annotations

import math

import numpy as np

#: A profile turning by more than this at a piece boundary has a corner there.
CORNER_DEG = 15.0
#: Parameter step from a piece boundary at which a flank's end slope is taken.
END_LIMIT = 1e-9
#: Tool points either side of a corner searched for the flanks' crossing.
CROSSING_REACH = 64


def corner_limits(prof, u, lo, hi):
    """(u, slopes): the tooth space's parameters ``u`` (sorted, from ``lo`` to ``hi``)
    with each corner inside it twice, the first entry its flank before, and the slopes
    d/du there (each end of the space from inside it: the ends are tip corners on some
    profiles).  Also the indices of the corners' first entries."""
    inner = np.arange(math.floor(lo) + 1, math.ceil(hi) + 1).astype(float)
    inner = inner[(inner > lo + END_LIMIT) & (inner < hi - END_LIMIT)]
    if len(inner):
        turn = turn_angles(prof.derivative(inner - END_LIMIT), prof.derivative(inner))
        inner = inner[np.abs(turn) > math.radians(CORNER_DEG)]
    u = np.sort(np.concatenate([u, inner]), kind="stable")
    first = np.searchsorted(u, inner, side="left")
    slopes = prof.derivative(u)
    before = np.concatenate([first, [len(u) - 1]])
    slopes[before] = prof.derivative(u[before] - END_LIMIT)
    slopes[0] = prof.derivative(np.array([lo + END_LIMIT]))[0]
    return u, slopes, first


def trim_swallowtails(first, *columns):
    """The tool profile's columns (h, R first, then any per-point arrays) with the two
    flanks' points at each corner (``first``, ``first + 1``) cut back to where their
    profiles cross; a corner whose flanks do not cross (a convex rotor corner, a gap)
    is left as it is."""
    h, R = columns[0], columns[1]
    drop = np.zeros(len(h), dtype=bool)
    out = [np.array(c, dtype=float, copy=True) for c in columns]
    for a in first:
        hit = _crossing(h, R, int(a))
        if hit is None:
            continue
        i, j, t = hit  # left segment (i - 1, i) at t, right segment (j, j + 1)
        for c, col in zip(out, columns, strict=True):
            c[a] = col[i - 1] + t * (col[i] - col[i - 1])
        drop[i:a] = True
        drop[a + 1:j + 1] = True
    return [c[~drop] for c in out]


def turn_angles(a, b):
    """The signed angles (radians) from each direction of ``a`` to the same row's of
    ``b``."""
    return np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], np.sum(a * b, -1))


def _crossing(h, R, a):
    """(i, j, t): the crossing nearest the corner of the flank before it (segments
    (i - 1, i), i <= a) and after it (segments (j, j + 1), j >= a + 1), t along the
    first; None if they do not cross within CROSSING_REACH points."""
    pts = np.column_stack([h, R])
    i = np.arange(a, max(a - CROSSING_REACH, 0), -1)
    j = np.arange(a + 1, min(a + 1 + CROSSING_REACH, len(h) - 1))
    if not len(i) or not len(j):
        return None
    p0, p1 = pts[i - 1][:, None], pts[i][:, None]
    q0, q1 = pts[j][None, :], pts[j + 1][None, :]
    r, s = p1 - p0, q1 - q0
    den = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    w = q0 - p0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * s[..., 1] - w[..., 1] * s[..., 0]) / den
        v = (w[..., 0] * r[..., 1] - w[..., 1] * r[..., 0]) / den
    ok = (den != 0.0) & (t >= 0.0) & (t <= 1.0) & (v >= 0.0) & (v <= 1.0)
    if not ok.any():
        return None
    ii, jj = np.nonzero(ok)
    k = int(np.argmin(ii + jj))  # the crossing fewest points from the corner
    return int(i[ii[k]]), int(j[jj[k]]), float(t[ii[k], jj[k]])
