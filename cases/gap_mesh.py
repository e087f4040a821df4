"""2D meshes of a clearance gap between two walls, from gmsh to a checked OpenFOAM mesh.

A gap is two walls given as polylines ``y(x)`` in the gap's own frame
(:class:`.gap_walls.GapWalls`).

The mesh is structured: the gap is split at its throat (minimum gap) and along its
centre line into four transfinite quad blocks, extruded one cell thick (front and back
``empty``).  Cells across the gap are graded toward both walls, cells along it toward the
throat; both gradings are geometric, and :attr:`GapMeshSpec.refinement` refines every
direction by the same factor while keeping the spacing law, which is what Richardson
extrapolation needs.

Patches: ``inlet``, ``outlet``, ``lowerWall``, ``upperWall`` (both in group ``walls``)
and ``frontAndBack``; the cell zone is ``fluid``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from rotorflow.errors import CaseError
from rotorflow.gmsh_session import gmsh_session

from .foam_files import ensure_system_files
from .foam_mesh import MeshQuality, convert
from .gap_walls import SPLINE_POINTS, GapWalls

PATCH_TYPES = {
    "inlet": "patch",
    "outlet": "patch",
    "lowerWall": "wall",
    "upperWall": "wall",
    "frontAndBack": "empty",
}

#: The throat must lie this fraction of the wall length away from either end, or the block
#: on the short side degenerates; extend the walls past the sealing line instead.
THROAT_END_MARGIN = 0.05



@dataclass(frozen=True)
class GapMeshSpec:
    """How finely to mesh a gap.  Counts and gradings are those of the default mesh.

    ``refinement`` multiplies every cell count and takes the ``refinement``-th root of
    every cell-to-cell growth rate, so the meshes of a Richardson sequence share one
    spacing law (2.0 halves every cell).
    """

    cells_across: int = 16
    """Cells across the gap; even, half per wall side."""
    wall_grading: float = 3.0
    """Centre-cell height over wall-cell height (>= 1): resolves the wall shear layers."""
    cells_along: int = 40
    """Cells along the gap on each side of the throat."""
    along_grading: float = 1.0
    """End-cell length over throat-cell length (>= 1); 1 for a parallel channel."""
    refinement: float = 1.0
    depth_m: float | None = None
    """Extrusion depth of the one-cell-thick 2D mesh; None: the minimum gap."""

    def __post_init__(self) -> None:
        if self.cells_across < 2 or self.cells_across % 2:
            raise CaseError(f"cells_across must be even and >= 2, got {self.cells_across}")
        if self.cells_along < 1:
            raise CaseError(f"cells_along must be >= 1, got {self.cells_along}")
        if self.wall_grading < 1 or self.along_grading < 1:
            raise CaseError("wall_grading and along_grading must be >= 1")
        if self.refinement <= 0:
            raise CaseError("refinement must be > 0")
        self.half_cells_across  # noqa: B018 - validates the refined counts are whole
        self.cells_along_refined  # noqa: B018

    def refined(self, factor: float) -> GapMeshSpec:
        return replace(self, refinement=self.refinement * factor)

    @staticmethod
    def _count(base: int, factor: float, what: str) -> int:
        n = base * factor
        if abs(n - round(n)) > 1e-9 or round(n) < 1:
            raise CaseError(f"refinement {factor} does not give a whole number of {what}")
        return int(round(n))

    @property
    def half_cells_across(self) -> int:
        return self._count(self.cells_across // 2, self.refinement, "cells across")

    @property
    def cells_along_refined(self) -> int:
        return self._count(self.cells_along, self.refinement, "cells along")

    @staticmethod
    def _rate(total: float, base_cells: int, factor: float) -> float:
        if base_cells < 2:
            return 1.0
        return (total ** (1.0 / (base_cells - 1))) ** (1.0 / factor)

    @property
    def across_rate(self) -> float:
        """Growth of cell height from a wall toward the centre line, per cell."""
        return self._rate(self.wall_grading, self.cells_across // 2, self.refinement)

    def along_rates(self, length_up: float, length_down: float) -> tuple[float, float]:
        """Growth of cell length away from the throat, per cell, upstream and downstream.

        The longer side grows by ``along_grading`` from throat to end; the shorter side's
        growth is chosen so that the two cells at the throat have the same length.  The
        total growth of each side is fixed at refinement 1 and kept for every refinement.
        """
        long_side, short_side = max(length_up, length_down), min(length_up, length_down)
        n = self.cells_along
        q_long = self._rate(self.along_grading, n, 1.0)
        first = long_side * _first_fraction(q_long, n)
        if n == 1:
            q_short = 1.0
        else:
            q_short = brentq(lambda q: short_side * _first_fraction(q, n) - first, 1e-3, 1e3)
        rates = tuple(q ** (1.0 / self.refinement) for q in (q_long, q_short))
        return rates if length_up >= length_down else rates[::-1]


def _first_fraction(q: float, n: int) -> float:
    """First cell of ``n`` growing by ``q`` per cell, as a fraction of their total."""
    return 1.0 / n if abs(q - 1) < 1e-12 else (q - 1) / (q**n - 1)


@dataclass(frozen=True)
class GapMesh:
    """A gap mesh written to disk, with what rotorflow needs to know of it."""

    path: Path
    walls: GapWalls = field(repr=False)
    spec: GapMeshSpec
    depth_m: float
    cells: int


def write_msh(walls: GapWalls, spec: GapMeshSpec, path: Path) -> GapMesh:
    """Mesh the gap with gmsh and write ASCII MSH 2.2 (what gmshToFoam reads) to ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    depth = spec.depth_m if spec.depth_m is not None else walls.min_gap
    names = {"lower": "lowerWall", "upper": "upperWall", "in": "inlet", "out": "outlet"}

    with gmsh_session("gap", log_dir=path.parent) as gmsh:
        geo = gmsh.model.geo
        blocks, _, _ = gap_blocks(geo, walls, spec, names)

        groups: dict[str, list[int]] = {name: [] for name in PATCH_TYPES}
        volumes = []
        for surface, patches in blocks:
            out = geo.extrude([(2, surface)], 0, 0, depth, numElements=[1], recombine=True)
            # extrude returns the top surface, the volume, then one side per loop edge.
            top, volume, sides = out[0], out[1], out[2:]
            groups["frontAndBack"] += [surface, top[1]]
            volumes.append(volume[1])
            for patch, (_, tag) in zip(patches, sides, strict=True):
                if patch is not None:
                    groups[patch].append(tag)
        geo.synchronize()
        for name, tags in groups.items():
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        gmsh.model.addPhysicalGroup(3, volumes, name="fluid")
        gmsh.model.mesh.generate(3)
        cells = sum(len(t) for t in gmsh.model.mesh.getElements(3)[1])
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.write(str(path))
    return GapMesh(path, walls, spec, depth, cells)


def gap_blocks(geo, walls: GapWalls, spec: GapMeshSpec, names: dict[str, str | None],
               to_plane=None):
    """The gap's four transfinite blocks, split at the throat and the mid-line.

    ``names`` gives the patch of the lower and upper walls and of the "in" and "out" ends
    (None: internal faces); ``to_plane`` maps gap-frame (x, y) into the model plane
    (identity by default).  Returns the blocks as (surface, patch of each loop edge), the
    corner points keyed (wall, station) and the end lines keyed (station, half).
    """
    xt = walls.throat_x
    margin = THROAT_END_MARGIN * walls.length
    if not walls.x_inlet + margin < xt < walls.x_outlet - margin:
        raise CaseError(
            "the minimum gap lies at an end of the walls; extend them past the sealing line"
        )
    n_half = spec.half_cells_across
    n_along = spec.cells_along_refined
    q_across = spec.across_rate
    q_along = spec.along_rates(xt - walls.x_inlet, walls.x_outlet - xt)

    def y_mid(x):
        return 0.5 * (walls.y_lower(x) + walls.y_upper(x))

    walls_y = {"lower": walls.y_lower, "mid": y_mid, "upper": walls.y_upper}
    stations = {"in": walls.x_inlet, "throat": xt, "out": walls.x_outlet}

    def point(x: float, y: float) -> int:
        if to_plane is not None:
            x, y = to_plane(x, y)
        return geo.addPoint(float(x), float(y), 0.0)

    corner = {(w, s): point(x, float(walls_y[w](x))) for w in walls_y
              for s, x in stations.items()}

    def wall_piece(w: str, s0: str, s1: str) -> int:
        # Evenly spaced control points: gmsh spaces the transfinite nodes by arc length
        # along the spline, which uneven control points would distort.
        x = np.linspace(stations[s0], stations[s1], SPLINE_POINTS)
        y = walls_y[w](x)
        inner = [point(float(a), float(b)) for a, b in zip(x[1:-1], y[1:-1], strict=True)]
        return geo.addSpline([corner[w, s0], *inner, corner[w, s1]])

    along = {(w, side): wall_piece(w, *ends) for w in walls_y
             for side, ends in (("up", ("in", "throat")), ("down", ("throat", "out")))}
    across = {(s, half): geo.addLine(corner[lo, s], corner[hi, s])
              for s in stations for half, (lo, hi) in (("lower", ("lower", "mid")),
                                                       ("upper", ("mid", "upper")))}
    for (_, side), c in along.items():
        # Cells shrink toward the throat: upstream pieces run toward it, downstream away.
        geo.mesh.setTransfiniteCurve(c, n_along + 1, "Progression",
                                     1 / q_along[0] if side == "up" else q_along[1])
    for (_, half), c in across.items():
        # Lines run lower -> upper: grow away from the lower wall, shrink to the upper.
        geo.mesh.setTransfiniteCurve(c, n_half + 1, "Progression",
                                     q_across if half == "lower" else 1 / q_across)

    # Each block: its loop (counter-clockwise) and the patch of each of its four edges.
    blocks = []
    for side, (s0, s1) in (("up", ("in", "throat")), ("down", ("throat", "out"))):
        for half, (lo, hi) in (("lower", ("lower", "mid")), ("upper", ("mid", "upper"))):
            loop = [along[lo, side], across[s1, half], -along[hi, side], -across[s0, half]]
            patches = [
                names["lower"] if lo == "lower" else None,
                names["out"] if s1 == "out" else None,
                names["upper"] if hi == "upper" else None,
                names["in"] if s0 == "in" else None,
            ]
            surface = geo.addPlaneSurface([geo.addCurveLoop(loop)])
            geo.mesh.setTransfiniteSurface(surface)
            geo.mesh.setRecombine(2, surface)
            blocks.append((surface, patches))
    return blocks, corner, across


def build_foam_mesh(case_dir: Path, walls: GapWalls, spec: GapMeshSpec
                    ) -> tuple[GapMesh, MeshQuality]:
    """Mesh into ``case_dir/gap.msh``, convert with gmshToFoam, set patch types, checkMesh
    (:func:`rotorflow.cases.foam_mesh.convert`).

    Missing ``system`` files get minimal stand-ins (checkMesh reads them).  A mesh that
    checkMesh rejects raises :class:`~rotorflow.cases.foam_mesh.MeshCheckError` with its
    complaints.
    """
    case_dir = Path(case_dir)
    ensure_system_files(case_dir)
    mesh = write_msh(walls, spec, case_dir / "gap.msh")
    return mesh, convert(case_dir, mesh.path.name, PATCH_TYPES, mesh.cells)
