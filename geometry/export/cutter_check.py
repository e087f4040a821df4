"""Whether a disc cutter cuts into its rotor anywhere (:mod:`.cutter`'s round trip).

The tool surface is screwed back into the rotor's transverse plane (a tool point at
height z lands where the helix turns it, :func:`.cutter._to_transverse`) and each image
point's signed distance to the profile is measured (negative inside the rotor).

The distances are to the profile's polygon (chord error POLYGON_TOL), signed by the
nearest feature (:class:`..polygons.PolygonDistance`).
Until 2026-11-30 they were Newton feet on the curve from the nearest vertex, which at a
corner can converge on the wrong piece: the 4/6 pin-cycloid female's tool circles
graze its flank within 0.1 um next to its tip corner, and the feet found on the land
beside it made that 20 to 56 um of "interference", or none, as the setting angle
moved by a quarter of a degree.

Each tool circle is sampled on a grid, and every grid interval that could hide a cut is
searched for its least distance: the distance changes by at most the distance moved,
so an interval whose ends lie d_a and d_b outside, with chord l between their images,
holds no inside point if d_a + d_b > l.
"""

from __future__ import annotations

import math

import numpy as np

from ..curves import sample
from ..polygons import PolygonDistance

#: Tool angles per radian of the grid, either side of the plane through both axes.
INTERFERENCE_DENSITY = 100
#: Tool circles sampled per interval between written tool points (and the points).
CIRCLES_PER_INTERVAL = 4
#: Golden-section steps of a grid interval's least distance (0.618^32: 2e-7 of it).
SEARCH_STEPS = 32
#: Polygon vertices whose segments are searched for the nearest: with 2, 45 of 200 000
#: points near the 4/6 male's root corners (its polygon's edges reach 0.5 mm there)
#: missed their nearest segment by up to 61 um; with 6, one by 1.7 um.
NEAREST = 6
#: Chordal tolerance of the profile polygon [m].
POLYGON_TOL = 1e-7
GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)


def interference(prof, setup, meridian) -> tuple[float, np.ndarray | None]:
    """(depth, where): the deepest point of the tool surface inside the rotor (>= 0)
    and that point in the turned rotor frame (None if it cuts nowhere).  ``meridian``
    is (s_nodes, h(s), R(s))."""
    from .cutter import _to_transverse, _tool_points

    s_nodes, hs, Rs = meridian
    s = np.concatenate([np.linspace(a, b, CIRCLES_PER_INTERVAL, endpoint=False)
                        for a, b in zip(s_nodes[:-1], s_nodes[1:], strict=True)]
                       + [s_nodes[-1:]])
    dist = _Distance(prof.point(sample(prof.curve, POLYGON_TOL)))
    # A tool point at angle psi lies at least C - R cos(psi) from the rotor's axis: the
    # angles where that exceeds the rotor's radius cannot cut it.
    reach = (setup.centre_distance - dist.r_max) / float(np.max(Rs(s)))
    span = math.acos(min(1.0, max(-1.0, reach))) + 0.05
    psi = np.linspace(-span, span, max(3, int(2 * span * INTERFERENCE_DENSITY) | 1))

    def signed(ss, pp):
        T, _ = _tool_points(setup, hs(ss), Rs(ss), pp)
        q = _to_transverse(T, setup.k)
        return q, dist(q)

    S, PSI = np.meshgrid(s, psi, indexing="ij")
    q, d = signed(S, PSI)
    k = np.unravel_index(np.argmin(d), d.shape)
    best = [float(d[k]), q[k]]
    hide = d[:, :-1] + d[:, 1:] < np.linalg.norm(q[:, 1:] - q[:, :-1], axis=-1) + 1e-9
    if hide.any():
        ss, a, b = S[:, :-1][hide], PSI[:, :-1][hide], PSI[:, 1:][hide]
        c, e = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
        fc, fe = signed(ss, c)[1], signed(ss, e)[1]
        for _ in range(SEARCH_STEPS):
            left = fc < fe  # the least lies in [a, e]: e becomes c
            a, b = np.where(left, a, c), np.where(left, e, b)
            c, e, fc, fe = (np.where(left, b - GOLDEN * (b - a), e),
                            np.where(left, c, a + GOLDEN * (b - a)),
                            np.where(left, np.nan, fe), np.where(left, fc, np.nan))
            fx = signed(ss, np.where(left, c, e))[1]
            fc, fe = np.where(left, fx, fc), np.where(left, fe, fx)
        qm, dm = signed(ss, 0.5 * (a + b))
        j = int(np.argmin(dm))
        if dm[j] < best[0]:
            best = [float(dm[j]), qm[j]]
    return (0.0, None) if best[0] >= 0.0 else (-best[0], best[1])


class _Distance(PolygonDistance):
    """The profile polygon's signed distance, beyond the rotor's circle the circle's (a
    lower bound: most of a tool circle's images lie there)."""

    def __init__(self, poly):
        super().__init__(poly, nearest=NEAREST)
        self.r_max = float(np.linalg.norm(self.poly, axis=-1).max())

    def __call__(self, q):
        shape = q.shape[:-1]
        q = q.reshape(-1, 2)
        out = np.linalg.norm(q, axis=-1) - self.r_max
        near = out <= 0.0
        if near.any():
            out[near] = super().__call__(q[near])
        return out.reshape(shape)
