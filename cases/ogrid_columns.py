"""Where the O-grid's columns go (:mod:`.ogrid`): anchored segments of a clustering law.

A stack of sections (:mod:`.polymesh`) joins node (i, j) of one section to node (i, j)
of the next, a rotor turn of a fraction of a degree later, so the 3D cells lean by how
far a node moves per unit of turn.  The shear of a cell face is the node's speed, in
metres of travel per metre of height: the rotor's own helix (about 1.2 at the tips of
the default machine, unavoidable) plus however fast the columns slide along the walls.
Two things made them slide fast (measured on a helical slice of the default machine:
nodes at 16 times the helix's speed, 87 deg non-orthogonality, skewness 25):

* a law normalised over the whole annulus: the crowding toward the sealing lines takes
  its columns from everywhere, and its total changes by 35 % over a lobe period (the
  deep mesh's long, nearly conformal gap at sigma_bar = 1 grows and shrinks), so every
  column moved to pay for it;
* a column snapped onto each sharp point of the inner rotor: as the point moved past the
  midway between two columns, the snap jumped to the next one.

Here the columns are placed between *anchors*, material points of the inner rotor (the
local minima of its profile's arc-length speed: at sigma_bar = 1 the zero-speed undercut
edges that seal, elsewhere its sharpest bends), each anchor a column at every angle.
Between two anchors a fixed number of columns (set by the inner rotor's material arc,
the same at every angle) sit at equal steps of the clustering law of
:func:`segment_law`, normalised over that segment only.  So the sharp points always carry
a column, no column ever jumps, and a change of the law moves columns of its own segment
only; the anchors themselves move with the inner rotor, at its helix's speed.
"""

from __future__ import annotations

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.geometry.planar import TWO_PI

#: Samples per profile piece for the anchors (the old snap's resolution: a sharp edge
#: found to 1/4096 of a piece, its chord sag checked by the grid's quality).
ANCHOR_SAMPLES = 4096
#: The scale of the sealing-line density h_ref / (h + h_ref): about its annulus mean on
#: the default machine (0.08 to 0.105 over a lobe period, measured), so ``gap_clustering``
#: keeps the share it had when the law was normalised over the annulus at every angle.
#: A constant, not that mean at each angle: the mean changes by 35 % over a period, and
#: a normalisation that follows it moves every column of the segment.
GAP_DENSITY_MEAN = 0.1
#: The chord sag the column law aims at, in first-cell heights (the quality check's limit
#: is 0.5: half of it leaves room for the tables' coarse curvature at sharp edges), and
#: the narrowest width it counts (a contact's clearance is never below it).
SAG_TARGET = 0.06
MIN_SAG_WIDTH = 1.0e-6
#: Fewest columns between two anchors (a segment needs room for its own clustering).
MIN_SEGMENT_COLUMNS = 4


def anchor_parameters(wall) -> np.ndarray:
    """Parameters of the inner wall's anchors: the local minima of the profile's
    arc-length speed below its median (sharp edges and tight bends), or, on a profile
    without any, the starts of its pieces.  Material points: the same at every angle."""
    n = wall.curve.n
    u = np.linspace(0.0, n, n * ANCHOR_SAMPLES + 1)[:-1]
    speed = np.linalg.norm(wall.curve.derivative(u), axis=1)
    low = (speed < np.roll(speed, 1)) & (speed <= np.roll(speed, -1)) & (speed < np.median(speed))
    k = np.nonzero(low)[0]
    return u[k] if len(k) else np.arange(n, dtype=float)


def segment_columns(wall, anchor_u: np.ndarray, columns: int) -> np.ndarray:
    """Columns in each segment (anchor a to a + 1): shares of the inner profile's mean of
    arc-length and turning fractions, largest-remainder rounding to ``columns``.  Taken
    from the profile in its own frame, so the counts are the same at every angle (from
    the turned wall, the remainders of congruent lobes tie to round-off that changes
    with the angle, and the counts swapped between neighbouring sections)."""
    curve = wall.curve
    n = curve.n
    u = np.linspace(0.0, n, n * ANCHOR_SAMPLES + 1)
    q = curve.point(u)
    d = np.diff(q, axis=0)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(d, axis=1))])
    heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    turn = np.concatenate([[0.0, 0.0], np.cumsum(np.abs(np.diff(heading)))])
    ends = np.append(anchor_u, anchor_u[0] + n)
    ends = np.where(ends > n, ends - n, ends)
    measure = 0.5 * (np.interp(ends, u, arc) / arc[-1] + np.interp(ends, u, turn) / turn[-1])
    share = np.mod(np.diff(measure), 1.0)
    raw = share / share.sum() * columns
    counts = np.floor(raw).astype(int)
    # Congruent lobes tie: ties go to the lower segment (a material rank).
    rank = np.argsort(-np.round(raw - counts, 6), kind="stable")
    counts[rank[:columns - counts.sum()]] += 1
    if counts.min() < MIN_SEGMENT_COLUMNS:
        raise CaseError(f"{columns} columns leave a segment between sharp points of the "
                        f"inner rotor with {counts.min()} (more columns)")
    return counts


def sag_columns(table, width_at, first) -> np.ndarray:
    """Cumulative count of the columns a wall needs (at its table's polar angles) for its
    chords to depart from it by at most SAG_TARGET of the first cell: a chord of length
    L on curvature kappa sags L^2 kappa / 8, the first cell is ``first`` (a share, or a
    function of the width giving it) times the radial width, so the columns per metre
    are sqrt(kappa / (8 SAG_TARGET first width)); kappa ds is the table's turning, so a
    sharp edge counts by its whole turn."""
    ds = np.diff(table.arc) * table.length
    dturn = np.diff(table.turn) * table.total_turn
    mid = 0.5 * (table.ang[1:] + table.ang[:-1])
    w = np.maximum(width_at(mid), MIN_SAG_WIDTH)
    share = first(w) if callable(first) else first
    need = np.sqrt(np.maximum(dturn * ds, 0.0) / (8.0 * SAG_TARGET * share * w))
    return np.concatenate([[0.0], np.cumsum(need)])


def segment_law(outer, inner, spec, scale: float, grid: np.ndarray, first=0.0
                ) -> np.ndarray:
    """The clustering law on polar angles ``grid``: the walls' mean arc fraction, a share
    ``gap_clustering`` by h_ref / (h + h_ref) (h the radial width, h_ref = ``gap_reach``
    times the diameter: toward every sealing line, following it as it moves), a share
    ``turn_clustering`` by the walls' turning (sharp bends); these three in columns (times
    ``spec.columns``).  With ``first`` (the first cell's share of the width) it adds the
    columns each wall needs for its chord sag (:func:`sag_columns`).  Each segment is
    normalised on its own, so only the terms' ratios matter."""
    mean = 0.5 * (outer.arc_at(grid) + inner.arc_at(grid))
    width = np.interp(grid, outer.ang, outer.radius) - np.interp(grid, inner.ang, inner.radius)
    h_ref = spec.gap_reach * scale
    density = h_ref / (np.maximum(width, 0.0) + h_ref)
    step = np.diff(grid)
    narrow = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * step)])
    # Per radian, as the arc and turning fractions are per turn: a unit-density annulus
    # has narrow = 2 pi.
    narrow = narrow / (GAP_DENSITY_MEAN * TWO_PI)
    turning = 0.5 * (np.interp(grid, outer.ang, outer.turn)
                     + np.interp(grid, inner.ang, inner.turn))
    plain = 1.0 - spec.gap_clustering - spec.turn_clustering
    law = plain * mean + spec.gap_clustering * narrow + spec.turn_clustering * turning
    if not first:
        return law

    def width_at(a):
        return np.interp(a, outer.ang, outer.radius) - np.interp(a, inner.ang, inner.radius)

    sag = sum(np.interp(grid, t.ang, sag_columns(t, width_at, first)) for t in (outer, inner))
    return law * spec.columns + sag


def column_angles(outer, inner, spec, scale: float, anchors: np.ndarray,
                  counts: np.ndarray, first=0.0) -> np.ndarray:
    """Polar angles of the columns: ``counts[a]`` columns from anchor a (included) toward
    anchor a + 1, at equal steps of :func:`segment_law` within the segment (``first``:
    the first cell's share of the width, for the law's sag term).  ``anchors`` are the
    anchors' polar angles, increasing from anchor 0 over less than a turn.

    (A monotone cubic of the column index through the anchors, which would smooth the
    spacing's jump at an anchor, was tried: 85 deg non-orthogonality against 79.5.)"""
    start = anchors[0]
    grid = np.linspace(start, start + TWO_PI, 8 * ANCHOR_SAMPLES + 1)
    law = segment_law(outer, inner, spec, scale, grid, first)
    ends = np.interp(np.append(anchors, start + TWO_PI), grid, law)
    targets = np.concatenate([
        ends[a] + (ends[a + 1] - ends[a]) * np.arange(c) / c for a, c in enumerate(counts)])
    ang = np.interp(targets, law, grid)
    ang[np.cumsum(np.concatenate([[0], counts[:-1]]))] = anchors  # exactly on the anchors
    return ang
