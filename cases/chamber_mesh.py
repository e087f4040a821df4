"""2D meshes of a compression chamber that leaks through a clearance gap into a plenum.

Layout (metres, the 2D plane; the mesh is one cell thick in z, depth ``depth_m``)::

        y = H(t) +----------- piston (moves in -y) ------------+
                 |                                              |
       sideWalls |                 chamber                      | sideWalls
                 |                                              |
        y = 0    +-------- bottomWall ----+  +--- bottomWall ---+
                                          |  |  <- gap inlet (opening in the bottom wall)
                                          |  |     gapWalls
                                          +--+  <- outlet: the plenum at suction pressure

The chamber is a ``width_m`` by ``height_m`` rectangle (its height at the start of the
compression).  The gap is a :class:`~rotorflow.cases.gap_walls.GapWalls` pair (case A's
gap geometry, e.g. :func:`~rotorflow.cases.gap_walls.rotor_tip_gap`) turned by -90 deg so
that its inlet is an opening in the middle of the bottom wall and its flow runs in -y;
its outlet is the plenum, a static-pressure boundary.  The bottom wall, the gap and the
outlet never move: the chamber is split at ``fixed_height`` into a lower part around the
opening, which stays still, and a structured block of rectangles above it, which the
piston squeezes (see :mod:`rotorflow.cases.chamber_case`).

Cells: the gap is structured (four transfinite blocks split at the throat and along the
centre line, counts and gradings from :class:`~rotorflow.cases.gap_mesh.GapMeshSpec`);
the chamber's lower part is an unstructured quad-dominant mesh whose cell size grows
geometrically from the gap's inlet spacing at the opening to ``width / chamber_cells``,
its upper part a structured block of that size.
Without walls (``walls=None``) the bottom wall is closed: the sealed chamber of the
adiabatic-compression check.

Patches: ``piston``, ``sideWalls``, ``bottomWall``, ``gapWalls`` (all walls), ``outlet``
(only with a gap) and ``frontAndBack`` (empty); cell zones ``chamber`` and ``gap``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.gmsh_session import gmsh_session

from .gap_mesh import GapMeshSpec, gap_blocks
from .gap_walls import GapWalls

WALL_PATCHES = ("piston", "sideWalls", "bottomWall", "gapWalls")

#: The lower, fixed part of the chamber may take at most this fraction of its height at
#: the start: the rest is squeezed by the piston, and at the end of a compression with a
#: volume ratio of 2 the moving part must keep a good share of its height.
MAX_FIXED_FRACTION = 0.3

#: A chamber must be this many opening widths wide, so that the opening sits in a wall
#: and the unstructured cells can grow between it and the side walls.
MIN_WIDTH_OVER_OPENING = 10.0


def patch_types(with_gap: bool) -> dict[str, str]:
    types = {name: "wall" for name in WALL_PATCHES}
    types["frontAndBack"] = "empty"
    if with_gap:
        types["outlet"] = "patch"
    else:
        del types["gapWalls"]
    return types


@dataclass(frozen=True)
class ChamberDomain:
    """The 2D domain at the start of the compression (see the module docstring)."""

    width_m: float
    height_m: float
    depth_m: float
    walls: GapWalls | None = field(default=None, repr=False)
    """The gap's walls in case A's gap frame; None: a sealed chamber."""

    def __post_init__(self) -> None:
        if min(self.width_m, self.height_m, self.depth_m) <= 0:
            raise CaseError("chamber width, height and depth must be > 0")
        if self.walls is not None and self.width_m < MIN_WIDTH_OVER_OPENING * self.opening_m:
            raise CaseError(
                f"chamber width {self.width_m:.3g} m is under {MIN_WIDTH_OVER_OPENING:g} "
                f"times the gap opening {self.opening_m:.3g} m"
            )

    @property
    def area_m2(self) -> float:
        """Chamber area (the gap's volume excluded)."""
        return self.width_m * self.height_m

    @property
    def volume_m3(self) -> float:
        return self.area_m2 * self.depth_m

    @property
    def opening_m(self) -> float:
        """Width of the gap's inlet, the opening in the bottom wall."""
        if self.walls is None:
            return 0.0
        return float(self.walls.gap(self.walls.x_inlet))

    @property
    def gap_flow_area_m2(self) -> float:
        """Minimum gap times depth: the flow area of the leakage path."""
        return 0.0 if self.walls is None else self.walls.min_gap * self.depth_m

    def to_plane(self, xg: np.ndarray, yg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gap frame -> chamber plane: turned by -90 deg, inlet centred on the bottom wall.

        A rotation keeps loops counter-clockwise, so the gap blocks keep their orientation.
        """
        w = self.walls
        y_mid_in = 0.5 * float(w.y_lower(w.x_inlet) + w.y_upper(w.x_inlet))
        return 0.5 * self.width_m + (np.asarray(yg) - y_mid_in), -(np.asarray(xg) - w.x_inlet)


@dataclass(frozen=True)
class ChamberMeshSpec:
    """How finely to mesh the chamber and its gap.

    ``refinement`` multiplies every cell count (the gap's through its GapMeshSpec, the
    chamber's through ``chamber_cells``) and shrinks the chamber's size growth rate by
    its root, so refined meshes keep one spacing law.
    """

    gap: GapMeshSpec = field(default_factory=lambda: GapMeshSpec(
        cells_across=8, wall_grading=2.0, cells_along=12, along_grading=4.0))
    """Coarser than case A's default: the gap's flow sets the time step (its throat cell,
    ~100 um along a 20 um rotor-tip gap, at Courant number 1 near the speed of sound:
    ~0.3 us), and a whole compression takes ~9000 steps.  Refining every count by 2
    moved the chamber pressure by at most 0.35 % of its rise (RMS 0.1 %)."""
    chamber_cells: int = 24
    """Cells across the chamber width where they are largest."""
    growth: float = 1.2
    """Cell-to-cell size growth away from the opening (unstructured part)."""
    refinement: float = 1.0

    def __post_init__(self) -> None:
        if self.chamber_cells < 4:
            raise CaseError("chamber_cells must be at least 4")
        if not self.growth > 1.0:
            raise CaseError("growth must be > 1")
        if self.refinement <= 0:
            raise CaseError("refinement must be > 0")

    def refined(self, factor: float) -> ChamberMeshSpec:
        return replace(self, refinement=self.refinement * factor)

    @property
    def gap_spec(self) -> GapMeshSpec:
        return self.gap.refined(self.refinement)

    @property
    def growth_refined(self) -> float:
        return self.growth ** (1.0 / self.refinement)

    def coarse_size(self, width_m: float) -> float:
        return width_m / (self.chamber_cells * self.refinement)

    def size_law(self, domain: ChamberDomain) -> tuple[float, float, float]:
        """Cell size at the opening, and the distances from it where the size starts and
        stops growing (size ~ fine + (growth - 1) * distance: geometric growth per cell)."""
        coarse = self.coarse_size(domain.width_m)
        fine = domain.opening_m / (self.gap.cells_across * self.refinement)
        dist_min = 0.5 * domain.opening_m
        return fine, dist_min, dist_min + (coarse - fine) / (self.growth_refined - 1.0)

    def fixed_height(self, domain: ChamberDomain) -> float:
        """Height of the chamber's lower, unstructured part that never moves: the size
        law's reach plus a coarse cell, or two coarse cells for a sealed chamber."""
        coarse = self.coarse_size(domain.width_m)
        if domain.walls is None:
            ys = 2 * coarse
        else:
            ys = self.size_law(domain)[2] + coarse
        if ys > MAX_FIXED_FRACTION * domain.height_m:
            raise CaseError(
                f"the chamber's fixed lower part ({ys:.3g} m) would take more than "
                f"{MAX_FIXED_FRACTION:g} of its height {domain.height_m:.3g} m; use more "
                "chamber cells or a faster growth")
        return ys


@dataclass(frozen=True)
class ChamberMesh:
    """A chamber mesh written to disk."""

    path: Path
    domain: ChamberDomain = field(repr=False)
    spec: ChamberMeshSpec
    cells: int
    cells_gap: int
    fixed_height_m: float
    """Height of the lower part that does not move (y below it: fixed points)."""


def write_msh(domain: ChamberDomain, spec: ChamberMeshSpec, path: Path) -> ChamberMesh:
    """Mesh the chamber (and gap) with gmsh; write ASCII MSH 2.2 to ``path``.

    The chamber is two surfaces: below ``fixed_height`` the unstructured part around the
    opening, which never moves; above it a structured block of rectangles, which the
    piston squeezes (rectangles stay rectangles, so its quality never degrades).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    W, H, D = domain.width_m, domain.height_m, domain.depth_m
    coarse = spec.coarse_size(W)
    ys = spec.fixed_height(domain)
    nx = max(1, round(W / coarse))
    ny = max(1, math.ceil((H - ys) / coarse))
    with gmsh_session("chamber", log_dir=path.parent) as gmsh:
        geo = gmsh.model.geo
        groups: dict[str, list[int]] = {name: [] for name in patch_types(domain.walls
                                                                            is not None)}
        surfaces: dict[str, list[tuple[int, list[str | None]]]] = {"chamber": [], "gap": []}
        c00, cW0 = geo.addPoint(0, 0, 0), geo.addPoint(W, 0, 0)
        c0s, cWs = geo.addPoint(0, ys, 0), geo.addPoint(W, ys, 0)
        cWH, c0H = geo.addPoint(W, H, 0), geo.addPoint(0, H, 0)
        right_lo, level, left_lo = (geo.addLine(cW0, cWs), geo.addLine(cWs, c0s),
                                    geo.addLine(c0s, c00))
        right_hi, top, left_hi = (geo.addLine(cWs, cWH), geo.addLine(cWH, c0H),
                                  geo.addLine(c0H, c0s))
        if domain.walls is None:
            bottom = [geo.addLine(c00, cW0)]
            bottom_patches: list[str | None] = ["bottomWall"]
            opening_curves: list[int] = []
        else:
            gap_blocks, inlet = _gap_blocks(geo, domain, spec.gap_spec)
            surfaces["gap"] = gap_blocks
            (a_pt, a_cv), (m_cv, b_pt) = inlet  # lower->mid and mid->upper inlet lines
            bottom = [geo.addLine(c00, a_pt), a_cv, m_cv, geo.addLine(b_pt, cW0)]
            bottom_patches = ["bottomWall", None, None, "bottomWall"]
            opening_curves = [a_cv, m_cv]
        lower = geo.addPlaneSurface([geo.addCurveLoop([*bottom, right_lo, level, left_lo])])
        geo.mesh.setRecombine(2, lower)
        upper = geo.addPlaneSurface([geo.addCurveLoop([-level, right_hi, top, left_hi])])
        for curve in (level, top):
            geo.mesh.setTransfiniteCurve(curve, nx + 1)
        for curve in (right_hi, left_hi):
            geo.mesh.setTransfiniteCurve(curve, ny + 1)
        geo.mesh.setTransfiniteSurface(upper)
        geo.mesh.setRecombine(2, upper)
        surfaces["chamber"] = [
            (lower, [*bottom_patches, "sideWalls", None, "sideWalls"]),
            (upper, [None, "sideWalls", "piston", "sideWalls"]),
        ]

        volumes: dict[str, list[int]] = {"chamber": [], "gap": []}
        for zone, blocks in surfaces.items():
            for surface, patches in blocks:
                out = geo.extrude([(2, surface)], 0, 0, D, numElements=[1], recombine=True)
                top_s, volume, sides = out[0], out[1], out[2:]
                groups["frontAndBack"] += [surface, top_s[1]]
                volumes[zone].append(volume[1])
                for patch, (_, tag) in zip(patches, sides, strict=True):
                    if patch is not None:
                        groups[patch].append(tag)
        geo.synchronize()
        _size_field(gmsh, domain, spec, coarse, opening_curves)
        for name, tags in groups.items():
            gmsh.model.addPhysicalGroup(2, tags, name=name)
        for zone, tags in volumes.items():
            if tags:
                gmsh.model.addPhysicalGroup(3, tags, name=zone)
        gmsh.option.setNumber("Mesh.Algorithm", 8)  # frontal-Delaunay for quads
        gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)  # blossom
        gmsh.model.mesh.generate(3)
        cells = {zone: sum(len(t) for tag in tags
                           for t in gmsh.model.mesh.getElements(3, tag)[1])
                 for zone, tags in volumes.items()}
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.write(str(path))
    return ChamberMesh(path, domain, spec, cells["chamber"] + cells["gap"], cells["gap"], ys)


def _size_field(gmsh, domain: ChamberDomain, spec: ChamberMeshSpec, coarse: float,
                opening: list[int]) -> None:
    """Cell size growing geometrically from the opening's spacing to ``coarse``."""
    opt = gmsh.option
    opt.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    opt.setNumber("Mesh.MeshSizeFromPoints", 0)
    opt.setNumber("Mesh.MeshSizeFromCurvature", 0)
    opt.setNumber("Mesh.MeshSizeMax", coarse)
    if not opening:
        opt.setNumber("Mesh.MeshSizeMin", coarse)
        return
    fine, dist_min, dist_max = spec.size_law(domain)
    field_ = gmsh.model.mesh.field
    dist = field_.add("Distance")
    field_.setNumbers(dist, "CurvesList", opening)
    field_.setNumber(dist, "Sampling", 50)
    thr = field_.add("Threshold")
    field_.setNumber(thr, "InField", dist)
    field_.setNumber(thr, "SizeMin", fine)
    field_.setNumber(thr, "SizeMax", coarse)
    field_.setNumber(thr, "DistMin", dist_min)
    field_.setNumber(thr, "DistMax", dist_max)
    field_.setAsBackgroundMesh(thr)


def _gap_blocks(geo, domain: ChamberDomain, gspec: GapMeshSpec):
    """The gap's four transfinite blocks (case A's layout, turned into the chamber plane).

    Returns the blocks as (surface, patch of each loop edge) and the two inlet lines as
    ((lower point, lower->mid line), (mid->upper line, upper point)).
    """
    # The inlet lines are the chamber's opening: internal faces.
    names = {"lower": "gapWalls", "upper": "gapWalls", "in": None, "out": "outlet"}
    blocks, corner, across = gap_blocks(geo, domain.walls, gspec, names, domain.to_plane)
    inlet = ((corner["lower", "in"], across["in", "lower"]),
             (across["in", "upper"], corner["upper", "in"]))
    return blocks, inlet
