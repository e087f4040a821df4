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
from scipy.optimize import brentq, minimize_scalar

from rotorflow.errors import CaseError

from ..family import Rotor, RotorPair
from ..planar import TWO_PI, cross, rotate
from .meshing import Gearing
from .profiles import TwinProfile

#: Samples per lobe on which a lobe's tip (largest radius) is bracketed before it is
#: polished; a tip is narrower than a lobe by far more than 1/512.
TIP_SCAN = 512
#: Half-width (in profile parameter) of the window in which a contact is sought around
#: its polygon estimate: a few polygon edges.
CONTACT_WINDOW = 0.02
#: Points of that window on which the law of gearing is bracketed.
CONTACT_GRID = 17
#: Male angles over one lobe period at which the contact line's length is figured.
CONTACT_LINE_SAMPLES = 24
#: Step in the profile parameter for the law of gearing's slope (central difference of
#: analytic curves: 1e-6 of a piece leaves ~1e-10 relative error).
LAW_STEP = 1e-6
#: Parameter tolerance of a contact: 1e-13 of a piece is far below a nanometre.
CONTACT_XTOL = 1e-13
#: A root of the law of gearing leaves at most this residual (per C): the law's slope
#: is ~C per unit parameter, so CONTACT_XTOL leaves ~1e-13; a bracket closed on a jump
#: of the law (a cusp's normal flip) leaves the jump, ~1e-4 and more.
ROOT_RESIDUAL = 1e-9
#: A zero of the law on a piece whose rolling angle is known is its contact only if
#: that angle is psi (mod a period) to this (rad): the law's zero is found to 1e-13 of
#: a piece, the rolling angle varies by at most ~1 rad per piece (more near a cusp's
#: sqrt(s) parametrisation, still far below this); a spurious zero lies ~1e-2 off.
ROLLING_TOL = 1e-6
#: Points per piece on which its rolling angle is bracketed (monotone on the pieces
#: seen; a few more guard a turning one).
ROLLING_SCAN = 9
#: Either side of a jump of the law, this far (in profile parameter) ...
CORNER_STEP = 1e-9
#: ... the normals of a cusp are opposite (cos -1); a corner's turn by less than
#: ~170 deg is a corner.
CUSP_COS = -0.985


def _illinois(f, a, b, fa, fb, iterations: int = 60) -> float:
    """A root of f in [a, b] (f(a), f(b) of opposite signs): regula falsi with the
    Illinois modification (superlinear, never leaves the bracket)."""
    side = 0
    c = a
    for _ in range(iterations):
        c = (a * fb - b * fa) / (fb - fa)
        fc = float(f(c)[0])
        if fc == 0.0 or abs(b - a) < CONTACT_XTOL:
            break
        if np.sign(fc) == np.sign(fb):
            b, fb = c, fc
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb *= 0.5
            side = 1
        if abs(b - a) < CONTACT_XTOL:
            break
    return float(c)


def _offset_rolling(t: float, piece, target: float) -> float:
    return float(np.asarray(piece.rolling_angle(np.array([t])))[0]) - target


@dataclass(frozen=True)
class TwinScrewPair(RotorPair):
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
        """(u, radius) of lobe 0's tip: its largest radius, polished (a land's middle)."""
        land = self._land(profile)
        if land is not None:
            return land[0], land[1]
        per = len(profile.pieces)
        u = np.linspace(0.0, per, TIP_SCAN * per, endpoint=False)
        r = np.linalg.norm(profile.point(u), axis=-1)
        k = int(np.argmax(r))
        h = per / (TIP_SCAN * per)
        res = minimize_scalar(lambda x: -float(np.linalg.norm(profile.point(np.array([x]))[0])),
                              bounds=(u[k] - h, u[k] + h), method="bounded",
                              options={"xatol": 1e-13})
        return float(res.x), -float(res.fun)

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

    # ------------------------------------------------------------ contacts
    def _law(self, u, psi: float):
        """The law of gearing on the male at parameters u, male angle psi: the cross
        product of the normal with the way to the pitch point (zero at a contact)."""
        male = self.male
        u = np.mod(np.atleast_1d(u), male.n)
        pitch = rotate(self.gearing.pitch_point[None, :], -psi)[0]
        return cross(male.normal(u), pitch - male.point(u))

    def _root(self, lo: float, hi: float, near: float, psi: float) -> float | None:
        """The contact on the male in [lo, hi] (profile parameter) nearest ``near`` at
        male angle psi (None if it has none there).

        Where the pieces give their rolling angles the contact is where that angle is
        psi (:meth:`_rolling_roots`), or a corner the contact rests on.  Elsewhere it is
        a root of the law of gearing, which is weaker near a cusp: there the normals of
        nearby points also pass through the pitch point (the evolute is near) and
        zeros come in close pairs that a coarse bracket misses."""
        found, known = self._rolling_roots(lo, hi, psi)
        if not known:
            found += self._law_roots(lo, hi, psi)
        if not found:
            return None
        return float(np.mod(min(found, key=lambda u: abs(u - near)), self.male.n))

    def _rolling_roots(self, lo: float, hi: float, psi: float) -> tuple[list, bool]:
        """(contacts in [lo, hi] by the pieces' rolling angles, whether every piece
        there gives one)."""
        male, per = self.male, len(self.male.pieces)
        found, known = [], True
        for j in range(math.floor(lo), math.ceil(hi)):
            a, b = max(lo, j), min(hi, j + 1)
            if b <= a:
                continue
            piece = male.pieces[j % per]
            t = np.linspace(a - j, b - j, ROLLING_SCAN)
            r = np.asarray(piece.rolling_angle(t), dtype=float)
            if not np.all(np.isfinite(r)):
                known = False
                continue
            if np.ptp(r) <= ROLLING_TOL:
                # A band: at its instant every point of it touches (the one nearest
                # the middle of [lo, hi] stands for it), else none does.
                if abs(math.remainder(r[0] - psi, self.period)) <= ROLLING_TOL:
                    found.append(float(np.clip(0.5 * (lo + hi), a, b)))
                continue
            # psi's images within a period of the piece's angles (its span < a period).
            base = r[0] + math.remainder(psi - r[0], self.period)
            for target in (base - self.period, base, base + self.period):
                g = r - target
                for i in np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]:
                    found.append(j + brentq(_offset_rolling, t[i], t[i + 1],
                                            args=(piece, target), xtol=CONTACT_XTOL))
                found.extend(j + t[np.nonzero(g == 0.0)[0]])
        for k in range(math.ceil(lo), math.floor(hi) + 1):
            if self._rests(float(k), psi, strict=True):
                found.append(float(k))
        return found, known

    def _law_roots(self, lo: float, hi: float, psi: float) -> list:
        """Roots of the law of gearing in [lo, hi], where the pieces give no rolling
        angle."""
        grid = np.linspace(lo, hi, CONTACT_GRID)
        # The law jumps at the joints between pieces (the normal turns there): each joint
        # gets its own bracket, so that a zero just beside it is not cancelled by it.
        joints = np.arange(math.ceil(lo), math.floor(hi) + 1, dtype=float)
        grid = np.unique(np.concatenate([grid, joints - CORNER_STEP, joints + CORNER_STEP]))
        grid = grid[(grid >= lo) & (grid <= hi)]
        vals = self._law(grid, psi)
        sign = np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0]
        law = lambda u: self._law(u, psi)  # noqa: E731
        out = []
        # The law also changes sign where the male's normal jumps.  At a corner that is
        # a contact: the corner seals while the normal's turn there sweeps through the
        # pitch point.  At a cusp the normal flips and the sign change is none.
        for j in sign:
            u = _illinois(law, grid[j], grid[j + 1], vals[j], vals[j + 1])
            if abs(float(law(u)[0])) <= ROOT_RESIDUAL * self.gearing.centre_distance:
                out.append(u)
                continue
            side = self.male.normal(np.mod(np.array([u - CORNER_STEP, u + CORNER_STEP]),
                                           self.male.n))
            if float(side[0] @ side[1]) > CUSP_COS:
                out.append(u)
        return out

    def _rolling(self, u: float) -> float:
        """The rolling angle of male point u (its piece's; NaN where it gives none)."""
        male = self.male
        v = float(np.mod(u, male.n))
        j = min(int(np.floor(v)), male.n - 1)
        k = j % len(male.pieces)
        return float(np.asarray(male.pieces[k].rolling_angle(np.array([v - j])))[0])

    def _rests(self, u: float, psi: float, strict: bool = False) -> bool:
        """Whether the contact rests on the male corner u at angle psi: strictly between
        the instants the pieces either side mesh their ends there (where those differ;
        the ends themselves are the pieces' contacts)."""
        a, b = self._rolling(u - CORNER_STEP), self._rolling(u + CORNER_STEP)
        if not (math.isfinite(a) and math.isfinite(b)):
            return not strict
        span = math.remainder(b - a, self.period)
        if strict and abs(span) <= ROLLING_TOL:
            return False
        x = math.remainder(psi - a, self.period)
        lo, hi = min(0.0, span), max(0.0, span)
        return lo - ROLLING_TOL <= x <= hi + ROLLING_TOL

    def contact_near(self, x, psi: float) -> tuple[np.ndarray, np.ndarray]:
        """(point, d point / d psi) of the contact of the rotors near ``x`` at male
        angle ``psi`` (fixed frame).

        At a contact the male's normal passes through the pitch point (the law of
        gearing), which holds for every conjugate arc whatever generated it; the root
        is sought on the male profile around the sampled point nearest ``x``.
        """
        local = rotate(np.asarray(x, dtype=float)[None, :], -psi)[0]
        u_grid, p_grid = self._foot_grid
        u0 = float(u_grid[int(np.argmin(np.linalg.norm(p_grid - local, axis=-1)))])
        u = self._root(u0 - CONTACT_WINDOW, u0 + CONTACT_WINDOW, u0, psi)
        if u is None:
            # No contact here: keep the polygon's corner, moving with neither rotor.
            return np.asarray(x, dtype=float), np.zeros(2)
        return self._contact_at(u, psi)

    def contact_between(self, u_poly, lo: int, hi: int, psi: float
                        ) -> tuple[np.ndarray, np.ndarray]:
        """(point, d point / d psi) of the contact on the male between polygon vertices
        ``lo`` and ``hi`` (indices into ``u_poly``, running up from lo to hi, around the
        closed profile): the root of the law of gearing nearest the middle."""
        male = self.male
        ulo = float(u_poly[lo])
        uhi = float(u_poly[hi]) + (male.n if hi < lo else 0.0)
        mid = 0.5 * (ulo + uhi)
        u = self._root(ulo, uhi, mid, psi)
        if u is None:
            # Just off a band's instant the lens can lie along the band's arc while the
            # contact has passed onto the next piece, beyond the lens's end (the
            # pin-cycloid's pin arc and the female corner D1): look a window further.
            u = self._root(ulo - CONTACT_WINDOW, uhi + CONTACT_WINDOW, mid, psi)
        if u is None:
            # No root in the lens (a conformal band at its tangency): its middle, with
            # no rate of its own (the band is not a sealing point that moves).
            return rotate(male.point(np.array([np.mod(mid, male.n)])), psi)[0], np.zeros(2)
        return self._contact_at(u, psi)

    def _contact_at(self, u: float, psi: float):
        """(point, d point / d psi) of the contact at male parameter u, fixed frame.

        The contact moves along the male as the rotors turn: law(u, psi) = 0 gives
        du/dpsi = -law_psi / law_u (implicit function), and the point R(psi) p(u)
        moves by J R p + R p' du/dpsi.  The sealing lines need this rate (a contact runs
        fast near the cusps, where differences between table nodes would blur it).
        """
        male = self.male
        uu = np.array([u])
        p, d, n = male.point(uu)[0], male.derivative(uu)[0], male.normal(uu)[0]
        pitch = rotate(self.gearing.pitch_point[None, :], -psi)[0]
        dpitch = np.array([pitch[1], -pitch[0]])  # d/dpsi of R(-psi) P
        h = LAW_STEP
        law_u = float(self._law(u + h, psi)[0] - self._law(u - h, psi)[0]) / (2.0 * h)
        law_psi = float(cross(n, dpitch))
        du = -law_psi / law_u if law_u != 0.0 else 0.0
        point = rotate(p[None, :], psi)[0]
        rate = np.array([-point[1], point[0]]) + rotate((d * du)[None, :], psi)[0]
        return point, rate

    @cached_property
    def contact_breaks(self) -> tuple:
        """Where the contact jumps along a band or turns a joint between arcs
        (:func:`.track_ends.contact_breaks`)."""
        from .track_ends import contact_breaks

        return contact_breaks(self)

    @cached_property
    def _foot_grid(self):
        from ..curves import sample

        u = sample(self.male, 1e-5 * self.gearing.centre_distance)
        return u, self.male.point(u)

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
        from .contact_line import contact_line_length

        out = {}
        hole = [a for (name, d), a in machine.opening_areas.items()
                if name == NAMES[False] and d > 0]
        if hole:
            out["blow_hole_area_mm2"] = float(max(a.max() for a in hole) * 1e6)
        arcs = self.rack
        if arcs is None or machine.sweep.kind == "conical":
            return out
        thetas = np.linspace(0.0, self.period, CONTACT_LINE_SAMPLES, endpoint=False)
        lengths = np.array([contact_line_length(self, arcs, machine.sweep, t) for t in thetas])
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
