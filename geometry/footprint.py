"""The region a working chamber's section covers over an interval of angles (its sweep).

A chamber's section is bounded by pieces of the rotors' surfaces, which turn rigidly
about their axes, and by still curves (the casing's bores, the family's cut lines); the
pieces end at corners that slide (contacts, tips on a bore).  A point that the section
covers at some angle in [psi_0, psi_1] and not at psi_0 has been crossed by the
section's boundary in between, so the sweep is the section at psi_0 and whatever its
boundary passes over.  Between two sampled sections the rotor pieces' passage is exact
up to the corners: each piece of a rotor's surface at one sample and the same surface's
piece at the next (the same material, told by where it lies in the rotor's own frame)
bound a band, closed by chords along the paths of its two corners.  So the sweep of
sampled sections and bands misses only what a corner's path bulges past its chord
(third order in the step per step).  A union of sampled sections alone misses the
strips their boundary crossed between the samples (first order; half order where a
sliver is born thin and moves fast, as twin-screw grooves are at the deep mesh).

Events between two samples, where a section's piece has no counterpart at the other:

* a sliver born (dying): two rotor surfaces that touched along a band come apart (close
  up).  Moved back (on) rigidly, its rotor pieces meet again; the angle where their
  signed gap vanishes is the birth (death), found by a root search on the rigid motion
  (no section cut).  One more section is cut just after the birth (before the death),
  where the sliver has its true extent, and the sliver's passage from its birth to that
  section is its band swept rigidly back;
* a pocket handed over (a family hands a trapped pocket from the dying chamber to the
  newborn one where its area is least): the least area of the rigidly moved pocket,
  again with one more section cut there.

A piece's surface is told by the distance of the section's vertices to each rotor's
profile, placed at ``speed_ratio * psi`` about its axis (every family's frame: rotor r
turns by its speed ratio times the reference angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: A section vertex this close to a rotor's surface (per centre distance) lies on it: the
#: families' polygons lie within their chord error (1e-6) and the twin screw's grown
#: rotors (2e-6) of the true surfaces; vertices of a bore or a cut line lie farther off
#: except at the corners.
ON_ROTOR = 2e-5
#: Chord tolerance (per centre distance) of the profiles the vertices are told against.
PROFILE_TOL = 2e-6
#: Sub-steps of a step scanned for a sliver's birth or death or a pocket's least area.
EVENT_SCAN = 16
#: How far (reference angle, rad) a sliver's birth is looked for behind the sample that
#: first holds it (its death ahead of the last), at least two steps: the samples of its
#: first 0.2 deg hold none of it (THIN).
EVENT_REACH = 0.02
#: Where the extra section of an event is cut: this fraction of the way from the event
#: to the sample it was found from.  Near the event a born sliver is a fraction of a
#: micrometre thin (its gap grows like the square of the angle, THIN) and its section
#: comes apart into specks; 0.3 deg after its birth the 4/6 pair's is 2 um wide.
EVENT_LEAD = 0.15
#: A ring whose area, its rotor pieces moved rigidly, falls to this fraction of its own
#: within the search closes there (a sliver's birth or death is looked for near it).
CLOSING = 0.05
#: Vertices of a rotor piece whose median gap locates a sliver's birth or death.
GAP_POINTS = 33
#: A corner path's midpoint farther off its chord than this fraction of the chord is
#: no smooth path (the piece's end went from one corner to another): the chord is kept.
BEND = 0.1
#: The events at which one more section is cut.
REFINE = ("sliver", "pocket")
#: Chains with fewer vertices are corners, not pieces of a surface.
MIN_CHAIN = 2
#: Rings of a section thinner than this on average (twice the area over the perimeter,
#: per centre distance) are dropped: a sliver just born, thinner than about twice the
#: twin screw's grown rotors' overlap, comes out of Clipper as a string of specks, not
#: as the sliver; the sliver's passage is then swept from its birth rigidly.
THIN = 1e-5


@dataclass(frozen=True)
class Chain:
    """A run of a section ring's vertices on one rotor's surface, ordered the way the
    profile's parameter runs."""

    rotor: int
    points: np.ndarray  # fixed frame
    lo: float  # profile parameter at its ends (unwrapped: lo <= hi)
    hi: float
    ring: int  # index of its ring in the sample


@dataclass(frozen=True)
class Sample:
    psi: float
    region: object  # CrossSection
    rings: tuple  # (ring, per-vertex rotor or -1)
    chains: tuple


class Surfaces:
    """The rotors' surfaces of a pair, to tell which one a section vertex lies on."""

    def __init__(self, pair):
        from scipy.spatial import cKDTree

        from .curves import sample

        axes = [np.asarray(r.axis, dtype=float) for r in pair.rotors]
        self.size = max(math.dist(axes[0], axes[-1]), 1e-2 * pair.diameter)
        self.rotors = []
        for r, axis in zip(pair.rotors, axes, strict=True):
            u = sample(r.profile, PROFILE_TOL * self.size)
            p = r.profile.point(u)
            self.rotors.append((axis, float(r.speed_ratio), u, p, cKDTree(p),
                                float(r.profile.n), float(np.linalg.norm(p, axis=1).max())))

    def move(self, points, rotor: int, dpsi: float) -> np.ndarray:
        """Points of rotor ``rotor`` after the reference rotor turns by dpsi."""
        axis, ratio = self.rotors[rotor][:2]
        return _rotate(points - axis, ratio * dpsi) + axis

    def classify(self, ring: np.ndarray, psi: float):
        """(rotor or -1, profile parameter) of each vertex of ``ring`` at angle psi."""
        cls = np.full(len(ring), -1)
        par = np.zeros(len(ring))
        best = np.full(len(ring), ON_ROTOR * self.size)
        for k, (axis, ratio, u, p, tree, n, _) in enumerate(self.rotors):
            x = _rotate(ring - axis, -ratio * psi)
            _, j = tree.query(x)
            m = len(p)
            for jj in (j - 1, j):  # the two edges at the nearest sample
                a, b = p[jj % m], p[(jj + 1) % m]
                ab = b - a
                t = np.clip(np.sum((x - a) * ab, -1) / np.sum(ab * ab, -1), 0.0, 1.0)
                d = np.linalg.norm(a + t[:, None] * ab - x, axis=-1)
                ua, ub = u[jj % m], u[(jj + 1) % m]
                ub = np.where(ub < ua, ub + n, ub)
                closer = d < best
                cls[closer] = k
                par[closer] = np.mod(ua + t * (ub - ua), n)[closer]
                best[closer] = d[closer]
        return cls, par


def _rotate(points, angle):
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def _area(ring) -> float:
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - y * np.roll(x, -1)))


def _chains(ring, cls, par, periods, index) -> list[Chain]:
    m = len(ring)
    change = np.nonzero(cls != np.roll(cls, 1))[0]
    if not len(change):
        runs = [np.arange(m + 1) % m] if cls[0] >= 0 else []
    else:
        order = (np.arange(m) + change[0]) % m
        cuts = np.nonzero(np.diff(cls[order]))[0] + 1
        runs = [order[a:b] for a, b in zip(np.r_[0, cuts], np.r_[cuts, m], strict=True)]
    out = []
    for r in runs:
        k = int(cls[r[0]])
        if k < 0 or len(r) < MIN_CHAIN:
            continue
        n = periods[k]
        steps = np.remainder(np.diff(par[r]) + 0.5 * n, n) - 0.5 * n
        s = par[r[0]] + np.concatenate([[0.0], np.cumsum(steps)])
        pts = ring[r]
        if s[-1] < s[0]:
            s, pts = s[::-1], pts[::-1]
        out.append(Chain(k, pts, float(s[0]), float(s[-1]), index))
    return out


class Sweeper:
    """Sweeps of one chamber's sections (``section_at(psi)``: polygons, fixed frame),
    cropped to ``crop`` (a CrossSection, or None)."""

    def __init__(self, surfaces: Surfaces, section_at, crop=None):
        self.surfaces = surfaces
        self.section_at = section_at
        self.crop = crop
        self.periods = [r[5] for r in surfaces.rotors]
        self.box = None if crop is None else np.reshape(crop.bounds(), (2, 2))
        self.events = []  # (kind, angle) of the events met, for tests and benches

    def sample(self, psi: float) -> Sample | None:
        from manifold3d import CrossSection, FillRule

        polys = [np.ascontiguousarray(q) for q in self.section_at(psi) if len(q) >= 3]
        if self.box is not None:  # (most of a chamber's life lies outside the crop)
            polys = [q for q in polys if np.all(q.max(0) >= self.box[0])
                     and np.all(q.min(0) <= self.box[1])]
        if not polys:
            return None
        region = CrossSection(polys, FillRule.Positive)
        if self.crop is not None:
            region = region ^ self.crop
        if region.is_empty():
            return None
        rings, chains = [], []
        thin = THIN * self.surfaces.size
        for ring in region.to_polygons():
            perimeter = float(np.sum(np.linalg.norm(np.roll(ring, -1, 0) - ring, axis=1)))
            if 2.0 * abs(_area(ring)) < thin * perimeter:
                continue
            i = len(rings)
            cls, par = self.surfaces.classify(ring, psi)
            rings.append((ring, cls))
            chains += _chains(ring, cls, par, self.periods, i)
        return Sample(psi, region, tuple(rings), tuple(chains))

    def sweep(self, psis):
        """The region the sections cover for psi in [psis[0], psis[-1]], sampled at
        ``psis`` (increasing)."""
        from manifold3d import CrossSection, OpType

        pieces = []
        self._bands = []
        prev = None
        for psi in psis:
            cur = self.sample(float(psi))
            if cur is not None:
                pieces.append(cur.region)
            if prev is not None:
                pieces += self._step(prev, cur, float(psi))
            prev = cur if cur is not None else _Empty(float(psi))
        pieces += _bands(self._bands)
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
                events.append((psi_b - ev[0], "born", ev[1], ring))
        for ring in sorted({c.ring for c in dying}):
            ev = self._event(a, ring, h, +1.0)
            if ev is not None:
                events.append((a.psi + ev[0], "dying", ev[1], ring))
        inside = [e for e in events if a.psi < e[0] < psi_b and e[2] in REFINE]
        self.events += [(kind, psi) for psi, _, kind, _ in events]
        if refine and inside:
            # Cut a section next to each event within the step and sweep the sub-steps
            # (their events, now right next to a sample, are swept rigidly).
            extra = sorted(psi + (EVENT_LEAD * (psi_b - psi) if side == "born"
                                  else -EVENT_LEAD * (psi - a.psi))
                           for psi, side, _, _ in inside)
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
        self._bands += [(p, q, a.psi, psi_b) for p, q in pairs]
        out = []
        for psi, side, kind, ring in events:
            smp, sign = (b, -1.0) if side == "born" else (a, +1.0)
            d = abs(psi - smp.psi)
            out += self._rigid(smp, ring, sign * d, kind)
        return [x for x in out if x is not None]

    def _match(self, ca, cb, h):
        """(pairs of chains at a and b on the same piece of surface, unmatched at b,
        unmatched at a).  The same piece: overlapping profile parameters; else a short
        piece that slid along its surface by less than the surface moved."""
        pairs = []
        used_a, used_b = set(), set()
        for i, x in enumerate(ca):
            for j, y in enumerate(cb):
                if x.rotor == y.rotor and _overlap(x, y, self.periods[x.rotor]):
                    pairs.append((x, y))
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

    def _event(self, smp, ring_index, h, sign):
        """(|dpsi|, kind) of the event of ring ``ring_index`` of sample ``smp`` within h
        in the direction ``sign`` (-1: back to a birth, +1: on to a death), found by
        moving its rotor vertices rigidly: "sliver" where a rotor piece's signed gap to
        the rest of the ring vanishes, "pocket" where the ring's area is least; None."""
        ring, cls = smp.rings[ring_index]
        a0 = _area(ring)
        orient = 1.0 if a0 > 0.0 else -1.0
        # A sliver is looked for beyond the step: the samples right after its birth
        # hold none of it (THIN).  The ring's area, cheap, brackets where it closes;
        # the gap of its rotor pieces then finds where.
        reach = max(2.0 * h, EVENT_REACH)
        ds = np.linspace(0.0, reach, int(math.ceil(EVENT_SCAN * reach / h)) + 1)
        areas = np.array([_area(self._moved(ring, cls, sign * d)) for d in ds]) * orient
        drop = np.nonzero(areas <= CLOSING * areas[0])[0]
        if len(drop):
            # From before the drop to past the least area (where the pieces, moved on
            # through each other, part again).
            j = drop[0]
            while j + 1 < len(ds) and areas[j + 1] < areas[j]:
                j += 1
            lo, hi = ds[max(drop[0] - 1, 0)], ds[min(j + 1, len(ds) - 1)]
            for k in sorted(set(cls[cls >= 0].tolist())):
                fine = np.linspace(lo, hi, 2 * (j + 2 - drop[0]) + 1)
                gaps = [self._gap(ring, cls, k, sign * d, orient) for d in fine]
                first = 0.0 if lo == 0.0 else self._gap(ring, cls, k, 0.0, orient)
                for i in range(1, len(fine)):
                    if gaps[i] <= 0.0 < min(gaps[i - 1], first) or \
                            (gaps[i] <= 0.0 < gaps[i - 1]):
                        from .scalar import root

                        d = root(lambda x: self._gap(ring, cls, k, sign * x, orient),
                                 float(fine[i - 1]), float(fine[i]), xtol=1e-9)
                        return d, "sliver"
        areas = np.abs(areas[ds <= h * (1.0 + 1e-12)])
        i = int(np.argmin(areas))
        if 0 < i < len(areas) - 1:
            from .scalar import minimum

            d, _ = minimum(lambda x: abs(_area(self._moved(ring, cls, sign * x))),
                           float(ds[i - 1]), float(ds[i + 1]), xtol=1e-9)
            return d, "pocket"
        return None

    def _moved(self, ring, cls, dpsi):
        q = ring.copy()
        for k in range(len(self.surfaces.rotors)):
            on = cls == k
            q[on] = self.surfaces.move(ring[on], k, dpsi)
        return q

    def _gap(self, ring, cls, k, dpsi, orient) -> float:
        """Median signed distance of the ring's rotor-k vertices, all moved rigidly by
        dpsi, to the ring's other edges (positive inside the ring)."""
        q = self._moved(ring, cls, dpsi)
        on = cls == k
        other = ~(on & np.roll(on, -1))  # edges not along rotor k
        if not other.any() or not on.any():
            return 0.0
        a = q[other]
        ab = np.roll(q, -1, axis=0)[other] - a
        x = q[on]
        x = x[np.linspace(0, len(x) - 1, min(len(x), GAP_POINTS)).astype(int)]
        t = np.clip(np.einsum("ijk,jk->ij", x[:, None] - a[None], ab)
                    / np.maximum(np.sum(ab * ab, -1), 1e-300), 0.0, 1.0)
        dist = np.linalg.norm(x[:, None] - (a[None] + t[..., None] * ab[None]), axis=-1)
        j = np.argmin(dist, axis=1)
        rel = x - a[j]
        side = np.sign(ab[j, 0] * rel[:, 1] - ab[j, 1] * rel[:, 0]) * orient
        return float(np.median(side * dist[np.arange(len(x)), j]))

    def _rigid(self, smp, ring_index, dpsi, kind):
        """The passage of ring ``ring_index`` of ``smp`` between its event (dpsi away)
        and the sample, swept rigidly: each rotor piece's band, and a pocket's own
        region at the event."""
        from manifold3d import CrossSection, FillRule

        out = []
        for c in smp.chains:
            if c.ring == ring_index:
                moved = self.surfaces.move(c.points, c.rotor, dpsi)
                out.append(_ring_section(np.concatenate([c.points, moved[::-1]])))
        if kind == "pocket":
            ring, cls = smp.rings[ring_index]
            out.append(CrossSection([np.ascontiguousarray(self._moved(ring, cls, dpsi))],
                                    FillRule.NonZero))
        return out


@dataclass(frozen=True)
class _Empty:
    """A sample where the chamber has no section (in the crop)."""

    psi: float
    chains: tuple = ()


def _overlap(x: Chain, y: Chain, n: float) -> bool:
    return any(x.lo <= y.hi + s and y.lo + s <= x.hi for s in (-n, 0.0, n))


def _bands(bands):
    """The band each piece of surface passes over between two samples: the piece at
    each, joined at its ends by its corners' paths, each the parabola through the
    corner's positions at three consecutive samples (the step before or after), or the
    chord where the piece is seen at two only."""
    before = {id(y): (x, t0) for x, y, t0, _ in bands}
    after = {id(x): (y, t1) for x, y, _, t1 in bands}
    out = []
    for x, y, t0, t1 in bands:
        ends = []
        for end in (-1, 0):
            p0, p1 = x.points[end], y.points[end]
            chord = 0.5 * (p0 + p1)
            mid = chord
            if id(x) in before:
                w, tw = before[id(x)]
                mid = _parabola((tw, w.points[end]), (t0, p0), (t1, p1), 0.5 * (t0 + t1))
            elif id(y) in after:
                z, tz = after[id(y)]
                mid = _parabola((t0, p0), (t1, p1), (tz, z.points[end]), 0.5 * (t0 + t1))
            # A corner that bends this sharply between samples is not one path (the
            # piece's end passed from one corner to another): keep the chord.
            if np.linalg.norm(mid - chord) > BEND * np.linalg.norm(p1 - p0):
                mid = chord
            ends.append(mid)
        ring = np.concatenate([x.points, ends[0][None], y.points[::-1], ends[1][None]])
        out.append(_ring_section(ring))
    return [b for b in out if b is not None]


def _parabola(a, b, c, t):
    """The quadratic through (ta, pa), (tb, pb), (tc, pc) at t (Lagrange)."""
    (ta, pa), (tb, pb), (tc, pc) = a, b, c
    la = (t - tb) * (t - tc) / ((ta - tb) * (ta - tc))
    lb = (t - ta) * (t - tc) / ((tb - ta) * (tb - tc))
    lc = (t - ta) * (t - tb) / ((tc - ta) * (tc - tb))
    return la * pa + lb * pb + lc * pc


def _ring_section(ring):
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


def crop_region(pair, margin: float = 1e-3):
    """Where every rotor's surface passes: the intersection of the annuli between each
    rotor profile's least and largest radius about its axis, widened by ``margin`` of
    the pair's size.  Outside it only one rotor's surface passes a point."""
    from manifold3d import CrossSection, FillRule

    out = None
    for r in pair.rotors:
        u = np.linspace(0.0, r.profile.n, 4096, endpoint=False)
        rad = np.linalg.norm(r.profile.point(u), axis=1)
        lo = rad.min() - margin * pair.diameter
        hi = rad.max() + margin * pair.diameter
        n = 1024
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
    return out
