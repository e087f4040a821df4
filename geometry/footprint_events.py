"""Slivers born and dying, and pockets handed over, between two sampled sections (the
events of :mod:`.footprint`), found by moving a section's rotor pieces rigidly.

A ring of a section with no piece matched at the neighbouring sample came or went in
between.  Moved rigidly towards that sample (each rotor vertex turned about its axis,
the still vertices kept), its area falls: where it falls to nearly nothing and the
median gap of a rotor piece to the rest of the ring changes sign, a sliver closes
there; where the area is least inside the step, a pocket was handed over there.  A
sliver's passage is swept per vertex, each from where its own surfaces touch (a sliver
may open along its length over a while; :mod:`.footprint_gaps`); a pocket's, rigidly
from the least area on.

A corner whose path turns between two samples (a chamber's tip, running along the
contact path, reaching a cut line and then sliding up it) is no event of a ring, but
the bands' smooth corner paths cut off the turn: there more samples are cut, homed in
on the turn (:meth:`Events._turns`).
"""

from __future__ import annotations

import math

import numpy as np

from .footprint_gaps import BIRTH_ROUNDS, EVENT_SCAN, Gaps
from .planar import cross
from .surfaces import area as _area
from .surfaces import turn as _turn

#: How far (reference angle, rad) a sliver's birth is looked for behind the sample that
#: first holds it (its death ahead of the last), at least two steps: the samples of its
#: first 0.2 deg hold none of it (THIN).
EVENT_REACH = 0.02
#: A ring whose area, its rotor pieces moved rigidly, falls to this fraction of its own
#: within the search closes there (a sliver's birth or death is looked for up to the
#: least area after that).
CLOSING = 0.05
#: A corner's path over a step turns (:func:`_turning`) where the parabolas through the
#: step and the sample before, and through the step and the sample after, put its
#: midpoint farther apart than this fraction of its chord (on a smooth path they agree
#: to third order in the step).
SMOOTH = 0.05
#: Samples cut at most to home in on a corner's turn (:meth:`Events._home`), and the
#: triangle (per centre distance squared) the turn may leave uncut.
TURNS = 4
TURN_AREA = 1e-7
#: A piece's end that grows (or shrinks) along its surface by this many times more than
#: in the steps before and after, and by more than JUMP_MIN of the profile's parameter
#: (a profile segment spans 1), jumped (:meth:`Events._jumps`).
JUMP = 4.0
JUMP_MIN = 0.05


class Events(Gaps):
    """The event methods of :class:`.footprint.Sweeper` (a mixin: it needs the sweeper's
    ``surfaces``)."""

    def _event(self, smp, ring_index, h, sign):
        """(|dpsi|, kind, reach) of the event of ring ``ring_index`` of sample ``smp``
        within h in the direction ``sign`` (-1: back to a birth, +1: on to a death),
        found by moving its rotor vertices rigidly: "sliver" where a rotor piece's
        signed gap to the rest of the ring vanishes (or, the ring's area not falling,
        bottoms out: :meth:`_closing_gap`), "pocket" where the ring's area is least;
        None.  ``reach``: how far the ring's own vertices' gaps are looked for
        (:meth:`_births`), to where its area, moved rigidly, is least."""
        ring, cls = smp.rings[ring_index]
        a0 = _area(ring)
        orient = 1.0 if a0 > 0.0 else -1.0
        # A sliver is looked for beyond the step: the samples right after its birth
        # hold none of it (THIN).  The ring's area, cheap, brackets where it closes:
        # from the sample to just past its least area after it falls to CLOSING
        # (where the pieces, moved on through each other, part again); the median gap
        # of its rotor pieces then tells a sliver.  Not from where it falls only: a
        # pocket between two contacts closes in its middle first, while it still has
        # a sixth of its area (the circular 4/6 pair's pocket born 116.2 deg after the
        # chamber, seen from 117.2 deg at 96 steps per period: its gap closes 0.55 deg
        # back, its area falls below CLOSING 0.94 deg back; the birth was missed, and
        # all it swept, 1.4e-3 of the largest discharge area).
        reach = max(2.0 * h, EVENT_REACH)
        ds = np.linspace(0.0, reach, int(math.ceil(EVENT_SCAN * reach / h)) + 1)
        areas = np.array([_area(self._moved(ring, cls, sign * d)) for d in ds]) * orient
        drop = np.nonzero(areas <= CLOSING * areas[0])[0]
        if len(drop):
            j = drop[0]
            while j + 1 < len(ds) and areas[j + 1] < areas[j]:
                j += 1
            hi = ds[min(j + 1, len(ds) - 1)]
            d = self._closing_gap(ring, cls, np.linspace(0.0, hi, 2 * (j + 1) + 1), sign,
                                  orient)
            if d is not None:
                return d, "sliver", max(float(hi), 2.0 * d)
        else:
            # A pocket between two contacts that converge closes as a sliver does, but
            # its rigidly moved area need not fall: the chords that close the ring join
            # pieces' ends that move apart, and soon span more than the pocket (the
            # pin-cycloid's pocket at the top cusp 10.0 rad after its chamber's birth
            # falls to a tenth at least, while its male piece's median gap closes 0.02
            # rad on).  Taken for a pocket handed over, it was swept only to that least
            # area, and only within the step: its last 0.01 rad, a film under a
            # micrometre crossing 0.13 mm2 near the cusp, went unswept by the finer
            # sweeps (docs/twin_screw.md, session 32).
            d = self._closing_gap(ring, cls, np.linspace(0.0, reach, 2 * EVENT_SCAN + 1),
                                  sign, orient, touching=True)
            if d is not None:
                least = float(ds[int(np.argmin(np.abs(areas)))])
                return d, "sliver", max(least, 2.0 * d)
        areas = np.abs(areas[ds <= h * (1.0 + 1e-12)])
        i = int(np.argmin(areas))
        if 0 < i < len(areas) - 1:
            from .scalar import minimum

            d, _ = minimum(lambda x: abs(_area(self._moved(ring, cls, sign * x))),
                           float(ds[i - 1]), float(ds[i + 1]), xtol=1e-9)
            return d, "pocket", d
        return None

    def _closing_gap(self, ring, cls, ds, sign, orient, touching=False):
        """The first move (of ``ds``, towards ``sign``) at which a rotor piece's median
        gap to the rest of the ring closes, interpolated between the moves; None.
        (Roughly: each vertex's own birth is found where it is swept, :meth:`_births`.)
        With ``touching``, a gap that bottoms out inside the scan below CLOSING of its
        own, without closing, touches at its least: conformal arcs (the circular pair's,
        ~116 deg after its chamber's birth) part from touching, and with polygons 16
        times finer their grown overlap no longer makes the gap cross (it bottoms out at
        0.03 um of 1 um), so their sliver's birth was not found at all."""
        least = None
        for k in sorted(set(cls[cls >= 0].tolist())):
            gaps = [self._gap(ring, cls, k, sign * d, orient) for d in ds]
            for i in range(1, len(ds)):
                if gaps[i] <= 0.0 < gaps[i - 1]:
                    w = gaps[i - 1] / (gaps[i - 1] - gaps[i])
                    return float(ds[i - 1] + w * (ds[i] - ds[i - 1]))
            i = int(np.argmin(gaps))
            if touching and 0 < i < len(ds) - 1 and gaps[i] <= CLOSING * gaps[0] and (
                    least is None or ds[i] < least):
                least = float(ds[i])
        return least

    def _moved(self, ring, cls, dpsi):
        q = ring.copy()
        for k in range(len(self.surfaces.rotors)):
            on = cls == k
            q[on] = self.surfaces.move(ring[on], k, dpsi)
        return q

    def _jumps(self, bands):
        """Bands of what a corner's jump exposed or covered between two samples (the
        bands' (piece at a, piece at b, psi_a, psi_b, sample a, sample b)).

        Where two rotor surfaces part along a stretch at once (the circular pair's
        conformal arcs, 148 deg after its chamber's birth) the new sliver is joined to
        a ring that has matched pieces, so no sliver event is seen: the pieces' end
        jumps along the surface, and the band's chord between the two ends misses what
        the stretch passed after it parted.  An end whose growth (in profile parameter)
        is JUMP times its growth in the steps before and after, per angle (a short step
        next to a turn's sample, :meth:`_turns`, grows little), is such a jump: each
        vertex of the stretch is swept from where its own gap closes (:meth:`_closing`),
        as a sliver's."""
        before = {id(y): k for k, (x, y, *_r) in enumerate(bands)}
        after = {id(x): k for k, (x, y, *_r) in enumerate(bands)}
        growth = [self._growth(x, y) for x, y, *_r in bands]
        rate = [np.abs(g[:2]) / (t1 - t0) for g, (_, _, t0, t1, *_r) in zip(growth, bands,
                                                                              strict=True)]
        out = []
        for k, (x, y, *_r) in enumerate(bands):
            near = [j for j in (before.get(id(x)), after.get(id(y))) if j is not None]
            for end in (0, 1):
                g = growth[k][end]
                if near and abs(g) > JUMP_MIN and rate[k][end] > JUMP * max(
                        rate[j][end] for j in near):
                    out += self._exposed(bands[k], end, g > 0.0)
        return out

    def _growth(self, x, y):
        """(at lo, at hi): how far the piece at b reaches beyond the piece at a in
        profile parameter (negative: short of it), and the shift that aligns them."""
        n = self.periods[x.rotor]
        s = next((s for s in (0.0, -n, n) if x.lo <= y.hi + s and y.lo + s <= x.hi), 0.0)
        return x.lo - (y.lo + s), (y.hi + s) - x.hi, s

    def _exposed(self, band, end, grew):
        """The band a jumped end's stretch passes: the stretch at b that was not on
        the boundary at a, back to where each of its vertices came apart from the other
        surface (``grew``), or the stretch at a that is not at b, on to where each
        closes."""
        from .footprint import ring_section

        x, y, t0, t1, a, b = band
        s = self._growth(x, y)[2]
        if grew:
            chain, smp, sign, par, lo, hi = y, b, -1.0, y.par + s, x.lo, x.hi
        else:
            chain, smp, sign, par, lo, hi = x, a, 1.0, x.par - s, y.lo, y.hi
        mask = par < lo if end == 0 else par > hi
        if mask.sum() < 2:
            return []
        ring, cls = smp.rings[chain.ring]
        pts = chain.points[mask]
        own, found = self._closing(ring, cls, chain.rotor, pts, sign * (t1 - t0),
                                   _contacts_in(chain, mask))
        if found.sum() < 2:
            return []
        axis, ratio = self.surfaces.rotors[chain.rotor][:2]
        moved = _turn((pts[found] - axis)[:, None], ratio * own[found])[:, 0] + axis
        band = ring_section(np.concatenate([pts[found], moved[::-1]]))
        return [] if band is None else [band]

    def _births(self, ring, cls, chain, dpsi, reach, psi=None) -> np.ndarray:
        """Per vertex of ``chain`` (a piece of a sliver found born or dying |dpsi| away,
        by the median of its gap), the rigid move (signed) to where its own surfaces
        touch: a sliver may open along its length over a while (a zipper), and the
        points each vertex passes are swept from its own opening.  Found on GAP_POINTS
        vertices and more where they differ (the rest interpolated along the chain),
        scanned over ``reach`` (signed: to where the ring's area is least,
        :meth:`_event`), bisected and carried to the touching (:meth:`.Gaps._closing`).
        An end at one of the section's contacts touches at the sample itself
        (:func:`_contacts_in`).  Not over twice |dpsi|
        only: a pocket between two contacts opens at its ends first, its middle later
        (the circular 4/6 pair's, 116.3 deg after the chamber's birth, opens 0.9 deg
        before its median gap at 48 steps per period), and the vertices beyond the
        scan were swept from its end, late."""
        own, found = self._closing(ring, cls, chain.rotor, chain.points, reach,
                                   _contacts_in(chain), BIRTH_ROUNDS, psi)
        return own if found.any() else np.full(len(chain.points), dpsi)

    def _rigid(self, smp, ring_index, dpsi, kind, reach):
        """The passage of ring ``ring_index`` of ``smp`` between its event (dpsi away)
        and the sample, swept rigidly: each rotor piece's band (a sliver's per vertex,
        looked for up to ``reach``), and a pocket's own region at the event."""
        from manifold3d import CrossSection, FillRule

        from .footprint import ring_section

        out = []
        ring, cls = smp.rings[ring_index]
        for c in smp.chains:
            if c.ring == ring_index:
                if kind == "sliver":
                    own = self._births(ring, cls, c, dpsi, reach, smp.psi)
                    axis, ratio = self.surfaces.rotors[c.rotor][:2]
                    moved = _turn((c.points - axis)[:, None], ratio * own)[:, 0] + axis
                else:
                    moved = self.surfaces.move(c.points, c.rotor, dpsi)
                out.append(ring_section(np.concatenate([c.points, moved[::-1]])))
        if kind == "pocket":
            out.append(CrossSection([np.ascontiguousarray(self._moved(ring, cls, dpsi))],
                                    FillRule.NonZero))
        return out

    def _turns(self, psis, cache):
        """``psis`` with more samples where a corner's path turns within a step (a
        contact reaching a cut line, :func:`_turning`), homed in on the turn
        (:meth:`_home`); the samples kept in ``cache``.  (The bands join a corner's
        samples by a smooth path, which cuts off what the corner passes beyond a turn.)"""
        for p in psis:
            cache[p] = self.sample(p)
        chains = [cache[p].chains if cache[p] is not None else () for p in psis]
        pairs = [self._match(a, b, t1 - t0)[0]
                 for a, b, t0, t1 in zip(chains, chains[1:], psis, psis[1:], strict=False)]
        extra = []
        for i in range(1, len(pairs) - 1):
            turn = _turn_in(pairs, psis, i)
            if turn is not None:
                extra += self._home(cache, psis[i - 1:i + 3], *turn)
        self.turns += extra
        return sorted(set(psis) | set(extra))

    def _home(self, cache, t, x, end, p, at):
        """Samples homing in on the turn of corner ``end`` of piece x (at t[1]) between
        t[1] and t[2], estimated at ``at`` (``p``: the corner at t[0..3]): each new
        corner lies on the path before the turn or after it and replaces that side's
        older sample in the lines whose meeting is the next estimate; while the
        triangle the turn cuts off from the chord is above TURN_AREA, TURNS samples at
        most."""
        tt, pp = list(t), list(p)  # the lines' samples: 0 -> 1 before, 2 -> 3 after
        out, least = [], 2.0 * TURN_AREA * self.surfaces.size ** 2
        for _ in range(TURNS):
            k = pp[1] + (at - tt[1]) * (pp[1] - pp[0]) / (tt[1] - tt[0])
            if abs(cross(k - pp[1], pp[2] - pp[1])) < least:
                break
            smp = cache[at] = self.sample(at)
            out.append(at)
            pair = [] if smp is None else self._match((x,), smp.chains, at - t[1])[0]
            if not pair:
                break
            q = pair[0][1].points[end]
            if _off(q, pp[0], pp[1]) <= _off(q, pp[2], pp[3]):  # still before the turn
                tt[:2], pp[:2] = [tt[1], at], [pp[1], q]
            else:
                tt[2:], pp[2:] = [at, tt[2]], [q, pp[2]]
            at = _turning(pp, tt, smooth=False)
            if at is None:
                break
        return out


def _contacts_in(chain, mask=None):
    """Indices, among ``chain``'s points (those of ``mask``), of its ends that are the
    section's contacts (:func:`.surfaces.chains`): they touch at the sample itself.
    Moved back with their neighbours, a contact (where a zipper has got to) swept a
    chord across what opened later: up to 150 um past the contact's path on the
    pin-cycloid's groove born along an arc, and 11 % past the fine sweep of the
    circular's conformal arcs parting at two steps in 3.75 deg (5.7 % so)."""
    mask = np.ones(len(chain.points), dtype=bool) if mask is None else mask
    n = int(mask.sum())
    return [i for i, e, on in ((0, 0, mask[0]), (n - 1, 1, mask[-1]))
            if on and chain.contact_ends[e]]


def _turn_in(pairs, psis, i):
    """(piece at psis[i], its end, the end's positions at psis[i - 1 .. i + 2], the
    angle) of the first corner of the pieces matched over step i (``pairs``: each
    step's) whose path turns within it (:func:`_turning`), or None."""
    before = {id(y): x for x, y in pairs[i - 1]}
    after = {id(x): y for x, y in pairs[i + 1]}
    for x, y in pairs[i]:
        if id(x) not in before or id(y) not in after:
            continue
        for end in (0, -1):
            p = [c.points[end] for c in (before[id(x)], x, y, after[id(y)])]
            at = _turning(p, psis[i - 1:i + 3])
            if at is not None:
                return x, end, p, at
    return None


def _off(q, a, b) -> float:
    """Distance of q from the line through a and b."""
    d = b - a
    return abs(cross(q - a, d)) / max(float(np.hypot(*d)), 1e-300)


def _turning(p, t, smooth=True):
    """The angle where a corner's path, seen at p[0..3] at angles t[0..3], turns
    between t[1] and t[2], or None: where the parabolas through the samples either
    side disagree (SMOOTH; unless not ``smooth``), and the lines p0 -> p1 and p2 -> p3,
    followed on as the angle goes, meet within the step, that meeting's angle (the two
    lines' mean).  A chamber's tip reaching a cut line: its path along the contact,
    then along the line (on the circular 4/6 pair, 26 deg after the chamber's birth,
    the bands' parabola cut off 0.13 mm2 there at 48 steps per period)."""
    from .footprint import _parabola

    mid = 0.5 * (t[1] + t[2])
    m0 = _parabola((t[0], p[0]), (t[1], p[1]), (t[2], p[2]), mid)
    m1 = _parabola((t[1], p[1]), (t[2], p[2]), (t[3], p[3]), mid)
    r = p[2] - p[1]
    if smooth and not np.linalg.norm(m1 - m0) > SMOOTH * float(np.hypot(*r)):
        return None
    v0 = (p[1] - p[0]) / (t[1] - t[0])  # the corner's speeds either side
    v1 = (p[3] - p[2]) / (t[3] - t[2])
    det = float(cross(v0, v1))
    if abs(det) <= 1e-12 * float(np.dot(v0, v0) + np.dot(v1, v1)):  # parallel, or still
        return None
    a0 = t[1] + cross(r, v1) / det  # along p1 + (a - t1) v0
    a1 = t[2] + cross(r, v0) / det  # along p2 + (a - t2) v1
    if not (t[1] < a0 < t[2] and t[1] < a1 < t[2]):
        return None
    return 0.5 * (a0 + a1)
