"""Sharp corners of a clearance offset: where the offset pieces of a cornered profile cross.

A profile whose pieces meet at an angle (the trochoidal pump profile's tip corners: the
flank, the trace of the mate's corner, meets the tip arc turning by 135 deg) has two
normals at the corner.  Offset into the material on the corner's inside (a rotor
shrunk at a convex corner), the two pieces' offsets cross at a point 1 / sin(beta / 2)
clearances from the corner (beta the corner's interior angle), and the raw offset runs
on past it into a small loop: the profile offset by a clearance is the set of points
at that distance from the material's edge, and its corner is that crossing.  So each
piece's offset is cut at the crossing (its parameter range trimmed,
:class:`.offsets.OffsetProfile`'s ``trims``); every point kept is at exactly the
clearance from the base profile.

Offset the other way at a corner (a rotor grown at a convex corner, shrunk at a
concave one: the pin-cycloid male's root corners, 90 deg), the two offsets part; the
points at the clearance from the corner there are the circular arc of radius c about
it, from one piece's end normal to the next one's start normal, so the offset goes
round it (:func:`corner_cuts`'s arcs; a polygon through the two offsets' ends alone would
close the gap with a chord c cos(t / 2) from the corner, 0.71 c at 90 deg).
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError

from .planar import cross

#: A junction whose tangent turns by more than this (rad) is a corner (tangent joins
#: agree to ~1e-9, the pin-cycloid's and trochoidal's corners by degrees).  Below it the
#: raw offsets miss each other by at most c x CORNER_TURN (4 nm at 40 um), far below any
#: export tolerance, and the pieces are left whole.
CORNER_TURN = 1e-4
#: Newton's iterations for the crossing and the distance (per C) at which it stops.
NEWTON_ITERATIONS = 30
NEWTON_TOL = 1e-14
#: Local parameter just short of a piece's end (evaluating at 1 would be the next piece).
END = 1.0 - 1e-12


def joint_turn(profile, j: int) -> float:
    """Signed turn (rad, counter-clockwise positive) of the tangent from the end of the
    piece before ``j`` to the start of piece ``j``; NaN where either tangent vanishes."""
    n = profile.n
    a = profile.derivative(np.array([(j - 1) % n + END]))[0]
    b = profile.derivative(np.array([float(j)]))[0]
    if not (a.any() and b.any()):
        return math.nan
    return math.atan2(float(cross(a, b)), float(a @ b))


def _crossing(raw, i: int, j: int) -> tuple[float, float]:
    """Local parameters (a on piece i, b on piece j) where the untrimmed offsets of the
    piece i ending at a corner and the piece j starting there cross: the tangent lines'
    crossing, then Newton on q_i(a) = q_j(b)."""
    def q(u):
        return raw.point(np.array([u]))[0], raw.derivative(np.array([u]))[0]

    def solve(ta, tb, rhs):
        m = np.column_stack([ta, -tb])
        return np.linalg.solve(m, rhs)

    pa, da = q(i + END)
    pb, db = q(float(j))
    s, r = solve(da, db, pb - pa)
    a, b = END + s, r
    scale = float(np.linalg.norm(pa))
    for _ in range(NEWTON_ITERATIONS):
        a, b = min(max(a, 0.0), END), min(max(b, 0.0), END)
        pa, da = q(i + a)
        pb, db = q(j + b)
        gap = pa - pb
        if np.linalg.norm(gap) <= NEWTON_TOL * scale:
            break
        s, r = solve(da, db, -gap)
        a, b = a + s, b + r
    return a, b


def corner_cuts(raw):
    """(trims, arcs) of the untrimmed offset ``raw`` (an OffsetProfile) at the base's
    corners, each corner told once by its turn: trims, per piece the local parameter
    range (lo, hi) it keeps, each piece cut where it crosses its neighbour's offset;
    arcs, per piece the turn (rad) of the tangent at its start where the two offsets
    part there (the offset goes round that corner on the clearance's arc), else 0.
    Either None without such corners.  A CaseError names a clearance that consumes a
    whole piece, or offsets that do not cross at a corner."""
    base = raw.base
    n = base.n
    lo, hi = np.zeros(n), np.ones(n)
    arcs = np.zeros(n)
    for j in range(n):
        turn = joint_turn(base, j)
        if not abs(turn) > CORNER_TURN:  # (a vanishing tangent is no corner to cut)
            continue
        if raw.direction * turn > 0.0:
            arcs[j] = turn  # the offsets part here
            continue
        p = base.point(np.array([float(j)]))[0] * 1e3
        where = f"its corner at ({p[0]:.3f}, {p[1]:.3f}) mm, where the profile turns by " \
                f"{math.degrees(turn):.1f} deg"
        i = (j - 1) % n
        a, b = _crossing(raw, i, j)
        qa = raw.point(np.array([i + a]))[0]
        qb = raw.point(np.array([j + b]))[0]
        if not (0.0 < a < 1.0 and 0.0 < b < 1.0) or not np.allclose(qa, qb, rtol=0.0,
                                                                     atol=1e-9):
            raise CaseError(f"a clearance on the {base.name} rotor does not close at {where}:"
                            f" its offsets there do not cross; make it smaller")
        hi[i], lo[j] = a, b
    if np.any(lo >= hi):
        k = int(np.argmax(lo >= hi))
        raise CaseError(f"a clearance on the {base.name} rotor consumes the whole piece {k} "
                        f"of its profile between two corners; make it smaller")
    cut = np.any(lo > 0.0) or np.any(hi < 1.0)
    trims = tuple((float(x), float(y)) for x, y in zip(lo, hi, strict=True)) if cut else None
    return trims, (tuple(float(t) for t in arcs) if arcs.any() else None)
