"""Which life of a groove a part of a twin-screw section belongs to (see :mod:`.regions`).

A groove lives from the mesh, where it is born on the side where the lobes come apart
(the top, y > 0), once round, to the mesh again, where it dies on the side where the
lobes go in (the bottom); its age is its mid-line's angle since it left the mesh.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..planar import TWO_PI
from .boundaries import CUSP_POINT, MALE

#: A pocket's area rate (per C^2 and radian) below this is no rate: it is handed over
#: by the side of the line of centres it lies on.
POCKET_RATE = 1e-12
#: A part with a point this far (rad) beyond the cusps' polar angle reaches out of the
#: mesh onto its bore (a bore's polygon vertex lies within a chord error, 1e-6 C, of it).
MESH_MARGIN = 1e-4


class GrooveAges:
    """The groove-age methods of :class:`.regions.SectionCutter` (a mixin: it needs the
    cutter's pair, cusp and frames)."""

    def _groove_age(self, rotor, rings, psi, side, groove=None, rate=0.0):
        """(groove index, age in male-angle units) of a part (module docstring).

        The age is the groove's mid-line angle from the line of centres, unwrapped over
        the groove's life: a life runs from the top of the mesh once round to its
        bottom, and with few lobes (a 1-lobe groove is the whole circumference) it lasts
        longer than a revolution, so the mid-line's angle alone does not tell which
        life a part is.  Its fluid does: a point of the part at polar angle ``a`` from
        the line of centres (positive towards the top, where the grooves are born) has
        travelled ``a mod 2 pi`` since it left the mesh, and lies ``f`` from the
        mid-line, so the groove's age is ``(a mod 2 pi) - f``; the point taken is the
        one farthest from the mesh, where that is unambiguous.

        A part wholly inside the mesh (between the cusps) goes by the cusp it reaches
        (its own, else its piece's ``side``): the top one is newborn, the bottom one
        dying.  A pocket that reaches neither (trapped between contacts, or open to
        both sides) belongs to the dying chamber while it shrinks and to the newborn one
        while it grows (``rate``: its area's rate per male angle, which is its torques'
        power): so it changes hands at its smallest, and the chambers' areas stay
        continuous but for that carry-over.  None for such a pocket when ``rate`` is
        None (not known: a polygons-only cut).
        """
        pair = self.pair
        n = pair.gearing.lobes_male if rotor == MALE else pair.gearing.lobes_female
        period = TWO_PI / n
        tip0 = pair.tip_angle(rotor)
        if groove is None:
            local = self.to_rotor(rotor, centroid(rings[0]), psi)
            groove = int(math.floor(((math.atan2(local[1], local[0]) - tip0) % TWO_PI)
                                    / period)) % n
        k = groove
        mid = tip0 + (k + 0.5) * period  # the groove's mid-line, own frame
        pts = np.concatenate(rings)
        if rotor == MALE:
            theta = math.remainder(mid + psi, TWO_PI)  # 0: facing the female axis
            a = np.arctan2(pts[:, 1], pts[:, 0])
            scale = 1.0
        else:
            theta = math.remainder(math.pi - (mid + self.female_angle(psi)), TWO_PI)
            a = np.arctan2(pts[:, 1], self.C - pts[:, 0])
            scale = 1.0 / self.ratio
        far = int(np.argmax(np.abs(a)))
        if abs(a[far]) > self._cusp_angle[rotor] + MESH_MARGIN:
            age = float(a[far]) % TWO_PI - math.remainder(float(a[far]) - theta, TWO_PI)
            return k, age * scale
        # In the mesh: the part's points all lie within a lobe period of the line of
        # centres, and so does the mid-line of its groove, seen from any of them.
        near = math.remainder(float(a[far]) - theta, TWO_PI)
        theta = float(a[far]) - near
        reach = self._reaches(pts)
        if reach != "":
            side = reach
        if side == "top":
            age = theta
        elif side == "bottom":
            age = theta + TWO_PI
        elif rate is None:
            return None  # (a polygons-only cut: the caller cuts in full)
        elif abs(rate) > POCKET_RATE * self.C ** 2:
            age = theta if rate > 0.0 else theta + TWO_PI
        else:
            age = theta if centroid(rings[0])[1] > 0.0 else theta + TWO_PI
        return k, age * scale

    @cached_property
    def _cusp_angle(self):
        """Each rotor's polar angle of the cusps from the line of centres."""
        return (math.atan2(self.yc, self.xc), math.atan2(self.yc, self.C - self.xc))

    def _reaches(self, pts) -> str:
        """"top" or "bottom" if points ``pts`` (a part's vertices) reach that cusp point
        and not the other, else ""."""
        tol = CUSP_POINT * self.C
        top = bool(np.any(np.hypot(pts[:, 0] - self.xc, pts[:, 1] - self.yc) < tol))
        bottom = bool(np.any(np.hypot(pts[:, 0] - self.xc, pts[:, 1] + self.yc) < tol))
        return "top" if top and not bottom else ("bottom" if bottom and not top else "")


def centroid(ring):
    """Centroid of the region a closed ring bounds (either orientation).

    Taken about the ring's first vertex: about the axis, a section's sliver a few
    nanometres across (Clipper's pieces between chords that cross along a band, as where
    the pin-cycloid's female groove is born) has cross products of 1e-3 m^2 whose
    rounding (3e-19 m^2) swamps its area (3e-21 m^2), which came out exactly zero and
    the centroid NaN.  A ring that still encloses nothing (collinear vertices on Clipper's
    grid) is located by its vertices' mean: the age asks only where it lies."""
    origin = ring[0]
    x, y = ring[:, 0] - origin[0], ring[:, 1] - origin[1]
    x2, y2 = np.concatenate([x[1:], x[:1]]), np.concatenate([y[1:], y[:1]])
    c = x * y2 - x2 * y
    a = 0.5 * c.sum()
    if a == 0.0:
        return ring.mean(0)
    return origin + np.array([((x + x2) * c).sum(), ((y + y2) * c).sum()]) / (6.0 * a)
