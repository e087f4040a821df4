"""The one-sided asymmetric cycloid / pin-arc profile (SRM's early asymmetric profile).

What the profile is (the construction, as the sources below describe it):

* the female rotor lies entirely inside its pitch circle: its lands are arcs of the
  pitch circle (female outer radius = r2), its grooves are cut below it;
* one flank of each female groove is a circular "pin" arc whose centre lies on the
  female pitch circle; its radius r is the groove depth, so the female root radius is
  r2 - r and, the pin being its own conjugate when its centre passes the pitch point,
  the male lobe carries the same arc up to its tip at r1 + r (the male lies entirely
  outside its pitch circle, its root radius being r1);
* the other female flank is the curve the male tip point traces on the female (an
  epitrochoid), and the male flanks are the curves the two female corners (where the
  groove meets the pitch circle) trace on the male (epicycloids, cusp on the male pitch
  circle).

Replacing the second circular flank of the symmetric circular profile by a
point-generated one is what made the profile asymmetric: the male tip becomes a sharp
point on that side, which shortens the blow-hole there.

Sources.  Xing Ziwen, "Screw Compressors: Theory, Design and Application" (in Chinese),
China Machine Press, Beijing, 2000, the chapter on rotor profiles ("one-sided
asymmetric cycloid / pin-tooth arc profile"); N. Stosic, I. K. Smith, A. Kovacevic,
"Screw Compressors: Mathematical Modelling and Performance Calculation", Springer,
2005, chapter 2 (review of rotor profiles, the SRM asymmetric profile); N. Stosic et
al., "Geometry of screw compressor rotors and their tools", J. Zhejiang Univ. Sci. A
12(4), 2011, doi:10.1631/jzus.A1000393 (the same review).  The texts could not be
opened from this workspace when this module was written: the construction above is
stated from them as recalled, and their section, page and figure numbers are NOT given
here because they were not checked.  Do not cite a page from this docstring.

Dimensions.  The construction fixes everything but one length, the pin radius r (=
male addendum = female dedendum); the sources draw the profile but give r only in
their figures, so it is the caller's.  :func:`pin_cycloid_from_diameters` takes it, and
the centre distance, from two outer diameters: the female's is its pitch diameter, so
C = D2 (N1 + N2) / (2 N2) and r = D1 / 2 - r1.  For seed 004's Table 1a machine (4/6,
D1 = 100 mm, D2 = 96 mm) that is C = 80 mm and r = 18 mm: the seed's diameters are
exactly those of this construction at that centre distance (seed 004 does not say
which profile its machine had; this is the profile that fits them, not a claim that
it is theirs).

Orientation (a choice, not the sources'): the pin arc is on the male's flank that
faces -y at theta = 0, the trailing flank as the male turns counter-clockwise.  The
mirror image is the same pair turning the other way.
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError

from ..planar import TWO_PI
from .arcs import CircleArc
from .meshing import Gearing, OnRotor
from .point_generated import PointTrace, check_no_overlap
from .profiles import JOIN_TOL, TwinProfile, check_no_loop


def _corners(g: Gearing, r: float):
    """The pin arc's end angle beta (from its centre) and the male angles at which the
    two female corners pass the pitch point (theta_1 > 0, the pin-side corner D1;
    theta_d < 0, the trochoid-side corner D2) and at which the male tip reaches the
    female pitch circle (theta_t), with D1 and D2 in the female frame."""
    c, r1, r2 = g.centre_distance, g.r1, g.r2
    k = r1 / r2
    # D1: where the pin circle (centre on the pitch circle) crosses the pitch circle.
    beta = -math.acos(r / (2.0 * r2))
    d1 = np.array([-r2 + r * math.cos(beta), r * math.sin(beta)])
    delta1 = math.atan2(-d1[1], -d1[0])
    # D2: where the male tip (radius r1 + r) crosses the female pitch circle.
    tip = r1 + r
    theta_t = math.acos((tip * tip + c * c - r2 * r2) / (2.0 * c * tip))
    trace = PointTrace("tip", (tip, 0.0), g, "male", theta_t, theta_t)
    d2 = trace.eval(np.array([0.0]))[0]
    delta2 = math.pi - math.atan2(d2[1], d2[0])
    return beta, d1, d2, delta1 / k, -delta2 / k, theta_t, delta1 + delta2


def _check_chain(profile: TwinProfile, scale: float) -> None:
    """Each piece must start where the previous one ends (the last one at the next
    lobe's first): the construction guarantees it, so a gap is a bug worth naming."""
    per = len(profile.pieces)
    for i in range(per):
        end = profile.point(np.array([i + 1 - 1e-15]))[0]
        start = profile.point(np.array([(i + 1) % profile.n]))[0]
        gap = float(np.linalg.norm(end - start))
        if gap > JOIN_TOL * scale:
            raise CaseError(f"the {profile.pieces[i].name} ends {gap * 1e3:.4g} mm from "
                            f"the next arc")


def pin_cycloid_pair(gearing: Gearing, pin_radius: float) -> tuple[TwinProfile, TwinProfile]:
    """Male and female profiles of the cycloid / pin-arc profile with pin radius
    ``pin_radius`` (the groove depth), checked for gaps, loops and interference."""
    g, r = gearing, pin_radius
    r1, r2 = g.r1, g.r2
    if not 0.0 < r < r2:
        raise CaseError(f"pin radius {r * 1e3:.4g} mm: it must lie between 0 and the female "
                        f"pitch radius {r2 * 1e3:.4g} mm (it is the female groove depth)")
    beta, d1, d2, theta_1, theta_d, theta_t, groove = _corners(g, r)
    if not groove < TWO_PI / g.lobes_female:
        raise CaseError(f"pin radius {r * 1e3:.4g} mm is too large for {g.lobes_male}/"
                        f"{g.lobes_female} lobes: the female groove spans "
                        f"{math.degrees(groove):.2f} deg of the pitch circle, more than a "
                        f"female lobe ({360.0 / g.lobes_female:.2f} deg), so no land is left")
    male = TwinProfile("male", (
        OnRotor(CircleArc("male root", (0.0, 0.0), r1, -theta_d - TWO_PI / g.lobes_male,
                          -theta_1), "male", gearing=g),
        PointTrace("pin-side corner D1", tuple(d1), g, "female", theta_1, 0.0, cusp="start"),
        OnRotor(CircleArc("pin arc", (r1, 0.0), r, beta, 0.0), "male", gearing=g),
        PointTrace("trochoid-side corner D2", tuple(d2), g, "female", theta_t, theta_d,
                   cusp="end"),
    ), g.lobes_male)
    female = TwinProfile("female", (
        PointTrace("male tip", (r1 + r, 0.0), g, "male", theta_t, 0.0),
        OnRotor(CircleArc("pin arc", (-r2, 0.0), r, 0.0, beta), "female"),
        OnRotor(CircleArc("female land", (0.0, 0.0), r2, math.pi + theta_1 * r1 / r2,
                          math.pi + theta_d * r1 / r2 + TWO_PI / g.lobes_female), "female"),
    ), g.lobes_female)
    for profile in (male, female):
        _check_chain(profile, g.centre_distance)
        check_no_loop(profile, g.centre_distance)
    # profiles.check_no_interference signs its gaps by the curve normal at the foot
    # point, which is ambiguous at this profile's sharp corners: use polygons instead.
    check_no_overlap(male, female, g)
    return male, female


def pin_cycloid_from_diameters(lobes_male: int, lobes_female: int, male_diameter: float,
                               female_diameter: float):
    """(gearing, male, female) of the profile whose outer diameters are the given ones:
    the female's is its pitch diameter, the male's exceeds its pitch diameter by twice
    the pin radius."""
    if not (male_diameter > 0.0 and female_diameter > 0.0):
        raise CaseError(f"outer diameters must be positive, got {male_diameter} and "
                        f"{female_diameter}")
    centre = female_diameter * (lobes_male + lobes_female) / (2.0 * lobes_female)
    g = Gearing(centre, lobes_male, lobes_female)
    return (g, *pin_cycloid_pair(g, 0.5 * male_diameter - g.r1))
