"""Where a section's rotor vertices, moved rigidly, meet the rest of their ring (for the
events of :mod:`.footprint_events`): the signed gaps, where each closes, and where the
true surfaces touch.

The sections' rotors are grown (the twin screw's by 2e-6 C along their normals, so that
touching rotors overlap and the fluid comes apart at every contact): moved back, a
vertex's grown gap closes while the true surfaces are still a growth's overlap apart.
Between conjugate surfaces the gap is least where they touch (the vertex was the
contact then) and opens as the square of the angle either side, so the grown gap
closes ~sqrt(2 g / k) before the touching and opens again as far beyond it: the middle
of the two crossings is the touching, to the gap's asymmetry (order g), whatever the
scan's step.  A sliver's vertices swept from the grown closing fell short by that
sqrt: the pin-cycloid's female groove, born along an arc, missed strips 50-110 um wide
of the discharge's sealed region (3.4e-3 of the largest discharge area against
sections with polygons 16 times finer, 24 points per period).  (The least of the gap
itself, tried first, is flat and noisy between conformal arcs: one chain's vertices
fell 0.001 rad either side of the other's, in two bands; the crossings agree to 2e-5
rad.)

A ring is cut at the cusp line (what lies beyond is another ring's): a vertex next to
the line may never see its gap to the ring close, and was swept as far as its
neighbours (interpolated), too short: the circular 4/6 pair's sliver born 116.25 deg
after its chamber, by the cusp line, lost 0.076 mm2 of its sweep at 24 points per
period and 0.033 at 48 (against its sections' union every 1e-5 rad).  Such a vertex is
swept back to where it touches the other rotor's true surface instead
(:meth:`Gaps._mate_touching`), 0.05 rad back on the line itself; measured 2026-11-30,
0.0001 mm2 left at both, and the discharge areas 5.3e-4 / 2.2e-4 / 1.0e-4 -> 2.2e-4 /
7.3e-5 / 5.1e-5 (circular) and 1.6e-4 / 7.2e-5 / 1.1e-4 -> 5.2e-5 / 3.6e-5 / 9.6e-5
(pin-cycloid) of their largest at 24 / 48 / 96 points per period (bench reference
rebuilt with it).  (To where it crossed the cusp line, tried before, swept some through
the male rotor; to the sooner of that and the touching, the circular's areas the same
and the pin-cycloid's discharge at 24 3.7 times farther off: beyond the line lies the
same chamber's other ring there.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import planar
from .surfaces import area as _area
from .surfaces import turn as _turn

#: Sub-steps of a step scanned for a sliver's birth or death or a pocket's least area.
EVENT_SCAN = 8
#: Vertices of a rotor piece whose median gap locates a sliver's birth or death, and
#: whose own births are found (the rest interpolated).
GAP_POINTS = 33
#: Bisections of a vertex's own grown closing in its scan interval (to 2^-8 of it).
BISECT = 8
#: A vertex's gap, past its grown closing, is scanned for where it opens again in this
#: many sub-steps of the closing's scan step, then in doubled ones, up to TOUCH_REACH
#: (reference angle, rad) past the closing; the opening bisected TOUCH_BISECT times.
#: (The pin-cycloid's groove born along an arc touches 0.0036-0.0067 rad past its grown
#: closing at every angle step, 3 to 12 scan steps at 768 samples per period: a window
#: of a few scan steps found it at 48 samples per period and not at 192.)
TOUCH_SCAN = 4
TOUCH_REACH = 0.05
TOUCH_BISECT = 10
#: A gap that falls below this (per centre distance) before it opens again crossed the
#: other surface (or a still curve): no touching, the grown closing is kept.  The
#: shipped overlap is 4e-6 C (twice the twin screw's growth).
TOUCH_DEPTH = 2e-5
#: Where the moves of two neighbouring vertices found differ by more than this fraction
#: of the scanned span, the vertex halfway is found too, up to BIRTH_ROUNDS times: a
#: sliver born along an arc at once opens at its ends as a zipper, where the moves run
#: from the arc's birth to nothing within a few of GAP_POINTS' spacing (interpolated
#: between them, the pin-cycloid's groove left a 0.8 mm stretch 50 um short).
BIRTH_JUMP = 1.0 / 16.0
BIRTH_ROUNDS = 5

#: A vertex whose gap to its ring does not close within the scan (the ring is cut off
#: beyond it) is scanned against the other rotor's true surface over this many spans.
MATE_REACH = 2


#: Rings whose edges :meth:`Gaps._ring_edges` keeps ready.
RING_MEMO = 16


@dataclass(frozen=True)
class _RingEdges:
    """A ring's edges not along one rotor: ``still`` (class, start, vector, squared
    length) per class whose edges keep their ends on one surface, in class order; the
    ends of the others (their starts, then their ends) and which of those ends lie
    on each rotor (``moving``: (rotor, mask))."""

    still: tuple
    ends: np.ndarray | None
    moving: tuple


class Gaps:
    """The gap methods of :class:`.footprint.Sweeper` (a mixin: it needs the sweeper's
    ``surfaces``)."""

    def _gap(self, ring, cls, k, dpsi, orient) -> float:
        """Median signed distance of the ring's rotor-k vertices, all moved rigidly by
        dpsi, to the ring's other edges (positive inside the ring)."""
        on = cls == k
        if not on.any() or np.all(on & np.roll(on, -1)):
            return 0.0
        x = ring[on]
        x = x[np.linspace(0, len(x) - 1, min(len(x), GAP_POINTS)).astype(int)]
        return float(np.median(self._gaps(ring, cls, k, x, np.array([dpsi]), orient)[0]))

    def _gaps(self, ring, cls, k, x, dpsi, orient) -> np.ndarray:
        """Signed distances (len(dpsi), len(x)) of points x of rotor k, each moved
        rigidly by each dpsi with the ring, to the ring's edges not along rotor k."""
        dpsi = np.asarray(dpsi, dtype=float)
        flat = self._gaps_each(ring, cls, k, np.tile(x, (len(dpsi), 1)),
                               np.repeat(dpsi, len(x)), orient)
        return flat.reshape(len(dpsi), len(x))

    def _gaps_each(self, ring, cls, k, x, dpsi, orient) -> np.ndarray:
        """Signed distance of each point x[v] of rotor k, moved rigidly by dpsi[v] with
        the ring, to the ring's edges not along rotor k (positive inside the ring).

        Distances and sides do not change under a rotation, so an edge whose two ends
        move together (one rotor's, or a still curve's) stays put and the points are
        turned back into its frame instead (a few points against every edge end per
        point); an edge between two surfaces moves its ends apart and is moved."""
        edges = self._ring_edges(ring, cls, k)
        dpsi = np.broadcast_to(np.asarray(dpsi, dtype=float), (len(x),))
        rotors = self.surfaces.rotors
        axis, ratio = rotors[k][:2]
        y = _turn((x - axis)[:, None], ratio * dpsi)[:, 0] + axis
        dist, side = [], []
        for c, a, ab, den in edges.still:
            if 0 <= c < len(rotors):
                ax, r = rotors[c][:2]
                yc = _turn((y - ax)[:, None], -r * dpsi)[:, 0] + ax
            else:
                yc = y
            d, s = _edge_distance(yc[:, None], a[None], ab[None], den[None])
            dist.append(d)
            side.append(s)
        if edges.ends is not None:
            ends, m = edges.ends, len(edges.ends) // 2
            q = np.broadcast_to(ring[ends], (len(x), len(ends), 2)).copy()
            for c, on_c in edges.moving:
                ax, r = rotors[c][:2]
                q[:, on_c] = _turn(ring[ends][on_c] - ax, r * dpsi) + ax
            ab = q[:, m:] - q[:, :m]
            d, s = _edge_distance(y[:, None], q[:, :m], ab, _dot(ab, ab))
            dist.append(d)
            side.append(s)
        # The nearest edge, the first of the nearest: as each group in turn kept only an
        # edge strictly nearer than the groups' before.
        dist, side = np.concatenate(dist, axis=1), np.concatenate(side, axis=1)
        j = np.argmin(dist, axis=1)
        v = np.arange(len(x))
        return side[v, j] * dist[v, j] * orient

    def _ring_edges(self, ring, cls, k) -> _RingEdges:
        """The edges of ``ring`` not along rotor k, grouped for :meth:`_gaps_each`
        (which asks for one ring's many times over, in scans and bisections); the last
        RING_MEMO kept."""
        memo = self.__dict__.setdefault("_ring_memo", {})
        key = (id(ring), id(cls), k)
        held = memo.get(key)
        if held is not None and held[0] is ring and held[1] is cls:
            return held[2]
        if len(memo) >= RING_MEMO:
            memo.pop(next(iter(memo)))
        on = cls == k
        other = np.nonzero(~(on & np.roll(on, -1)))[0]
        nxt = (other + 1) % len(ring)
        ca, cb = cls[other], cls[nxt]
        same = ca == cb
        still = []
        for c in np.unique(ca[same]):
            sel = same & (ca == c)
            a = ring[other[sel]]
            ab = ring[nxt[sel]] - a
            still.append((int(c), a, ab, _dot(ab, ab)))
        ends, moving = None, []
        if not same.all():
            ends = np.concatenate([other[~same], nxt[~same]])
            moving = [(c, cls[ends] == c) for c in range(len(self.surfaces.rotors))
                      if (cls[ends] == c).any()]
        out = _RingEdges(tuple(still), ends, tuple(moving))
        memo[key] = (ring, cls, out)
        return out

    def _closing(self, ring, cls, rotor, x, span, fixed=(), rounds=0, psi=None):
        """Per point of ``x`` (rotor ``rotor``'s, on ``ring``): the rigid move (signed,
        within ``span``) to where its gap to the ring's other edges closes, and whether
        it closes there.  Found on GAP_POINTS of them, and between two of those whose
        moves differ by more than BIRTH_JUMP of ``span`` on the point halfway, up to
        ``rounds`` times (BIRTH_ROUNDS); the rest interpolated along x, from the points
        whose touching is found where any is (a point whose gap does not open again, at
        a piece's end next to the other rotor's, would pull its neighbours back to its
        grown closing).  The points ``fixed`` (indices: a section's contacts) touch at
        the sample.  Given the sample's angle ``psi``, a point whose gap never closes
        within ``span`` is moved to where it touches the other rotor's true surface
        (:meth:`_mate_touching`), if it does."""
        orient = 1.0 if _area(ring) > 0.0 else -1.0
        n = len(x)
        pick = np.unique(np.linspace(0, n - 1, min(n, GAP_POINTS)).astype(int))
        ds = np.linspace(0.0, abs(span), 2 * EVENT_SCAN + 1) * np.sign(span)
        at, hit, touched = self._closing_at(ring, cls, rotor, x[pick], ds, orient)
        if len(fixed):
            # (a contact of the section is where the surfaces touch now)
            at[np.isin(pick, fixed)] = 0.0
            hit[np.isin(pick, fixed)] = touched[np.isin(pick, fixed)] = True
        for _ in range(rounds):
            k = np.nonzero(hit)[0]
            a, b = pick[k[:-1]], pick[k[1:]]
            far = (b - a > 1) & (np.abs(at[k[1:]] - at[k[:-1]]) > BIRTH_JUMP * abs(span))
            if not far.any():
                break
            more = (a[far] + b[far]) // 2
            at2, hit2, t2 = self._closing_at(ring, cls, rotor, x[more], ds, orient)
            pick = np.concatenate([pick, more])
            order = np.argsort(pick)
            pick, at, hit, touched = pick[order], np.concatenate([at, at2])[order], \
                np.concatenate([hit, hit2])[order], np.concatenate([touched, t2])[order]
        if psi is not None and not hit.all():
            w = np.nonzero(~hit)[0]
            far = np.linspace(0.0, MATE_REACH * abs(span), 2 * MATE_REACH * EVENT_SCAN + 1)
            at2, hit2 = self._mate_touching(rotor, x[pick[w]], far * np.sign(span), psi)
            at[w[hit2]], hit[w[hit2]], touched[w[hit2]] = at2[hit2], True, True
        if not hit.any():
            return np.full(n, span), np.zeros(n, dtype=bool)
        use = hit & touched if (hit & touched).any() else hit
        own = np.interp(np.arange(n), pick[use], at[use])
        found = np.interp(np.arange(n), pick, hit.astype(float)) > 0.5
        return own, found

    def _closing_at(self, ring, cls, rotor, x, ds, orient):
        """(move, whether its gap closes, whether its touching is found) per point of x:
        scanned over ``ds``, bisected, and on to where the true surfaces touch
        (:meth:`_touching`) where they do."""
        g = self._gaps(ring, cls, rotor, x, ds, orient)
        crossed = (g[1:] <= 0.0) & (g[:-1] > 0.0)
        hit = crossed.any(axis=0)
        first = np.argmax(crossed, axis=0)
        at = self._bisect(ring, cls, rotor, x, ds[first], ds[first + 1], True, orient, BISECT)
        touched = np.zeros(len(x), dtype=bool)
        if hit.any():
            h = np.nonzero(hit)[0]
            at[h], touched[h] = self._touching(ring, cls, rotor, x[h], at[h], ds[1] - ds[0],
                                               orient)
        return at, hit, touched

    def _mate_each(self, rotor, x, dpsi, psi) -> np.ndarray:
        """Signed distance of each point x[v] of rotor ``rotor``, moved rigidly by
        dpsi[v] from the sample at ``psi``, to the other rotors' true surfaces there
        (positive outside them)."""
        axis, ratio = self.surfaces.rotors[rotor][:2]
        dpsi = np.broadcast_to(np.asarray(dpsi, dtype=float), (len(x),))
        y = planar.rotate(x - axis, ratio * dpsi) + axis
        return np.min([self.surfaces.outside(c, y, psi + dpsi)
                       for c in range(len(self.surfaces.rotors)) if c != rotor], axis=0)

    def _mate_gaps(self, rotor, x, dpsi, psi) -> np.ndarray:
        """:meth:`_mate_each` (len(dpsi), len(x)) of points x each moved by each dpsi."""
        dpsi = np.asarray(dpsi, dtype=float)
        flat = self._mate_each(rotor, np.tile(x, (len(dpsi), 1)), np.repeat(dpsi, len(x)),
                               psi)
        return flat.reshape(len(dpsi), len(x))

    def _mate_touching(self, rotor, x, ds, psi):
        """(move, whether found) per point of x (rotor ``rotor``'s, at the sample
        ``psi``) whose gap to its ring never closes (the ring is cut off beyond it, at
        the cusp line): where it touches the other rotor's true surface, moving over
        ``ds``.  The point lies on its grown rotor, so its distance to the true mate
        closes and opens again about the touching: the middle of the two crossings
        (the closing where it does not open again within the scan, or where the gap
        falls below TOUCH_DEPTH first: it went through)."""
        g = self._mate_gaps(rotor, x, ds, psi)
        shut = (g[1:] <= 0.0) & (g[:-1] > 0.0)
        found = shut.any(axis=0)
        i = np.argmax(shut, axis=0)
        close = np.zeros(len(x))
        if found.any():
            f = np.nonzero(found)[0]
            close[f] = self._mate_bisect(rotor, x[f], ds[i[f]], ds[i[f] + 1], psi, True)
        after = np.arange(len(ds))[:, None] > i[None, :]
        opened = after & (g > 0.0)
        again = opened.any(axis=0)
        j = np.argmax(opened, axis=0)
        inside = after & (np.arange(len(ds))[:, None] < j[None, :])
        deep = (np.where(inside, g, np.inf) <= -TOUCH_DEPTH * self.surfaces.size).any(axis=0)
        at = close.copy()
        if (found & again & ~deep).any():
            w = np.nonzero(found & again & ~deep)[0]
            at[w] = 0.5 * (close[w] + self._mate_bisect(rotor, x[w], ds[j[w] - 1], ds[j[w]],
                                                        psi, False))
        return at, found

    def _mate_bisect(self, rotor, x, lo, hi, psi, open_lo) -> np.ndarray:
        """Per point of x: where its gap to the other rotors (:meth:`_mate_gaps`)
        closes (``open_lo``) or opens again between the moves lo and hi, bisected
        BISECT + TOUCH_BISECT times."""
        for _ in range(BISECT + TOUCH_BISECT):
            mid = 0.5 * (lo + hi)
            same = (self._mate_each(rotor, x, mid, psi) > 0.0) == open_lo
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        return 0.5 * (lo + hi)

    def _bisect(self, ring, cls, rotor, x, lo, hi, open_lo, orient, rounds):
        """Per point of x: where its gap closes (``open_lo``) or opens again between
        the moves lo and hi, bisected ``rounds`` times: the last bracket's middle."""
        for _ in range(rounds):
            mid = 0.5 * (lo + hi)
            same = (self._gaps_each(ring, cls, rotor, x, mid, orient) > 0.0) == open_lo
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        return 0.5 * (lo + hi)

    def _touching(self, ring, cls, rotor, x, at, step, orient):
        """Per point: where the true surfaces touch, from ``at``, where its grown gap
        closes (moving by ``step``'s sign): the middle between that and where the gap
        opens again beyond it (an overlap of the grown rotors, never deeper than
        TOUCH_DEPTH, within TOUCH_REACH); ``at`` where it does not open again."""
        n = len(x)
        sign = math.copysign(1.0, step)
        q = np.full(n, abs(step) / TOUCH_SCAN)
        start = at.copy()
        found = np.zeros(n, dtype=bool)
        lo, hi = at.copy(), at.copy()
        todo = np.ones(n, dtype=bool)
        k = np.arange(1, TOUCH_SCAN + 1)
        deep = -TOUCH_DEPTH * self.surfaces.size
        while todo.any():
            w = np.nonzero(todo)[0]
            ds = start[w][None, :] + sign * q[w][None, :] * k[:, None]
            g = self._gaps_each(ring, cls, rotor, np.tile(x[w], (len(k), 1)), ds.ravel(),
                                orient).reshape(len(k), len(w))
            opened = g > 0.0
            again = opened.any(axis=0)
            first = np.argmax(opened, axis=0)
            before = np.arange(len(k))[:, None] < np.where(again, first, len(k))[None, :]
            through = ((g <= deep) & before).any(axis=0)
            got = again & ~through
            u = np.arange(len(w))
            found[w[got]] = True
            lo[w[got]] = np.where(first > 0, ds[np.maximum(first - 1, 0), u], start[w])[got]
            hi[w[got]] = ds[first, u][got]
            on = ~again & ~through & (np.abs(ds[-1] - at[w]) < TOUCH_REACH)
            todo[:] = False
            todo[w[on]] = True
            start[w[on]] = ds[-1][on]
            q[w[on]] *= 2.0
        out = at.copy()
        if not found.any():
            return out, found
        f = np.nonzero(found)[0]
        again = self._bisect(ring, cls, rotor, x[f], lo[f], hi[f], False, orient,
                             TOUCH_BISECT)
        out[f] = 0.5 * (at[f] + again)
        return out, found


def _dot(u, v):
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1]


def _edge_distance(y, a, ab, den):
    """Distances (v, e) of points y (v, 1, 2) to the segments from a along ab (1 or v,
    e, 2; ``den`` their squared lengths) and the side each lies on (+1 left of it)."""
    ay0, ay1 = y[..., 0] - a[..., 0], y[..., 1] - a[..., 1]
    ab0, ab1 = ab[..., 0], ab[..., 1]
    t = np.clip((ay0 * ab0 + ay1 * ab1) / np.maximum(den, 1e-300), 0.0, 1.0)
    d0, d1 = ay0 - t * ab0, ay1 - t * ab1
    return np.sqrt(d0 * d0 + d1 * d1), np.sign(ab0 * ay1 - ab1 * ay0)
