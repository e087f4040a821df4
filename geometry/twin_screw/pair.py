"""A twin-screw rotor pair on the family seam (seeds 003, 004).

Frames (metres, radians): the male axis O1 at the origin, the female axis O2 at (C, 0)
(see :mod:`.meshing`); the male turns counter-clockwise by ``psi``, the female clockwise
by ``psi N1 / N2``; rotor 0, the reference, is the male.  Each rotor turns in its own
bore, of its outer radius (zero tip clearance: clearances are the leakage model's), and
the two bores intersect at the cusps (x_c, +-y_c).

What the seam asks of the pair is built here from :mod:`.regions` (the section cut into
groove parts) and :mod:`.section` (one chamber's tables over its life).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.optimize import minimize_scalar

from rotorflow.errors import CaseError

from .. import scalar
from ..family import Rotor, RotorPair
from ..planar import TWO_PI, rotate
from .contact_search import ContactSearch
from .meshing import Gearing
from .profiles import TwinProfile

#: Samples per lobe on which a lobe's tip (largest radius) is bracketed before it is
#: polished; a tip is narrower than a lobe by far more than 1/512.
TIP_SCAN = 512
#: Samples within this (per C) of the largest radius lie on an arc of that radius (a
#: land: the arc's rounding is ~1e-16 C, while the samples next to a smooth tip fall
#: below it by more than 1e-10 C, and a sharp one's by far more).
PLATEAU_TOL = 1e-12
#: Bisections of a land's clockwise end (from a sample's bracket to rounding).
PLATEAU_STEPS = 60
#: Male angles over one lobe period at which the contact line's length is figured.
CONTACT_LINE_SAMPLES = 24


@dataclass(frozen=True)
class TwinScrewPair(ContactSearch, RotorPair):
    """Male and female profiles of one gearing, with their bores."""

    family = "twin-screw"
    #: The section's loads are exact per section (snapped ends, no square-root kinks
    #: like the internal gear's fillet contacts) and a section costs a Boolean cut; the
    #: power balance of the loads' linear interpolant converges at second order and
    #: twice the curves' grid puts it at 2e-5 for the 4/6 examples (1e-4 at 1x).
    section_refinement = 2
    #: The table's port areas are the face sections inside the ports (summary.py).
    port_areas = True
    radial_ports = True
    #: The section table runs from the zero node before the birth to the one after the
    #: death (found by cutting sections on its grid).
    life_on_nodes = False
    #: Two rotors on parallel axes in cylindrical bores: no conical sweep (its section's
    #: scale would shrink the centre distance along z, and its loads were left null).
    conical_sweep = False

    gearing: Gearing
    male: TwinProfile
    female: TwinProfile
    label: str = "twin-screw"
    #: How the blow-hole is spanned (:mod:`.blowhole`): "cusp-plane" or "plane".
    blow_hole: str = "cusp-plane"

    def __post_init__(self):
        if self.male.lobes != self.gearing.lobes_male or \
                self.female.lobes != self.gearing.lobes_female:
            raise CaseError("the profiles' lobe counts differ from the gearing's")
        if self.male_radius + self.female_radius <= self.gearing.centre_distance:
            raise CaseError("the bores do not intersect: the rotors never mesh")

    # ------------------------------------------------------------ dimensions
    @property
    def diameter(self) -> float:
        """The male's outer diameter (the family's figures are normalised by it)."""
        return 2.0 * self.male_radius

    @cached_property
    def male_radius(self) -> float:
        return self._tip(self.male)[1]

    @cached_property
    def female_radius(self) -> float:
        return self._tip(self.female)[1]

    @cached_property
    def cusp(self) -> tuple[float, float]:
        c, r1, r2 = self.gearing.centre_distance, self.male_radius, self.female_radius
        x = (c * c + r1 * r1 - r2 * r2) / (2.0 * c)
        return x, math.sqrt(r1 * r1 - x * x)

    def _tip(self, profile: TwinProfile) -> tuple[float, float]:
        """(u, radius) of lobe 0's tip: its largest radius, polished (a land's middle;
        an arc of the largest radius that is no land, its clockwise end: :meth:`_top`)."""
        land = self._land(profile)
        if land is not None:
            return land[0], land[1]
        top = self._top(profile)
        if top is not None:
            return top[0], top[2]
        per = len(profile.pieces)
        u = np.linspace(0.0, per, TIP_SCAN * per, endpoint=False)
        r = np.linalg.norm(profile.point(u), axis=-1)
        k = int(np.argmax(r))
        h = per / (TIP_SCAN * per)
        res = minimize_scalar(lambda x: -float(np.linalg.norm(profile.point(np.array([x]))[0])),
                              bounds=(u[k] - h, u[k] + h), method="bounded",
                              options={"xatol": 1e-13})
        return float(res.x), -float(res.fun)

    def _top(self, profile: TwinProfile):
        """(u of its clockwise end, u of its counter-clockwise end, radius) of lobe 0's
        arc of the largest radius, or None where the largest radius is a point (a tip).

        On such an arc (the pin-cycloid female's land, on its pitch circle) every point
        is a largest one, and rounding picked any of its samples for the tip: the land's
        pin-side corner (u 2.009 on the seed-004 4/6, where its figures were checked) or
        its trochoid-side one, a land's width away (u 2.999 with a male diameter of 101
        or 102.4 mm, on the 5/6 and the 3/5).  The tip point sets the grooves' sectors
        (:mod:`.ages`: at the trochoid-side corner a pocket straddled the ray and its
        female part was booked a chamber older), where the tips cross the cusps (the
        blow-hole's slots: none was booked) and the tip lines.  So the tip is the arc's
        clockwise end, the first in u (the pin-side corner), and the arc's other end
        is kept for telling which lobe a groove's corner on it belongs to
        (:attr:`tip_spans`).  Both ends by bisection from the samples' brackets."""
        return self._tops[0 if profile is self.male else 1]

    @cached_property
    def _tops(self):
        return tuple(self._find_top(p) for p in (self.male, self.female))

    def _find_top(self, profile: TwinProfile):
        per = len(profile.pieces)
        u = np.linspace(0.0, per, TIP_SCAN * per, endpoint=False)
        r = np.linalg.norm(profile.point(u), axis=-1)
        k = int(np.argmax(r))
        tol = PLATEAU_TOL * self.gearing.centre_distance
        m = len(u)
        flat = r >= r[k] - tol
        if flat.all() or not (flat[(k - 1) % m] or flat[(k + 1) % m]):
            return None
        rmax = float(r[k])

        def at(i):  # sample i's parameter, counted on across lobe 0's ends
            return float(u[i % m] + per * math.floor(i / m))

        def holds(x):
            return float(np.linalg.norm(profile.point(np.array([x]))[0])) >= rmax - tol

        lo = hi = k
        while flat[(lo - 1) % m]:
            lo -= 1
        while flat[(hi + 1) % m]:
            hi += 1
        start, _ = scalar.edge(holds, at(lo), at(lo - 1), PLATEAU_STEPS)
        end, _ = scalar.edge(holds, at(hi), at(hi + 1), PLATEAU_STEPS)
        shift = per * math.floor(start / per)  # (lobe 0's: the tips are numbered from it)
        return start - shift, end - shift, rmax

    @cached_property
    def tip_spans(self) -> tuple[float, float]:
        """Per rotor (male, female): the polar angle its lobe's arc of the largest
        radius spans counter-clockwise from the tip point (:meth:`_top`; 0 for a tip)."""
        out = []
        for profile in (self.male, self.female):
            top = None if self._land(profile) is not None else self._top(profile)
            if top is None:
                out.append(0.0)
                continue
            a, b = profile.point(np.array(top[:2]))
            out.append(float(np.remainder(math.atan2(b[1], b[0]) - math.atan2(a[1], a[0]),
                                          TWO_PI)))
        return tuple(out)

    def _land(self, profile: TwinProfile):
        """(u of its middle, radius, (u_cw, u_ccw) of its corners) of lobe 0's land, or
        None for a lobe with a tip point (LAND_TOL).  The middle is the land's middle by
        polar angle (the lobe's centre line on a symmetric lobe)."""
        return self._lands[0 if profile is self.male else 1]

    #: Profiles whose lands are treated as lands (:mod:`.lands`).  The pin-cycloid
    #: female's tip is an arc on its bore too, but keeps the tip-point treatment its
    #: published figures were checked with until its lands are validated.
    LAND_PROFILES = ("trochoidal",)

    @cached_property
    def _lands(self):
        from .lands import find_land

        if self.label not in self.LAND_PROFILES:
            return (None, None)

        return tuple(find_land(p, self.gearing.centre_distance)
                     for p in (self.male, self.female))

    @property
    def has_lands(self) -> bool:
        return any(land is not None for land in self._lands)

    def corner_points(self, profile: TwinProfile) -> np.ndarray:
        """Where the grooves meet the bore, rotor frame: per lobe its clockwise and its
        counter-clockwise land corner ((2 N, 2), lobe order) on a rotor with lands, its
        tip point ((N, 2)) otherwise."""
        land = self._land(profile)
        if land is None:
            return self.tip_points(profile)
        ends = profile.point(np.array(land[2]))
        turns = TWO_PI * np.arange(profile.lobes) / profile.lobes
        return np.concatenate([rotate(ends, t) for t in turns])

    def land_half_width(self, rotor: int) -> float:
        """Half the polar angle a lobe's land spans (0 for a tip point)."""
        profile = self.male if rotor == 0 else self.female
        land = self._land(profile)
        if land is None:
            return 0.0
        a, b = profile.point(np.array(land[2]))
        return 0.5 * abs(math.remainder(math.atan2(b[1], b[0]) - math.atan2(a[1], a[0]),
                                        TWO_PI))

    def tip_points(self, profile: TwinProfile) -> np.ndarray:
        """Every lobe's tip point in the rotor's own frame, lobe order."""
        return self._tips[0 if profile is self.male else 1]

    @cached_property
    def _tips(self):
        return tuple(self._tip_points(p) for p in (self.male, self.female))

    def _tip_points(self, profile: TwinProfile) -> np.ndarray:
        u0, _ = self._tip(profile)
        p = profile.point(np.array([u0]))[0]
        return rotate(p[None, :], TWO_PI * np.arange(profile.lobes) / profile.lobes)

    def tip_angle(self, rotor: int) -> float:
        profile = self.male if rotor == 0 else self.female
        p = self.tip_points(profile)[0]
        return math.atan2(p[1], p[0])

    @cached_property
    def contact_breaks(self) -> tuple:
        """Where the contact jumps along a band or turns a joint between arcs
        (:func:`.track_ends.contact_breaks`)."""
        from .track_ends import contact_breaks

        return contact_breaks(self)

    # ------------------------------------------------------------ the family seam
    @cached_property
    def rotors(self) -> tuple[Rotor, Rotor]:
        g = self.gearing
        return (Rotor("male", self.male, (0.0, 0.0), g.lobes_male, 1.0, g.r1),
                Rotor("female", self.female, (g.centre_distance, 0.0), g.lobes_female,
                      -g.lobes_male / g.lobes_female, g.r2))

    @cached_property
    def cutter(self):
        from .regions import SectionCutter

        return SectionCutter(self)

    @cached_property
    def female_shift(self) -> float:
        from .section import female_shift

        return female_shift(self)

    def section(self, points_per_period: int):
        # A section table costs a cut per angle: every sweep of this pair shares it.
        if points_per_period not in self._sections:
            from .section import section_chamber

            self._sections[points_per_period] = section_chamber(self, points_per_period)
        return self._sections[points_per_period]

    @cached_property
    def _sections(self) -> dict:
        return {}

    @cached_property
    def cut_memo(self) -> dict:
        """Sections cut at residues of one period (:func:`.section.chamber_polygons`)."""
        return {}

    @property
    def film_deficit(self) -> float:
        """The sections' rotors are grown by GROW on each wall (:mod:`.regions`); the
        chords' sagittas, inside the curve on one wall and outside on its mate, about
        cancel across a film."""
        from . import regions

        return 2.0 * regions.GROW

    def chamber_polygons(self, phi: float, contacts: list | None = None):
        from .section import chamber_polygons

        return chamber_polygons(self, phi, contacts)

    @cached_property
    def working_area(self) -> float:
        """The two bores' union: the chambers plus both rotors' material."""
        c, r1, r2 = self.gearing.centre_distance, self.male_radius, self.female_radius
        x, y = self.cusp
        lens = (r1 * r1 * math.acos(x / r1) - x * y
                + r2 * r2 * math.acos((c - x) / r2) - (c - x) * y)
        return math.pi * (r1 * r1 + r2 * r2) - lens

    def casing_bores(self, bore_radius: float | None = None):
        if bore_radius is not None:
            raise CaseError("a twin-screw casing has one bore per rotor, each of its "
                            "rotor's outer radius; bore_radius does not apply")
        return (((0.0, 0.0), self.male_radius),
                ((self.gearing.centre_distance, 0.0), self.female_radius))

    def gap_walls(self, angle: float, gap: float, **options):
        """The interlobe clearance gap at male angle ``angle`` (:mod:`.sealing_gap`):
        lower wall the male, upper the female; at the contact nearest the pitch point
        unless ``contact`` (an index, bottom to top) picks another; the clearance on the
        male unless ``clearance_on="female"``; ``inlet_ratio``, ``outlet_ratio``,
        ``points`` as for every family."""
        from .sealing_gap import sealing_gap_walls

        return sealing_gap_walls(self, angle, gap, **options)

    def wall_speeds(self, angle: float, omega_reference: float, **options
                    ) -> tuple[float, float]:
        """(male, female) surface speeds along the gap relative to its moving contact,
        the male turning at ``omega_reference`` (:mod:`.sealing_gap`)."""
        from .sealing_gap import sealing_wall_speeds

        return sealing_wall_speeds(self, angle, omega_reference, **options)

    def radial_port(self, machine, timing):
        from .radial_port import radial_port

        return radial_port(machine, timing)

    def figures(self) -> dict:
        from .figures import pair_figures

        return pair_figures(self)

    def contact_table(self, step_deg: float = 1.0, span_deg: float | None = None):
        from .section import contact_table

        return contact_table(self, step_deg, span_deg)

    def digest(self) -> str:
        text = repr((self.label, self.gearing, self.male_radius, self.female_radius,
                     self.male.area, self.female.area))
        return hashlib.sha256(text.encode()).hexdigest()[:8]

    @property
    def rack(self) -> tuple | None:
        """The rack arcs that generated both rotors (None for a pair of other making)."""
        arcs = [getattr(p, "arc", None) for p in self.male.pieces]
        if all(getattr(p, "rotor", None) == "male" for p in self.male.pieces) and all(arcs):
            return tuple(arcs)
        return None

    def swept_figures(self, machine) -> dict:
        """The blow-hole's area (:mod:`.blowhole`: the largest opening at the discharge-
        side cusp to the chamber ahead) and seed 004 Fig. 2, the interlobe contact
        line's length over one lobe period (straight from the rack, :mod:`.contact_line`)."""
        from .blowhole import NAMES
        from .contact_line import contact_line_lengths

        out = {}
        hole = [a for (name, d), a in machine.opening_areas.items()
                if name == NAMES[False] and d > 0]
        if hole:
            out["blow_hole_area_mm2"] = float(max(a.max() for a in hole) * 1e6)
        arcs = self.rack
        if arcs is None or machine.sweep.kind == "conical":
            return out
        thetas = np.linspace(0.0, self.period, CONTACT_LINE_SAMPLES, endpoint=False)
        lengths = contact_line_lengths(self, arcs, machine.sweep, thetas)
        return {**out, "contact_line_length_max_mm": float(lengths.max() * 1e3),
                "contact_line_length_min_mm": float(lengths.min() * 1e3)}

    @cached_property
    def lobe_depths(self) -> tuple[float, float]:
        """Each rotor's lobe depth, outer radius less root radius."""
        out = []
        for profile, radius in ((self.male, self.male_radius), (self.female, self.female_radius)):
            u = np.linspace(0.0, profile.n, 64 * profile.n, endpoint=False)
            out.append(radius - float(np.linalg.norm(profile.point(u), axis=-1).min()))
        return out[0], out[1]

    def oil_films(self, paths) -> tuple:
        from ..films import rotor_films

        return rotor_films(self, paths)

    def face_columns(self, machine) -> dict:
        from .leakage import front_lines

        return front_lines(self, machine)

    def leakage_paths(self, far_lines, track_lines=None, opening_areas=None) -> tuple:
        from .leakage import twin_screw_paths

        return twin_screw_paths(track_lines or {}, opening_areas or {})
