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

#: Coordinates run in units of C / UNITS inside Clipper (it rounds to 1e-8).
UNITS = 1000.0
#: Chordal sampling tolerance of profiles and bores per centre distance: 1e-6 puts the
#: area error of a groove (2/3 tol x perimeter) near 1e-5 of its area.
SAMPLE_TOL = 1e-6
#: How far the rotors are grown (per C) so that touching rotors overlap: twice the
#: chord error, so that the inscribed polygons of two touching curves always cross.
GROW = 2e-6
#: Edge-classification tolerance per C: a boundary edge within this of a bore circle
#: or of the cusp line lies on it (a few chord errors; nothing else comes that close
#: except the rotor flanks next to a tip, whose ends are snapped anyway).
ON_TOL = 5e-6
#: A point this far (per C) inside the lens from a cusp tells which fluid piece holds
#: the cusp (the cusp itself is a corner of the bores).
CUSP_PROBE = 2e-3

#: A fluid corner at a contact is the end of the overlap lens within this (per C): along
#: a conformal band (a female tip rolling in a male root) the grown chords can cross
#: a little away from where the lens's Boolean put its end.
LENS_MATCH = 2e-3
#: Gauss nodes per polygon edge for its sliver and length (the edge is a short smooth
#: arc: 6 nodes integrate it to rounding).
SLIVER_NODES = 6
#: A fluid vertex within this (per C) of a rotor polygon's vertex is that vertex (Clipper
#: rounds to 1e-11 C; new intersection vertices are farther from every old one).
SAME_VERTEX = 1e-9

MALE, FEMALE, BORE_M, BORE_F, CUSP, NEW = 0, 1, 2, 3, 4, -1


@dataclass(frozen=True)
class _Rotor:
    polygon: np.ndarray
    tree: object
    tips: np.ndarray
    sliver: np.ndarray  # per edge j (vertex j to j + 1): area between curve and chord
    length: np.ndarray  # per edge: the curve's length
    u: np.ndarray  # the profile parameter of each vertex


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
class _Run:
    """A wetted arc of one rotor in a part, from a to b; an end at a contact is
    ``(None, polygon vertex)`` until the contacts are resolved."""

    part: object
    rotor: int
    a: object
    b: object
    first: int  # rotor-polygon index of its first and last vertex (-1: none)
    last: int
    contact_start: bool = False
    contact_end: bool = False


def _key(x, scale):
    return (round(x[0] / (SAME_VERTEX * scale)), round(x[1] / (SAME_VERTEX * scale)))


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
    contacts: list = field(default_factory=list)  # points
    side: str = ""  # "top" (newborn side), "bottom" (dying side) or "" (isolated)
    piece: int = 0  # which connected piece of the whole fluid it was cut from
    polygons: list = field(default_factory=list)  # rings, metres, fixed frame


class SectionCutter:
    """Cuts sections of one pair (see the module docstring)."""

    def __init__(self, pair):
        self.pair = pair
        g = pair.gearing
        self.C = g.centre_distance
        self.k = UNITS / self.C  # metres -> Clipper units
        self.ratio = g.lobes_male / g.lobes_female  # female turns per male turn
        self.R = (pair.male_radius, pair.female_radius)
        self.O = (np.zeros(2), np.array([self.C, 0.0]))
        c = self.C
        self.xc = (c * c + self.R[0] ** 2 - self.R[1] ** 2) / (2.0 * c)
        self.yc = math.sqrt(max(self.R[0] ** 2 - self.xc ** 2, 0.0))

    # ------------------------------------------------------------ fixed data
    @cached_property
    def _rotor_data(self):
        """Per rotor: the grown polygon (own frame, metres), its KD-tree, its tip points,
        and per polygon edge the sliver between chord and curve and the curve's length
        (so that a run of edges gives the true area and length, not the chords')."""
        out = []
        for profile in (self.pair.male, self.pair.female):
            u = sample(profile, SAMPLE_TOL * self.C)
            p = profile.point(u)
            sliver, length = _slivers(profile, u)
            grown = p + GROW * self.C * profile.normal(u)
            out.append(_Rotor(grown, cKDTree(grown), self.pair.tip_points(profile),
                              sliver, length, u))
        return out

    @cached_property
    def _bores(self):
        from manifold3d import CrossSection

        rings = []
        for o, r in zip(self.O, self.R):
            n = int(math.ceil(math.pi / math.acos(1.0 - SAMPLE_TOL * self.C / r)))
            a = np.linspace(0.0, TWO_PI, n, endpoint=False)
            rings.append(CrossSection([np.ascontiguousarray(
                (o + r * np.c_[np.cos(a), np.sin(a)]) * self.k)]))
        return rings[0] + rings[1]

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
    def cut(self, psi: float) -> list[Part]:
        from manifold3d import CrossSection

        polys = []
        for r in (MALE, FEMALE):
            p = self._rotor_data[r].polygon
            polys.append(CrossSection([np.ascontiguousarray(self.rotor_at(r, p, psi) * self.k)]))
        fluid = self._bores - polys[0] - polys[1]
        self._runs = []
        probes = np.array([[self.xc, self.yc * (1.0 - CUSP_PROBE) - CUSP_PROBE * self.C],
                           [self.xc, -self.yc * (1.0 - CUSP_PROBE) + CUSP_PROBE * self.C]])
        parts = []
        for number, piece in enumerate(fluid.decompose()):
            rings = [q / self.k for q in piece.to_polygons()]
            holds = [any(_inside(ring, pt) for ring in rings[:1]) for pt in probes]
            side = "top" if holds[0] and not holds[1] else (
                "bottom" if holds[1] and not holds[0] else "")
            (x0, _), (x1, _) = np.asarray(piece.bounds()).reshape(2, 2) / self.k
            halves = []
            if x0 < self.xc:
                halves.append((MALE, piece if x1 <= self.xc else piece ^ self._halves[0]))
            if x1 > self.xc:
                halves.append((FEMALE, piece if x0 >= self.xc else piece ^ self._halves[1]))
            for rotor, half in halves:
                if side == "" and self._isolated(rotor, x0, x1):
                    part = self._whole_groove(rotor, piece, psi)
                    part.piece = number
                    parts.append(part)
                    continue
                for sub in half.decompose():
                    part = self._part(rotor, sub, psi, side)
                    if part is not None:
                        part.piece = number
                        parts.append(part)
        self._contacts(psi, (polys[0] ^ polys[1]).decompose())
        self._close_chains(psi)
        self._loads()
        return parts

    def _isolated(self, rotor, x0, x1) -> bool:
        """A piece wholly beyond the other bore's reach is one whole groove, bounded by
        its rotor and its bore alone."""
        if rotor == MALE:
            return x1 < self.C - self.R[1]
        return x0 > self.R[0]

    def _whole_groove(self, rotor, piece, psi) -> Part:
        """A whole groove: its area and wetted length are every whole groove's (cut
        once), its loads those of the arc between its two tips (equal radii: no
        torque)."""
        if rotor not in self._whole:
            self._whole[rotor] = self._part(rotor, piece, psi, "")
        ref = self._whole[rotor]
        rings = [q / self.k for q in piece.to_polygons()]
        cen = _centroid(rings[0])
        groove, age = self._groove_age(rotor, cen, psi, "")
        n = len(self._rotor_data[rotor].tips)
        tips = self.rotor_at(rotor, self._rotor_data[rotor].tips, psi)
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
        area = sub.area() / self.k ** 2
        if area <= 0.0:
            return None
        rings = [q / self.k for q in sub.to_polygons()]
        part = Part(rotor, 0, 0.0, area, np.zeros((2, 2)), np.zeros(2), np.zeros(2),
                    side=side, polygons=rings)
        for ring in rings:
            self._walk(ring, psi, part)
        cen = _centroid(rings[0])
        part.groove, part.age = self._groove_age(rotor, cen, psi, side)
        return part

    # ------------------------------------------------------------ boundaries
    def _labels(self, ring, psi):
        """Per vertex: (label, index in its rotor polygon or -1); per edge: label."""
        tol = ON_TOL * self.C
        n = len(ring)
        vlab = np.full(n, NEW)
        vidx = np.full(n, -1)
        for r in (MALE, FEMALE):
            d, k = self._rotor_data[r].tree.query(self.to_rotor(r, ring, psi))
            hit = (d < SAME_VERTEX * self.C) & (vlab == NEW)
            vlab[hit], vidx[hit] = r, k[hit]
        for r, code in ((MALE, BORE_M), (FEMALE, BORE_F)):
            on = np.abs(np.linalg.norm(ring - self.O[r], axis=-1) - self.R[r]) < tol
            vlab[on & (vlab == NEW)] = code
        nxt = np.roll(vlab, -1)
        on_cusp = ((np.abs(ring[:, 0] - self.xc) < tol)
                   & (np.abs(np.roll(ring[:, 0], -1) - self.xc) < tol))
        rotor_end = np.where(vlab <= FEMALE, vlab, np.where(nxt <= FEMALE, nxt, NEW))
        rotor_end[(vlab <= FEMALE) & (nxt <= FEMALE) & (vlab != nxt) & (vlab >= 0)] = NEW
        elab = np.where(rotor_end >= 0, rotor_end, np.where(vlab == nxt, vlab, NEW))
        elab[on_cusp & ~((vlab == nxt) & (vlab <= FEMALE) & (vlab >= 0))] = CUSP
        bore = (elab == NEW) & np.isin(vlab, (BORE_M, BORE_F)) & np.isin(nxt, (BORE_M, BORE_F))
        elab[bore] = np.where(np.linalg.norm(ring[bore] - self.O[0], axis=-1) < self.R[0] + tol,
                              BORE_M, BORE_F)
        rest = elab == NEW
        if rest.any():
            # An edge between two new corners (a cusp-line cut and a contact, say) lies
            # on whichever rotor's chords pass through its middle.
            mid = 0.5 * (ring[rest] + np.roll(ring, -1, axis=0)[rest])
            d = [self._segment_distance(r, self.to_rotor(r, mid, psi)) for r in (MALE, FEMALE)]
            elab[rest] = np.where(d[0] <= d[1], MALE, FEMALE)
        return elab, vidx

    def _segment_distance(self, r, x):
        """Distance from points x (rotor r's frame) to rotor r's polygon's edges."""
        rd = self._rotor_data[r]
        p = rd.polygon
        m = len(p)
        _, k = rd.tree.query(x, k=2)
        best = np.full(len(x), np.inf)
        for j in (k[:, 0], k[:, 1]):
            for a, b in ((p[j - 1], p[j]), (p[j], p[(j + 1) % m])):
                e = b - a
                t = np.clip(np.sum((x - a) * e, -1) / np.maximum(np.sum(e * e, -1), 1e-300),
                            0.0, 1.0)
                best = np.minimum(best, np.linalg.norm(a + t[:, None] * e - x, axis=-1))
        return best

    def _walk(self, ring, psi, part: Part) -> None:
        """Add the loads, wetted lengths, tips and contacts of one boundary ring, and
        the curves' slivers to the part's polygon area."""
        lab, vidx = self._labels(ring, psi)
        change = np.nonzero(lab != np.roll(lab, 1))[0]
        if not len(change):
            return
        start = int(change[0])
        lab, vidx = np.roll(lab, -start), np.roll(vidx, -start)
        v = np.roll(ring, -start, axis=0)
        edges = np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=-1)
        cuts = list(np.nonzero(lab != np.roll(lab, 1))[0]) + [len(lab)]
        n = len(lab)
        for i0, i1 in zip(cuts[:-1], cuts[1:]):
            r = int(lab[i0])
            if r in (BORE_M, BORE_F):
                o, rad = self.O[r - BORE_M], self.R[r - BORE_M]
                half = np.clip(edges[i0:i1] / (2.0 * rad), 0.0, 1.0)
                th = 2.0 * np.arcsin(half)
                part.area += float(np.sum(0.5 * rad * rad * (th - np.sin(th))))
                del o
                continue
            if r not in (MALE, FEMALE):
                continue
            before, after = int(lab[i0 - 1]), int(lab[i1 % n])
            idx = vidx[i0:i1 + 1] if i1 < n else np.append(vidx[i0:], vidx[0])
            area, length = self._run_true(r, idx, edges[i0:i1])
            part.area += area
            part.perimeter[r] += length
            k = idx[idx >= 0]
            self._runs.append(_Run(part, r, self._snap_tip(r, v[i0], before, psi, part),
                                   self._snap_tip(r, v[i1 % n], after, psi, part),
                                   int(k[0]) if len(k) else -1, int(k[-1]) if len(k) else -1))

    def _run_true(self, r, idx, chords):
        """(area to add to the polygon's, true length) of a run along rotor r whose
        vertices have rotor-polygon indices ``idx`` (-1: a new vertex at an end)."""
        rd = self._rotor_data[r]
        m = len(rd.polygon)
        k = idx[idx >= 0]
        length = float(chords.sum())
        area = GROW * self.C * length  # the polygon runs along the grown rotor
        if len(k) < 2:
            return area, length
        step = (k[1:] - k[:-1] + m // 2) % m - m // 2
        if not np.all(np.abs(step) == 1):
            return area, length
        # The fluid lies outside the rotor: it runs along it clockwise (step -1), and
        # the curve's slivers are outside its chords.
        e = np.where(step < 0, k[1:], k[:-1]) % m
        inner = float(rd.length[e].sum())
        length += inner - float(np.sum(chords[_inner_edges(idx)]))
        area += float(np.sum(step * rd.sliver[e]))
        return area, length

    def _snap_tip(self, r, x, neighbour, psi, part: Part):
        """The end of rotor r's wetted arc at polygon vertex x where it meets a bore (the
        lobe's tip point); None where it meets the other rotor (a contact, resolved per
        overlap by :meth:`_contacts`); x itself where it meets the cusp line."""
        if neighbour in (BORE_M, BORE_F):
            tips = self.rotor_at(r, self._rotor_data[r].tips, psi)
            k = int(np.argmin(np.linalg.norm(tips - x, axis=-1)))
            part.tips.append((r, k, tips[k]))
            return tips[k]
        if neighbour in (MALE, FEMALE) and neighbour != r:
            return (None, x)
        return x

    def _contacts(self, psi, lenses) -> None:
        """Give both ends of every overlap of the grown rotors one contact point.

        Where the rotors touch, the grown polygons overlap over a lens; its two ends
        belong to the parts on either side.  A lens can hold more than one true contact
        (conformal arcs touch along a band, with a pocket of sub-micron depth between),
        so each end snapped to its nearest contact would leave the arc between them
        wetted by nobody and the loads at uniform pressure unbalanced.  Every end of a
        lens takes the one contact nearest the lens's middle (the pocket goes to one
        side).
        """
        by_point = {}
        rd = self._rotor_data[MALE]
        m = len(rd.polygon)
        for lens in lenses:
            for ring in lens.to_polygons():
                ring = ring / self.k
                d, k = rd.tree.query(self.to_rotor(MALE, ring, psi))
                on = d < SAME_VERTEX * self.C
                ends = ring[~on & (self._female_distance(ring, psi) > SAME_VERTEX * self.C)]
                if not len(ends):
                    continue
                idx = np.sort(k[on])
                if len(idx) >= 2:
                    gap = np.diff(np.append(idx, idx[0] + m))
                    j = int(np.argmax(gap))  # the lens's male arc is the complement
                    lo, hi = idx[(j + 1) % len(idx)], idx[j]
                    c = self.pair.contact_between(rd.u, lo, hi, m, psi)
                else:
                    c = self.pair.contact_near(ends.mean(0), psi)
                for e in ends:
                    by_point[_key(e, self.C)] = (e, c)
        known = list(by_point.values())
        pts = np.array([e for e, _ in known]) if known else np.zeros((0, 2))
        for q in self._runs:
            for which in ("a", "b"):
                end = getattr(q, which)
                if isinstance(end, tuple):
                    setattr(q, "contact_start" if which == "a" else "contact_end", True)
                    # The fluid's corner is the lens's end up to Clipper's separate
                    # rounding of the two Booleans (and, along a conformal band, the
                    # chords' crossings): the nearest lens end within LENS_MATCH.
                    d = np.linalg.norm(pts - end[1], axis=-1) if len(pts) else np.inf
                    j = int(np.argmin(d)) if len(pts) else -1
                    if j >= 0 and d[j] < LENS_MATCH * self.C:
                        c = known[j][1]
                    else:
                        c = self.pair.contact_near(end[1], psi)
                    setattr(q, which, c)
                    if not any(c is d for d in q.part.contacts):
                        q.part.contacts.append(c)

    def _female_distance(self, pts, psi):
        return self._rotor_data[FEMALE].tree.query(self.to_rotor(FEMALE, pts, psi))[0]

    def _close_chains(self, psi) -> None:
        """Make each rotor's wetted arcs meet end to start across every contact.

        The fluid runs along a rotor clockwise; after a run that ends at a contact the
        next run (the next start lower along the profile) must begin at that same
        point, or the arc between them would be wetted by nobody (a sub-micron pocket
        inside a lens whose two ends found different contacts).  The next run's start
        takes the end's point; both are contacts of one lens.
        """
        for r in (MALE, FEMALE):
            runs = [q for q in self._runs if q.rotor == r]
            rd = self._rotor_data[r]
            m = len(rd.polygon)
            if len(runs) < 2:
                continue
            a_idx = np.array([rd.tree.query(self.to_rotor(r, q.a, psi))[1] for q in runs])
            for q in runs:
                if not q.contact_end:
                    continue
                b = rd.tree.query(self.to_rotor(r, q.b, psi))[1]
                below = (b - a_idx) % m
                j = int(np.argmin(np.where(below == 0, m, below) if False else below))
                nxt = runs[j]
                if nxt is not q and nxt.contact_start:
                    nxt.a = q.b

    def _loads(self) -> None:
        for q in self._runs:
            d = q.b - q.a
            q.part.force[q.rotor] += (d[1], -d[0])
            o = self.O[q.rotor]
            q.part.torque[q.rotor] += -0.5 * (np.sum((q.b - o) ** 2) - np.sum((q.a - o) ** 2))

    def _groove_age(self, rotor, centroid, psi, side):
        """(groove index, age in male-angle units) of a part (module docstring)."""
        pair = self.pair
        n = pair.gearing.lobes_male if rotor == MALE else pair.gearing.lobes_female
        period = TWO_PI / n
        local = self.to_rotor(rotor, centroid, psi)
        tip0 = pair.tip_angle(rotor)
        k = int(math.floor(((math.atan2(local[1], local[0]) - tip0) % TWO_PI) / period)) % n
        mid = tip0 + (k + 0.5) * period  # the groove's mid-line, own frame
        if rotor == MALE:
            theta = math.remainder(mid + psi, TWO_PI)  # 0: facing the female axis
            scale = 1.0
        else:
            theta = math.remainder(math.pi - (mid + self.female_angle(psi)), TWO_PI)
            scale = 1.0 / self.ratio
        if side == "top":
            age = theta
        elif side == "bottom":
            age = theta + TWO_PI
        elif abs(theta) < period:  # a pocket in the mesh
            age = theta if centroid[1] > 0.0 else theta + TWO_PI
        else:
            age = theta % TWO_PI
        return k, age * scale


def _inner_edges(idx):
    """Edges of a run (from vertex i to i + 1) whose both ends are rotor vertices."""
    ok = idx >= 0
    return np.nonzero(ok[:-1] & ok[1:])[0]


def _inside(ring, pt) -> bool:
    """Even-odd point-in-polygon test."""
    x, y = ring[:, 0], ring[:, 1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    cond = (y > pt[1]) != (y2 > pt[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = x + (pt[1] - y) * (x2 - x) / (y2 - y)
    return bool(np.sum(cond & (pt[0] < xi)) % 2)


def _centroid(ring):
    x, y = ring[:, 0], ring[:, 1]
    x2, y2 = np.roll(x, -1), np.roll(y, -1)
    c = x * y2 - x2 * y
    a = 0.5 * c.sum()
    return np.array([((x + x2) * c).sum(), ((y + y2) * c).sum()]) / (6.0 * a)
