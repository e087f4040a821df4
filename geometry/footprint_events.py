"""Slivers born and dying, and pockets handed over, between two sampled sections (the
events of :mod:`.footprint`), found by moving a section's rotor pieces rigidly.

A ring of a section with no piece matched at the neighbouring sample came or went in
between.  Moved rigidly towards that sample (each rotor vertex turned about its axis,
the still vertices kept), its area falls: where it falls to nearly nothing and the
median gap of a rotor piece to the rest of the ring changes sign, a sliver closes
there; where the area is least inside the step, a pocket was handed over there.  A
sliver's passage is swept per vertex, each from where its own gap closes (a sliver may
open along its length over a while); a pocket's, rigidly from the least area on.
"""

from __future__ import annotations

import math

import numpy as np

from .surfaces import area as _area
from .surfaces import turn as _turn

#: Sub-steps of a step scanned for a sliver's birth or death or a pocket's least area.
EVENT_SCAN = 8
#: How far (reference angle, rad) a sliver's birth is looked for behind the sample that
#: first holds it (its death ahead of the last), at least two steps: the samples of its
#: first 0.2 deg hold none of it (THIN).
EVENT_REACH = 0.02
#: A ring whose area, its rotor pieces moved rigidly, falls to this fraction of its own
#: within the search closes there (a sliver's birth or death is looked for up to the
#: least area after that).
CLOSING = 0.05
#: Vertices of a rotor piece whose median gap locates a sliver's birth or death, and
#: whose own births are found (the rest interpolated).
GAP_POINTS = 33
#: Bisections of a vertex's own birth in its scan interval (to 2^-8 of it).
BISECT = 8
#: A piece's end that grows (or shrinks) along its surface by this many times more than
#: in the steps before and after, and by more than JUMP_MIN of the profile's parameter
#: (a profile segment spans 1), jumped (:meth:`Events._jumps`).
JUMP = 4.0
JUMP_MIN = 0.05


class Events:
    """The event methods of :class:`.footprint.Sweeper` (a mixin: it needs the sweeper's
    ``surfaces``)."""

    def _event(self, smp, ring_index, h, sign):
        """(|dpsi|, kind) of the event of ring ``ring_index`` of sample ``smp`` within h
        in the direction ``sign`` (-1: back to a birth, +1: on to a death), found by
        moving its rotor vertices rigidly: "sliver" where a rotor piece's signed gap to
        the rest of the ring vanishes, "pocket" where the ring's area is least; None."""
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
            for k in sorted(set(cls[cls >= 0].tolist())):
                fine = np.linspace(0.0, hi, 2 * (j + 1) + 1)
                gaps = [self._gap(ring, cls, k, sign * d, orient) for d in fine]
                for i in range(1, len(fine)):
                    if gaps[i] <= 0.0 < gaps[i - 1]:
                        # (roughly: each vertex's own birth is found where it is swept,
                        # _births)
                        w = gaps[i - 1] / (gaps[i - 1] - gaps[i])
                        return float(fine[i - 1] + w * (fine[i] - fine[i - 1])), "sliver"
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
        on = cls == k
        if not on.any() or np.all(on & np.roll(on, -1)):
            return 0.0
        x = ring[on]
        x = x[np.linspace(0, len(x) - 1, min(len(x), GAP_POINTS)).astype(int)]
        return float(np.median(self._gaps(ring, cls, k, x, np.array([dpsi]), orient)[0]))

    def _gaps(self, ring, cls, k, x, dpsi, orient) -> np.ndarray:
        """Signed distances (len(dpsi), len(x)) of points x of rotor k, each moved
        rigidly by each dpsi with the ring, to the ring's edges not along rotor k."""
        return np.array([self._gaps_each(ring, cls, k, x, np.full(len(x), d), orient)
                         for d in dpsi])

    def _gaps_each(self, ring, cls, k, x, dpsi, orient) -> np.ndarray:
        """Signed distance of each point x[v] of rotor k, moved rigidly by dpsi[v] with
        the ring, to the ring's edges not along rotor k (positive inside the ring)."""
        on = cls == k
        other = np.nonzero(~(on & np.roll(on, -1)))[0]
        ends = np.concatenate([other, (other + 1) % len(ring)])
        q = np.broadcast_to(ring[ends], (len(x), len(ends), 2)).copy()
        for c, (axis, ratio, *_rest) in enumerate(self.surfaces.rotors):
            sel = cls[ends] == c
            if sel.any():
                q[:, sel] = _turn(ring[ends][sel] - axis, ratio * dpsi) + axis
        axis, ratio = self.surfaces.rotors[k][:2]
        y = _turn((x - axis)[:, None], ratio * dpsi)[:, 0] + axis
        a, b = q[:, :len(other)], q[:, len(other):]
        ab = b - a
        t = np.clip(np.einsum("vek,vek->ve", y[:, None] - a, ab)
                    / np.maximum(np.einsum("vek,vek->ve", ab, ab), 1e-300), 0.0, 1.0)
        dist = np.linalg.norm(y[:, None] - (a + t[..., None] * ab), axis=-1)
        j = np.argmin(dist, axis=1)
        v = np.arange(len(x))
        rel = y - a[v, j]
        side = np.sign(ab[v, j, 0] * rel[:, 1] - ab[v, j, 1] * rel[:, 0]) * orient
        return side * dist[v, j]

    def _jumps(self, bands):
        """Bands of what a corner's jump exposed or covered between two samples (the
        bands' (piece at a, piece at b, psi_a, psi_b, sample a, sample b)).

        Where two rotor surfaces part along a stretch at once (the circular pair's
        conformal arcs, 148 deg after its chamber's birth) the new sliver is joined to
        a ring that has matched pieces, so no sliver event is seen: the pieces' end
        jumps along the surface, and the band's chord between the two ends misses what
        the stretch passed after it parted.  An end whose growth (in profile parameter)
        is JUMP times its growth in the steps before and after is such a jump: each
        vertex of the stretch is swept from where its own gap closes (:meth:`_closing`),
        as a sliver's."""
        before = {id(y): k for k, (x, y, *_r) in enumerate(bands)}
        after = {id(x): k for k, (x, y, *_r) in enumerate(bands)}
        growth = [self._growth(x, y) for x, y, *_r in bands]
        out = []
        for k, (x, y, *_r) in enumerate(bands):
            near = [j for j in (before.get(id(x)), after.get(id(y))) if j is not None]
            for end in (0, 1):
                g = growth[k][end]
                if near and abs(g) > max(JUMP * max(abs(growth[j][end]) for j in near),
                                         JUMP_MIN):
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
        own, found = self._closing(ring, cls, chain.rotor, pts, sign * (t1 - t0))
        if found.sum() < 2:
            return []
        axis, ratio = self.surfaces.rotors[chain.rotor][:2]
        moved = _turn((pts[found] - axis)[:, None], ratio * own[found])[:, 0] + axis
        band = ring_section(np.concatenate([pts[found], moved[::-1]]))
        return [] if band is None else [band]

    def _closing(self, ring, cls, rotor, x, span):
        """Per point of ``x`` (rotor ``rotor``'s, on ``ring``): the rigid move (signed,
        within ``span``) to where its gap to the ring's other edges closes, and whether
        it closes there.  Found on GAP_POINTS of them, scanned and bisected; the rest
        interpolated along x."""
        orient = 1.0 if _area(ring) > 0.0 else -1.0
        n = len(x)
        pick = np.unique(np.linspace(0, n - 1, min(n, GAP_POINTS)).astype(int))
        ds = np.linspace(0.0, abs(span), 2 * EVENT_SCAN + 1) * np.sign(span)
        g = self._gaps(ring, cls, rotor, x[pick], ds, orient)
        crossed = (g[1:] <= 0.0) & (g[:-1] > 0.0)
        hit = crossed.any(axis=0)
        if not hit.any():
            return np.full(n, span), np.zeros(n, dtype=bool)
        first = np.argmax(crossed, axis=0)
        lo, hi = ds[first], ds[first + 1]
        for _ in range(BISECT):
            mid = 0.5 * (lo + hi)
            open_ = self._gaps_each(ring, cls, rotor, x[pick], mid, orient) > 0.0
            lo, hi = np.where(open_, mid, lo), np.where(open_, hi, mid)
        own = np.interp(np.arange(n), pick[hit], (0.5 * (lo + hi))[hit])
        found = np.interp(np.arange(n), pick, hit.astype(float)) > 0.5
        return own, found

    def _births(self, ring, cls, chain, dpsi) -> np.ndarray:
        """Per vertex of ``chain`` (a piece of a sliver found born or dying |dpsi| away,
        by the median of its gap), the rigid move (signed) to where its own gap closes:
        a sliver may open along its length over a while (a zipper), and the points each
        vertex passes are swept from its own opening.  Found on GAP_POINTS vertices
        (the rest interpolated along the chain), scanned over twice |dpsi| and bisected."""
        own, found = self._closing(ring, cls, chain.rotor, chain.points, 2.0 * dpsi)
        return own if found.any() else np.full(len(chain.points), dpsi)

    def _rigid(self, smp, ring_index, dpsi, kind):
        """The passage of ring ``ring_index`` of ``smp`` between its event (dpsi away)
        and the sample, swept rigidly: each rotor piece's band, and a pocket's own
        region at the event."""
        from manifold3d import CrossSection, FillRule

        from .footprint import ring_section

        out = []
        ring, cls = smp.rings[ring_index]
        for c in smp.chains:
            if c.ring == ring_index:
                if kind == "sliver":
                    own = self._births(ring, cls, c, dpsi)
                    axis, ratio = self.surfaces.rotors[c.rotor][:2]
                    moved = _turn((c.points - axis)[:, None], ratio * own)[:, 0] + axis
                else:
                    moved = self.surfaces.move(c.points, c.rotor, dpsi)
                out.append(ring_section(np.concatenate([c.points, moved[::-1]])))
        if kind == "pocket":
            out.append(CrossSection([np.ascontiguousarray(self._moved(ring, cls, dpsi))],
                                    FillRule.NonZero))
        return out


