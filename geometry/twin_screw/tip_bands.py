"""Where a twin-screw rotor runs along its bore next to a tip (see :mod:`.boundaries`).

A rotor whose profile lies within TIP_BAND of its bore over an arc next to a tip (a
rounded tip, the pin-cycloid female's land 0.44 rad wide, the pin-cycloid male's arc
behind its tip) seals along that whole arc: nothing wets it, and a part's wetted arc
that ends on it ends at the tip, the one point every part agrees on.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

#: A rotor within this (per C) of its bore over an arc about its tip seals along the whole
#: arc: a cut at the cusp that ends on it ends at the tip.  Four times the rotors' growth
#: (the grown rotor reaches the bore where the gap is below one growth, and leaves fluid
#: slivers a fraction of a micron thick just beyond): a 1-lobe rotor's tip can be nearly
#: as curved as its bore over a millimetre, beyond TIP_MATCH (0.55 mm measured on the
#: circular 1/1 pair at C = 78 mm), where no real clearance is this small (0.6 um).
TIP_BAND = 8e-6
#: Bisections of a sample spacing for where a rotor leaves its tip band (2^-40 of a
#: spacing of ~0.1 mm: far below the chord error).
BAND_BISECTIONS = 40
#: A contact this near (per C) the end of a tip band is at its corner (8 um at C = 80
#: mm, :data:`.boundaries.TIP_MATCH`'s reach for a cut at a tip).
BAND_CORNER = 1e-4
#: Contact ends of one rotor within this (per C) are one (both sides of a contact take
#: the very same snapped point; this is rounding's margin).
SAME_END = 1e-9


class TipBands:
    """The tip-band methods of :class:`.regions.SectionCutter` (a mixin: it needs the
    cutter's pair, rotors, bores and frames)."""

    def _in_tip_band(self, r, k, x, psi) -> bool:
        """Whether x lies on rotor r's bore next to tip k where the rotor runs within
        TIP_BAND of its bore all the way from the tip."""
        lo, hi = self._tip_bands[r]
        local = self.to_rotor(r, np.asarray(x)[None, :], psi)[0]
        if np.linalg.norm(local) < self.R[r] - TIP_BAND * self.C:
            return False
        tip = self._rotor_data[r].tips[k]
        off = math.remainder(math.atan2(local[1], local[0]) - math.atan2(tip[1], tip[0]),
                             2.0 * math.pi)
        return lo <= off <= hi

    def tip_band(self, r) -> tuple[float, float]:
        """Rotor r's band about its tip: the polar angles of its ends from the tip's."""
        return self._tip_bands[r]

    @cached_property
    def _tip_bands(self):
        """Per rotor, the polar angles (from its tip's) between which its profile lies
        within TIP_BAND of its outer radius, next to the tip: the sampled profile's last
        vertex within it, then the curve itself between that vertex and the next (the
        samples lie up to 0.1 mm apart on an arc this close to the bore: the
        pin-cycloid male's band is 0.0038 rad long, its last vertex 0.0020 rad from the
        tip, and a cut at the cusp 0.0024 rad behind it, 0.2 um under the bore, ended
        short of the tip while the part across the line took it: 0.12 mm of the male
        was nobody's for 0.004 rad after the tip passed the top cusp)."""
        out = []
        for r, profile in enumerate((self.pair.male, self.pair.female)):
            u = self._rotor_data[r].u
            pts = profile.point(u)
            rad = np.linalg.norm(pts, axis=-1)
            tip = self._rotor_data[r].tips[0]
            m = len(u)
            i0 = int(np.argmin(np.linalg.norm(pts - tip, axis=-1)))
            near = self.R[r] - rad < TIP_BAND * self.C
            ends = []
            for step in (-1, 1):
                i = i0
                while near[(i + step) % m] and (i + step - i0) * step < m // 2:
                    i += step
                end = self._band_end(profile, u[i % m], u[(i + step) % m], step, r)
                ends.append(math.remainder(math.atan2(end[1], end[0])
                                           - math.atan2(tip[1], tip[0]), 2.0 * math.pi))
            out.append((min(ends + [0.0]), max(ends + [0.0])))
        return out

    def _band_end(self, profile, a, b, step, r):
        """The point of ``profile`` between parameters a (within TIP_BAND of rotor r's
        bore) and b (the next sample, beyond it) where it leaves the band, by bisection
        (the radius falls monotonically there: a sample spacing is a short arc)."""
        n = profile.n
        if (b - a) * step < 0.0:  # the parameter wraps round between them
            b += step * n
        limit = self.R[r] - TIP_BAND * self.C
        for _ in range(BAND_BISECTIONS):
            mid = 0.5 * (a + b)
            if np.linalg.norm(profile.point(np.array([mid % n]))[0]) > limit:
                a = mid
            else:
                b = mid
        return profile.point(np.array([a % n]))[0]

    @cached_property
    def _band_corners(self):
        """Per rotor, (tips, 2, 2): both ends of every tip's band on its bore, own frame."""
        out = []
        for r in (0, 1):
            tips = self._rotor_data[r].tips
            ang = np.arctan2(tips[:, 1], tips[:, 0])[:, None] + np.array(self._tip_bands[r])
            out.append(self.R[r] * np.stack([np.cos(ang), np.sin(ang)], -1))
        return out

    def _close_bands(self, runs, psi) -> None:
        """A wetted arc that ends at a contact at the corner of a tip band, where no
        other part's arc of that rotor ends, ends at the band's tip instead.

        Beyond such a contact the rotor runs on its bore to its tip, wetted by nobody:
        the fluid across the corner, between it and the other bore, is thinner than the
        rotors' overlap and has no part.  On the pin-cycloid pair the male tip, the
        female land's corner and the top cusp meet at one angle; for 3e-5 rad before it
        and 8e-6 after, the land's few microns in the lens were no part's, and its arc
        from the contact to its tip nobody's (22 % of the female's largest part force).
        A band whose tip lies inside the other bore is not closed so (see below).
        ``runs`` holds (run, "a" or "b") of every arc end resolved to a contact."""
        tol = SAME_END * self.C
        for run, which in runs:
            end = getattr(run, which)
            others = [getattr(q, w) for q, w in runs
                      if q.rotor == run.rotor and (q is not run or w != which)]
            if others and (np.linalg.norm(np.array(others) - end, axis=-1) < tol).any():
                continue
            corners = self.rotor_at(run.rotor, self._band_corners[run.rotor].reshape(-1, 2),
                                    psi)
            d = np.linalg.norm(corners - end, axis=-1)
            j = int(np.argmin(d))
            if d[j] >= BAND_CORNER * self.C:
                continue
            tip = self.rotor_at(run.rotor, self._rotor_data[run.rotor].tips[j // 2], psi)
            other = 1 - run.rotor
            # Only a band that leaves the lens for its own bore is dry: one inside the
            # other bore (the circular female's tip rolling in the male root) has the
            # other rotor across it, and a pocket there lost both rotors' arcs.
            if np.linalg.norm(tip - self.O[other]) > self.R[other]:
                setattr(run, which, tip)
