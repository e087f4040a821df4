"""The blow-hole of a pair with lands (the trochoidal pump profile): the flank pocket.

On a pair with lands (:mod:`.lands`) one rotor's land covers each cusp at every angle
(the corners of both rotors reach a cusp together, seed 003's trochoidal profile), so
the cusp line is never free at a cusp point and :class:`.blowhole.CuspRay` finds no
opening.  The chambers meet elsewhere: the space between the flanks, a pocket closed
off from both grooves by two contacts, crosses the cusp line from the bottom cusp to
the top one once per lobe period; its male half is booked to the male groove's chamber
and its female half to the female groove's (:mod:`.regions`).  In every other pass the
two are one chamber (the chamber's own grooves meeting, :func:`.section._female_shift`);
in the passes between they are two chambers, and the pocket's cut by the cusp line is
the opening between them, the cusp plane's blow-hole as on a pair with tip points.  It
is named by the side of the line of centres its middle lies on (bottom: "blow-hole",
top: "blow-hole-suction").

:class:`PocketRay` gives that cut's length at any angle from the rotors' polygons;
:func:`corner_crossings` the angles at which a corner crosses a cusp, where a pocket is
born or dies (the passes' ends, between which the pair of chambers it joins is fixed).
"""

from __future__ import annotations

import math

import numpy as np

from .blowhole import CuspRay, cusp_crossings
from .boundaries import CUSP_POINT
from .regions import FEMALE, MALE

#: Angles per batch (their arrays are angles x polygon edges).
POCKET_CHUNK = 64


class PocketRay(CuspRay):
    """Free length of the cusp line between the cusps, away from both cusp points, on
    one side of the line of centres (the interface :class:`.blowhole.WidthTable` reads:
    ``pair`` and ``width(psi, top, direction)``).  The cusp ray's frame and edges: its
    pruning keeps every edge that can reach the line x = x_c, which is all this needs."""

    def width(self, psi, top: bool, direction=None) -> np.ndarray:
        """Length of the cusp line's free stretches that reach neither cusp point and
        whose middles lie on the ``top`` (y > 0) or bottom side, per male angle.
        ``direction`` is not used: the cut is the cusp plane's (the seed 004 plane
        through the contact line's highest point is a tip point's construction)."""
        psi = np.atleast_1d(np.asarray(psi, dtype=float))
        if len(psi) > POCKET_CHUNK:
            return np.concatenate([self.width(psi[i:i + POCKET_CHUNK], top)
                                   for i in range(0, len(psi), POCKET_CHUNK)])
        ys, owner = [], []
        for r in (MALE, FEMALE):
            a, b = self.edges[r][:2]
            ang = self.angle(r, psi)[:, None]
            c, s = np.cos(ang), np.sin(ang)
            o = self.axes[r]
            xa = c * a[None, :, 0] - s * a[None, :, 1] + o[0] - self.xc
            ya = s * a[None, :, 0] + c * a[None, :, 1] + o[1]
            xb = c * b[None, :, 0] - s * b[None, :, 1] + o[0] - self.xc
            yb = s * b[None, :, 0] + c * b[None, :, 1] + o[1]
            # half-open test: an edge ending on the line counts once
            cross = (xa > 0.0) != (xb > 0.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                y = ya + (yb - ya) * xa / (xa - xb)
            ys.append(np.where(cross, y, np.nan))
            owner.append(np.full(cross.shape, r))
        ys, owner = np.concatenate(ys, 1), np.concatenate(owner, 1)
        return np.array([self._free(row[~np.isnan(row)], who[~np.isnan(row)], top)
                         for row, who in zip(ys, owner, strict=True)])

    def _free(self, y, who, top: bool) -> float:
        """The free stretches of the line x = x_c from its crossings ``y`` with the
        rotors ``who``: the line is outside both rotors below the bores, and a rotor's
        crossings toggle inside / outside it (even-odd)."""
        order = np.argsort(y, kind="stable")
        y, who = y[order], who[order]
        inside = np.cumsum(np.stack([who == MALE, who == FEMALE]), 1) % 2
        free = ~inside.any(0)  # after each crossing
        tol = CUSP_POINT * self.pair.gearing.centre_distance
        total = 0.0
        for k in np.nonzero(free[:-1])[0]:
            lo, hi = max(y[k], -self.yc), min(y[k + 1], self.yc)
            if hi <= lo or lo < -self.yc + tol or hi > self.yc - tol:
                continue  # outside the bores, or at a cusp point (the cusp ray's)
            if (lo + hi > 0.0) == top:
                total += hi - lo
        return total


def corner_crossings(pair, a: float, b: float) -> np.ndarray:
    """Male angles in [a, b] at which a land corner of either rotor crosses either
    cusp (:func:`.blowhole.tip_crossings` with corners for tips, both cusps: a pocket
    is born at one and dies at the other)."""
    angles = {}
    for rotor, profile in ((MALE, pair.male), (FEMALE, pair.female)):
        corners = pair.corner_points(profile)[:2]  # lobe 0's: the others repeat them
        angles[rotor] = [math.atan2(p[1], p[0]) for p in corners]
    return np.unique(cusp_crossings(pair, a, b, angles, (True, False)))
