"""An asymmetric rack: a circular leading flank and a straight trailing flank.

One pitch of the rack along +b (rack frame of :mod:`.meshing`):

* "trailing flank": the straight line tangent to the female tip circle of the previous
  pitch and to the male tip circle (the internal common tangent of the two);
* "male tip": centre (h_m - R_t, 0), radius R_t;
* "female tip": centre (0, b_f) on the pitch line, radius h_f, tangent to the male tip
  circle (so the leading flank is the circular S of :mod:`.circular`).

The straight flank generates involute flanks on both rotors, the circles the rounded
leading side: the lobe is no longer symmetric about its axis, which is what asymmetric
profiles do to shrink the blow-hole on one side.  This is a rack of this module's own
making, not a published profile: seed 004 gives only the 4/6 machine's diameters, lobe
counts, wraps and length (its Table 1a), no arcs, and seed 003 gives no asymmetric
compressor rack.  It exercises the generation with a line next to circles.
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError

from .arcs import CircleArc, Line
from .meshing import Gearing
from .profiles import TwinProfile, rack_pair

#: The two circles must stand apart by more than 1e-6 of their radii for the straight
#: flank to exist as a line: closer, it shrinks to a point and the rack is the symmetric
#: circular one (use :mod:`.circular`).
MIN_APART = 1e-6


def _internal_tangent(ca, ra, cb, rb):
    """Points on circles A and B of their internal common tangent with A on its left
    and B on its right, running from B to A with increasing b (None if the circles
    overlap, so no such line exists)."""
    d = ca - cb
    length = float(np.linalg.norm(d))
    if length <= (ra + rb) * (1.0 + MIN_APART):
        return None
    gamma = math.acos((ra + rb) / length)
    base = math.atan2(d[1], d[0])
    for ang in (base + gamma, base - gamma):
        n = np.array([math.cos(ang), math.sin(ang)])  # n . x = c; A at +ra, B at -rb
        ta, tb = ca - ra * n, cb + rb * n
        e = ta - tb
        left = np.array([-e[1], e[0]])
        if e[1] > 0.0 and np.dot(ca - ta, left) > 0.0:
            return ta, tb
    return None


def asymmetric_rack(gearing: Gearing, male_addendum: float, female_addendum: float,
                    tip_radius: float) -> tuple:
    """One pitch of the asymmetric rack, ordered along +b."""
    p = gearing.pitch
    a_tip = male_addendum - tip_radius
    if not (female_addendum > 0.0 and 0.0 < tip_radius and a_tip < 0.0):
        raise CaseError("rack arc 'male tip': the asymmetric rack needs a positive female "
                        "addendum and a tip radius larger than the male addendum")
    reach = tip_radius + female_addendum
    b_f = math.sqrt(reach * reach - a_tip * a_tip)
    ca, cf = np.array([a_tip, 0.0]), np.array([0.0, b_f])
    touch = _internal_tangent(ca, tip_radius, cf - [0.0, p], female_addendum)
    if touch is None:
        raise CaseError(f"rack arc 'trailing flank': the male tip circle (radius "
                        f"{tip_radius * 1e3:.4g} mm) and the previous female tip circle "
                        f"overlap or touch, so no straight flank joins them")
    ta, tb = touch
    lead = math.atan2(cf[1] - ca[1], cf[0] - ca[0])
    trail = math.atan2(ta[1] - ca[1], ta[0] - ca[0])
    start = math.pi + lead
    end_dir = tb + [0.0, p] - cf
    end = start - (start - math.atan2(end_dir[1], end_dir[0])) % (2.0 * math.pi)
    return (Line("trailing flank", tuple(tb), tuple(ta)),
            CircleArc("male tip", tuple(ca), tip_radius, trail, lead),
            CircleArc("female tip", tuple(cf), female_addendum, start, end))


def asymmetric_pair(gearing: Gearing, male_addendum: float, female_addendum: float,
                    tip_radius: float) -> tuple[TwinProfile, TwinProfile]:
    """Male and female profiles of the asymmetric rack, checked."""
    return rack_pair(gearing, asymmetric_rack(gearing, male_addendum, female_addendum,
                                              tip_radius))
