"""The region a working chamber's section covers over an interval of angles (its sweep).

A chamber's section is bounded by pieces of the rotors' surfaces, which turn rigidly
about their axes, and by still curves (the casing's bores, the family's cut lines); the
pieces end at corners that slide (contacts, tips on a bore).  A point that the section
covers at some angle in [psi_0, psi_1] and not at psi_0 has been crossed by the
section's boundary in between, so the sweep is the section at psi_0 and whatever its
boundary passes over.  Between two sampled sections the rotor pieces' passage is exact
up to the corners: each piece of a rotor's surface at one sample and the same surface's
piece at the next (the same material, told by where it lies in the rotor's own frame)
bound a band, closed along the paths of its two corners (interpolated between the
samples).  So the sweep of sampled sections and bands misses only what a corner's path
bulges past its interpolant, and the lens a piece passes over beyond both its
positions where its radius about its axis has an extremum (third order in the step per
step; not swept).  A union of sampled sections alone misses the
strips their boundary crossed between the samples (first order; half order where a
sliver is born thin and moves fast, as twin-screw grooves are at the deep mesh).

Events between two samples, where a ring of a section has no piece matching the other
sample's (:mod:`.footprint_events`):

* a sliver born (dying): two rotor surfaces that touched along a band come apart (close
  up).  Moved back (on) rigidly, its rotor pieces meet again; each vertex is swept from
  where its own surfaces touch (a sliver may open along its length over a while; the
  grown rotors meet earlier, :mod:`.footprint_gaps`), no section cut.  A union of
  sections misses most of what a sliver passes: the 4/6 pin-cycloid's female groove,
  born 2.1 deg after the table's birth node, sweeps 1.67 mm2 of one corner of the lens
  in its first 0.6 deg (1.13 swept from where the grown rotors met), of which the union
  of its sections every 0.02 deg holds 0.12 mm2, every 0.001 deg 0.88 (1.14 with
  polygons 16 times finer; tests/test_twin_screw_port_areas.py);
* a pocket handed over (a family hands a trapped pocket from the dying chamber to the
  newborn one where its area is least): swept rigidly from the least area of the
  rigidly moved pocket;
* a piece's end that jumps along its surface (a sliver that opens, or closes, right
  next to its chamber, so its ring keeps matched pieces): the stretch it jumped over is
  swept per vertex, as a sliver's (:meth:`.footprint_events.Events._jumps`);
* a corner whose path turns (a tip reaching a cut line): more samples, homed in on the
  turn (:meth:`.footprint_events.Events._turns`).

The corners are where a piece of one rotor meets another's or a still curve.  Where
two rotors touch, the section (cut from rotors grown so that they overlap) ends half an
overlap lens short of the contact: each piece's end there is carried on to the
section's own contact (CONTACT_REACH), so that the bands' corners run along the path of
contact, not beside it.  Each vertex must be told to the right rotor; in a film
thinner than the profiles' chord error (the circular pair's conformal arcs) that takes
the true curves
(:meth:`.surfaces.Surfaces._films`).

Optionally (REFINE) one more section is cut just after each event, where the sliver has
its true extent, and the sub-steps are swept.

What the sweeps' accuracy makes of the port areas is measured in :mod:`.ports`.  A
piece's surface is told by :mod:`.surfaces`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .footprint_events import Events
from .surfaces import Chain, Surfaces
from .surfaces import area as _area
from .surfaces import chains as surface_chains

#: Where the extra section of an event is cut: this fraction of the way from the event
#: to the sample it was found from.  Near the event a born sliver is a fraction of a
#: micrometre thin (its gap grows like the square of the angle, THIN) and its section
#: comes apart into specks; 0.3 deg after its birth the 4/6 pair's is 2 um wide.
EVENT_LEAD = 0.15
#: A corner's path farther off its chord (at any of PATH_T) than this fraction of the
#: chord is no smooth path (the piece's end went from one corner to another): that
#: fit is not used.
BEND = 0.1
#: Where between two samples each corner's path is evaluated (fractions of the step):
#: five points leave 1/36 of the path's bulge past its chord to the polyline's own
#: sag (the midpoint alone left a quarter).
PATH_T = np.linspace(0.0, 1.0, 7)[1:-1]
#: The events at which one more section is cut ("sliver", "pocket"; none by default:
#: with each vertex swept from its own birth, the 4/6 pin-cycloid's young sweep at 96
#: samples per period is 9e-5 of the largest discharge area off the one at 768 without
#: them, 2.6e-4 with them, and they cost a section cut each).
REFINE = ()
#: Two pieces of one surface that share less than this fraction of the shorter one's
#: profile parameters are not matched when each shares at least this much with another
#: piece at the other sample: they only graze.  Where the 1-1 pumps' contact crosses
#: the cusp line at the pitch point, a piece below it at one sample and the piece above
#: it at the next share the few hundredths of a degree of surface that crossed (0.039
#: and 0.006 of the shorter piece on the involute at 24 and 48 points per period, 0.021
#: and 0.0014 on the circular), and the band between
#: them, closed along paths from one's corners to the other's, which are different
#: corners, spanned 112 mm2 of the lens that no section covers: the involute pump's
#: discharge area erred by 8.1e-3 of its largest value at 48 points per period.  What
#: keeps a real match is the condition on both pieces, not the share alone: a piece
#: that splits or merges, or slides, has a side with no other partner, and may share
#: as little as 0.0015 (the 4/6 pin-cycloid at 48); where both pieces have other
#: partners the shipped pairs share 0.75 or more (the circular 4/6 at 24 and 96) or
#: graze (the 1-1 pumps above; 24, 48 and 96 points per period measured).
GRAZE = 0.1
#: Rings of a section thinner than this on average (twice the area over the perimeter,
#: per centre distance, plus what the family's polygons take off a film,
#: :attr:`.family.RotorPair.film_deficit`) are not followed from sample to sample: a
#: sliver just born, thinner than about twice the twin screw's grown rotors' overlap,
#: comes out of Clipper as a string of specks, not as the sliver; its passage is swept
#: from its birth rigidly, a dying film's to its death.  It bounds the true thickness,
#: so that polygons of any fineness follow the same films (the twin screw's grown
#: rotors take 4e-6 C off every film: 1e-5 of its polygons' own, as before).  Why finer
#: polygons do not follow thinner films, and lower values for the table's polygons were
#: not adopted: docs/twin_screw.md, session 30.
THIN = 1.4e-5
#: A rotor piece's end next to the other rotor's piece is carried on to the section's
#: nearest contact within this (per centre distance; :func:`.surfaces.chains`).  The
#: grown rotors' overlap lens ends the section's pieces half a lens short of the
#: contact (a median 97 um, up to 0.5 mm on the circular pair's near-conformal arcs):
#: the bands' corners ran beside the contact path and strips along it went unswept
#: (the circular's discharge area 5.9e-3, its suction 8.3e-4 of the largest off the
#: areas with polygons 16 times finer at 24 points per period; 1.1e-3 and 2.4e-5 with
#: the contacts).  The family cuts its sections whole for them (the section table's
#: samples are cut whole anyway).
CONTACT_REACH = 1e-2


@dataclass(frozen=True)
class Sample:
    psi: float
    region: object  # CrossSection
    rings: tuple  # (ring, per-vertex rotor or -1)
    chains: tuple


class Sweeper(Events):
    """Sweeps of one chamber's sections (``section_at(psi, contacts)``: polygons, fixed
    frame, the contacts bounding them appended to the list ``contacts``, as
    :meth:`.family.RotorPair.chamber_polygons`), cropped to ``crop`` (a CrossSection,
    or None)."""

    def __init__(self, surfaces: Surfaces, section_at, crop=None, annuli=None):
        self.surfaces = surfaces
        self.section_at = section_at
        self.crop = crop
        self.annuli = annuli  # ((centre, r_lo, r_hi), ...) of a crop_region, if known
        self.periods = [r[5] for r in surfaces.rotors]
        self.box = None if crop is None else np.reshape(crop.bounds(), (2, 2))
        self.events = []  # (kind, angle) of the events met, for tests and benches
        self.turns = []  # the samples cut at corners' turns (Events._turns), likewise

    def sample(self, psi: float) -> Sample | None:
        from manifold3d import CrossSection, FillRule

        contacts = []
        polys = [np.ascontiguousarray(q) for q in self.section_at(psi, contacts)
                 if len(q) >= 3]
        if self.crop is not None:  # (most of a chamber's life lies outside the crop)
            polys = [q for q in polys if self._near_crop(q)]
        if not polys:
            return None
        region = CrossSection(polys, FillRule.Positive)
        if self.crop is not None:
            region = region ^ self.crop
        if region.is_empty():
            return None
        rings, chains = [], []
        thin = (THIN - self.surfaces.film_deficit) * self.surfaces.size
        for ring in region.to_polygons():
            perimeter = float(np.sum(np.linalg.norm(np.diff(ring, axis=0, append=ring[:1]),
                                                    axis=1)))
            if 2.0 * abs(_area(ring)) < thin * perimeter:
                continue
            i = len(rings)
            cls, par = self.surfaces.classify(ring, psi)
            rings.append((ring, cls))
            chains += surface_chains(ring, cls, par, self.periods, i,
                                     contacts, CONTACT_REACH * self.surfaces.size)
        return Sample(psi, region, tuple(rings), tuple(chains))

    def _near_crop(self, q) -> bool:
        """Whether polygon q may meet the crop: within its box, and a vertex within an
        edge's length of every annulus (crop_region's) that bounds it."""
        if np.any(q.max(0) < self.box[0]) or np.any(q.min(0) > self.box[1]):
            return False
        if self.annuli is None:
            return True
        reach = float(np.max(np.hypot(*np.diff(q, axis=0).T)))
        ok = np.ones(len(q), dtype=bool)
        for centre, lo, hi in self.annuli:
            r = np.hypot(q[:, 0] - centre[0], q[:, 1] - centre[1])
            ok &= (r >= lo - reach) & (r <= hi + reach)
        return bool(ok.any())

    def sweep(self, psis):
        """The region the sections cover for psi in [psis[0], psis[-1]], sampled at
        ``psis`` (increasing)."""
        from manifold3d import CrossSection

        pieces = []
        self._bands = []
        prev = None
        cache = {}
        for psi in self._turns([float(p) for p in psis], cache):
            cur = cache[psi] if psi in cache else self.sample(psi)
            if cur is not None:
                pieces.append(cur.region)
            if prev is not None:
                pieces += self._step(prev, cur, float(psi))
            prev = cur if cur is not None else _Empty(float(psi))
        pieces += _bands(self._bands) + self._jumps(self._bands)
        if not pieces:
            return CrossSection()
        out = _union(pieces)
        return out if self.crop is None else out ^ self.crop

    # ------------------------------------------------------------------ one step
    def _step(self, a, b, psi_b, refine=True):
        """Bands between samples a and b (either may be _Empty), with the events between
        them (one more section cut at each, unless ``refine`` is off)."""
        ca = a.chains if isinstance(a, Sample) else ()
        cb = b.chains if b is not None else ()
        pairs, born, dying = self._match(ca, cb, psi_b - a.psi)
        h = psi_b - a.psi
        events = []
        # A ring with a piece matched is no newcomer: its unmatched pieces are corners'.
        born = [c for c in born if c.ring not in {y.ring for _, y in pairs}]
        dying = [c for c in dying if c.ring not in {x.ring for x, _ in pairs}]
        for ring in sorted({c.ring for c in born}):
            ev = self._event(b, ring, h, -1.0)
            if ev is not None:
                events.append((psi_b - ev[0], "born", ev[1], ring, ev[2]))
        for ring in sorted({c.ring for c in dying}):
            ev = self._event(a, ring, h, +1.0)
            if ev is not None:
                events.append((a.psi + ev[0], "dying", ev[1], ring, ev[2]))
        inside = [e for e in events if a.psi < e[0] < psi_b and e[2] in REFINE]
        self.events += [(kind, psi) for psi, _, kind, *_ in events]
        if refine and inside:
            # Cut a section next to each event within the step and sweep the sub-steps
            # (their events, now right next to a sample, are swept rigidly).
            extra = sorted(psi + (EVENT_LEAD * (psi_b - psi) if side == "born"
                                  else -EVENT_LEAD * (psi - a.psi))
                           for psi, side, *_ in inside)
            self.events = self.events[:len(self.events) - len(events)]
            out = []
            prev = a
            for psi in extra + [psi_b]:
                cur = self.sample(psi) if psi != psi_b else b
                if cur is not None and psi != psi_b:
                    out.append(cur.region)
                out += self._step(prev, cur, psi, refine=False)
                prev = cur if cur is not None else _Empty(psi)
            return out
        self._bands += [(p, q, a.psi, psi_b, a, b) for p, q in pairs]
        out = []
        for psi, side, kind, ring, reach in events:
            smp, sign = (b, -1.0) if side == "born" else (a, +1.0)
            out += self._rigid(smp, ring, sign * abs(psi - smp.psi), kind, sign * reach)
        return [x for x in out if x is not None]

    def _match(self, ca, cb, h):
        """(pairs of chains at a and b on the same piece of surface, unmatched at b,
        unmatched at a).  The same piece: overlapping profile parameters; else a short
        piece that slid along its surface by less than the surface moved."""
        pairs = []
        used_a, used_b = set(), set()
        shared = [(i, j, _shared(x, y, self.periods[x.rotor]))
                  for i, x in enumerate(ca) for j, y in enumerate(cb) if x.rotor == y.rotor]
        shared = [(i, j, f) for i, j, f in shared if f is not None]
        own_a = {i for i, _, f in shared if f >= GRAZE}
        own_b = {j for _, j, f in shared if f >= GRAZE}
        for i, j, f in shared:
            if f < GRAZE and i in own_a and j in own_b:
                continue  # (each has a piece of its own at the other sample: GRAZE)
            pairs.append((ca[i], cb[j]))
            used_a.add(i)
            used_b.add(j)
        for i, x in enumerate(ca):
            if i in used_a:
                continue
            reach = abs(self.surfaces.rotors[x.rotor][1] * h) * self.surfaces.rotors[x.rotor][6]
            best = None
            for j, y in enumerate(cb):
                if j in used_b or y.rotor != x.rotor:
                    continue
                d = float(np.min(np.linalg.norm(
                    self.surfaces.move(x.points, x.rotor, h)[:, None] - y.points[None], axis=-1)))
                if d < reach and (best is None or d < best[0]):
                    best = (d, j)
            if best is not None:
                pairs.append((x, cb[best[1]]))
                used_a.add(i)
                used_b.add(best[1])
        born = [y for j, y in enumerate(cb) if j not in used_b]
        dying = [x for i, x in enumerate(ca) if i not in used_a]
        return pairs, born, dying


@dataclass(frozen=True)
class _Empty:
    """A sample where the chamber has no section (in the crop)."""

    psi: float
    chains: tuple = ()


def _shared(x: Chain, y: Chain, n: float) -> float | None:
    """The profile parameter range x and y share (either way round the profile's
    period n), over the shorter one's; None where they do not meet."""
    best = max(min(x.hi, y.hi + s) - max(x.lo, y.lo + s) for s in (-n, 0.0, n))
    if best < 0.0:
        return None
    shorter = min(x.hi - x.lo, y.hi - y.lo)
    return 1.0 if best >= shorter else best / shorter  # (a point lies within: 1)


def _bands(bands):
    """The band each piece of surface passes over between two samples: the piece at
    each, joined at its ends by its corners' paths, each evaluated at PATH_T: the mean
    of the parabolas through the corner's positions at three consecutive samples (the
    step before and the step after; with equal steps, at the step's middle, that is
    the cubic through all four), one of them where the piece is seen at three samples
    only or the other bends past BEND, the chord at two.  (The midpoint of one
    parabola, which stood here, cut off a quarter of the path's bulge past its chord:
    the circular pair's contact path bends up to 25 um off its 1 mm steps at 24 points
    per period, and its discharge area erred by 2.0e-4 of its largest, 5.2e-5 now.)"""
    before = {id(y): (x, t0) for x, y, t0, *_ in bands}
    after = {id(x): (y, t1) for x, y, _, t1, *_ in bands}
    s = PATH_T[:, None]
    out = []
    for x, y, t0, t1, *_ in bands:
        t = t0 + s * (t1 - t0)
        ends = []
        for end in (-1, 0):
            p0, p1 = x.points[end], y.points[end]
            chord = (1.0 - s) * p0 + s * p1
            fits = []
            if id(x) in before:
                w, tw = before[id(x)]
                fits.append(_parabola((tw, w.points[end]), (t0, p0), (t1, p1), t))
            if id(y) in after:
                z, tz = after[id(y)]
                fits.append(_parabola((t0, p0), (t1, p1), (tz, z.points[end]), t))
            # A fit that bends this sharply between samples is not one path (the piece's
            # end passed from one corner to another at that neighbour): it is dropped.
            reach = BEND * np.linalg.norm(p1 - p0)
            fits = [f for f in fits if np.max(np.linalg.norm(f - chord, axis=1)) <= reach]
            ends.append(np.mean(fits, axis=0) if fits else chord)
        ring = np.concatenate([x.points, ends[0], y.points[::-1], ends[1][::-1]])
        out.append(ring_section(ring))
    return [b for b in out if b is not None]


def _parabola(a, b, c, t):
    """The quadratic through (ta, pa), (tb, pb), (tc, pc) at t (Lagrange)."""
    (ta, pa), (tb, pb), (tc, pc) = a, b, c
    la = (t - tb) * (t - tc) / ((ta - tb) * (ta - tc))
    lb = (t - ta) * (t - tc) / ((tb - ta) * (tb - tc))
    lc = (t - ta) * (t - tb) / ((tc - ta) * (tc - tb))
    return la * pa + lb * pb + lc * pc


def ring_section(ring):
    from manifold3d import CrossSection, FillRule

    if len(ring) < 3:
        return None
    # NonZero: where a piece turns past the direction of its motion the band folds over
    # itself, and both lobes were passed over.
    return CrossSection([np.ascontiguousarray(ring)], FillRule.NonZero)


#: Pieces joined per Clipper call in :func:`_union` (as ports.UNION_BATCH).
UNION_BATCH = 8


def _union(pieces):
    from manifold3d import CrossSection, OpType

    while len(pieces) > 1:
        pieces = [CrossSection.batch_boolean(pieces[i:i + UNION_BATCH], OpType.Add)
                  for i in range(0, len(pieces), UNION_BATCH)]
    return pieces[0]


#: Sides of the polygons of the crop's circles (each holds its circle: only where it
#: ends matters, not how round it is, and every section is cut by it).
CROP_SIDES = 256


def crop_region(pair, margin: float = 1e-3):
    """(region, annuli): where every rotor's surface passes, the intersection of the
    annuli between each rotor profile's least and largest radius about its axis,
    widened by ``margin`` of the pair's size (outside it only one rotor's surface passes
    a point), and those annuli ((centre, r_lo, r_hi), ...)."""
    from manifold3d import CrossSection, FillRule

    out = None
    annuli = []
    for r in pair.rotors:
        u = np.linspace(0.0, r.profile.n, 4096, endpoint=False)
        rad = np.linalg.norm(r.profile.point(u), axis=1)
        lo = rad.min() - margin * pair.diameter
        hi = rad.max() + margin * pair.diameter
        annuli.append((np.asarray(r.axis, dtype=float), max(lo, 0.0), hi))
        n = CROP_SIDES
        a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        circle = np.c_[np.cos(a), np.sin(a)]
        # The polygon circumscribes the outer circle and is inscribed in the inner one
        # (scaled by 1 / cos(pi / n)), so the annulus holds the true one.
        outer = np.asarray(r.axis) + hi / math.cos(math.pi / n) * circle
        inner = np.asarray(r.axis) + max(lo, 0.0) * circle
        rings = [np.ascontiguousarray(outer)]
        if lo > 0.0:
            rings.append(np.ascontiguousarray(inner[::-1]))
        ann = CrossSection(rings, FillRule.Positive)
        out = ann if out is None else out ^ ann
    return out, tuple(annuli)
