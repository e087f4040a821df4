"""Screw-pump profiles: N-N pairs of identical rotors, one tool cutting both (seed 003).

Vacuum and multiphase screw pumps run 1-1 rotors (multi-lobe N-N as an option, seed 003
Fig. 4) with one profile for both, on pitch circles of equal radius r = C / 2; each
rotor's outer radius R and root radius rho = C - R.  Two constructions (seed 003 Fig. 3
names the circular, trochoidal and involute profiles; it gives no dimensions):

* ``circular``: the symmetric circular rack (:mod:`.circular`) with equal addenda and
  equal circles (:func:`identical_tip_radius`): the rack is then point-symmetric about
  its pitch-line point between the circles, so the male and female it generates are one
  rotor.  Smooth throughout: small blow-hole, large carry-over (the seed's words).
* ``trochoidal`` (:func:`trochoidal_pair`): each lobe is a tip arc of radius R and a
  root arc of radius rho, each over half the lobe (w = pi / N), joined by flanks that
  are the traces of the mate's tip corners (:class:`.point_generated.PointTrace`).  The
  tip arc of one rotor runs on the root arc of the other through the mesh (both on the
  centre line, whose normal passes the pitch point); when the arcs part, each rotor's
  tip corner follows the mate's flank.  Each corner's trace (below) is a loop through
  rho and back to R on one ray; the flank is the half of it that lies under the tip arc
  (it cuts the lobe's neck: the lobes are mushroom-shaped), the other half falls in the
  mate's open groove.  Which half goes where is what the interference check decides:
  the other choices overlap by up to 1.3 mm.  Relative to the rotor, a mate's point at
  radius R traces, with both rotors at one speed, X(t) = C e^{-it} - R e^{-2it} (corner
  on the centre line at t = 0), so |X|^2 = C^2 + R^2 - 2 C R cos t: the trace runs from
  rho (t = 0) out to R at cos t_R = C / (2R) = r / R, where Im X = sin t (2 R cos t -
  C) = 0 -- it ends on the ray it started on.  The flank spans no angle, which is why
  tip and root arcs take half a lobe each.  Sharp tip corners: small carry-over, large
  blow-hole (the seed's words).  A clearance offset cuts the pieces' offsets where they
  cross at a corner (:mod:`..offset_corners`); no disc cutter can make the rotor, since
  its flanks run under its tip arcs (the tool cuts 7 mm into the tips).

* ``involute`` (:func:`involute_rack`): a rack of straight flanks joined by a tip and a
  root circle of one radius, tangent to both (rack generation, as seed 003 says of its
  involute profile).  Each straight flank generates on both rotors an involute of the
  base circle r cos(alpha), alpha the flank's inclination from the line of centres (the
  pressure angle); the circles round the tips and the roots.  The rack is symmetric
  about its flanks' midpoints on the pitch line, so male and female are one rotor.  The
  circles' radius fixes alpha, since the four pieces fill one pitch: up to the
  circular profile's radius (the flank shrinks to nothing) or, on a rack deeper than a
  quarter of its pitch (many lobes), to p / 4 (the flanks stand on the line of centres,
  alpha = 0); as the circles shrink to points alpha tends to atan(p / 4 h).  By default
  the circles are centred on the pitch line (radius = the addendum; cos alpha = 4 h /
  p, h the addendum and p the rack's pitch), as the circular profile's default centres
  its circle there.  Rounded tips like the circular's: the seed groups the two ("high
  carryover").
"""

from __future__ import annotations

import math

from rotorflow.errors import CaseError

from .arcs import CircleArc, Line
from .meshing import Gearing, OnRotor
from .point_generated import PointTrace, check_no_overlap
from .profiles import TwinProfile, check_no_loop, rack_pair


def identical_pair(gearing: Gearing, male_addendum: float, female_addendum: float) -> bool:
    """Equal lobe counts and outer diameters: a pair that can be one rotor twice."""
    return (gearing.lobes_male == gearing.lobes_female
            and abs(male_addendum - female_addendum) <= 1e-9 * gearing.centre_distance)


def check_identical(gearing: Gearing, male_addendum: float, female_addendum: float,
                    profile: str) -> None:
    """A pump profile needs equal lobe counts and equal outer diameters."""
    g = gearing
    if g.lobes_male != g.lobes_female:
        raise CaseError(f"the {profile} pump profile makes identical rotors: lobes_male and "
                        f"lobes_female must be equal, got {g.lobes_male}/{g.lobes_female}")
    if not identical_pair(g, male_addendum, female_addendum):
        raise CaseError(f"the {profile} pump profile makes identical rotors: "
                        f"male_diameter_mm and female_diameter_mm must be equal, got "
                        f"{2e3 * (g.r1 + male_addendum):.6g} and "
                        f"{2e3 * (g.r2 + female_addendum):.6g}")


def identical_tip_radius(gearing: Gearing, addendum: float) -> float:
    """The symmetric circular rack's male-tip radius for which male and female are one
    rotor: both circles of one radius, (H^2 + (p/2)^2) / (4 H), H = 2 x addendum."""
    h, half = 2.0 * addendum, 0.5 * gearing.pitch
    return (h * h + half * half) / (4.0 * h)


def trochoidal_pair(gearing: Gearing, outer_radius: float) -> tuple[TwinProfile, TwinProfile]:
    """Male and female of the trochoidal pump profile (module docstring), checked for
    loops and interference."""
    g, R = gearing, outer_radius
    c, n = g.centre_distance, g.lobes_male
    rho = c - R
    if not (g.r1 < R < c):
        raise CaseError(f"the trochoidal pump profile's outer radius {R * 1e3:.4g} mm must lie "
                        f"between the pitch radius {g.r1 * 1e3:.4g} mm and the centre "
                        f"distance {c * 1e3:.4g} mm (the root radius C - R is positive)")
    w = math.pi / n  # tip and root arcs: half a lobe each
    t_r = math.acos(g.r1 / R)  # turn from the centre line until a corner leaves the flank
    def corner(angle: float) -> tuple[float, float]:
        return (R * math.cos(angle), R * math.sin(angle))

    # Male frame, lobe 0: the tip arc centred on +x (facing the female at theta = 0).
    male = TwinProfile("male", (
        PointTrace("female tip corner", corner(math.pi + 0.5 * w), g, "female",
                   0.5 * w, 0.5 * w + t_r),
        OnRotor(CircleArc("tip", (0.0, 0.0), R, -0.5 * w, 0.5 * w), "male"),
        PointTrace("female tip corner", corner(math.pi - 0.5 * w), g, "female",
                   -0.5 * w - t_r, -0.5 * w),
        OnRotor(CircleArc("root", (0.0, 0.0), rho, 0.5 * w, 1.5 * w), "male"),
    ), n)
    # Female frame, lobe 0: the root arc centred on -x (facing the male's tip).
    female = TwinProfile("female", (
        PointTrace("male tip corner", corner(0.5 * w), g, "male", -0.5 * w + t_r, -0.5 * w),
        OnRotor(CircleArc("root", (0.0, 0.0), rho, math.pi - 0.5 * w, math.pi + 0.5 * w),
                "female"),
        PointTrace("male tip corner", corner(-0.5 * w), g, "male", 0.5 * w, 0.5 * w - t_r),
        OnRotor(CircleArc("tip", (0.0, 0.0), R, math.pi + 0.5 * w, math.pi + 1.5 * w),
                "female"),
    ), n)
    for profile in (male, female):
        check_no_loop(profile, c)
    check_no_overlap(male, female, g)
    return male, female


def involute_rack(gearing: Gearing, addendum: float, radius: float | None = None):
    """One pitch of the involute pump rack (module docstring), ordered along +b: the
    tip circle (centre a = h - rho), the falling flank, the root circle (a = rho - h),
    the rising flank; h the addendum of both rotors, rho the circles' radius (default
    h, or half the largest radius, :func:`largest_circle`, when h is not below it).
    The flank's angle alpha from the a axis solves p/2 cos(a) + 2 (rho - h) sin(a) =
    2 rho (the pieces fill half a pitch: p/2 - 2 h tan(a) = 2 rho (1 - sin a) / cos a),
    on the root phi + acos(2 rho / norm) (the other makes the flank run backwards)."""
    h, half = addendum, 0.5 * gearing.pitch
    largest, why = largest_circle(gearing, h)
    rho = (h if h < largest else 0.5 * largest) if radius is None else radius
    if not rho > 0.0:
        raise CaseError(f"tip_radius_mm = {rho * 1e3:.4g}: the involute pump rack's tip and "
                        f"root circles need a positive radius")
    if not rho < largest:
        raise CaseError(f"tip_radius_mm = {rho * 1e3:.4g} {why}: the involute pump rack's "
                        f"circles must be smaller than {largest * 1e3:.4g} mm")
    alpha = _flank_angle(gearing, h, rho)
    s, c = math.sin(alpha), math.cos(alpha)
    g = 0.5 * math.pi - alpha  # each circle's half span about its apex
    tip = CircleArc("tip circle", (h - rho, 0.0), rho, -g, g)
    root = CircleArc("root circle", (rho - h, half), rho, math.pi + g, math.pi - g)
    top, low = h - rho * (1.0 - s), rho * (1.0 - s) - h
    fall = Line("falling flank", (top, rho * c), (low, half - rho * c))
    rise = Line("rising flank", (low, half + rho * c), (top, 2.0 * half - rho * c))
    return tip, fall, root, rise


def circle_radius(gearing: Gearing, h: float, alpha: float) -> float:
    """The involute rack's circle radius for the flank angle ``alpha`` (rad): the pitch
    equation solved for rho, rho = (p/2 - 2 h tan a) cos a / (2 (1 - sin a)); a
    CaseError naming pressure_angle_deg outside the angles the rack admits."""
    half = 0.5 * gearing.pitch
    least = _flank_angle(gearing, h, largest_circle(gearing, h)[0])
    most = math.atan2(half, 2.0 * h)  # the circles shrunk to points
    if not least < alpha < most:
        raise CaseError(f"pressure_angle_deg = {math.degrees(alpha):.4g} is outside what the "
                        f"involute pump rack admits here: between {math.degrees(least):.4g} "
                        f"and {math.degrees(most):.4g} deg")
    return (half - 2.0 * h * math.tan(alpha)) * math.cos(alpha) / (2.0 * (1.0 - math.sin(alpha)))


def _flank_angle(gearing: Gearing, h: float, rho: float) -> float:
    """The flank's angle alpha from the a axis for circles of radius rho: the root
    phi + acos(2 rho / norm) of p/2 cos(a) + 2 (rho - h) sin(a) = 2 rho."""
    half, big = 0.5 * gearing.pitch, 2.0 * (rho - h)
    return math.atan2(big, half) + math.acos(min(1.0, 2.0 * rho / math.hypot(half, big)))


def largest_circle(gearing: Gearing, h: float) -> tuple[float, str]:
    """(the involute rack's largest circle radius, what a larger one does).  The two roots
    of the angle's equation meet at the circular profile's radius, where the flank has
    no length; on a rack deeper than a quarter of its pitch the working root reaches
    alpha = 0 first, at rho = p / 4 (always below the circular's: their difference is
    (2 h - p / 2)^2 / (8 h))."""
    if 4.0 * h > gearing.pitch:
        return 0.25 * gearing.pitch, "tips the flanks past the line of centres"
    return identical_tip_radius(gearing, h), "leaves no straight flank (the circular profile)"


def pressure_angle(rack) -> float:
    """The involute rack's flank angle from the line of centres (its pressure angle)."""
    return rack[1].inclination()


def involute_pair(gearing: Gearing, male_addendum: float, female_addendum: float,
                  tip_radius: float | None) -> tuple[TwinProfile, TwinProfile]:
    """Male and female of the involute pump profile (identical rotors), checked for
    undercuts, loops and interference."""
    check_identical(gearing, male_addendum, female_addendum, "involute")
    return rack_pair(gearing, involute_rack(gearing, male_addendum, tip_radius))
