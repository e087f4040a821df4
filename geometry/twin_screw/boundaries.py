"""Walking the boundary of a fluid part of a twin-screw section (see :mod:`.regions`).

Every edge of a part's polygon lies on the male, the female, a bore or the cusp line;
runs of edges on one rotor are the rotor's wetted arcs.  Their ends are snapped to the
true curves (a tip to the lobe's tip point, a contact to the point where the law of
gearing holds), their slivers between chord and curve added to the area, and each
arc's load per unit pressure is its ends' (force rot(b - a), torque
-1/2 (|b - O|^2 - |a - O|^2)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..planar import TWO_PI
from .tip_bands import TipBands

#: Edge-classification tolerance per C: a boundary edge within this of a bore circle
#: or of the cusp line lies on it (a few chord errors; nothing else comes that close
#: except the rotor flanks next to a tip, whose ends are snapped anyway).
ON_TOL = 5e-6
#: A fluid vertex within this (per C) of a rotor polygon's vertex is that vertex (Clipper
#: rounds to 1e-11 C; new intersection vertices are farther from every old one).
SAME_VERTEX = 1e-9
#: A fluid corner at a contact is the end of the overlap lens within this (per C): along
#: a conformal band (a female tip rolling in a male root) the grown chords can cross
#: a little away from where the lens's Boolean put its end.
LENS_MATCH = 2e-3

#: A cut at the cusp this near a tip (per C) ends at the tip: where the grown rotor
#: overlaps its bore, the part on one side ends its arc at the bore (the tip) and the
#: other at the cusp line.  A rounded tip's lens (up to ~0.2 mm at C = 78 mm) is
#: TIP_BAND's; this takes a cut end that is the tip up to 8 um at C = 80 mm.  It was
#: 5e-3 (0.4 mm): then a cut end that far from a tip moved to it, and the rotor's arc
#: between them to the part across the cusp line, a jump in both parts' loads 0.008
#: rad (male) or 0.012 rad (female) off the tip's passage (seed 004's 4/6 pairs).
TIP_MATCH = 1e-4
#: The same for a land's corner or the cusp point it passes (:meth:`Boundaries._snap_land`).
LAND_MATCH = 5e-3

#: A cut along the cusp line ending this near (per C) a cusp point starts there: the
#: bores' polygons meet within a chord error (1e-6 C) of the true cusp.
CUSP_POINT = 5e-5

MALE, FEMALE, BORE_M, BORE_F, CUSP, NEW = 0, 1, 2, 3, 4, -1


def turning_rate(gearing, rotor: int, point: np.ndarray) -> np.ndarray:
    """d point / d psi of a point turning with ``rotor`` (psi the male angle): its speed
    ratio times J (point - axis), the female turning back at N_male / N_female."""
    axis = np.zeros(2) if rotor == MALE else gearing.female_axis
    w = 1.0 if rotor == MALE else -gearing.lobes_male / gearing.lobes_female
    rel = point - axis
    return w * np.array([-rel[1], rel[0]])


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


def _key(x, scale):
    return (round(x[0] / (SAME_VERTEX * scale)), round(x[1] / (SAME_VERTEX * scale)))


def _inner_edges(idx):
    """Edges of a run (from vertex i to i + 1) whose both ends are rotor vertices."""
    ok = idx >= 0
    return np.nonzero(ok[:-1] & ok[1:])[0]



class Boundaries(TipBands):
    """The boundary methods of :class:`.regions.SectionCutter` (a mixin: it needs the
    cutter's rotors, bores, cusp line and unit scale)."""

    # ------------------------------------------------------------ boundaries
    def _labels(self, rings, psi):
        """Per ring of ``rings``: (label per edge, index in its rotor polygon or -1 per
        vertex).  All rings of a section at once (numpy's cost is per call, not per
        vertex): each vertex's successor is the next in its own ring."""
        tol = ON_TOL * self.C
        ring = np.concatenate(rings)
        n = len(ring)
        ends = np.cumsum([len(q) for q in rings])
        starts = ends - [len(q) for q in rings]
        after = np.arange(1, n + 1)
        after[ends - 1] = starts
        vlab = np.full(n, NEW)
        vidx = np.full(n, -1)
        todo = np.arange(n)  # (the female is asked only for what the male is not)
        for r in (MALE, FEMALE):
            d, k = self._same_vertex(r, self.to_rotor(r, ring[todo], psi))
            hit = d < SAME_VERTEX * self.C
            vlab[todo[hit]], vidx[todo[hit]] = r, k[hit]
            todo = todo[~hit]
        # A bore bounds the fluid only on the union's boundary: a corner on one bore's
        # circle inside the other bore is not the bore's.  A rotor's tip lies on its own
        # bore, so the corners of the pockets along a conformal band (the circular 4/6
        # female tip rolling in the male root, inside the male bore) lie on the female's
        # circle too; taken for bore corners, the female chord between two of them was
        # an arc of the bore and the male run's ends snapped to male tips: at psi 0.7887
        # three such pockets booked no load (1.1e-3 of the largest part's force left on
        # each rotor), at 0.7890 one booked a whole male groove's (the net force ~ it).
        dist = [np.linalg.norm(ring - o, axis=-1) - rad for o, rad in zip(self.O, self.R,
                                                                        strict=True)]
        for r, code in ((MALE, BORE_M), (FEMALE, BORE_F)):
            on = (np.abs(dist[r]) < tol) & (dist[1 - r] > -tol)
            vlab[on & (vlab == NEW)] = code
        nxt = vlab[after]
        ahead = ring[after]
        on_cusp = (np.abs(ring[:, 0] - self.xc) < tol) & (np.abs(ahead[:, 0] - self.xc) < tol)
        rotor_end = np.where(vlab <= FEMALE, vlab, np.where(nxt <= FEMALE, nxt, NEW))
        rotor_end[(vlab <= FEMALE) & (nxt <= FEMALE) & (vlab != nxt) & (vlab >= 0)] = NEW
        elab = np.where(rotor_end >= 0, rotor_end, np.where(vlab == nxt, vlab, NEW))
        chord = (vlab == nxt) & (vlab <= FEMALE) & (vlab >= 0)
        # A rotor's chord that runs within the tolerance of the cusp line (a flank
        # nearly parallel to it) ends where the line cuts it, at a new vertex on that
        # chord: up to there it is the rotor's, or both sides of the line lose a piece of
        # it (microns, where the flank is nearly parallel to the line).
        for r in (MALE, FEMALE):
            for cut, new in ((on_cusp & ~chord & (vlab == r) & (nxt == NEW), ahead),
                             (on_cusp & ~chord & (nxt == r) & (vlab == NEW), ring)):
                if cut.any():
                    d = self._segment_distance(r, self.to_rotor(r, new[cut], psi))
                    chord[np.nonzero(cut)[0][d < SAME_VERTEX * self.C]] = True
        elab[on_cusp & ~chord] = CUSP
        # An edge between two corners on bores is a bore's arc only if it runs on the
        # union's boundary, never through the lens inside both bores: a rotor's chord
        # lying on its own bore (the pin-cycloid female's land, sampled in chords 0.18
        # mm long) joins two new corners on the bores where the land crosses the lens,
        # from its contact with the male to the cusp, 0.0052 rad before the male tip
        # reaches the top cusp; taken for the bore, the female arc from the contact to
        # its tip was nobody's (29 % of the largest part's force left over).
        mid = 0.5 * (ring + ahead)
        dm, df = (np.linalg.norm(mid - o, axis=-1) - r for o, r in zip(self.O, self.R,
                                                                        strict=True))
        union = ((np.abs(dm) < tol) & (df > -tol)) | ((np.abs(df) < tol) & (dm > -tol))
        bore = (elab == NEW) & (vlab >= BORE_M) & (vlab <= BORE_F) \
            & (nxt >= BORE_M) & (nxt <= BORE_F) & union
        elab[bore] = np.where(np.linalg.norm(ring[bore] - self.O[0], axis=-1) < self.R[0] + tol,
                              BORE_M, BORE_F)
        rest = elab == NEW
        if rest.any():
            # An edge between two new corners (a cusp-line cut and a contact, say) lies
            # on whichever rotor's chords pass through its middle.
            mid = 0.5 * (ring[rest] + ahead[rest])
            d = [self._segment_distance(r, self.to_rotor(r, mid, psi)) for r in (MALE, FEMALE)]
            elab[rest] = np.where(d[0] <= d[1], MALE, FEMALE)
        return [(elab[a:b], vidx[a:b]) for a, b in zip(starts, ends, strict=True)]

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

    def _walk(self, ring, labels, psi, part) -> None:
        """Add the loads, wetted lengths, tips and contacts of one boundary ring (its
        :meth:`_labels`), and the curves' slivers to the part's polygon area."""
        lab, vidx = labels
        change = np.nonzero(lab != np.concatenate([lab[-1:], lab[:-1]]))[0]
        if not len(change):
            return
        # (the ring from its first change of label on; slices, not np.roll: a ring's
        # few dozen vertices cost numpy's calls, not its arithmetic)
        start = int(change[0])
        lab = np.concatenate([lab[start:], lab[:start]])
        vidx = np.concatenate([vidx[start:], vidx[:start]])
        v = np.concatenate([ring[start:], ring[:start]])
        d = np.diff(v, axis=0, append=v[:1])
        edges = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
        cuts = (change - start).tolist() + [len(lab)]
        n = len(lab)
        for i0, i1 in zip(cuts[:-1], cuts[1:], strict=False):
            r = int(lab[i0])
            if r in (BORE_M, BORE_F):
                o, rad = self.O[r - BORE_M], self.R[r - BORE_M]
                half = np.clip(edges[i0:i1] / (2.0 * rad), 0.0, 1.0)
                th = 2.0 * np.arcsin(half)
                part.area += float(np.sum(0.5 * rad * rad * (th - np.sin(th))))
                del o
                continue
            if r == CUSP:
                self._cusp_cut(v[i0], v[i1 % n], float(edges[i0:i1].sum()), part)
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

    def _tips_at(self, r, psi):
        """Rotor r's tip points at male angle psi, fixed frame (kept for the last psi:
        every run's ends ask)."""
        held = self.__dict__.get("_tips_held")
        if held is None or held[0] != psi:
            tips = [self.rotor_at(q, self._rotor_data[q].tips, psi) for q in (0, 1)]
            for t in tips:
                t.flags.writeable = False  # (shared by the parts' tips)
            held = self._tips_held = (psi, tips)
        return held[1][r]

    def _cusp_cut(self, a, b, length, part) -> None:
        """A run along the cusp line that starts or ends at a cusp point is the part's
        opening across the cusp plane there (the blow-hole's section, :mod:`.blowhole`)."""
        tol = CUSP_POINT * self.C
        at_cusp = False
        for y in (self.yc, -self.yc):
            if min(abs(a[1] - y), abs(b[1] - y)) < tol:
                part.cusp_cut += length
                part.cusp_top = y > 0.0
                at_cusp = True
        if not at_cusp and any(self._lands):
            # Lands cover the cusps: the chambers meet across the cusp line in the
            # pocket between the flanks (:mod:`.flank_pocket`), named by its side.
            part.cusp_cut += length
            part.cusp_top = a[1] + b[1] > 0.0

    def _run_true(self, r, idx, chords):
        """(area to add to the polygon's, true length) of a run along rotor r whose
        vertices have rotor-polygon indices ``idx`` (-1: a new vertex at an end)."""
        rd = self._rotor_data[r]
        m = len(rd.polygon)
        k = idx[idx >= 0]
        length = float(chords.sum())
        area = self.grow * length  # the polygon runs along the grown rotor
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

    def _snap_tip(self, r, x, neighbour, psi, part):
        """The end of rotor r's wetted arc at polygon vertex x where it meets a bore (the
        lobe's tip point); None where it meets the other rotor (a contact, resolved per
        overlap by :meth:`_contacts`); x itself where it meets the cusp line."""
        if self._lands[r]:
            return self._snap_land(r, x, neighbour, psi, part)
        if neighbour in (BORE_M, BORE_F):
            tips = self._tips_at(r, psi)
            k = self._tip_of(r, x, tips)
            part.tips.append((r, k, tips[k]))
            return tips[k]
        if neighbour in (MALE, FEMALE) and neighbour != r:
            return (None, x)
        if neighbour == CUSP:
            # A tip passing the cusp: the bore and the cusp line meet there, and the part
            # on one side may end its arc at the bore (snapped to the tip) while the
            # other ends it at the cusp line a lens's length away.  Both take the tip.
            tips = self._tips_at(r, psi)
            d = np.linalg.norm(tips - x, axis=-1)
            k = int(np.argmin(d))
            if d[k] < TIP_MATCH * self.C or self._in_tip_band(r, k, x, psi):
                return tips[k]
        return x

    def _tip_of(self, r, x, tips) -> int:
        """The lobe of rotor r at whose top the bore end x lies (``tips``: the tip
        points, fixed frame): the nearest tip point, or where the lobe's largest radius
        is an arc (the pin-cycloid female's land, its tip point the clockwise end:
        :attr:`.TwinScrewPair.tip_spans`) the nearest such arc.  A groove meets the bore
        at both ends of a land, and the nearest tip point to its corner at the far end
        is the next lobe's where the land is wider than half a lobe (38.5 of 72 deg on
        the 3/5, 53.7 of 90 on the 3/4): both ends of the groove's arc took that tip,
        which booked no load for a groove cut in the mesh, where a whole one books its
        two tips' (a female groove's force left over at uniform pressure), and its tip
        lines were lost."""
        span = self.pair.tip_spans[r]
        if span == 0.0:
            return int(np.argmin(np.linalg.norm(tips - x, axis=-1)))
        o = self.O[r]
        t = np.arctan2(tips[:, 1] - o[1], tips[:, 0] - o[0])
        # x's angle from each arc's middle, less the arc's half-width: 0 on the arc
        off = np.remainder(math.atan2(x[1] - o[1], x[0] - o[0]) - t - 0.5 * span + math.pi,
                           TWO_PI) - math.pi
        return int(np.argmin(np.maximum(np.abs(off) - 0.5 * span, 0.0)))

    def _snap_land(self, r, x, neighbour, psi, part):
        """:meth:`_snap_tip` on a rotor with lands (arcs on its bore, :meth:`.TwinScrewPair
        ._land`).  A groove meets its bore at a land's corner (its sealing point, booked as
        the lobe's tip), a land crossing the cusp meets the other bore at the cusp point.
        Beyond either lies a gap, the land's arc on its own bore, whose pressure falls from
        one side's to the other's: each side loads it up to its middle (uniform pressure
        then loads the rotor all round, as a tip point's rotor is; a land's arc about the
        axis has no torque, so the shaft power is the same either way)."""
        if neighbour in (MALE, FEMALE):
            return (None, x) if neighbour != r else x
        corners = self.rotor_at(r, self._rotor_data[r].corners, psi)
        d = np.linalg.norm(corners - x, axis=-1)
        j = int(np.argmin(d))
        cusps = np.array([[self.xc, self.yc], [self.xc, -self.yc]])
        dc = np.linalg.norm(cusps - x, axis=-1)
        i = int(np.argmin(dc))
        if neighbour == CUSP:
            if min(d[j], dc[i]) > LAND_MATCH * self.C:
                return x
            return cusps[i] if dc[i] < d[j] else corners[j]
        end = cusps[i] if dc[i] < d[j] else corners[j]
        if dc[i] >= d[j]:
            part.corners.append((r, j, corners[j]))
        return self.gap_middle(r, end, j // 2, psi)

    def gap_middle(self, r, end, lobe, psi):
        """The middle of the gap (lobe ``lobe``'s land on rotor r's own bore, outside the
        other bore) that begins at ``end``, a corner or a cusp point (fixed frame)."""
        o = self.O[r]
        lo, hi = self._rotor_data[r].corners[2 * lobe:2 * lobe + 2]
        turn = psi if r == MALE else self.female_angle(psi)
        ta = math.atan2(lo[1], lo[0]) + turn
        span = math.remainder(math.atan2(hi[1], hi[0]) - math.atan2(lo[1], lo[0]),
                              2.0 * math.pi) % (2.0 * math.pi)
        gamma = self._cusp_angle[r]
        towards = 0.0 if r == MALE else math.pi  # the other axis, from this one
        cuts = [0.0, span]
        for c in (towards - gamma, towards + gamma):
            off = (c - ta) % (2.0 * math.pi)
            if 0.0 < off < span:
                cuts.append(off)
        cuts.sort()
        e = math.atan2(end[1] - o[1], end[0] - o[0])
        k = int(np.argmin([abs(math.remainder(ta + c - e, 2.0 * math.pi)) for c in cuts]))
        for a, b in ((cuts[k], cuts[min(k + 1, len(cuts) - 1)]),
                     (cuts[max(k - 1, 0)], cuts[k])):
            mid = ta + 0.5 * (a + b)
            if b > a and abs(math.remainder(mid - towards, 2.0 * math.pi)) > gamma:
                return o + self.R[r] * np.array([math.cos(mid), math.sin(mid)])
        return end  # no gap beside it (the land lies in the lens there)

    @cached_property
    def _lands(self) -> tuple[bool, bool]:
        pair = self.pair
        return tuple(pair._land(p) is not None for p in (pair.male, pair.female))

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
                d, k = self._same_vertex(MALE, self.to_rotor(MALE, ring, psi))
                on = d < SAME_VERTEX * self.C
                ends = ring[~on & (self._female_distance(ring, psi) > SAME_VERTEX * self.C)]
                if not len(ends):
                    continue
                idx = np.sort(k[on])
                if len(idx) >= 2:
                    gap = np.diff(np.append(idx, idx[0] + m))
                    j = int(np.argmax(gap))  # the lens's male arc is the complement
                    lo, hi = idx[(j + 1) % len(idx)], idx[j]
                    c = self.pair.contact_between(rd.u, lo, hi, psi)
                else:
                    c = self.pair.contact_near(ends.mean(0), psi)
                for e in ends:
                    by_point[_key(e, self.C)] = (e, c)
        known = list(by_point.values())
        pts = np.array([e for e, _ in known]) if known else np.zeros((0, 2))
        resolved = []
        for q in self._runs:
            for which in ("a", "b"):
                end = getattr(q, which)
                if isinstance(end, tuple):
                    # The fluid's corner is the lens's end up to Clipper's separate
                    # rounding of the two Booleans (and, along a conformal band, the
                    # chords' crossings): the nearest lens end within LENS_MATCH.
                    d = np.linalg.norm(pts - end[1], axis=-1) if len(pts) else np.inf
                    j = int(np.argmin(d)) if len(pts) else -1
                    if j >= 0 and d[j] < LENS_MATCH * self.C:
                        c, rate = known[j][1]
                    else:
                        c, rate = self.pair.contact_near(end[1], psi)
                    setattr(q, which, c)
                    resolved.append((q, which))
                    if not any(c is d for d in q.part.contacts):
                        q.part.contacts.append(c)
                        q.part.contact_rates.append(rate)
        self._close_bands(resolved, psi)

    def _female_distance(self, pts, psi):
        return self._same_vertex(FEMALE, self.to_rotor(FEMALE, pts, psi))[0]

    def _same_vertex(self, r, x):
        """(distance, index) of rotor r's polygon vertex nearest each point of x (own
        frame), looked for only within SAME_VERTEX (elsewhere inf and an index past the
        end): a bounded search prunes the tree, three times faster."""
        return self._rotor_data[r].tree.query(x, distance_upper_bound=2.0 * SAME_VERTEX * self.C)

    def _loads(self) -> None:
        for q in self._runs:
            d = q.b - q.a
            q.part.force[q.rotor] += (d[1], -d[0])
            o = self.O[q.rotor]
            q.part.torque[q.rotor] += -0.5 * (np.sum((q.b - o) ** 2) - np.sum((q.a - o) ** 2))

