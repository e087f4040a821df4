"""A structured O-grid of the internal-gear working domain at one rotor angle (issue 16).

The working domain is the fluid between the outer rotor's inner profile (relieved by the
clearance, a true normal offset, :func:`..geometry.offsets.offset_profile`, as in
:mod:`..geometry.internal_gear.sealing_gap`) and the inner rotor: an annulus.  One block
covers it, ``columns`` cells around and ``cells_across_gap`` cells from the inner wall to
the outer one, so every sealing gap is spanned by exactly that many cells, and the node
count and numbering are the same at every angle (what a moving grid needs).

Construction, at outer-rotor angle ``phi``:

* Both walls are star-shaped about the outer rotor's axis O1 (checked; a wall that a ray
  from O1 crosses twice raises), so a node of either wall is named by its polar angle
  about O1.  A column sits on each *anchor*, a sharp point of the inner profile (at
  sigma_bar = 1 its undercut edges, which seal; the seam is the first), and a fixed
  number of columns between each two anchors at equal steps of a monotone law of polar
  angle that mixes the two walls' mean arc fraction with shares crowded toward the
  sealing lines (where the walls are close) and toward the walls' sharp bends,
  normalised per segment (:mod:`.ogrid_columns`: so the columns move smoothly with the
  angle, which is what a helical stack of sections needs).  Inner nodes are put on the
  true curve by bisection.
* The outer node of a column is the inner node's foot point on the outer wall where the
  walls are close (so a column crosses a sealing gap square, not along the polar ray,
  which meets a contact at the angle between its normal, through the pitch point, and
  O1), the polar correspondence where they are far apart, blended smoothly; a few Jacobi
  sweeps slide the far outer nodes along the wall to even out their spacing (boundary
  nodes stay on the true curves; near a gap they are fixed).  A fold raises.
* Each column's line blends the straight chord with the cubic Hermite curve square to
  both walls (``orthogonal_blend``, a quarter by default), its nodes clustered toward
  both walls by a two-sided tanh law (``wall_clustering``; 0 = uniform).  Interior nodes
  are not Laplace-smoothed: on a wall of 20 mm radius, averaging two neighbours 1 mm
  apart moves a node 25 um, more than the clearance, which would push the first row
  through the wall in the gap.

The result's quality is measured by :mod:`.ogrid_quality`; :func:`make_ogrid` refuses a
grid that fails with one line naming the angle and the measure.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.geometry.offsets import Clearance, offset_profile
from rotorflow.geometry.planar import TWO_PI, rotate

from .ogrid_columns import anchor_parameters, column_angles, segment_columns
from .ogrid_quality import QualityLimits, check, chord_sag, measure

#: Wall samples per profile piece used to tabulate polar angle and arc length; nodes are
#: then bisected onto the true curve, so this only has to bracket them (and resolve the
#: arc length to far below a column's share: 4096 samples per piece).
SAMPLES_PER_PIECE = 4096
#: The most a foot-matched outer node's offset from its polar position may shrink per
#: column, in polar steps (:func:`_matched_outer`): below 1, so the nodes still advance
#: (a leading and a lagging offset shrinking at the same column could still fold them:
#: the fold check below stays).
FADE_STEP = 0.9
#: Bisection steps for a wall node's parameter: 2^-50 of a sample interval, far below
#: a nanometre on a 0.1 m rotor.
BISECTIONS = 50
#: Gauss-Newton steps of a foot point from its nearest wall sample (quadratic close to
#: the curve; 8 steps from a sample 1/4096 of a piece away leave ~1e-15 of the piece).
FOOT_NEWTON_STEPS = 8
#: Smallest polar-angle step between wall samples, rad: a ray from O1 that meets a wall
#: twice shows as a step at or below zero (the inner profile's zero-speed point at
#: sigma_bar = 1 turns slowly but never back: its smallest step is ~5e-14 rad).
MIN_POLAR_STEP = 0.0


@dataclass(frozen=True)
class OGridSpec:
    """Resolution and shape controls of the O-grid."""

    #: Cells around the annulus.  With the first (whole-annulus) column law, 1024 kept the
    #: skewness under 4 over a lobe period of the default pair at 20 um (512: 7.4), but
    #: its wall polygon cut 3.6 um off the inner rotor's sharp edge next to a contact
    #: (phi = 0), more than the first cell; 2048 cut 0.015 um.  The anchored law with its
    #: sag term (:mod:`.ogrid_columns`) keeps 512 columns within the limits at 100 um.
    columns: int = 2048
    cells_across_gap: int = 8  # cells from the inner wall to the outer (at every contact)
    #: tanh stretching parameter (0 = uniform across).  3.5, not 2: in a helical stack the
    #: first cell on the wall of the largest chamber (27 mm across) leans with the nodes'
    #: travel, and with a 2 mm tall first cell that gave boundary skewness 5.4 (4.4 at 3,
    #: 3.8 at 3.5, on a 12-layer slice of the default machine).
    wall_clustering: float = 3.5
    #: 0 = straight connecting lines, 1 = Hermite lines square to both walls.  A quarter:
    #: over a lobe period (2048 columns, every 6 deg) straight lines leave checkMesh's
    #: skewness at 5.7 (tall first cells leaning on the pin flanks), 0.25 brings it to
    #: 3.7; 0.5 and more invert cells in the wide chambers, where neighbouring normals
    #: fan across each other.
    orthogonal_blend: float = 0.25
    smoothing_sweeps: int = 4
    #: Wall distance, as a fraction of the rotor diameter, over which the column lines turn
    #: from the polar correspondence to the inner nodes' foot points on the outer wall.
    #: 0.01 gives the default pair 2 deg less non-orthogonality but folds the outer nodes
    #: of the family's n5-lambda1.3 example at 5 of 11 angles; 0.005 folds none.
    foot_match_reach: float = 0.005
    #: Share of the columns crowded toward the sealing lines, and the wall distance (a
    #: fraction of the diameter) that counts as near one (:mod:`.ogrid_columns`).  0.3
    #: since the law has its own term for the chord sag (which was what the crowding
    #: bought): at 0.6 the sag term lacked columns at the outer bends next to an anchor
    #: (sag 0.54 of the first cell at 6 and 54 deg).
    gap_clustering: float = 0.3
    gap_reach: float = 0.001
    #: Wall distance (a fraction of the diameter) below which the cells across fade from
    #: the tanh law to even steps (:func:`radial_law`); 0 keeps the tanh law everywhere.
    even_reach: float = 0.0
    #: Share of the columns placed by the walls' turning angle: at sigma_bar = 1 the
    #: inner profile's sharp edge bends so tightly that chords of even 100 um cut more
    #: than the first cell off it.  With the law normalised per segment between the
    #: sharp points, 0.15 crowded the sharp edge facing the largest chamber to 15 um
    #: columns whose 27 mm lines crossed (inverted cells at 0 and 13 deg); 0.08 left
    #: 79.5 deg non-orthogonality, 0.04 (the sag term doing the rest) 75.6.
    turn_clustering: float = 0.04
    smoothing_relax: float = 0.5  # under-relaxation of each Jacobi sweep

    def key(self) -> dict:
        """The fields that determine the grid, for run keys; ``even_reach`` only when set
        (it came after runs were recorded, and at 0 changes nothing)."""
        out = asdict(self)
        if not out["even_reach"]:
            del out["even_reach"]
        return out

    def check(self) -> None:
        if self.columns < 8:
            raise CaseError(f"columns must be at least 8, got {self.columns}")
        if self.cells_across_gap < 1:
            raise CaseError(f"cells_across_gap must be at least 1, got {self.cells_across_gap}")
        if not 0.0 <= self.orthogonal_blend <= 1.0:
            raise CaseError(f"orthogonal_blend must lie in [0, 1], got {self.orthogonal_blend}")
        if (not 0.0 <= self.gap_clustering or not 0.0 <= self.turn_clustering
                or not self.gap_clustering + self.turn_clustering < 1.0
                or not self.gap_reach > 0.0):
            raise CaseError("gap_clustering and turn_clustering must be >= 0 with a sum "
                            "below 1, and gap_reach positive")
        if not self.foot_match_reach >= 0.0:
            raise CaseError(f"foot_match_reach must not be negative, got {self.foot_match_reach}")
        if not self.even_reach >= 0.0:
            raise CaseError(f"even_reach must not be negative, got {self.even_reach}")
        if self.wall_clustering < 0.0 or self.smoothing_sweeps < 0:
            raise CaseError("wall_clustering and smoothing_sweeps must not be negative")
        if not 0.0 < self.smoothing_relax <= 1.0:
            raise CaseError(f"smoothing_relax must lie in (0, 1], got {self.smoothing_relax}")


@dataclass(frozen=True)
class Wall:
    """One wall in the fixed frame: a rotor's profile turned by ``turn`` about ``axis``."""

    curve: object  # PieceCurve or OffsetProfile in the rotor's frame
    turn: float
    axis: np.ndarray

    def point(self, u):
        return rotate(self.curve.point(u), self.turn) + self.axis

    def normal(self, u):
        """Unit normal out of the region the profile encloses, fixed frame."""
        return rotate(self.curve.normal(u), self.turn)


def walls(pair, phi: float, gap: float) -> tuple[Wall, Wall]:
    """(outer, inner) walls at outer-rotor angle ``phi`` [rad], the outer rotor relieved
    by ``gap`` [m] (outward, as :func:`..geometry.internal_gear.sealing_gap` does)."""
    outer, inner = pair.rotors
    where = f"no O-grid at phi = {math.degrees(phi):.6g} deg"
    if not gap > 0.0:
        raise CaseError(f"{where}: the clearance must be positive, got {gap} m")
    try:
        relieved = offset_profile(outer.profile, Clearance((gap,)), +1)
    except CaseError as exc:
        raise CaseError(f"{where}: {exc}") from None
    return (Wall(relieved, phi * outer.speed_ratio, np.asarray(outer.axis, float)),
            Wall(inner.profile, phi * inner.speed_ratio, np.asarray(inner.axis, float)))


class _PolarTable:
    """A wall tabulated by polar angle about O1 (unwrapped, increasing from ``start``)
    and by arc length, with exact inversion polar angle -> wall parameter."""

    def __init__(self, wall: Wall, start: float, where: str):
        n = wall.curve.n
        u = np.linspace(0.0, n, n * SAMPLES_PER_PIECE + 1)
        p = wall.point(u)
        ang = np.unwrap(np.arctan2(p[:, 1], p[:, 0]))
        step = np.diff(ang)
        if not step.min() > MIN_POLAR_STEP or abs(ang[-1] - ang[0] - TWO_PI) > 1e-9:
            raise CaseError(f"{where}: the {wall.curve.name} wall is not star-shaped about "
                            "the outer rotor's axis (a ray from it crosses the wall twice)")
        # Three periods, so every polar angle in [start, start + 2 pi] has samples on both
        # sides (a node just past the seam must not fall before the first sample).
        shift = np.floor((start - ang[0]) / TWO_PI) * TWO_PI
        self.u = np.concatenate([u[:-1] + k * n for k in (-1, 0, 1)] + [u[-1:] + n])
        self.ang = np.concatenate([ang[:-1] + shift + k * TWO_PI for k in (-1, 0, 1)]
                                  + [ang[-1:] + shift + TWO_PI])
        q = wall.point(self.u)
        self.radius = np.linalg.norm(q, axis=1)
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
        total = arc[-1] / 3.0
        self.arc = (arc - np.interp(start, self.ang, arc)) / total
        # Cumulative turning of the tangent (a sharp bend asks for columns that its arc
        # length alone would not give it; equal steps of sqrt(kappa) ds, which would
        # equalise the chord sag, were tried and left the sharp edge coarser: the table
        # does not resolve kappa there, only the total turn).
        d = np.diff(q, axis=0)
        heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
        turn = np.concatenate([[0.0, 0.0], np.cumsum(np.abs(np.diff(heading)))])
        self.turn = (turn - np.interp(start, self.ang, turn)) / (turn[-1] / 3.0)
        self.length, self.total_turn = total, turn[-1] / 3.0
        self.wall = wall

    def foot_parameters(self, x: np.ndarray) -> np.ndarray:
        """Parameters (in this table's unwrapped range) of the wall points nearest x:
        nearest sample, then Gauss-Newton on (q(u) - x) . q'(u) = 0 on the true curve."""
        from scipy.spatial import cKDTree

        q = self.wall.point(self.u)
        _, k = cKDTree(q).query(x)
        u = self.u[k].copy()
        du = np.diff(self.u).max()
        for _ in range(FOOT_NEWTON_STEPS):
            d = self.wall.curve.derivative(u)
            d = rotate(d, self.wall.turn)
            r = self.wall.point(u) - x
            step = np.sum(r * d, 1) / np.maximum(np.sum(d * d, 1), 1e-300)
            u = u - np.clip(step, -du, du)
        return u

    def arc_at(self, ang):
        return np.interp(ang, self.ang, self.arc)

    def parameter_at(self, ang):
        """Wall parameter of the points at polar angles ``ang`` (start <= ang < start + 2pi),
        by bisection on the true curve between the bracketing samples."""
        i = np.clip(np.searchsorted(self.ang, ang) - 1, 0, len(self.ang) - 2)
        a, b = self.u[i].copy(), self.u[i + 1].copy()
        base = self.ang[i]
        for _ in range(BISECTIONS):
            m = 0.5 * (a + b)
            q = self.wall.point(m)
            # Polar angle relative to the bracket's start, in (-pi, pi]: no unwrapping.
            rel = np.arctan2(q[:, 1], q[:, 0]) - base
            rel = (rel + math.pi) % TWO_PI - math.pi
            left = rel < ang - base
            a, b = np.where(left, m, a), np.where(left, b, m)
        return 0.5 * (a + b)


def radial_fractions(cells: int, clustering: float) -> np.ndarray:
    """Node fractions 0..1 across, clustered toward both ends by a tanh law."""
    eta = np.linspace(0.0, 1.0, cells + 1)
    if clustering == 0.0:
        return eta
    return 0.5 * (1.0 + np.tanh(clustering * (eta - 0.5)) / math.tanh(0.5 * clustering))


def radial_law(spec: OGridSpec, widths: np.ndarray, scale: float) -> np.ndarray:
    """Node fractions across each column of radial width ``widths`` (len(widths),
    cells + 1): the tanh law, faded to even steps where the walls are closer than about
    ``spec.even_reach`` times ``scale`` (the weight of the tanh law is w^2 / (w^2 + r^2)).

    Why even in the gaps: a gap's flow is a Couette-Poiseuille profile with no boundary
    layer to resolve, and the finite-volume flux of the Poiseuille part with the wall's
    half-cell gradient overshoots by 2 / n^2 on n even cells, but by 18.6 / 8.7 / 3.9 %
    on 4 / 6 / 9 cells of the tanh law at 3 (computed, 1D); the 3D study's total leakage
    was 22 / 9 / 4 % above its extrapolation on those counts."""
    tanh = radial_fractions(spec.cells_across_gap, spec.wall_clustering)
    widths = np.asarray(widths, float)
    if spec.even_reach == 0.0:
        return np.broadcast_to(tanh, (widths.size, tanh.size))
    even = np.linspace(0.0, 1.0, tanh.size)
    r = spec.even_reach * scale
    w = (widths * widths / (widths * widths + r * r))[:, None]
    return w * tanh + (1.0 - w) * even


def _connect(p0, n0, p1, n1, s, blend):
    """Nodes at fractions s (one row per column) on the lines from p0 (inner wall) to p1
    (outer wall): (columns, nodes across, 2)."""
    chord = p1 - p0
    length = np.linalg.norm(chord, axis=1)[:, None]
    t0, t1 = length * n0, length * n1
    s = s[:, :, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    p0, p1, t0, t1, chord = (v[:, None, :] for v in (p0, p1, t0, t1, chord))
    hermite = h00 * p0 + h10 * t0 + h01 * p1 + h11 * t1
    straight = p0 + s * chord
    return blend * hermite + (1.0 - blend) * straight


def _smooth_directions(n: np.ndarray, sweeps: int, relax: float) -> np.ndarray:
    """Jacobi sweeps of unit vectors around the (periodic) columns, renormalised."""
    for _ in range(sweeps):
        mean = 0.5 * (np.roll(n, 1, axis=0) + np.roll(n, -1, axis=0))
        n = n + relax * (mean - n)
        n = n / np.linalg.norm(n, axis=1)[:, None]
    return n


def _matched_outer(outer: _PolarTable, p_in, u_polar, spec, scale: float, where: str):
    """Outer-wall parameters of the columns: the foot points of the inner nodes where the
    walls are close (so lines cross a sealing gap square, not along the polar ray, which
    meets a contact at the angle between its normal, through the pitch point, and O1),
    the polar correspondence where they are far apart, blended smoothly between."""
    u_foot = outer.foot_parameters(p_in)
    # The foot parameter may land a period off the polar one at the seam.
    n = outer.wall.curve.n
    u_foot = u_foot + n * np.round((u_polar - u_foot) / n)
    dist = np.linalg.norm(outer.wall.point(u_foot) - p_in, axis=1)
    w = np.exp(-(dist / (spec.foot_match_reach * scale)) ** 2)
    # The blend w u_foot + (1 - w) u_polar folds where w fades faster than the polar
    # nodes advance while the foot points lead them by more than a few columns (the
    # n5-lambda1.3 example's anchored columns, at 3 of 10 angles).  So the offset from the
    # polar nodes may shrink by at most FADE_STEP of a polar step per column: a leading
    # offset fades later (forward pass), a lagging one sets in earlier (backward pass).
    # Both passes are maxima of continuous functions: continuous in the angle.
    offset = w * (u_foot - u_polar)
    step = FADE_STEP * np.diff(np.append(u_polar, u_polar[0] + n))
    u = u_polar + _fade(np.maximum(offset, 0.0), step) - _fade(-np.minimum(offset, 0.0)[::-1],
                                                               np.roll(step, 1)[::-1])[::-1]
    u = _smooth_sliding(outer, u, spec.smoothing_sweeps, spec.smoothing_relax * (1.0 - w))
    du = np.diff(np.append(u, u[0] + n))
    if not du.min() > 0.0:
        i = int(np.argmin(du))
        raise CaseError(f"{where}: the matched outer-wall nodes fold back at column {i} "
                        "(lower foot_match_reach)")
    return u


def _fade(offset, step):
    """The least sequence at or above ``offset`` that falls by at most ``step[i]`` from
    column i to i + 1 (periodic: two passes around)."""
    d = offset.copy()
    m = len(d)
    for k in range(2 * m):
        i = k % m
        j = (i + 1) % m
        d[j] = max(d[j], d[i] - step[i])
    return d


def _smooth_sliding(table: _PolarTable, u, sweeps: int, relax: float):
    """Jacobi sweeps of the outer nodes' arc positions (they slide along the wall, staying
    on it): where the foot points of a curved inner wall bunch on the outer wall and leave
    long chords between, this evens the spacing out.  ``relax`` is per column, zero
    where the walls are close: there a node slid by more than the gap height tilts its
    column past the cells' height and inverts them (found at 256 and 512 columns)."""
    order = np.argsort(table.u)
    s = np.interp(u, table.u[order], table.arc[order])
    for _ in range(sweeps):
        mean = 0.5 * (np.roll(s, 1) + np.roll(s, -1))
        # The seam: the neighbours of the first and last columns are a period away.
        mean[0] = 0.5 * (s[-1] - 1.0 + s[1])
        mean[-1] = 0.5 * (s[-2] + s[0] + 1.0)
        s = s + relax * (mean - s)
    return np.interp(s, table.arc[order], table.u[order])


def _wall_normals(wall: Wall, u, p):
    """Unit normals, with the radial direction where the profile has a point of zero
    speed (the inner profile's undercut point at sigma_bar = 1: no tangent there)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        n = wall.normal(u)
    bad = ~np.all(np.isfinite(n), axis=1)
    if bad.any():
        r = p[bad] - wall.axis
        n[bad] = r / np.linalg.norm(r, axis=1)[:, None]
    return n


@dataclass(frozen=True)
class OGrid:
    """Nodes ``points[i, j]``: column i (counter-clockwise, periodic), row j from the inner
    wall (0) to the outer wall (cells_across); cell (i, j) has corners (i, j), (i+1, j),
    (i+1, j+1), (i, j+1) with i + 1 taken modulo the column count."""

    phi: float
    points: np.ndarray  # (columns, cells_across + 1, 2) [m]
    #: (columns, 2): how far the true inner and outer walls depart from the grid's wall
    #: chord from column i to i + 1, at the chord's middle parameter [m].
    wall_sag: np.ndarray | None = None

    @property
    def columns(self) -> int:
        return self.points.shape[0]

    @property
    def cells_across(self) -> int:
        return self.points.shape[1] - 1

    @property
    def cells(self) -> int:
        return self.columns * self.cells_across


def build_ogrid(pair, phi: float, gap: float, spec: OGridSpec = OGridSpec()) -> OGrid:
    """The O-grid at outer-rotor angle ``phi`` [rad] with clearance ``gap`` [m], not yet
    checked (:func:`make_ogrid` checks)."""
    spec.check()
    where = f"no O-grid at phi = {math.degrees(phi):.6g} deg"
    outer_wall, inner_wall = walls(pair, phi, gap)
    anchor_u = anchor_parameters(inner_wall)
    a = inner_wall.point(anchor_u)
    anchors = np.arctan2(a[:, 1], a[:, 0])
    anchors = anchors[0] + np.mod(anchors - anchors[0], TWO_PI)
    if not np.all(np.diff(anchors) > 0.0):
        raise CaseError(f"{where}: the inner wall's sharp points are not in polar order")
    outer = _PolarTable(outer_wall, anchors[0], where)
    inner = _PolarTable(inner_wall, anchors[0], where)
    counts = segment_columns(inner_wall, anchor_u, spec.columns)
    def first(widths):  # the first cell's share of the radial width
        return radial_law(spec, np.atleast_1d(widths), pair.diameter)[:, 1]

    ang = column_angles(outer, inner, spec, pair.diameter, anchors, counts, first)
    u_in = inner.parameter_at(ang)
    p_in = inner_wall.point(u_in)
    u_out = _matched_outer(outer, p_in, outer.parameter_at(ang), spec, pair.diameter, where)
    p_out = outer_wall.point(u_out)
    n_out = _wall_normals(outer_wall, u_out, p_out)
    n_in = _wall_normals(inner_wall, u_in, p_in)
    s = radial_law(spec, np.linalg.norm(p_out - p_in, axis=1), pair.diameter)
    n_in = _smooth_directions(n_in, spec.smoothing_sweeps, spec.smoothing_relax)
    n_out = _smooth_directions(n_out, spec.smoothing_sweeps, spec.smoothing_relax)
    x = _connect(p_in, n_in, p_out, n_out, s, spec.orthogonal_blend)
    sag = np.stack([chord_sag(inner_wall, u_in, inner_wall.curve.n),
                    chord_sag(outer_wall, u_out, outer_wall.curve.n)], 1)
    return OGrid(phi, x, sag)


def make_ogrid(pair, phi: float, gap: float, spec: OGridSpec = OGridSpec(), limits=None):
    """(grid, quality): the O-grid, checked by :func:`.ogrid_quality.check` (CaseError
    naming the angle and the failed measure)."""
    grid = build_ogrid(pair, phi, gap, spec)
    quality = measure(grid)
    check(quality, phi, spec, limits or QualityLimits())
    return grid, quality
