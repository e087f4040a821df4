"""The blow-hole: where a chamber's sealing lines leave a gap at a cusp of the bores.

A chamber is closed against its neighbours by the tip lines on the bores and the
interlobe contact line; the contact line ends short of the cusp line, and the male and
female tips cross the cusp at different places, so the curved triangle between the
contact line's end and the two tips' crossings is open (seed 004: "a space curved
triangle").  Its area depends on the surface chosen to span it.

Two planes through the cusp line are offered (``[machine] blow_hole``); in both the
area is the plane's fluid region next to the cusp line, between the male and the
female tip's crossings of the cusp (the triangle's two corners there).

``"cusp-plane"`` (default): the plane through both cusp lines, the one that splits
every section into its male and female grooves (:mod:`.regions`).  In a section where
the male groove and the female groove meeting at a cusp belong to different chambers
(one tip has passed the cusp, the other not yet), the segment of the cusp line from
the cusp point to the first rotor is the opening between those two chambers; its
width swept along the rotors is the area (:class:`..section.Opening`,
:attr:`..machine.SweptMachine.opening_areas`).  Every path from one chamber into the
other through the triangle crosses that plane (it is where the chambers are told
apart), so this cut is consistent with the chamber volumes by construction; it bounds
the narrowest section from above.

``"plane"``: seed 004's approximation, the plane through the cusp line and "the highest
point of the contact line", taken as the interlobe contact point nearest the cusp.  Its
region next to the cusp line is cut the same way, by a ray from the cusp towards that
point.  The ray stops at the first rotor, so where a lobe hides the contact point from
the cusp (the circular rack: the ray stops 12.7 mm out, the point is 17.3 mm away) the
region ends before it: seed 004's plane triangle is then no triangle, and what is
integrated is the plane's free region next to the cusp line.

Two constructions meet: the sections' Booleans book each cut to its two chambers
(:func:`openings_of`: which chambers, at the section nodes), and a ray along the cusp
line against the rotors' polygons gives the width at any angle (:class:`CuspRay`), so
the sweep integrates it without interpolating across its jumps (a lobe's rounded tip
reaching the cusp line cuts the segment short at once).  Which chambers the cut joins
changes only where a tip crosses the cusp, an angle known in closed form.

A pair with lands (the trochoidal pump profile) has a land on each cusp at every angle,
so its chambers meet across the cusp line away from the cusp points, in the pocket
between the flanks: :mod:`.flank_pocket` gives that cut's width and where it changes
hands (a corner crossing a cusp); the nodes' bookings are the same.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from ..planar import TWO_PI
from ..section import Opening
from .regions import FEMALE, MALE

#: The openings' names: at the bottom cusp, where the lobes go into mesh and the chambers
#: are compressed (seed 004's blow-hole), and at the top one, where they come apart
#: (between chambers filling, or just closed from suction).
NAMES = {False: "blow-hole", True: "blow-hole-suction"}
#: The ray's table (:class:`WidthTable`): samples per lobe period to start from, the
#: largest distance (per C) of a cell's midpoint from its chord (twice the polygons' chord
#: error: below it the refinement would chase their vertices), the narrowest cell
#: (rad: a jump's bracket), and the refinement rounds that allows (halving 2e-3 rad).
RAY_SAMPLES = 512
WIDTH_TOL = 2e-6
JUMP_XTOL = 1e-11
REFINE_ROUNDS = 40
#: Angles per batch of the ray (its arrays are angles x polygon edges), and the span
#: (rad) of a batch: a batch over a narrow span faces few edges (:meth:`CuspRay._facing`).
RAY_CHUNK = 128
RAY_SPAN = 0.05
#: Margin (rad) of an edge's polar window: rounding only (the edge's own span is added).
FACING_MARGIN = 1e-6
#: Share of a slot's nodes with an open cusp cut that must book it for the slot to open
#: (:func:`build_openings`): all do where the opening is the chamber's, one stray did.
MAJORITY = 0.5


def openings_of(parts, qs):
    """(chamber, name, offset of the chamber beyond, width) of every opening across the
    cusp plane at one section: a piece of fluid whose male and female parts both reach
    the cusp point and belong to different chambers."""
    by_piece = defaultdict(dict)
    for p, q in zip(parts, qs, strict=True):
        if p.cusp_cut > 0.0:
            by_piece[p.piece].setdefault(p.rotor, []).append((p, q))
    out = []
    for rotors in by_piece.values():
        if len(rotors.get(MALE, ())) != 1 or len(rotors.get(FEMALE, ())) != 1:
            continue
        (pm, qm), (pf, qf) = rotors[MALE][0], rotors[FEMALE][0]
        if qm == qf:
            continue
        # Both parts see the one cut, each from its side; their lengths agree to the
        # Boolean's rounding.
        width = 0.5 * (pm.cusp_cut + pf.cusp_cut)
        name = NAMES[pm.cusp_top]
        out.append((qm, name, qf - qm, width))
        out.append((qf, name, qm - qf, width))
    return out


class CuspRay:
    """The free length of the cusp line from a cusp point to the first rotor, at any
    male angle (the rotors' polygons sampled to the sections' tolerance)."""

    def __init__(self, pair):
        self.pair = pair
        self.xc, self.yc = pair.cusp
        g = pair.gearing
        self.ratio = g.lobes_male / g.lobes_female
        self.axes = (np.zeros(2), np.array([g.centre_distance, 0.0]))
        self.edges = []
        for r in (MALE, FEMALE):
            p = pair.cutter.profile_samples[r][1]
            q = np.roll(p, -1, axis=0)
            # Points of the cusp segment lie at least this far from the rotor's axis.
            reach = abs(self.xc - self.axes[r][0])
            near = np.maximum(np.linalg.norm(p, axis=-1), np.linalg.norm(q, axis=-1)) >= reach
            near |= np.roll(near, 1)
            p, q = p[near], q[near]
            # Each edge's polar angle (its middle's) and half the angle it spans: only
            # edges turned into the ray's angular window about this axis can cross it.
            mid = 0.5 * (p + q)
            polar = np.arctan2(mid[:, 1], mid[:, 0])
            span = 0.5 * np.linalg.norm(q - p, axis=-1) / np.linalg.norm(mid, axis=-1)
            self.edges.append((p, q, polar, span))

    def angle(self, r, psi):
        return psi if r == MALE else -self.ratio * psi

    def cusp_point(self, top: bool) -> np.ndarray:
        return np.array([self.xc, self.yc if top else -self.yc])

    def width(self, psi, top: bool, direction=None) -> np.ndarray:
        """Free length from the top (or bottom) cusp along ``direction`` (a unit vector
        into the bores; default along the cusp line) to the first rotor, per angle."""
        psi = np.atleast_1d(np.asarray(psi, dtype=float))
        # Angles x edges arrays: batches of angles within RAY_SPAN of each other, which
        # face few edges.
        bins = np.floor(psi / RAY_SPAN)
        if np.ptp(bins) > 0:
            out = np.empty(psi.shape)
            for b in np.unique(bins):
                sel = bins == b
                out[sel] = self.width(psi[sel], top, direction)
            return out
        if len(psi) > RAY_CHUNK:
            return np.concatenate([self.width(psi[i:i + RAY_CHUNK], top, direction)
                                   for i in range(0, len(psi), RAY_CHUNK)])
        d = np.array([0.0, -1.0 if top else 1.0]) if direction is None else direction
        n = np.array([-d[1], d[0]])
        c0 = self.cusp_point(top)
        best = np.full(psi.shape, 2.0 * self.yc)
        for r in (MALE, FEMALE):
            a, b = self._facing(r, psi, c0, d)
            ang = self.angle(r, psi)[:, None]
            c, s = np.cos(ang), np.sin(ang)
            o = self.axes[r] - c0
            # both ends of every edge in the ray's frame: along it (t) and across (h)
            xa = c * a[None, :, 0] - s * a[None, :, 1] + o[0]
            ya = s * a[None, :, 0] + c * a[None, :, 1] + o[1]
            xb = c * b[None, :, 0] - s * b[None, :, 1] + o[0]
            yb = s * b[None, :, 0] + c * b[None, :, 1] + o[1]
            ha, hb = xa * n[0] + ya * n[1], xb * n[0] + yb * n[1]
            ta, tb = xa * d[0] + ya * d[1], xb * d[0] + yb * d[1]
            cross = (ha * hb <= 0.0) & (ha != hb)
            with np.errstate(divide="ignore", invalid="ignore"):
                t = ta + (tb - ta) * ha / (ha - hb)
            t = np.where(cross & (t >= 0.0), t, np.inf)
            best = np.minimum(best, t.min(axis=1, initial=np.inf))
        return best


    def _facing(self, r, psi, c0, d):
        """Rotor r's edges that can cross the ray at any of the angles ``psi``: those
        whose polar angle about the rotor's axis, turned by the rotor's angle, falls
        within the polar angles the ray spans about that axis (the ray, a segment not
        through the axis, spans the angles between its ends'), with a margin."""
        p, q, polar, span = self.edges[r]
        ends = np.array([c0, c0 + 2.0 * self.yc * d]) - self.axes[r]
        seen = np.arctan2(ends[:, 1], ends[:, 0])
        centre = math.atan2(math.sin(seen[0]) + math.sin(seen[1]),
                            math.cos(seen[0]) + math.cos(seen[1]))
        half = 0.5 * abs(math.remainder(seen[1] - seen[0], TWO_PI))
        ang = self.angle(r, psi)
        lo, hi = float(ang.min()), float(ang.max())
        # polar + ang within centre +- half for some ang in [lo, hi]
        off = np.abs(np.remainder(polar + 0.5 * (lo + hi) - centre + math.pi, TWO_PI)
                     - math.pi)
        keep = off <= half + 0.5 * (hi - lo) + span + FACING_MARGIN
        return p[keep], q[keep]


class WidthTable:
    """The ray's width over one lobe period (it repeats), linear between samples that
    are refined until every cell's midpoint lies within WIDTH_TOL of the chord.  So the
    jumps (a lobe reaching the ray cuts it short at once) end up between two samples
    JUMP_XTOL apart, and the square-root fall after them (the rounded tip closing on
    the cusp) is followed as closely as the smooth parts."""

    def __init__(self, ray: CuspRay, top: bool, direction=None):
        period = TWO_PI / ray.pair.gearing.lobes_male
        self.period = period
        tol = WIDTH_TOL * ray.pair.gearing.centre_distance
        x = np.linspace(0.0, period, RAY_SAMPLES + 1)
        w = ray.width(x, top, direction)
        xs, ws = [x], [w]
        lo, hi, wlo, whi = x[:-1], x[1:], w[:-1], w[1:]  # the cells still to test
        for _ in range(REFINE_ROUNDS):
            wide = hi - lo > JUMP_XTOL
            lo, hi, wlo, whi = lo[wide], hi[wide], wlo[wide], whi[wide]
            if not len(lo):
                break
            mid = 0.5 * (lo + hi)
            wm = ray.width(mid, top, direction)
            bad = np.abs(wm - 0.5 * (wlo + whi)) > tol
            xs.append(mid[bad])
            ws.append(wm[bad])
            lo, hi = np.concatenate([lo[bad], mid[bad]]), np.concatenate([mid[bad], hi[bad]])
            wlo, whi = (np.concatenate([wlo[bad], wm[bad]]),
                        np.concatenate([wm[bad], whi[bad]]))
        x, w = np.concatenate(xs), np.concatenate(ws)
        order = np.argsort(x, kind="stable")
        x, w = x[order], w[order]
        self.x, self.w = x, w

    def __call__(self, psi) -> np.ndarray:
        return np.interp(np.mod(psi, self.period), self.x, self.w)

    def breakpoints(self, a: float, b: float) -> np.ndarray:
        """The samples' angles in [a, b] (all periods)."""
        k0, k1 = math.floor(a / self.period), math.ceil(b / self.period)
        x = (self.x[None, :] + self.period * np.arange(k0, k1 + 1)[:, None]).ravel()
        return x[(x >= a) & (x <= b)]


def tip_crossings(pair, a: float, b: float, top: bool) -> np.ndarray:
    """Male angles in [a, b] where a tip of either rotor crosses the top (or bottom)
    cusp, and where a one-lobe rotor's tip crosses the other cusp: its one groove
    reaches both cusps, so which chambers meet at this cusp changes there too.  (The
    1-1 pumps' blow-holes were booked over whole slots between this cusp's crossings,
    of which the chamber's own were the latter halves: their areas' integrals held half
    a slot of the ray's width inside one chamber's groove, and at 4 k + 1 points per
    period the halves' nodes fell one short of MAJORITY and no blow-hole was booked.)"""
    out = cusp_crossings(pair, a, b, {r: [pair.tip_angle(r)] for r in (MALE, FEMALE)}, (top,))
    g = pair.gearing
    single = {r: [pair.tip_angle(r)] for r, n in ((MALE, g.lobes_male),
                                                  (FEMALE, g.lobes_female)) if n == 1}
    if single:
        out = np.concatenate([out, cusp_crossings(pair, a, b, {MALE: [], FEMALE: [], **single},
                                                  (not top,))])
    return np.unique(out)


def cusp_crossings(pair, a: float, b: float, angles: dict, tops) -> np.ndarray:
    """Male angles in [a, b] where a point of a rotor at one of its polar angles
    ``angles[rotor]`` (rotor frame) crosses a cusp (``tops``: True the top one).  A
    rotor point's angle is linear in the male angle (the male turns +1, the female
    -N1/N2), so its crossings repeat every lobe period."""
    g = pair.gearing
    xc, yc = pair.cusp
    period = TWO_PI / g.lobes_male
    ratio = g.lobes_male / g.lobes_female
    out = []
    for rotor, axis_x, rate in ((MALE, 0.0, 1.0), (FEMALE, g.centre_distance, -ratio)):
        for top in tops:
            seen = math.atan2(yc if top else -yc, xc - axis_x)
            for angle in angles[rotor]:
                c = (seen - angle) / rate
                first = c + period * math.ceil((a - c) / period)
                out.extend(np.arange(first, b, period))
    return np.array(out)


def build_openings(pair, psi, per_node, tracks=()) -> tuple[Opening, ...]:
    """The chamber's openings: the nodes' bookings (name, offset, width) give which
    chamber lies beyond between two tip crossings; the ray gives the width, along the
    cusp line or, with ``pair.blow_hole == "plane"``, towards the contact line's point
    nearest the cusp (seed 004's plane, found among the interlobe ``tracks``)."""
    # Lands cover the cusps: the opening is the flank pocket's cut, which changes
    # hands where a corner crosses a cusp (:mod:`.flank_pocket`, built on CuspRay:
    # imported here).
    from .flank_pocket import PocketRay, corner_crossings

    lands = pair.has_lands
    ray = PocketRay(pair) if lands else CuspRay(pair)
    booked = defaultdict(set)
    for i, items in enumerate(per_node):
        for name, offset, _ in items:
            booked[name].add((i, offset))
    out = []
    for name in sorted(booked):
        top = name == NAMES[True]
        cross = (corner_crossings(pair, psi[0], psi[-1]) if lands
                 else tip_crossings(pair, psi[0], psi[-1], top))
        events = np.concatenate([[psi[0]], cross, [psi[-1]]])
        slot = np.searchsorted(events, psi, side="right") - 1
        votes = defaultdict(lambda: defaultdict(int))
        for i, offset in booked[name]:
            votes[int(slot[i])][offset] += 1
        direction = None
        if pair.blow_hole == "plane":
            direction = _towards_contact(ray.cusp_point(top), tracks)
        table = WidthTable(ray, top, direction)
        open_ = table(psi) > 0.0
        by_offset = defaultdict(list)
        for k, counts in votes.items():
            # A slot whose nodes with an opening mostly book none (or that has none
            # open) is no opening of this chamber: the node right after a corner
            # crossing can still see the last of the pocket that just changed hands
            # (the 1-1 trochoidal at 768 nodes per period booked such a node's whole
            # slot, doubling its blow-hole; the pin-cycloid 4/6 from 384 gained stray
            # 0.001 mm2 keys, the 2-2 trochoidal at 1536 empty ones).
            n_open = np.count_nonzero(open_ & (slot == k))
            if n_open == 0 or sum(counts.values()) < MAJORITY * n_open:
                continue
            offset = max(counts, key=counts.get)
            by_offset[offset].append((events[k], events[k + 1]))
        for offset in sorted(by_offset):
            out.append(Opening(name, offset, np.array(sorted(by_offset[offset])), table))
    return tuple(out)


def _towards_contact(cusp, tracks) -> np.ndarray | None:
    """Unit vector from the cusp to the nearest point of the interlobe contact line (the
    contact line's "highest point" of seed 004), from the section tracks' points."""
    pts = [t.points[t.present] for t in tracks if t.kind == "interlobe"]
    pts = np.concatenate(pts) if pts else np.zeros((0, 2))
    if not len(pts):
        return None
    v = pts[int(np.argmin(np.linalg.norm(pts - cusp, axis=-1)))] - cusp
    return v / np.linalg.norm(v)
