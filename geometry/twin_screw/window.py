"""The grooves a twin-screw section's Boolean cut can leave out (see :mod:`.regions`).

Away from the mesh every groove of a section is a whole groove: the rotor's profile
from one tip to the next and its bore's arc, the same shape for every lobe, turned.
Clipper's sweep costs about its vertices, and at any angle more than half of each
rotor's grooves lie out of the other bore's reach.  Those grooves are covered before
the cut (their stretch of the rotor's ring replaced by an arc just outside the bore,
from tip to tip) and booked as the first whole groove cut, turned to their place.

A rotor is windowed only where its tips reach past its bore (so that the sections'
grooves are closed at the tips) and it has no lands, and only once a whole groove of it
has been cut.
"""

from __future__ import annotations

import math

import numpy as np

from ..planar import TWO_PI, rotate
from .boundaries import FEMALE, MALE

#: The covering arc's radius, per bore radius, beyond the bore: its chords stay outside
#: the bore (ARC_STEP of the largest step that keeps them there).
ARC_GAP = 1e-3
ARC_STEP = 0.9
#: A groove counts as out of reach only this far (per C) clear of the other bore's
#: nearest point, so that its arc never meets the other rotor.
CLEARANCE = 1e-3


class GrooveWindow:
    """Per rotor of a :class:`.regions.SectionCutter`: each groove's stretch of the grown
    polygon (own frame), its covering arc, and the turned copies of a whole groove."""

    def __init__(self, cutter):
        self.cutter = cutter
        self.rotors = [self._rotor(r) for r in (MALE, FEMALE)]
        self.whole = {}  # rotor -> (groove, rings in the rotor's own frame)

    def _rotor(self, r):
        """Per groove: (the indices of its stretch of the grown polygon, from its
        clockwise tip on; the tip and the arc that replace the stretch; the stretch's
        and the arc's points, for the reach test), or None when the rotor is not
        windowed."""
        cut = self.cutter
        rd = cut._rotor_data[r]
        poly, radius = rd.polygon, cut.R[r]
        n, m = len(rd.tips), len(poly)
        if cut._lands[r] or n < 2:
            return None
        _, tip = rd.tree.query(rd.tips)
        if np.any(np.linalg.norm(poly[tip], axis=1) <= radius):
            return None
        outer = radius * (1.0 + ARC_GAP)
        step = ARC_STEP * 2.0 * math.acos(1.0 / (1.0 + ARC_GAP))
        grooves = []
        for k in range(n):
            a, b = int(tip[k]), int(tip[(k + 1) % n])
            idx = np.arange(a, b if b > a else b + m) % m
            t0 = math.atan2(poly[a, 1], poly[a, 0])
            span = (math.atan2(poly[b, 1], poly[b, 0]) - t0) % TWO_PI
            th = t0 + np.linspace(0.0, span, int(math.ceil(span / step)) + 1)
            arc = outer * np.c_[np.cos(th), np.sin(th)]
            cover = np.concatenate([poly[a:a + 1], arc])
            grooves.append((idx, cover, np.concatenate([poly[idx], arc])))
        return grooves

    def out_of_reach(self, r, psi) -> list[int]:
        """The grooves of rotor r wholly out of the other bore's reach at male angle
        psi (covering arcs included); none until a whole groove of r has been cut."""
        grooves = self.rotors[r]
        if grooves is None or r not in self.whole:
            return []
        cut = self.cutter
        ang = psi if r == MALE else cut.female_angle(psi)
        c, s = math.cos(ang), math.sin(ang)
        margin = CLEARANCE * cut.C
        out = []
        for k, (_, _, hull) in enumerate(grooves):
            x = c * hull[:, 0] - s * hull[:, 1]
            if r == MALE and x.max() < cut.C - cut.R[FEMALE] - margin:
                out.append(k)
            elif r == FEMALE and cut.C + x.min() > cut.R[MALE] + margin:
                out.append(k)
        return out

    def ring(self, r, psi, covered) -> np.ndarray:
        """Rotor r's grown polygon at male angle psi (fixed frame, metres), the grooves
        ``covered`` replaced by their arcs."""
        cut = self.cutter
        poly = cut._rotor_data[r].polygon
        if covered:
            grooves = self.rotors[r]
            skip = set(covered)
            poly = np.concatenate([cover if k in skip else poly[idx]
                                   for k, (idx, cover, _) in enumerate(grooves)])
        return cut.rotor_at(r, poly, psi)

    def keep(self, r, groove, rings, psi) -> None:
        """Hold a whole groove of rotor r cut at psi (its rings, fixed frame)."""
        if r not in self.whole:
            self.whole[r] = (groove, [self.cutter.to_rotor(r, q, psi) for q in rings])

    def turned(self, r, groove, psi) -> list[np.ndarray]:
        """The held whole groove turned to groove ``groove`` at male angle psi (fixed
        frame)."""
        held, rings = self.whole[r]
        n = len(self.rotors[r])
        turn = (groove - held) * TWO_PI / n
        return [self.cutter.rotor_at(r, rotate(q, turn), psi) for q in rings]
