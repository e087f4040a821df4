"""Checks on sampled closed curves: self-intersections, simplicity, signed area.

A profile or a section of a solid is only valid when its polygon is simple (an offset
that folds, or two rotors that interfere, show up here); nothing is ever repaired.
"""

from __future__ import annotations

import numpy as np

from rotorflow.errors import CaseError

from .planar import cross


def _segments_cross(a, b, c, d):
    """Proper or touching intersection of segments ab and cd (arrays of pairs)."""
    def orient(p, q, r):
        return cross(q - p, r - p)

    o1, o2 = orient(a, b, c), orient(a, b, d)
    o3, o4 = orient(c, d, a), orient(c, d, b)
    return (o1 * o2 <= 0.0) & (o3 * o4 <= 0.0) & ~((o1 == 0) & (o2 == 0))


def self_intersections(poly: np.ndarray) -> np.ndarray:
    """Indices (i, j) of non-adjacent edges of the closed polygon that intersect."""
    return rings_intersections([poly])


def rings_intersections(rings) -> np.ndarray:
    """Pairs of intersecting edges among closed rings (edges numbered ring after ring;
    edges sharing a vertex of the same ring are not compared).

    Edges are bucketed on a uniform grid of cell size equal to the longest edge, so
    only edges in neighbouring cells are compared.
    """
    a = np.concatenate(rings)
    b = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    ring_id = np.concatenate([np.full(len(r), k) for k, r in enumerate(rings)])
    first = np.concatenate([[0], np.cumsum([len(r) for r in rings])])[:-1]
    last = first + np.array([len(r) for r in rings]) - 1
    lo = np.minimum(a, b)
    hi = np.maximum(a, b)
    cell = max(float(np.linalg.norm(b - a, axis=-1).max()), 1e-300)
    origin = lo.min(0)
    ilo = np.floor((lo - origin) / cell).astype(np.int64)
    ihi = np.floor((hi - origin) / cell).astype(np.int64)
    # every edge spans at most 2 x 2 cells
    keys, owners = [], []
    width = int(ihi[:, 0].max()) + 3
    for dx in (0, 1):
        for dy in (0, 1):
            cx, cy = ilo[:, 0] + dx, ilo[:, 1] + dy
            ok = (cx <= ihi[:, 0]) & (cy <= ihi[:, 1])
            keys.append((cy * width + cx)[ok])
            owners.append(np.nonzero(ok)[0])
    keys = np.concatenate(keys)
    owners = np.concatenate(owners)
    order = np.argsort(keys, kind="stable")
    keys, owners = keys[order], owners[order]
    starts = np.nonzero(np.diff(np.concatenate([[-1], keys])))[0]
    ends = np.append(starts[1:], len(keys))
    pairs = []
    sizes = ends - starts
    for size in np.unique(sizes):
        if size < 2:
            continue
        grp = starts[sizes == size]
        idx = owners[grp[:, None] + np.arange(size)[None, :]]
        ii, jj = np.triu_indices(size, 1)
        pairs.append(np.stack([idx[:, ii].ravel(), idx[:, jj].ravel()], -1))
    if not pairs:
        return np.zeros((0, 2), dtype=int)
    pr = np.unique(np.sort(np.concatenate(pairs), axis=1), axis=0)
    i, j = pr[:, 0], pr[:, 1]
    same = ring_id[i] == ring_id[j]
    r = ring_id[i]
    adjacent = same & ((j - i == 1) | ((i == first[r]) & (j == last[r])) | (i == j))
    i, j = i[~adjacent], j[~adjacent]
    hit = _segments_cross(a[i], b[i], a[j], b[j])
    return np.stack([i[hit], j[hit]], -1)


def check_simple(poly, what: str) -> None:
    """Raise CaseError naming ``what`` and where, if the closed polygon (or the rings of
    a list of polygons) self-intersects."""
    rings = poly if isinstance(poly, list | tuple) else [poly]
    hits = rings_intersections(rings)
    if len(hits):
        p = np.concatenate(rings)[hits[0, 0]]
        raise CaseError(f"the {what} self-intersects near ({p[0] * 1e3:.4f}, {p[1] * 1e3:.4f}) mm")


def signed_area(poly: np.ndarray) -> float:
    return 0.5 * float(np.sum(cross(poly, np.roll(poly, -1, axis=0))))


#: Nearest vertices among which point_gap looks for the closest segment: enough when no
#: edge is longer than the distances measured (callers sample with a short max step).
GAP_NEAREST = 16


class PolygonDistance:
    """Distances to one closed counter-clockwise polygon from many points: to the
    segments at the ``nearest`` vertices closest to each point (edges short against the
    distances measured), signed by the nearest feature (negative inside): the nearest
    segment's normal, or at a vertex both its segments' (exact in 2D, and cheap: no
    point-in-polygon test)."""

    def __init__(self, poly, nearest: int = GAP_NEAREST):
        from scipy.spatial import cKDTree

        self.poly = np.asarray(poly, dtype=float)
        self.nearest = min(nearest, len(self.poly))
        self.tree = cKDTree(self.poly)
        e = np.roll(self.poly, -1, axis=0) - self.poly  # segment i: vertex i to i + 1
        self.normal = np.column_stack([e[:, 1], -e[:, 0]]) / np.linalg.norm(e, axis=-1)[:, None]

    def nearest_points(self, points):
        """(distance, sign, vertex): the unsigned distance, the nearest feature's sign
        (+1 outside) and the vertex nearest each point."""
        n, poly = len(self.poly), self.poly
        _, k = self.tree.query(points, self.nearest)
        k = k.reshape(len(points), self.nearest)
        idx = np.concatenate([k, k - 1], axis=1) % n
        a, b = poly[idx], poly[(idx + 1) % n]
        ab, ap = b - a, points[:, None, :] - a
        t = np.clip(np.sum(ap * ab, -1) / np.sum(ab * ab, -1), 0.0, 1.0)
        r = ap - t[..., None] * ab
        d = np.linalg.norm(r, axis=-1)
        j = np.argmin(d, axis=1)
        rows = np.arange(len(points))
        seg, tj, rj = idx[rows, j], t[rows, j], r[rows, j]
        at = np.where(tj >= 1.0, (seg + 1) % n, seg)  # the vertex, where it ends there
        feature = np.where(((tj > 0.0) & (tj < 1.0))[:, None], self.normal[seg],
                           self.normal[(at - 1) % n] + self.normal[at])
        sign = np.where(np.sum(rj * feature, -1) < 0.0, -1.0, 1.0)
        return d[rows, j], sign, k[:, 0]

    def __call__(self, points):
        d, sign, _ = self.nearest_points(points)
        return sign * d


def polygon_gap(points, poly, nearest: int = GAP_NEAREST):
    """Signed distance of each point to the closed polygon (negative inside), by
    point-to-segment distances (:class:`PolygonDistance`) and an even-odd inside test:
    no curve, no Newton, so the sign stays right next to a sharp corner (where a sign
    taken from a curve's normal is ambiguous)."""
    from matplotlib.path import Path

    d, _, _ = PolygonDistance(poly, nearest).nearest_points(points)
    return np.where(Path(poly).contains_points(points), -d, d)
