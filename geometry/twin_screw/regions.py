"""The fluid of a twin-screw transverse section, cut into groove parts.

At male angle ``psi`` the section's fluid is the two bores less both rotors.  The line
through the two cusps (where the bores intersect) splits it into the male side and the
female side; every connected piece on the male side lies in one male groove, every
piece on the female side in one female groove (a lobe tip that seals on its bore closes
a groove; one that has crossed the cusp line cuts the fluid there).  That split is the
usual definition of the interlobe areas (the "cusp plane").

Which life of a groove a part belongs to: a groove lives from the mesh, where it is
born on the side where the lobes come apart (the top, y > 0: both rotors' surfaces move
+y at the pitch point), once round, to the mesh again, where it dies on the side where
the lobes go in (the bottom).  Near the mesh a groove can hold parts of both lives at
once; a part whose fluid reaches the top cusp is newborn, one that reaches the bottom
cusp is dying, and a pocket trapped between contacts goes by the side of the line of
centres it lies on.

Loads and sealing points come from the parts' boundaries.  Per unit pressure the force
of the fluid on a rotor arc from a to b (region on the left) is rot(b - a) = (dy, -dx)
and its torque about the rotor's axis O is -1/2 (|b - O|^2 - |a - O|^2) (exact for any
curve between those ends); so only the ends of each wetted arc matter, and they are
snapped to the true curves: a tip to the lobe's tip point, a contact to the point where
the male meets the female (its rolling angle is ``psi``), a cut to the cusp line as the
polygons give it (chord error only).

The polygons are sampled to ``tol`` and the rotors grown by ``grow`` along their normals,
so that rotors that touch (zero clearance) overlap a little and the fluid parts come
apart at every contact; Clipper (manifold3d) does the Boolean work.  Clipper keeps 8
decimals, so everything here runs in units of ``C / UNITS`` (1e-11 C resolution).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from ..curves import sample
from ..planar import TWO_PI, rotate
from .ages import GrooveAges
from .boundaries import FEMALE, LENS_MATCH, MALE, Boundaries
from .window import GrooveWindow

#: Coordinates run in units of C / UNITS inside Clipper (it rounds to 1e-8).
UNITS = 1000.0
#: Chordal sampling tolerance of profiles and bores per centre distance: 1e-6 puts the
#: area error of a groove (2/3 tol x perimeter) near 1e-5 of its area.
SAMPLE_TOL = 1e-6
#: How far the rotors are grown (per C) so that touching rotors overlap: twice the
#: chord error, so that the inscribed polygons of two touching curves always cross.
GROW = 2e-6
#: A point this far (per C) inside the lens from a cusp tells which fluid piece holds
#: the cusp (the cusp itself is a corner of the bores).
CUSP_PROBE = 2e-3

#: An isolated piece within this fraction of a whole groove's area is a whole groove
#: (the first one must be at least this fraction of C^2).
WHOLE_FRACTION = 1e-2
#: Gauss nodes per polygon edge for its sliver and length (the edge is a short smooth
#: arc: 6 nodes integrate it to rounding).
SLIVER_NODES = 6



@dataclass(frozen=True)
class _Rotor:
    polygon: np.ndarray
    tree: object
    tips: np.ndarray
    sliver: np.ndarray  # per edge j (vertex j to j + 1): area between curve and chord
    length: np.ndarray  # per edge: the curve's length
    u: np.ndarray  # the profile parameter of each vertex
    corners: np.ndarray  # where grooves meet the bore (:meth:`.TwinScrewPair.corner_points`)


def _slivers(profile, u):
    """Per edge of the polyline through ``profile(u)``: the signed area between the
    curve and its chord (positive where the curve bulges out of the material) and the
    curve's length, by Gauss-Legendre on each edge's parameter interval."""
    x, w = np.polynomial.legendre.leggauss(SLIVER_NODES)
    n = profile.n
    a = u
    b = np.append(u[1:], u[0] + n)
    t = 0.5 * (a[:, None] + b[:, None]) + 0.5 * (b - a)[:, None] * x[None, :]
    ww = 0.5 * (b - a)[:, None] * w[None, :]
    p = profile.point(np.mod(t, n))
    d = profile.derivative(np.mod(t, n))
    pa = profile.point(a)[:, None, :]
    sliver = 0.5 * np.sum(((p - pa)[..., 0] * d[..., 1] - (p - pa)[..., 1] * d[..., 0]) * ww, 1)
    length = np.sum(np.linalg.norm(d, axis=-1) * ww, 1)
    return sliver, length


@dataclass
class Part:
    """One connected piece of fluid on one rotor's side of the cusp line."""

    rotor: int  # MALE or FEMALE: whose groove
    groove: int
    age: float  # the groove's age since birth, male-angle units
    area: float
    force: np.ndarray  # (2 rotors, 2) per unit pressure
    torque: np.ndarray  # (2,)
    perimeter: np.ndarray  # (2,) wetted rotor edge length
    tips: list = field(default_factory=list)  # (rotor, tip index, point)
    #: (rotor, corner index, point): the land corners that close it on its bore (a
    #: rotor with lands books these, not tips: a land's two corners bound different
    #: grooves, or on a one-lobe rotor the one groove at both ends)
    corners: list = field(default_factory=list)
    contacts: list = field(default_factory=list)  # points
    contact_rates: list = field(default_factory=list)  # d point / d psi of each
    side: str = ""  # "top" (newborn side), "bottom" (dying side) or "" (isolated)
    piece: int = 0  # which connected piece of the whole fluid it was cut from
    walked: bool = False  # cut from the fluid's pieces and walked: its age is found after
    polygons: list = field(default_factory=list)  # rings, metres, fixed frame
    #: length of its cut along the cusp line from its own side's cusp point (the
    #: opening to the other rotor's groove there; :mod:`.blowhole`)
    cusp_cut: float = 0.0
    cusp_top: bool = False  # whether that cusp point is the top one (y > 0)


class SectionCutter(GrooveAges, Boundaries):
    """Cuts sections of one pair (see the module docstring)."""

    def __init__(self, pair):
        self.pair = pair
        g = pair.gearing
        self.C = g.centre_distance
        self.k = UNITS / self.C  # metres -> Clipper units
        self.ratio = g.lobes_male / g.lobes_female  # female turns per male turn
        self.grow = GROW * self.C
        self.R = (pair.male_radius, pair.female_radius)
        self.O = (np.zeros(2), np.array([self.C, 0.0]))
        c = self.C
        self.xc = (c * c + self.R[0] ** 2 - self.R[1] ** 2) / (2.0 * c)
        self.yc = math.sqrt(max(self.R[0] ** 2 - self.xc ** 2, 0.0))

    # ------------------------------------------------------------ fixed data
    @cached_property
    def profile_samples(self):
        """Per rotor (male, female): parameters and points of its profile sampled to
        SAMPLE_TOL (the sections' polygons before growing; the blow-hole's ray reads
        them too)."""
        out = []
        for profile in (self.pair.male, self.pair.female):
            u = sample(profile, SAMPLE_TOL * self.C)
            out.append((u, profile.point(u)))
        return tuple(out)

    @cached_property
    def _rotor_data(self):
        """Per rotor: the grown polygon (own frame, metres), its KD-tree, its tip points,
        and per polygon edge the sliver between chord and curve and the curve's length
        (so that a run of edges gives the true area and length, not the chords')."""
        out = []
        for profile, (u, p) in zip((self.pair.male, self.pair.female), self.profile_samples,
                                   strict=True):
            sliver, length = _slivers(profile, u)
            grown = p + GROW * self.C * profile.normal(u)
            out.append(_Rotor(grown, cKDTree(grown), self.pair.tip_points(profile),
                              sliver, length, u, self.pair.corner_points(profile)))
        return out

    @cached_property
    def _bores(self):
        """The rings (Clipper units) of the union of both bores."""
        from manifold3d import CrossSection

        rings = []
        for o, r in zip(self.O, self.R, strict=True):
            n = int(math.ceil(math.pi / math.acos(1.0 - SAMPLE_TOL * self.C / r)))
            a = np.linspace(0.0, TWO_PI, n, endpoint=False)
            rings.append(CrossSection([np.ascontiguousarray(
                (o + r * np.c_[np.cos(a), np.sin(a)]) * self.k)]))
        return [np.ascontiguousarray(q) for q in (rings[0] + rings[1]).to_polygons()]

    @cached_property
    def _halves(self):
        from manifold3d import CrossSection

        big = 10.0 * UNITS
        x = self.xc * self.k
        left = np.array([[-big, -big], [x, -big], [x, big], [-big, big]])
        right = np.array([[x, -big], [big, -big], [big, big], [x, big]])
        return CrossSection([left]), CrossSection([right])

    def female_angle(self, psi):
        """The female's turn (counter-clockwise) at male angle psi."""
        return -psi * self.ratio

    def rotor_at(self, r, points, psi):
        """Points of rotor r's own frame in the fixed frame at male angle psi."""
        ang = psi if r == MALE else self.female_angle(psi)
        return rotate(points, ang) + self.O[r]

    def to_rotor(self, r, x, psi):
        ang = psi if r == MALE else self.female_angle(psi)
        return rotate(x - self.O[r], -ang)

    # ------------------------------------------------------------ one section
    def cut(self, psi: float, polygons_only: bool = False) -> list[Part]:
        """The section's parts at male angle psi.  With ``polygons_only`` each part has
        its polygons, rotor, groove and age, and no loads, tips or contacts unless its
        age needs them (:meth:`_light_parts`): the ports' off-grid sections need only
        which chamber a polygon is (a whole cut 10.3 ms, a polygons-only one 7.6 on
        the 4/6 pin-cycloid; 11.5 and 6.6 on the circular)."""
        from manifold3d import CrossSection, FillRule

        # (the grooves out of the mesh's reach are left out, and booked turned: :mod:`.window`)
        covered = [self.window.out_of_reach(r, psi) for r in (MALE, FEMALE)]
        rings = [np.ascontiguousarray(self.window.ring(r, psi, covered[r]) * self.k)
                 for r in (MALE, FEMALE)]
        # The bores' ring, both rotors' reversed: winding +1 in the fluid alone (one
        # Clipper sweep, 1.45 ms against 2.05 for building the rotors and subtracting).
        fluid = CrossSection([*self._bores, *(q[::-1].copy() for q in rings)],
                             FillRule.Positive)
        self._runs = []
        parts, pending = self._pieces(fluid, psi)
        parts += self._turned(covered, psi)
        if polygons_only:
            light = self._light_parts(pending, psi, rings)
            return [p for p in (light[p] if isinstance(p, int) else p for p in parts)
                    if p is not None]
        walked = self._parts(pending, psi)
        parts = [walked[p] if isinstance(p, int) else p for p in parts]
        parts = [p for p in parts if p is not None]
        self._contacts(psi, _overlap(rings).decompose())
        self._loads()
        for part in parts:
            if part.walked:
                rate = part.torque[MALE] - self.ratio * part.torque[FEMALE]
                part.groove, part.age = self._groove_age(part.rotor, part.polygons, psi,
                                                         part.side, rate=rate)
        return parts

    def _pieces(self, fluid, psi):
        """(parts, pending): the fluid's pieces split at the cusp line; whole grooves
        as Parts, the rest as indices into pending ((rotor, sub-piece, side, piece
        number)), walked together later."""
        probes = np.array([[self.xc, self.yc * (1.0 - CUSP_PROBE) - CUSP_PROBE * self.C],
                           [self.xc, -self.yc * (1.0 - CUSP_PROBE) + CUSP_PROBE * self.C]])
        parts, pending = [], []
        for number, piece in enumerate(fluid.decompose()):
            rings = [q / self.k for q in piece.to_polygons()]
            # (the probes lie in the mesh: most pieces' boxes miss them)
            box = np.asarray(piece.bounds()).reshape(2, 2) / self.k
            holds = [bool(np.all((pt >= box[0]) & (pt <= box[1]))) and _inside(rings[0], pt)
                     for pt in probes]
            side = "top" if holds[0] and not holds[1] else (
                "bottom" if holds[1] and not holds[0] else "")
            (x0, _), (x1, _) = box
            halves = []
            if x0 < self.xc:
                halves.append((MALE, piece if x1 <= self.xc else piece ^ self._halves[0]))
            if x1 > self.xc:
                halves.append((FEMALE, piece if x0 >= self.xc else piece ^ self._halves[1]))
            for rotor, half in halves:
                if side == "" and self._isolated(rotor, x0, x1) and self._whole_size(rotor, piece):
                    part = self._whole_groove(rotor, piece, psi, rings)
                    part.piece = number
                    parts.append(part)
                    continue
                for sub in half.decompose():
                    parts.append(len(pending))  # its place, filled once all are walked
                    pending.append((rotor, sub, side, number))
        return parts, pending

    def _light_parts(self, subs, psi, rings) -> list[Part | None]:
        """:meth:`_parts` with polygons, groove and age only.  A pocket whose age needs
        its area rate is walked with the contacts of the lenses within LENS_MATCH of it
        (a farther lens's ends are no candidates for its corners): its loads come out
        as in the whole cut."""
        out, rated = [], []
        for rotor, sub, side, number in subs:
            if sub.area() <= 0.0:
                out.append(None)
                continue
            own = [q / self.k for q in sub.to_polygons()]
            out.append(Part(rotor, 0, 0.0, sub.area() / self.k ** 2, np.zeros((2, 2)),
                            np.zeros(2), np.zeros(2), side=side, piece=number, polygons=own))
            age = self._groove_age(rotor, own, psi, side, rate=None)
            if age is None:
                rated.append(len(out) - 1)
            else:
                out[-1].groove, out[-1].age = age
        if rated:
            walked = self._parts([subs[i] for i in rated], psi)
            pts = np.concatenate([q for part in walked for q in part.polygons])
            reach = LENS_MATCH * self.C
            lo, hi = pts.min(0) - reach, pts.max(0) + reach
            lenses = [x for x in _overlap(rings).decompose()
                      if _meets(np.asarray(x.bounds()).reshape(2, 2) / self.k, lo, hi)]
            self._contacts(psi, lenses)
            self._loads()
            for i, part in zip(rated, walked, strict=True):
                rate = part.torque[MALE] - self.ratio * part.torque[FEMALE]
                part.groove, part.age = self._groove_age(part.rotor, part.polygons, psi,
                                                         part.side, rate=rate)
                out[i] = part
        return out

    def _turned(self, covered, psi) -> list[Part]:
        """The whole grooves ``covered`` (per rotor) as Parts, turned from the one held."""
        out = []
        for rotor, grooves in zip((MALE, FEMALE), covered, strict=True):
            for k in grooves:
                out.append(self._whole_groove(rotor, None, psi,
                                              self.window.turned(rotor, k, psi), known=k))
                out[-1].piece = -len(out)  # (pieces of their own)
        return out

    @cached_property
    def window(self) -> GrooveWindow:
        return GrooveWindow(self)

    def _isolated(self, rotor, x0, x1) -> bool:
        """A piece wholly beyond the other bore's reach is one whole groove, bounded by
        its rotor and its bore alone."""
        if rotor == MALE:
            return x1 < self.C - self.R[1]
        return x0 > self.R[0]

    def _whole_size(self, rotor, piece) -> bool:
        """Whether an isolated piece is a groove's size (not a sliver left between a
        tip and its bore's polygon, which goes the general way)."""
        ref = self._whole.get(rotor)
        size = piece.area() / self.k ** 2
        if ref is None:
            return size > WHOLE_FRACTION * self.C ** 2
        return abs(size - ref.area) < WHOLE_FRACTION * ref.area

    def _whole_groove(self, rotor, piece, psi, rings, known=None) -> Part:
        """A whole groove (``rings``: its polygons, metres; ``known``: its index, if
        known): its area and wetted length are every whole groove's (cut once), its
        loads those of the arc between its two tips (equal radii: no torque)."""
        if rotor not in self._whole:
            self._whole[rotor] = self._part(rotor, piece, psi, "")
        ref = self._whole[rotor]
        n = len(self._rotor_data[rotor].tips)
        tips = self._tips_at(rotor, psi)
        # The groove is the one between the two tips its boundary passes (its centroid
        # may lie beyond a tip's ray under a hooked flank).
        if self._lands[rotor]:
            # Groove k runs from lobe k's counter-clockwise land corner (2 k + 1) to lobe
            # k + 1's clockwise one; its ring passes through both.
            corners = self.rotor_at(rotor, self._rotor_data[rotor].corners, psi)
            near = np.min(np.linalg.norm(rings[0][None, :, :] - corners[1::2, None, :],
                                         axis=-1), 1)
            groove, age = self._groove_age(rotor, rings, psi, "", groove=int(np.argmin(near)))
            a, b = corners[(2 * groove + 2) % (2 * n)], corners[2 * groove + 1]
            # loads up to the middles of the gaps beyond the corners (Boundaries._snap_land)
            fa = self.gap_middle(rotor, a, (groove + 1) % n, psi)
            fb = self.gap_middle(rotor, b, groove, psi)
            force = np.zeros((2, 2))
            force[rotor] = (fb[1] - fa[1], -(fb[0] - fa[0]))
            return Part(rotor, groove, age, ref.area, force, np.zeros(2), ref.perimeter.copy(),
                        corners=[(rotor, (2 * groove + 2) % (2 * n), a),
                                 (rotor, 2 * groove + 1, b)], side="", polygons=rings)
        if known is None:
            # (squared distances: the order is the distances')
            diff = rings[0][None, :, :] - tips[:, None, :]
            near = np.min(np.einsum("tvk,tvk->tv", diff, diff), 1)
            pair = sorted(np.argsort(near)[:2])  # one tip only on a one-lobe rotor
            k = pair[1] if n > 2 and (pair[0], pair[1]) == (0, n - 1) else pair[0]
            # Two lobes: both grooves lie between the same two tips; the centroid of a
            # groove spanning half a turn lies within it.
            known = int(k) if n > 2 else None
        groove, age = self._groove_age(rotor, rings, psi, "", groove=known)
        self.window.keep(rotor, groove, rings, psi)
        # The fluid runs clockwise along the rotor, from the groove's counter-clockwise
        # tip (k + 1) to its clockwise one (k).
        a, b = tips[(groove + 1) % n], tips[groove]
        force = np.zeros((2, 2))
        force[rotor] = (b[1] - a[1], -(b[0] - a[0]))
        return Part(rotor, groove, age, ref.area, force, np.zeros(2), ref.perimeter.copy(),
                    tips=[(rotor, (groove + 1) % n, a), (rotor, groove, b)], side="",
                    polygons=rings)

    @cached_property
    def _whole(self) -> dict:
        return {}

    def _part(self, rotor, sub, psi, side) -> Part | None:
        return self._parts([(rotor, sub, side, 0)], psi)[0]

    def _parts(self, subs, psi) -> list[Part | None]:
        """The parts of sub-pieces ``subs`` ((rotor, CrossSection, side, piece number)),
        their boundaries labelled together (:meth:`_labels`); None for an empty one."""
        parts, rings = [], []
        for rotor, sub, side, number in subs:
            area = sub.area() / self.k ** 2
            if area <= 0.0:
                parts.append(None)
                continue
            own = [q / self.k for q in sub.to_polygons()]
            parts.append(Part(rotor, 0, 0.0, area, np.zeros((2, 2)), np.zeros(2), np.zeros(2),
                              side=side, piece=number, polygons=own, walked=True))
            rings.extend((ring, parts[-1]) for ring in own)
        if rings:
            labels = self._labels([ring for ring, _ in rings], psi)
            for (ring, part), lab in zip(rings, labels, strict=True):
                self._walk(ring, lab, psi, part)
        return parts


def _overlap(rings):
    """Where the rotors' rings (Clipper units) overlap: with a reversed box round both,
    winding +1 there alone (one Clipper sweep, without building each rotor's)."""
    from manifold3d import CrossSection, FillRule

    big = 10.0 * UNITS
    box = np.array([[-big, -big], [-big, big], [big, big], [big, -big]])
    return CrossSection([*rings, box], FillRule.Positive)


def _meets(box, lo, hi) -> bool:
    """Whether the box ((x0, y0), (x1, y1)) meets the box from lo to hi."""
    return bool(np.all(box[0] <= hi) and np.all(box[1] >= lo))


def _inside(ring, pt) -> bool:
    """Even-odd point-in-polygon test."""
    x, y = ring[:, 0], ring[:, 1]
    x2, y2 = np.concatenate([x[1:], x[:1]]), np.concatenate([y[1:], y[:1]])
    cond = (y > pt[1]) != (y2 > pt[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = x + (pt[1] - y) * (x2 - x) / (y2 - y)
    return bool(np.sum(cond & (pt[0] < xi)) % 2)
