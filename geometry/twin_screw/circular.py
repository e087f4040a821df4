"""The symmetric circular profile: a rack of circular arcs only.

One pitch of the rack is two circles that meet tangentially (an S-curve, so the rack is
smooth and every rack point meshes at one finite shift):

* "male tip": centre (h_m - R_t, 0), radius R_t, convex towards the female; its top at
  a = h_m is the male's outer radius r1 + h_m and the female's root radius r2 - h_m.
* "female tip": centre (R_f - h_f, p / 2), radius R_f, convex towards the male; its
  bottom at a = -h_f is the female's outer radius r2 + h_f and the male's root radius.

Tangency fixes R_t + R_f = (H^2 + (p/2)^2) / (2 H), H = h_m + h_f, so the rack has three
free dimensions (h_m, h_f, R_t) besides the pitch.  The profile is symmetric about each
lobe's axis (seeds 003 and 004 name the "symmetric circular" profile; neither gives its
dimensions, which are the caller's).
"""

from __future__ import annotations

import math

from rotorflow.errors import CaseError

from .arcs import CircleArc
from .meshing import Gearing
from .profiles import TwinProfile, rack_pair


def symmetric_circular_rack(gearing: Gearing, male_addendum: float, female_addendum: float,
                            tip_radius: float) -> tuple[CircleArc, CircleArc]:
    """One pitch of the symmetric circular rack, ordered along +b."""
    half = 0.5 * gearing.pitch
    h = male_addendum + female_addendum
    if not h > 0.0:
        raise CaseError(f"the rack's depth (male plus female addendum) must be positive, "
                        f"got {h * 1e3:.4g} mm")
    both = (h * h + half * half) / (2.0 * h)
    r_female = both - tip_radius
    if not 0.0 < tip_radius < both:
        raise CaseError(f"rack arc 'male tip': its radius {tip_radius * 1e3:.4g} mm must lie "
                        f"strictly between 0 and {both * 1e3:.4g} mm for the two rack circles "
                        f"to meet tangentially over one pitch (at {both * 1e3:.4g} mm the "
                        f"female tip circle vanishes)")
    a_tip = male_addendum - tip_radius
    a_root = r_female - female_addendum
    joint = math.atan2(half, a_root - a_tip)  # from the male tip's centre, off the a axis
    tip = CircleArc("male tip", (a_tip, 0.0), tip_radius, -joint, joint)
    root = CircleArc("female tip", (a_root, half), r_female, math.pi + joint, math.pi - joint)
    return tip, root


def symmetric_circular_pair(gearing: Gearing, male_addendum: float, female_addendum: float,
                            tip_radius: float) -> tuple[TwinProfile, TwinProfile]:
    """Male and female profiles of the symmetric circular rack, checked."""
    return rack_pair(gearing, symmetric_circular_rack(gearing, male_addendum,
                                                      female_addendum, tip_radius))
