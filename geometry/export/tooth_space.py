"""The tooth space a disc cutter makes: from a tip of the rotor's profile through its root
to the next tip (:mod:`.cutter`).

The root is the smallest radius of the lobe period centred on u = 0, the tips the
largest radii within a lobe period either side.  Where a root or a tip is an arc of one
radius about the rotor's axis (the trochoidal pump profile's tip and root arcs), the
root is the middle of the arc's parameter range (its middle on a circular piece) and
each tip the end of its arc next to the root: the corner where the space's flank begins.
"""

from __future__ import annotations

import numpy as np

#: Bisection steps (2^-60 of a bracket: machine precision).
BISECT = 60
#: Scan points per profile piece on which a tooth space's root and tips are bracketed
#: (a multiple of 2, so that the middles and ends of pieces are scan points).
SPACE_SCAN = 512
#: A scan point is the extremum itself when the radial slope there is below this share
#: of its neighbours' (rounding, at a symmetric profile's root or tip).
SPACE_SNAP = 1e-9
#: Radii within this share of a root's or tip's lie on its arc (a constant radius, to
#: rounding): the space's root is that arc's middle, its tips the arcs' ends.
SPACE_FLAT = 1e-12


def _radial_slope(curve, u):
    """p . p' (half the derivative of the squared radius)."""
    u = np.atleast_1d(np.asarray(u, dtype=float))
    return np.sum(curve.point(u) * curve.derivative(u), -1)


def _extremum(curve, u0: float, h: float) -> float:
    """The radius extremum bracketed by the scan point ``u0`` and its neighbours ``h``
    away: the scan point itself if the slope vanishes there to rounding (or changes sign
    across it, a corner), else the slope's root by bisection."""
    fa, f0, fb = _radial_slope(curve, [u0 - h, u0, u0 + h])
    if abs(f0) <= SPACE_SNAP * max(abs(fa), abs(fb)):
        return u0
    if np.sign(fa) != np.sign(f0):
        lo, hi, flo = u0 - h, u0, fa
    elif np.sign(f0) != np.sign(fb):
        lo, hi, flo = u0, u0 + h, f0
    else:
        return u0
    for _ in range(BISECT):
        mid = 0.5 * (lo + hi)
        fm = float(_radial_slope(curve, mid)[0])
        if np.sign(fm) == np.sign(flo):
            lo, flo = mid, fm
        else:
            hi = mid
    return 0.5 * (lo + hi)


def tooth_space(curve) -> tuple[float, float, float]:
    """(tip, root, tip): the parameters bounding the tooth space whose root is the
    smallest radius of the lobe period centred on u = 0, the tips the largest radii
    within a lobe period before and after it."""
    per = curve.n / curve.lobes
    h = 1.0 / SPACE_SCAN
    m = int(round(per * SPACE_SCAN))

    def scan(a):
        u = a + h * np.arange(m + 1)
        return u, np.linalg.norm(curve.point(u), axis=-1)

    u, r = scan(-0.5 * per)
    lo, hi = _flat(curve, u, r, int(np.argmin(r)), h)
    root = _extremum(curve, float(u[np.argmin(r)]), h) if lo == hi else 0.5 * (lo + hi)
    ub, rb = scan(root - per)
    ua, ra = scan(root)
    ib, ia = int(np.argmax(rb[1:-1])) + 1, int(np.argmax(ra[1:-1])) + 1
    # a tip that is an arc of the outer radius (the trochoidal profile's) bounds the
    # space at its end next to the root: the corner, where the space's flank begins
    before = _flat(curve, ub, rb, ib, h)[1]
    after = _flat(curve, ua, ra, ia, h)[0]
    before = _extremum(curve, float(ub[ib]), h) if before == ub[ib] else before
    after = _extremum(curve, float(ua[ia]), h) if after == ua[ia] else after
    return before, root, after


def _flat(curve, u, r, i: int, h: float) -> tuple[float, float]:
    """The ends of the arc of the extreme radius r[i] about scan point i (radii within
    SPACE_FLAT of it), each found to rounding between its last scan point and the next;
    (u[i], u[i]) where the extremum is a point."""
    def on(x):
        return abs(float(np.linalg.norm(curve.point(np.array([x]))[0])) - r[i]) \
            <= SPACE_FLAT * r[i]

    ends = []
    for step in (-1, 1):
        j = i
        while 0 <= j + step < len(u) and abs(r[j + step] - r[i]) <= SPACE_FLAT * r[i]:
            j += step
        if j == i:
            ends.append(float(u[i]))
            continue
        a, b = float(u[j]), float(u[j]) + step * h  # on, off the arc
        for _ in range(BISECT):
            mid = 0.5 * (a + b)
            a, b = (mid, b) if on(mid) else (a, mid)
        ends.append(a)
    return ends[0], ends[1]
