"""Quality of a 2D structured O-grid (:mod:`.ogrid`), measured by our own code.

The measures follow OpenFOAM's definitions (``primitiveMeshTools``) on the grid's
internal faces (edges, in 2D), so the figures can be set against checkMesh's on the
one-cell-thick extrusion:

* cell area by the shoelace formula, and the smallest corner area (the cross product of
  the two edges at each corner): a corner at or below zero is an inverted or non-convex
  quad, which a finite-volume solver cannot use;
* non-orthogonality: the angle between an internal edge's normal and the line joining the
  centroids of its two cells;
* skewness (``primitiveMeshTools::faceSkewness``): the distance from the edge's
  midpoint to where that centroid line crosses the edge, over the edge's extent in that
  direction (at least 0.2 of the centroid distance); on a wall edge, the midpoint's
  offset from the foot of the cell's centroid, at least 0.4 of its distance;
* aspect ratio: a cell's longest edge over its shortest;
* cells across the smallest gap: the rows a line from the inner wall to the outer one
  crosses at the narrowest column (an O-grid's every column has ``cells_across`` rows;
  the tests check this at the true contact points independently).

:func:`check` turns a failure into one CaseError line naming the angle and the measure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

#: OpenFOAM's floors of the skewness normalisation, times the centre distance (internal)
#: and the centre-to-wall distance (boundary), ``primitiveMeshTools`` v1912.
INTERNAL_FLOOR = 0.2
BOUNDARY_FLOOR = 0.4


@dataclass(frozen=True)
class QualityLimits:
    """What a grid must meet (OpenFOAM's checkMesh defaults where it has one)."""

    #: checkMesh counts faces above 70 deg as severely non-orthogonal; the solvers still
    #: run with non-orthogonal correctors up to about 85 deg, beyond which the correction
    #: diverges: refuse there.
    max_non_orthogonality_deg: float = 85.0
    #: checkMesh's limit for internal faces ("maxInternalSkewness 4").
    max_skewness: float = 4.0
    #: In a 20 um gap spanned by 8 cells with ~1 mm columns the cells are ~400:1; that is
    #: what gap meshes of the field carry (SCORG reports 100-1000).  Beyond 1e4 the
    #: pressure equation's matrix loses diagonal dominance in double precision.
    max_aspect_ratio: float = 1.0e4
    #: See GridQuality.max_wall_sag_ratio.
    max_wall_sag_ratio: float = 0.5


@dataclass(frozen=True)
class GridQuality:
    cells: int
    min_area: float  # m2
    min_corner_area: float  # m2, smallest corner cross product / 2
    max_non_orthogonality_deg: float
    mean_non_orthogonality_deg: float
    max_skewness: float
    max_aspect_ratio: float
    cells_across_smallest_gap: int
    smallest_gap: float  # m, shortest column (inner node to outer node)
    total_area: float  # m2
    #: Largest departure of a true wall from the grid's wall chord over the height of
    #: the first cell on it there: above 1/2 the first row no longer lies along the wall
    #: (the chord cuts a sharp edge off and opens the seal), so the gap is not resolved.
    max_wall_sag_ratio: float = 0.0

    def row(self) -> str:
        return (f"cells {self.cells}, min area {self.min_area:.3g} m2, non-orth max "
                f"{self.max_non_orthogonality_deg:.1f} deg (mean "
                f"{self.mean_non_orthogonality_deg:.1f}), skewness {self.max_skewness:.3g}, "
                f"aspect {self.max_aspect_ratio:.3g}, {self.cells_across_smallest_gap} cells "
                f"across the smallest gap {self.smallest_gap * 1e6:.4g} um")


def chord_sag(wall, u: np.ndarray, n: int) -> np.ndarray:
    """Distance of the true wall from each chord between neighbouring nodes, at the
    middle parameter (the nodes' parameters increase, the last chord across the seam)."""
    u_next = np.append(u[1:], u[0] + n)
    a, b = wall.point(u), wall.point(u_next)
    q = wall.point(0.5 * (u + u_next))
    e = b - a
    return np.abs(e[:, 0] * (q - a)[:, 1] - e[:, 1] * (q - a)[:, 0]) / np.linalg.norm(e, axis=1)


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def cell_corners(points: np.ndarray) -> np.ndarray:
    """(columns, rows, 4, 2) corners of each cell, counter-clockwise."""
    nxt = np.roll(points, -1, axis=0)
    # Column i runs counter-clockwise and row j outward, so (i, j), (i, j+1), (i+1, j+1),
    # (i+1, j) is the counter-clockwise order.
    return np.stack([points[:, :-1], points[:, 1:], nxt[:, 1:], nxt[:, :-1]], axis=2)


def cell_areas_and_centroids(corners: np.ndarray):
    x, y = corners[..., 0], corners[..., 1]
    xn, yn = np.roll(x, -1, axis=-1), np.roll(y, -1, axis=-1)
    c = x * yn - xn * y
    area = 0.5 * c.sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = ((x + xn) * c).sum(-1) / (6.0 * area)
        cy = ((y + yn) * c).sum(-1) / (6.0 * area)
    return area, np.stack([cx, cy], -1)


def _skewness(a, b, sv, d_len, floor):
    """OpenFOAM's normalisation of a skewness vector sv on face a-b: over the face's
    extent along sv from its centre, at least ``floor`` times the centre distance."""
    mid = 0.5 * (a + b)
    length = np.linalg.norm(sv, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        hat = sv / length[..., None]
    extent = np.abs(np.sum(hat * (a - mid), -1))
    fd = np.maximum(floor * d_len, np.nan_to_num(extent))
    return length / fd


def _face_measures(a, b, c_own, c_nei):
    """Non-orthogonality [deg] and skewness of edges a-b between cells c_own, c_nei."""
    e = b - a
    n = np.stack([e[..., 1], -e[..., 0]], -1)
    d = c_nei - c_own
    d_len = np.linalg.norm(d, axis=-1)
    cos = np.abs(np.sum(n * d, -1)) / (np.linalg.norm(n, axis=-1) * d_len)
    non_orth = np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
    cpf = 0.5 * (a + b) - c_own
    sv = cpf - (np.sum(n * cpf, -1) / np.sum(n * d, -1))[..., None] * d
    return non_orth, _skewness(a, b, sv, d_len, INTERNAL_FLOOR)


def _wall_skewness(a, b, c_own):
    """OpenFOAM's boundary-face skewness: the face centre's offset from the foot of the
    cell centre on the face's plane."""
    e = b - a
    n = np.stack([e[..., 1], -e[..., 0]], -1)
    n = n / np.linalg.norm(n, axis=-1)[..., None]
    cpf = 0.5 * (a + b) - c_own
    d = np.sum(n * cpf, -1)[..., None] * n
    return _skewness(a, b, cpf - d, np.linalg.norm(d, axis=-1), BOUNDARY_FLOOR)


def measure(grid) -> GridQuality:
    p = grid.points
    corners = cell_corners(p)
    area, cen = cell_areas_and_centroids(corners)
    corner_area = 0.5 * _cross(np.roll(corners, -1, axis=2) - corners,
                               np.roll(corners, 1, axis=2) - corners)
    # Internal edges along a row (between rows j and j+1) and along a column (between
    # columns i and i+1, periodic).
    nxt = np.roll(p, -1, axis=0)
    no_r, sk_r = _face_measures(p[:, 1:-1], nxt[:, 1:-1], cen[:, :-1], cen[:, 1:])
    no_c, sk_c = _face_measures(nxt[:, :-1], nxt[:, 1:], cen, np.roll(cen, -1, axis=0))
    sk_w = np.concatenate([_wall_skewness(p[:, 0], nxt[:, 0], cen[:, 0]),
                           _wall_skewness(p[:, -1], nxt[:, -1], cen[:, -1])])
    edges = np.linalg.norm(np.roll(corners, -1, axis=2) - corners, axis=-1)
    gaps = np.linalg.norm(p[:, -1] - p[:, 0], axis=1)
    non_orth = np.concatenate([no_r.ravel(), no_c.ravel()])
    return GridQuality(
        cells=int(area.size),
        min_area=float(area.min()),
        min_corner_area=float(corner_area.min()),
        max_non_orthogonality_deg=float(np.nanmax(non_orth)) if non_orth.size else 0.0,
        mean_non_orthogonality_deg=float(np.nanmean(non_orth)) if non_orth.size else 0.0,
        max_skewness=float(np.nanmax(np.concatenate([sk_r.ravel(), sk_c.ravel(), sk_w]))),
        max_aspect_ratio=float(np.max(edges.max(-1) / edges.min(-1))),
        cells_across_smallest_gap=int(p.shape[1] - 1),
        smallest_gap=float(gaps.min()),
        total_area=float(area.sum()),
        max_wall_sag_ratio=_sag_ratio(grid, p),
    )


def _sag_ratio(grid, p) -> float:
    if grid.wall_sag is None:
        return 0.0
    nxt = np.roll(p, -1, axis=0)
    first = np.stack([np.minimum(np.linalg.norm(p[:, 1] - p[:, 0], axis=1),
                                 np.linalg.norm(nxt[:, 1] - nxt[:, 0], axis=1)),
                      np.minimum(np.linalg.norm(p[:, -1] - p[:, -2], axis=1),
                                 np.linalg.norm(nxt[:, -1] - nxt[:, -2], axis=1))], 1)
    return float(np.max(grid.wall_sag / first))


def check(q: GridQuality, phi: float, spec, limits: QualityLimits) -> None:
    """CaseError (one line: the angle and the measure) for a grid that fails."""
    at = f"O-grid at phi = {math.degrees(phi):.6g} deg"
    if not q.min_corner_area > 0.0 or not q.min_area > 0.0:
        raise CaseError(f"{at}: inverted cell (min area {q.min_area:.3g} m2, min corner "
                        f"area {q.min_corner_area:.3g} m2)")
    if q.cells_across_smallest_gap < spec.cells_across_gap:
        raise CaseError(f"{at}: gap under-resolved ({q.cells_across_smallest_gap} cells "
                        f"across, {spec.cells_across_gap} asked)")
    if not q.max_wall_sag_ratio <= limits.max_wall_sag_ratio:
        raise CaseError(f"{at}: gap under-resolved (a wall departs from its chord by "
                        f"{q.max_wall_sag_ratio:.3g} first-cell heights, limit "
                        f"{limits.max_wall_sag_ratio:.3g}: more columns)")
    for name, value, limit in (
            ("non-orthogonality", q.max_non_orthogonality_deg, limits.max_non_orthogonality_deg),
            ("skewness", q.max_skewness, limits.max_skewness),
            ("aspect ratio", q.max_aspect_ratio, limits.max_aspect_ratio)):
        if not value <= limit:
            raise CaseError(f"{at}: {name} {value:.4g} above the limit {limit:.4g}")
