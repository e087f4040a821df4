"""Lands: lobes whose tip is an arc on the bore (the screw pumps' trochoidal profile).

A land spans a finite polar angle at the outer radius; its corners are where the
grooves on either side meet the bore, and its middle stands for the lobe's tip (the
lobe's centre line on a symmetric lobe).  Found from the sampled profile alone, so any
profile with such an arc gets the same treatment.
"""

from __future__ import annotations

import math

import numpy as np

from ..planar import TWO_PI
from .boundaries import MALE, turning_rate
from .pair import TIP_SCAN
from .profiles import TwinProfile

#: A lobe whose profile stays within this (per C) of its outer radius over more than
#: LAND_SAMPLES scan samples has a land (an arc on its bore, the screw pumps' trochoidal
#: tip arc), not a tip point: its corners bound the grooves, its middle is the lobe's
#: tip.  1e-12 C is rounding of an analytic circle; a rounded tip leaves it at once.
LAND_TOL = 1e-12
LAND_SAMPLES = 4
#: Bisection steps for a land's corner (parameter halved each: 1e-16 of a piece).
CORNER_STEPS = 60


def find_land(profile: TwinProfile, c: float):
    """Lobe 0's land (:meth:`.TwinScrewPair._land`), or None.  The whole closed profile
    is scanned (a lobe's parameter range may begin on its neighbour's land) and the land
    nearest u = 0 taken as lobe 0's."""
    per = profile.n
    m = TIP_SCAN * len(profile.pieces) * profile.lobes
    h = per / m
    u = np.linspace(0.0, per, m, endpoint=False)
    r = np.linalg.norm(profile.point(u), axis=-1)
    top = float(r.max())
    on = r >= top - LAND_TOL * c
    if on.sum() <= LAND_SAMPLES * profile.lobes or on.all():
        return None
    # the longest run of samples on the land (it may wrap past u = 0)
    order = np.roll(np.arange(m), -int(np.argmin(on)))  # starts off the land
    edges = np.diff(np.concatenate([[0], on[order].astype(int), [0]]))
    starts, stops = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
    k = int(np.argmin(order[starts]))  # the land whose run starts nearest u = 0
    if stops[k] - starts[k] <= LAND_SAMPLES:
        return None
    first, last = u[order[starts[k]]], u[order[stops[k] - 1]]

    def radius(x: float) -> float:
        return float(np.linalg.norm(profile.point(np.array([x % per]))[0]))

    def corner(inside: float, outside: float) -> float:
        for _ in range(CORNER_STEPS):
            mid = 0.5 * (inside + outside)
            if radius(mid) >= top - LAND_TOL * c:
                inside = mid
            else:
                outside = mid
        return inside % per

    ua, ub = corner(first, first - h), corner(last, last + h)
    pa, pb = profile.point(np.array([ua, ub]))
    ta, tb = math.atan2(pa[1], pa[0]), math.atan2(pb[1], pb[0])
    span = math.remainder(tb - ta, TWO_PI)
    if span < 0.0:  # (clockwise corner, counter-clockwise corner)
        ua, ub, ta, span = ub, ua, tb, -span
    # its middle by polar angle (monotone along a land on the bore), by bisection
    mid = ta + 0.5 * span
    lo, hi = ua, ub if ub > ua else ub + per
    for _ in range(CORNER_STEPS):
        x = 0.5 * (lo + hi)
        q = profile.point(np.array([x % per]))[0]
        if math.remainder(math.atan2(q[1], q[0]) - mid, TWO_PI) < 0.0:
            lo = x
        else:
            hi = x
    return 0.5 * (lo + hi) % per, top, (ua, ub)


def corner_seals(pair, parts, qs):
    """The land corners' sealing points (:meth:`.boundaries.Boundaries._snap_land`), for
    :func:`.section._seals`: (chamber, track name, kind, point, chamber beyond, rate).

    A land's corner is a sealing point whenever it bounds a part: the land's other
    corner need not (it may still be in the other bore), and on a one-lobe rotor both
    corners bound the one groove, in one life in the section.  Across the land lies the
    neighbouring groove one lobe period on in age: on a one-lobe rotor the groove's own
    next turn, one lead along the rotor (the land is a helical band between two turns
    of one channel), which the section cannot show (its land's far side is the same
    groove).  So beyond a leading corner is the chamber one period older, beyond a
    trailing one the chamber one period younger.  A groove runs from its lobe's
    counter-clockwise corner (odd index) to the next lobe's clockwise one (even): the
    male turns counter-clockwise, led by the even corner; the female clockwise, by the
    odd one."""
    out = []
    for p, q in zip(parts, qs, strict=True):
        for rotor, j, pt in p.corners:
            leading = (j % 2 == 0) if rotor == MALE else (j % 2 == 1)
            name = f"tip-{'male' if rotor == MALE else 'female'}-{'lead' if leading else 'trail'}"
            out.append((q, name, "tip", pt, q + (1 if leading else -1),
                        turning_rate(pair.gearing, rotor, pt)))
    return out
