"""The transverse section of the internal-gear pair with its rotors turning (issue 17).

A straight slab of depth ``depth`` of the working domain, one cell thick, on the O-grid of
:mod:`.ogrid` (same node count and numbering at every angle).  The mesh is the grid at the
start angle; the motion is the grid at *key frames* (every ``span / frames`` of outer-rotor
angle), written as point displacements from the start grid into the time folders, which
the stock ``uniformInterpolatedDisplacement`` condition reads and interpolates linearly in
time.  Every patch, front and back included, carries that condition, so every point is a
boundary point and follows the prescription exactly (:mod:`.prescribed_motion`, verified).
The front and back are therefore not ``empty`` (an empty patch's points would be left to
the Laplacian motion solver) but walls on which the gas slips: one cell thick, the flow is
two-dimensional all the same.  With ``ports`` (:mod:`.moving_ports`) the back face holds
the suction port and the front face the discharge port of the product's straight machine
of the slab's depth.

What is checked before anything is written (:func:`key_frames`):

* every key frame passes the O-grid's quality limits (:func:`.ogrid.make_ogrid`);
* no cell degenerates *between* frames either: under linear interpolation of the nodes a
  cell's area and each of its corner cross products are quadratics in time, so their
  least value over an interval follows exactly from the frames at both ends and the
  interpolated middle (:func:`interval_minimum`); one at or below zero is a CaseError.

:func:`interpolation_error` measures what linear interpolation between frames costs
against the exact grid at every mid-frame: how far the interpolated wall nodes lie off
the true walls (what the gas sees: the clearance) and how far any node lies from its exact
position (this includes the grid's own jitter along the walls, see the function).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.quasi1d.perfect_gas import PerfectGas

from .ogrid import OGridSpec, _PolarTable, make_ogrid, walls
from .ogrid_quality import cell_corners

#: Interpolated wall nodes must lie within this fraction of the clearance of the true
#: walls at every mid-frame: the gap's flow area goes with its height, so at 5 % the
#: leakage of the worst node's column is off by a few per cent at most, for a moment
#: (the error falls to zero at every frame).  The default pair at 100 um, 512 columns:
#: 2.4 / 7.7 / 34 / 82 um at frames every 0.25 / 0.5 / 1 / 2 deg.
WALL_ERROR_RATIO = 0.05
#: A column whose inner-to-outer length is at most this many clearances is a gap column:
#: its cells form the zone ``gaps`` whose Courant number is measured, and they belong to
#: no chamber's pressure average.
GAP_COLUMN_RATIO = 3.0


@dataclass(frozen=True)
class MovingSection:
    """The section in motion (SI): the pair, its clearance and grid, the angles it turns
    through, and the gas it holds: closed, or with ``ports``
    (:class:`.moving_ports.SectionPorts`: suction on the back face, discharge on the
    front)."""

    pair: Any
    gap: float  # clearance, m
    spec: OGridSpec
    start: float  # outer-rotor angle at t = 0, rad
    span: float  # outer-rotor angle turned through, rad
    frames: int  # key-frame intervals over the span
    omega_outer: float  # rad/s
    depth: float = 0.01  # slab depth, m
    p0: float = 1.0e5  # Pa, uniform at the start unless initial_p names a chamber's
    T0: float = 293.15  # K
    gas: PerfectGas = field(default_factory=PerfectGas)
    initial_p: dict | None = None  # slot -> Pa
    initial_T: dict | None = None  # slot -> K (T0 elsewhere)
    #: {"p": (cells,), "T": (cells,), "U": (cells, 3)}: the whole start state, e.g. the
    #: end of a run of the same grid that stopped at this section's start angle
    #: (:func:`.moving_case.end_fields`); overrides p0, T0 and the slots' values.
    initial_fields: dict | None = None
    ports: Any = None  # .moving_ports.SectionPorts, or None: closed

    def check(self) -> None:
        if not self.gap > 0.0:
            raise CaseError(f"the clearance must be positive, got {self.gap} m")
        if not self.span > 0.0 or self.frames < 1:
            raise CaseError(f"the span must be positive and the key frames at least one "
                            f"interval, got {math.degrees(self.span):g} deg in {self.frames}")
        if not self.omega_outer > 0.0 or not self.depth > 0.0:
            raise CaseError("the rotor speed and the slab depth must be positive")
        if not self.p0 > 0.0 or not self.T0 > 0.0:
            raise CaseError("the start pressure and temperature must be positive")
        if self.ports is not None:
            self.ports.check()

    @property
    def frame_angles(self) -> np.ndarray:
        return self.start + self.span * np.arange(self.frames + 1) / self.frames

    @property
    def frame_times(self) -> np.ndarray:
        return (self.frame_angles - self.start) / self.omega_outer

    @property
    def duration(self) -> float:
        return self.span / self.omega_outer


def interval_minimum(f0: np.ndarray, fm: np.ndarray, f1: np.ndarray) -> np.ndarray:
    """Least value over t in [0, 1] of the quadratics through (0, f0), (1/2, fm), (1, f1)."""
    b = 4.0 * fm - 3.0 * f0 - f1
    a = 2.0 * f0 + 2.0 * f1 - 4.0 * fm
    low = np.minimum(f0, f1)
    with np.errstate(divide="ignore", invalid="ignore"):  # a = 0: no interior minimum
        t = -b / (2.0 * a)
        inside = (a > 0.0) & (t > 0.0) & (t < 1.0)
        return np.where(inside, np.minimum(low, f0 + b * t + a * t * t), low)


def _areas(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cell areas, corner cross products / 2) of a grid's nodes, (columns, rows[, 4])."""
    c = cell_corners(points)
    x, y = c[..., 0], c[..., 1]
    area = 0.5 * (x * np.roll(y, -1, -1) - np.roll(x, -1, -1) * y).sum(-1)
    e1, e2 = np.roll(c, -1, axis=2) - c, np.roll(c, 1, axis=2) - c
    corner = 0.5 * (e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0])
    return area, corner


def check_motion(angles: np.ndarray, points: list) -> None:
    """CaseError (one line) when a cell's area or a corner's cross product is at or below
    zero at a key frame or anywhere between two (linear interpolation of the nodes)."""
    for k, p in enumerate(points):
        area, corner = _areas(p)
        if not (area.min() > 0.0 and corner.min() > 0.0):
            raise CaseError(f"key frame at {math.degrees(angles[k]):.6g} deg degenerates: "
                            f"smallest cell area {area.min():.3g} m2, corner "
                            f"{corner.min():.3g} m2")
    for k in range(len(points) - 1):
        lo = [interval_minimum(a0, am, a1) for a0, am, a1 in zip(
            _areas(points[k]), _areas(0.5 * (points[k] + points[k + 1])),
            _areas(points[k + 1]), strict=True)]
        if not (lo[0].min() > 0.0 and lo[1].min() > 0.0):
            raise CaseError(f"the motion between key frames at {math.degrees(angles[k]):.6g} "
                            f"and {math.degrees(angles[k + 1]):.6g} deg inverts a cell "
                            f"(smallest area {lo[0].min():.3g} m2): more key frames")


def key_frames(s: MovingSection) -> list:
    """The O-grids at the key-frame angles, each passing the O-grid's limits, and the
    motion between them checked (:func:`check_motion`)."""
    s.check()
    grids = [make_ogrid(s.pair, float(a), s.gap, s.spec)[0] for a in s.frame_angles]
    check_motion(s.frame_angles, [g.points for g in grids])
    return grids


def _wall_offsets(pair, phi: float, gap: float, inner_nodes, outer_nodes) -> np.ndarray:
    """Distance of each wall node from its true wall at ``phi`` (inner, outer), m: the
    foot point by the O-grid's own Gauss-Newton search on the true curve."""
    out = []
    for wall, x in zip(reversed(walls(pair, phi, gap)), (inner_nodes, outer_nodes),
                       strict=True):
        table = _PolarTable(wall, 0.0, f"phi = {math.degrees(phi):.6g} deg")
        u = table.foot_parameters(x)
        out.append(np.linalg.norm(wall.point(u) - x, axis=1))
    return np.stack(out, 1)


def interpolation_error(s: MovingSection, grids: list) -> dict:
    """Linear interpolation between key frames against the exact grid at every mid-frame:
    ``wall_m``, the largest distance of an interpolated wall node from the true wall (the
    criterion, :data:`WALL_ERROR_RATIO`); ``node_m``, the largest distance of any node from
    its exact position.  The second does not fall with the frame spacing below ~0.1 deg:
    the O-grid's columns jitter along the walls by tens of micrometres as the angle
    changes (its column law reads tabulated turning of the walls, sampled in each rotor's
    own frame), which moves nodes along the walls, not off them."""
    wall = node = 0.0
    for k in range(len(grids) - 1):
        mid = 0.5 * (s.frame_angles[k] + s.frame_angles[k + 1])
        exact = make_ogrid(s.pair, float(mid), s.gap, s.spec)[0].points
        lin = 0.5 * (grids[k].points + grids[k + 1].points)
        node = max(node, float(np.linalg.norm(lin - exact, axis=-1).max()))
        wall = max(wall, float(_wall_offsets(s.pair, mid, s.gap, lin[:, 0], lin[:, -1]).max()))
    return {"wall_m": wall, "node_m": node, "wall_ratio": wall / s.gap,
            "frame_deg": math.degrees(s.span / s.frames)}


def wall_velocity_check(s: MovingSection, grids: list) -> dict:
    """The mesh's wall-node velocity (what ``movingWallVelocity`` imposes, from the frames'
    differences) against each rotor's own surface velocity omega x r: the largest and the
    RMS difference of the tangential components, over the rotor's tip speed.  The normal
    components agree (both describe the same moving wall); the tangential ones need not,
    since the grid's wall nodes slide along the walls."""
    out = {}
    dt = s.duration / s.frames
    for row, name, rotor in ((0, "innerRotor", s.pair.rotors[1]),
                             (-1, "outerRotor", s.pair.rotors[0])):
        omega = float(rotor.speed_ratio) * s.omega_outer
        axis = np.asarray(rotor.axis, float)
        diffs, tip = [], 0.0
        for k in range(len(grids) - 1):
            a, b = grids[k].points[:, row], grids[k + 1].points[:, row]
            x = 0.5 * (a + b)
            v_mesh = (b - a) / dt
            r = x - axis
            v_rotor = omega * np.stack([-r[:, 1], r[:, 0]], 1)
            t = np.roll(x, -1, 0) - np.roll(x, 1, 0)  # the wall's tangent at the node
            t /= np.linalg.norm(t, axis=1)[:, None]
            diffs.append(np.sum((v_mesh - v_rotor) * t, 1))
            tip = max(tip, abs(omega) * float(np.linalg.norm(r, axis=1).max()))
        d = np.concatenate(diffs)
        out[name] = {"max": float(np.abs(d).max()) / tip,
                     "rms": float(np.sqrt(np.mean(d * d))) / tip, "tip_speed": tip}
    return out


def checked_frames(s: MovingSection) -> tuple[list, dict]:
    """(key-frame grids, interpolation error): :func:`key_frames`, and a CaseError (one
    line) when interpolated wall nodes leave the walls by more than
    :data:`WALL_ERROR_RATIO` of the clearance at a mid-frame."""
    grids = key_frames(s)
    err = interpolation_error(s, grids)
    if not err["wall_ratio"] <= WALL_ERROR_RATIO:
        # the error goes as the frame spacing squared
        need = math.ceil(s.frames * math.sqrt(err["wall_ratio"] / WALL_ERROR_RATIO))
        raise CaseError(f"key frames every {err['frame_deg']:.4g} deg move wall nodes up to "
                        f"{err['wall_m'] * 1e6:.3g} um off the walls ({err['wall_ratio']:.1%} "
                        f"of the clearance, limit {WALL_ERROR_RATIO:.0%}): about {need} "
                        f"frames over the span")
    return grids, err
