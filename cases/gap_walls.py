"""A clearance gap's two walls, as polylines ``y(x)`` in the gap's own frame.

``x`` runs along the gap from inlet to outlet (the common tangent at the sealing line),
``y`` across it, the lower wall below the upper one everywhere.  The geometry supplies
the walls from a rotor pair at a chosen angle (:meth:`RotorPair.gap_walls`);
:func:`parallel_channel`, :func:`cylinder_pair` and :func:`rotor_tip_gap` are the
analytic members.  :mod:`.gap_mesh` meshes them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.optimize import brentq, minimize_scalar

from rotorflow.errors import CaseError

#: Two gaps closer than this fraction of the minimum gap count as equally narrow when the
#: throat is located (a parallel channel has its "throat" in the middle, not at one end).
THROAT_FLAT_TOL = 1e-6

#: A gap counts as narrow where it is at most this multiple of its minimum; the length of
#: that stretch is the gap length L of the correlations (L/h).
NARROW_GAP_RATIO = 2.0

#: Evenly spaced points per wall piece handed to gmsh as spline control points: with 241
#: the spline follows the interpolated wall to ~1e-9 of the gap (81 left 1e-4).
SPLINE_POINTS = 241


def _as_polyline(points: np.ndarray, name: str) -> np.ndarray:
    arr = np.array(points, dtype=float)  # a copy: the caller's array is never touched
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < 2:
        raise CaseError(f"{name} wall must be an (n >= 2, 2) array of (x, y) points")
    if not np.all(np.isfinite(arr)):
        raise CaseError(f"{name} wall has non-finite points")
    if np.any(np.diff(arr[:, 0]) <= 0):
        raise CaseError(f"{name} wall x must increase strictly from inlet to outlet")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class GapWalls:
    """The two walls of a gap as polylines of (x, y) points in metres, x increasing.

    Between the points the walls are interpolated by cubic splines (straight lines for
    two points).  Both walls must span the same x range.
    """

    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        lower = _as_polyline(self.lower, "lower")
        upper = _as_polyline(self.upper, "upper")
        span = max(lower[-1, 0] - lower[0, 0], upper[-1, 0] - upper[0, 0])
        if abs(lower[0, 0] - upper[0, 0]) > 1e-9 * span or abs(lower[-1, 0] - upper[-1, 0]) > (
            1e-9 * span
        ):
            raise CaseError("lower and upper walls must span the same x range")
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)
        x = self.sample_x(2001)
        if np.any(self.gap(x) <= 0):
            raise CaseError("the walls touch or cross: the upper wall must stay above the lower")

    @functools.cached_property
    def _splines(self):
        def spline(p: np.ndarray):
            return make_interp_spline(p[:, 0], p[:, 1], k=min(3, len(p) - 1))

        return spline(self.lower), spline(self.upper)

    @property
    def x_inlet(self) -> float:
        return float(self.lower[0, 0])

    @property
    def x_outlet(self) -> float:
        return float(self.lower[-1, 0])

    def sample_x(self, n: int) -> np.ndarray:
        return np.linspace(self.x_inlet, self.x_outlet, n)

    def y_lower(self, x: np.ndarray | float) -> np.ndarray:
        return self._splines[0](x)

    def y_upper(self, x: np.ndarray | float) -> np.ndarray:
        return self._splines[1](x)

    def slope_lower(self, x: np.ndarray | float) -> np.ndarray:
        return self._splines[0].derivative()(x)

    def slope_upper(self, x: np.ndarray | float) -> np.ndarray:
        return self._splines[1].derivative()(x)

    def gap(self, x: np.ndarray | float) -> np.ndarray:
        """Vertical distance between the walls (the gap where both are nearly parallel)."""
        return self.y_upper(x) - self.y_lower(x)

    @functools.cached_property
    def throat_x(self) -> float:
        """x of the minimum gap; the middle of the narrowest stretch when it is flat."""
        x = self.sample_x(4001)
        g = self.gap(x)
        narrow = x[g <= g.min() * (1 + THROAT_FLAT_TOL)]
        if narrow[-1] - narrow[0] > 2 * (x[1] - x[0]):
            return float(0.5 * (narrow[0] + narrow[-1]))
        i = int(np.argmin(g))
        lo, hi = x[max(i - 1, 0)], x[min(i + 1, len(x) - 1)]
        res = minimize_scalar(
            lambda s: float(self.gap(s)), bounds=(lo, hi), method="bounded",
            options={"xatol": 1e-12 * (self.x_outlet - self.x_inlet)},
        )
        return float(res.x)

    @property
    def min_gap(self) -> float:
        return float(self.gap(self.throat_x))

    @property
    def length(self) -> float:
        return self.x_outlet - self.x_inlet

    def narrow_length(self, ratio: float = NARROW_GAP_RATIO) -> float:
        """Length of the stretch around the throat where the gap is at most ``ratio`` times
        its minimum: the gap length L of L/h (a parallel channel: its whole length)."""
        limit = ratio * self.min_gap

        def edge(end: float) -> float:
            if self.gap(end) <= limit:
                return end
            return brentq(lambda x: float(self.gap(x)) - limit, self.throat_x, end)

        return edge(self.x_outlet) - edge(self.x_inlet)

    def extended(self, inlet_m: float = 0.0, outlet_m: float = 0.0) -> GapWalls:
        """New walls continued straight along their end tangents by the given lengths."""
        if inlet_m < 0 or outlet_m < 0:
            raise CaseError("wall extensions must be >= 0")

        def extend(p: np.ndarray, y, dy) -> np.ndarray:
            pts = [p]
            if inlet_m > 0:
                x0 = p[0, 0]
                pts.insert(0, [[x0 - inlet_m, float(y(x0) - inlet_m * dy(x0))]])
            if outlet_m > 0:
                x1 = p[-1, 0]
                pts.append([[x1 + outlet_m, float(y(x1) + outlet_m * dy(x1))]])
            return np.vstack(pts)

        if inlet_m == 0 and outlet_m == 0:
            return self
        # Straight pieces join the spline with matching slope; resample the original walls
        # densely so the joined polyline's spline does not overshoot at the junctions.
        x = self.sample_x(SPLINE_POINTS * 4)
        lower = np.column_stack([x, self.y_lower(x)])
        upper = np.column_stack([x, self.y_upper(x)])
        lower = extend(lower, self.y_lower, self.slope_lower)
        upper = extend(upper, self.y_upper, self.slope_upper)
        if inlet_m > 0:
            lower, upper = _fill_straight(lower, 0), _fill_straight(upper, 0)
        if outlet_m > 0:
            lower, upper = _fill_straight(lower, -1), _fill_straight(upper, -1)
        return GapWalls(lower, upper)


def _fill_straight(p: np.ndarray, end: int, n: int = 20) -> np.ndarray:
    """Put ``n`` points on the straight segment at ``end`` (0 or -1) of polyline ``p``."""
    if end == 0:
        a, b = p[0], p[1]
        seg = a + np.linspace(0, 1, n, endpoint=False)[:, None] * (b - a)
        return np.vstack([seg, p[1:]])
    a, b = p[-2], p[-1]
    seg = a + np.linspace(0, 1, n + 1)[1:, None] * (b - a)
    return np.vstack([p[:-1], seg])


def parallel_channel(gap_m: float, length_m: float) -> GapWalls:
    """A plain parallel channel: walls y = 0 and y = gap, x from 0 to length."""
    if gap_m <= 0 or length_m <= 0:
        raise CaseError("channel gap and length must be > 0")
    return GapWalls(
        np.array([[0.0, 0.0], [length_m, 0.0]]), np.array([[0.0, gap_m], [length_m, gap_m]])
    )


def cylinder_pair(
    gap_m: float,
    radius_lower_m: float,
    radius_upper_m: float,
    upstream_m: float,
    downstream_m: float | None = None,
    points: int = 201,
) -> GapWalls:
    """The gap between two circular walls with minimum gap ``gap_m`` at x = 0.

    A positive radius is convex toward the gap (a rotor tip), a negative one concave (a
    bore), ``math.inf`` flat.  The walls span ``-upstream_m <= x <= downstream_m``
    (``downstream_m`` defaults to ``upstream_m``).
    """
    downstream_m = upstream_m if downstream_m is None else downstream_m
    if gap_m <= 0 or upstream_m <= 0 or downstream_m <= 0:
        raise CaseError("gap and wall extents must be > 0")
    for r in (radius_lower_m, radius_upper_m):
        if abs(r) <= max(upstream_m, downstream_m):
            raise CaseError("each wall radius must exceed the wall extent in magnitude")
    x = np.linspace(-upstream_m, downstream_m, points)

    def sag(r: float) -> np.ndarray:  # rise of a circle of radius r above its tangent
        if math.isinf(r):
            return np.zeros_like(x)
        return np.sign(r) * (abs(r) - np.sqrt(r * r - x * x))

    lower = np.column_stack([x, -sag(radius_lower_m)])
    upper = np.column_stack([x, gap_m + sag(radius_upper_m)])
    return GapWalls(lower, upper)


def rotor_tip_gap(
    gap_m: float,
    radius_m: float,
    inlet_gap_ratio: float = 20.0,
    outlet_gap_ratio: float = 3.0,
    points: int = 201,
) -> GapWalls:
    """Two equal convex walls cut where the gap is ``inlet_gap_ratio`` and
    ``outlet_gap_ratio`` times its minimum.

    Upstream the flow comes slowly from a wide inlet, so the inlet total pressure is the
    upstream chamber's; downstream the walls stop soon after the throat, where the jet
    leaves them (a static-pressure outlet on the jet, as into a chamber), which keeps a
    laminar jet from attaching to one diverging wall or the other.  Wider gaps, whose jets
    are turbulent, need the cut closer: the leakage matrix ends them at 1.5 times the
    minimum (:data:`rotorflow.cases.gap_study.OUTLET_GAP_RATIO`, where the reason is).
    """
    if inlet_gap_ratio <= 1 or outlet_gap_ratio <= 1:
        raise CaseError("inlet and outlet gap ratios must exceed 1")

    def extent(ratio: float) -> float:  # gap(x) = gap + 2 (R - sqrt(R^2 - x^2))
        sag = 0.5 * (ratio - 1) * gap_m
        if sag >= radius_m:
            raise CaseError("rotor_tip_gap: the radius is too small for that gap ratio")
        return math.sqrt(radius_m**2 - (radius_m - sag) ** 2)

    return cylinder_pair(gap_m, radius_m, radius_m, extent(inlet_gap_ratio),
                         extent(outlet_gap_ratio), points)
