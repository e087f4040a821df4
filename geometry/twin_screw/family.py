"""The twin-screw family's [machine] section: rack-generated pairs (seeds 003, 004).

[machine] keys (besides type and length_mm):

* ``profile``: "circular" (the symmetric circular rack, :mod:`.circular`),
  "line-circle" (an asymmetric rack of this project's own making, :mod:`.asymmetric`)
  or "pin-cycloid" (SRM's asymmetric pin-arc / cycloid profile, :mod:`.pin_cycloid`:
  the female lies inside its pitch circle, so female_diameter_mm is its pitch diameter
  and the male's addendum is the pin radius), or "trochoidal" (a screw-pump profile of
  identical rotors with sharp tip corners, :mod:`.pump_profiles`; equal lobe counts and
  diameters), or "involute" (the screw pumps' rack of straight flanks and tip and root
  circles, :mod:`.pump_profiles`; identical rotors likewise).  With equal lobe counts
  and diameters, "circular" makes identical rotors too (the screw pumps' circular
  profile, seed 003);
* ``lobes_male``, ``lobes_female``: any combination (3/5, 4/5, 4/6, 5/6, 5/7, ...);
* ``centre_distance_mm``: the pitch circles follow, r = C N / (N1 + N2);
* ``male_diameter_mm``, ``female_diameter_mm``: the outer diameters, which fix the
  rack's depth on each side of the pitch line;
* ``tip_radius_mm`` (optional): the rack's male-tip circle; by default the one that
  centres the female tip's circle on the pitch line (circular; for equal lobe counts
  and diameters the one of equal circles, whose rotors are identical) or 0.9 of it
  (line-circle, so that the straight flank exists); on the involute pump rack its tip
  and root circles' radius (default the addendum: both centred on the pitch line; half
  the largest radius the rack admits where the addendum is not below it), which sets
  the flanks' pressure angle;
* ``pressure_angle_deg`` (optional, involute only, instead of tip_radius_mm): the
  flanks' angle from the line of centres, which sets the circles' radius;
* ``blow_hole`` (optional): the surface that spans the blow-hole (:mod:`.blowhole`),
  "cusp-plane" (default) or "plane" (seed 004's plane through the contact line's end).
"""

from __future__ import annotations

import dataclasses
import math

from rotorflow.errors import CaseError

from ..family import Family, number, register
from .asymmetric import asymmetric_pair
from .circular import symmetric_circular_pair
from .meshing import Gearing
from .pair import TwinScrewPair
from .pin_cycloid import pin_cycloid_pair
from .pump_profiles import (
    check_identical,
    circle_radius,
    identical_pair,
    identical_tip_radius,
    involute_pair,
    trochoidal_pair,
)
from .tip_window import RACKS, remedy

KEYS = frozenset({"profile", "lobes_male", "lobes_female", "centre_distance_mm",
                  "male_diameter_mm", "female_diameter_mm", "tip_radius_mm",
                  "pressure_angle_deg", "blow_hole"})
#: How the blow-hole is spanned (:mod:`.blowhole`).
BLOW_HOLES = ("cusp-plane", "plane")
def _pin_cycloid(gearing: Gearing, male_addendum: float, female_addendum: float,
                 tip_radius: float | None):
    """SRM's asymmetric pin-arc / cycloid profile (:mod:`.pin_cycloid`): its female lies
    inside the pitch circle and its pin radius is the male's addendum."""
    if abs(female_addendum) > PITCH_TOL * gearing.centre_distance:
        g = gearing
        d2 = 2e3 * (g.r2 + female_addendum)
        c = d2 * (g.lobes_male + g.lobes_female) / (2 * g.lobes_female)
        # (12 digits: either remedy, copied as printed, lies within PITCH_TOL; 6 digits
        # left 82.2857 mm for a 5/7 pair 4e-7 C off, refused as "96 mm, not 96 mm")
        raise CaseError(f"the pin-cycloid female's outer diameter is its pitch diameter "
                        f"{2e3 * g.r2:.12g} mm, not {d2:.12g} mm: give female_diameter_mm = "
                        f"{2e3 * g.r2:.12g} or centre_distance_mm = {c:.12g}")
    if tip_radius is not None:
        raise CaseError("tip_radius_mm does not apply to the pin-cycloid profile (its pin "
                        "radius is the male addendum)")
    return pin_cycloid_pair(gearing, male_addendum)


def _trochoidal(gearing: Gearing, male_addendum: float, female_addendum: float,
                tip_radius: float | None):
    """The trochoidal screw-pump profile (:mod:`.pump_profiles`): identical rotors."""
    check_identical(gearing, male_addendum, female_addendum, "trochoidal")
    if tip_radius is not None:
        raise CaseError("tip_radius_mm does not apply to the trochoidal profile (its tips "
                        "are sharp corners)")
    return trochoidal_pair(gearing, gearing.r1 + male_addendum)


PROFILES = {"circular": symmetric_circular_pair, "line-circle": asymmetric_pair,
            "pin-cycloid": _pin_cycloid, "trochoidal": _trochoidal, "involute": involute_pair}
#: Profiles that take no rack tip circle (tip_radius_mm does not apply), or set their
#: own default for it (the involute's circles).
OWN_TIP_RADIUS = ("pin-cycloid", "trochoidal", "involute")
#: A female outer radius this close (per C) to the pitch radius is on it.
PITCH_TOL = 1e-9
#: The line-circle rack's default male-tip circle, per the centred one: 10 % smaller
#: leaves room for the straight flank between the circles.
LINE_CIRCLE_TIP = 0.9


def centred_tip_radius(gearing: Gearing, male_addendum: float, female_addendum: float):
    """The rack's male-tip radius that puts the female tip's circle centre on the pitch
    line (the circular rack's two circles then meet at the pitch line)."""
    half, h = 0.5 * gearing.pitch, male_addendum + female_addendum
    return (h * h + half * half) / (2.0 * h) - female_addendum


def build(profile: str, lobes_male: int, lobes_female: int, centre_distance: float,
          male_diameter: float, female_diameter: float,
          tip_radius: float | None = None,
          pressure_angle: float | None = None) -> TwinScrewPair:
    """A checked pair (SI lengths; ``pressure_angle`` in rad, the involute's only)."""
    if profile not in PROFILES:
        raise CaseError(f"unknown twin-screw profile {profile!r} "
                        f"(known: {', '.join(sorted(PROFILES))})")
    g = Gearing(centre_distance, lobes_male, lobes_female)
    hm = 0.5 * male_diameter - g.r1
    hf = 0.5 * female_diameter - g.r2
    if not hm > 0.0:
        raise CaseError(f"the male diameter {male_diameter * 1e3:.4g} mm is inside its pitch "
                        f"circle ({2e3 * g.r1:.4g} mm): the male has no addendum")
    if hf < -PITCH_TOL * centre_distance:
        raise CaseError(f"the female diameter {female_diameter * 1e3:.4g} mm is inside its "
                        f"pitch circle ({2e3 * g.r2:.4g} mm)")
    for name, root, diameter in (("female", g.r2 - hm, male_diameter),
                                 ("male", g.r1 - hf, female_diameter)):
        if not root > 0.0:
            other = "male" if name == "female" else "female"
            raise CaseError(f"the {other} diameter {diameter * 1e3:.4g} mm leaves the {name} "
                            f"no root (the {other} tips reach {-root * 1e3:.4g} mm past its "
                            f"axis): the centre distance {centre_distance * 1e3:.4g} mm is "
                            f"too small for these diameters")
    given = tip_radius is not None
    if pressure_angle is not None:
        if profile != "involute":
            raise CaseError(f"pressure_angle_deg applies to the involute profile only, not "
                            f"to the {profile} profile")
        if tip_radius is not None:
            raise CaseError("give tip_radius_mm or pressure_angle_deg, not both: each sets "
                            "the other on the involute rack")
        tip_radius = circle_radius(g, hm, pressure_angle)
    if tip_radius is None and profile not in OWN_TIP_RADIUS:
        tip_radius = centred_tip_radius(g, hm, hf)
        if profile == "line-circle":
            tip_radius *= LINE_CIRCLE_TIP
        elif identical_pair(g, hm, hf):
            # N-N with equal diameters: the rack whose male and female are one rotor
            tip_radius = identical_tip_radius(g, hm)
    try:
        male, female = PROFILES[profile](g, hm, hf, tip_radius)
    except CaseError as e:
        if pressure_angle is not None:
            # (an undercut names the circles: say what set them)
            raise CaseError(f"pressure_angle_deg = {math.degrees(pressure_angle):.4g} (tip "
                            f"and root circles of {tip_radius * 1e3:.4g} mm): {e}") from None
        if profile in RACKS and str(e).startswith(("undercut", "rack arc")):
            raise CaseError(f"{e}; {remedy(profile, g, hm, hf, tip_radius, given)}") from None
        raise
    return TwinScrewPair(g, male, female, profile)


def from_section(m: dict, where: str) -> TwinScrewPair:
    for key in ("lobes_male", "lobes_female", "centre_distance_mm", "male_diameter_mm",
                "female_diameter_mm"):
        if key not in m:
            raise CaseError(f"missing key '{key}' in {where}")
    n1 = number(m, "lobes_male", where, integer=True)
    n2 = number(m, "lobes_female", where, integer=True)
    if n1 < 1 or n2 < 1:
        raise CaseError(f"lobe counts must be positive in {where}, got {n1}/{n2}")
    c = number(m, "centre_distance_mm", where) * 1e-3
    if not c > 0.0:
        raise CaseError(f"centre_distance_mm must be positive in {where}")
    d1 = number(m, "male_diameter_mm", where) * 1e-3
    d2 = number(m, "female_diameter_mm", where) * 1e-3
    if not (d1 > 0.0 and d2 > 0.0):
        raise CaseError(f"the rotor diameters must be positive in {where}")
    if d1 / 2 + d2 / 2 <= c:
        raise CaseError(f"the bores do not meet in {where}: the outer radii "
                        f"({d1 * 500:.4g} + {d2 * 500:.4g} mm) must exceed the centre "
                        f"distance ({c * 1e3:.4g} mm)")
    tip = number(m, "tip_radius_mm", where) * 1e-3 if "tip_radius_mm" in m else None
    angle = (math.radians(number(m, "pressure_angle_deg", where))
             if "pressure_angle_deg" in m else None)
    hole = m.get("blow_hole", BLOW_HOLES[0])
    if hole not in BLOW_HOLES:
        raise CaseError(f"blow_hole = {hole!r} in {where} is not one of "
                        f"{', '.join(repr(b) for b in BLOW_HOLES)}")
    try:
        pair = build(m.get("profile", "circular"), n1, n2, c, d1, d2, tip, angle)
    except CaseError as e:
        raise CaseError(f"{e} ({where})") from None
    if hole == "plane" and pair.has_lands:
        # seed 004's plane runs through the contact line's end at a cusp; lands cover
        # the cusps, and the chambers meet in the flank pocket instead (.flank_pocket)
        raise CaseError(f"blow_hole = 'plane' in {where}: the {pair.label} profile's "
                        f"lands cover the cusps; its blow-hole is the cusp plane's")
    return dataclasses.replace(pair, blow_hole=hole)


def examples() -> dict[str, TwinScrewPair]:
    """Pairs for the family contract tests: seed 004's 4/6 machine size (male 100 mm,
    female 96 mm; the centre distance, not given there, assumed 78 mm) with the
    circular and the line-circle rack."""
    return {
        "circular-4-6": build("circular", 4, 6, 0.078, 0.100, 0.096),
        "line-circle-4-6": build("line-circle", 4, 6, 0.078, 0.100, 0.096),
    }


FAMILY = register(Family("twin-screw", KEYS, from_section, examples))
