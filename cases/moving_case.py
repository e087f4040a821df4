"""The OpenFOAM case of the section in motion (:mod:`.moving_section`), run and judged.

Written (:func:`write_case`): the one-cell-thick polyMesh of the start grid
(:mod:`.polymesh`; patches ``innerRotor``, ``outerRotor`` and ``frontAndBack``, all
walls), the cellZones of the chambers at the start angle (:mod:`.machine_zones`; the gap
columns, at most :data:`.moving_section.GAP_COLUMN_RATIO` clearances long, go to the zone
``gaps`` instead), the faceZones of the sealing lines between chambers, and the key
frames' displacements ``keyDisplacement`` in their time folders.  rhoPimpleFoam, laminar,
perfect gas, at rest at the start, a fixed time step dividing the key-frame interval.
Walls: on the rotors, each rotor's own omega x r tangentially and the mesh's motion
normally (:mod:`.moving_walls`: ``timeVaryingMappedFixedValue`` of samples exact for the
fixed step, so no gas crosses a wall).  Closed (no ports): ``slip`` on front and back.
With ports (``MovingSection.ports``, :mod:`.moving_ports`): the end faces are the
patches ``back`` (suction) and ``front`` (discharge), each face port or plate by its
centre's position at every evaluation.

Written every time step (``postProcessing``): the mass in the domain, each chamber's
volume-averaged pressure, the flow through each sealing faceZone, and the largest Courant
number in the gap cells and in the whole domain; with ports, the flow through
``back`` and ``front`` (their plate faces carry none).  :func:`.moving_run.judge`
accepts a run
("completed") that reached its end time with finite pressures, a largest Courant
number at most ``max_courant`` (the step is fixed, so nothing else holds it) and a mass
that stayed within ``mass_tol`` of its start (closed domain) or of its start plus what
came in through the ports (:func:`.moving_run.mass_balance`); otherwise the run is
"incomplete", "inconsistent", "diverged" or "crashed", kept with its log tail and never
used.  The per-step chamber pressures are those of the start angle's zones; over more
than a few degrees take them from the grid's topology at written frames
(:mod:`.moving_chambers`).
"""

from __future__ import annotations

import functools
import hashlib
import math
import shutil
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.geometry.sweep import Sweep

from . import foam_case, moving_ports, moving_walls
from .foam import Step
from .foam_case import Plan
from .foam_dicts import (
    control_dict,
    field_value,
    fv_schemes,
    thermophysical_properties,
    turbulence_properties,
)
from .foam_files import write_dict, write_field
from .foam_mesh import judge_check_mesh
from .machine_case import seal_name, slot_name
from .machine_zones import NONE, ChamberZones, chamber_zones, seal_faces, write_zones
from .moving_run import SOLVER, MovingRun, end_fields, judge  # noqa: F401 (the runner's API)
from .moving_section import GAP_COLUMN_RATIO, MovingSection, checked_frames, wall_velocity_check
from .polymesh import HEADER, build_polymesh, write_mesh

FIELD = "keyDisplacement"
ROTORS = ("innerRotor", "outerRotor")
ENDS = "frontAndBack"


@dataclass(frozen=True)
class RunControls:
    """Time stepping and acceptance."""

    #: Fixed time steps per key-frame interval: the wall velocity that keeps the mesh
    #: flux (:mod:`.moving_walls`) needs the step in advance.  64 at 0.25 deg frames
    #: (2.6e-7 s at 2500 rpm) is about what Courant 0.5 in the gap columns asked of the
    #: adjustable step at 100 um from rest; over a lobe period the chamber before top
    #: dead centre leaks harder and 64 reaches Courant 2.1, 192 stays at 0.69
    #: (tests/data/cfd/moving/record.py): the judge below refuses a run above
    #: ``max_courant``, it does not adjust the step.
    steps_per_frame: int = 64
    #: A run whose largest Courant number (on the flux relative to the moving cells)
    #: exceeds this is "inconsistent".  Below 1 PISO (one outer corrector) is safe
    #: anywhere; above it a run must be judged by its chamber pressures against a
    #: smaller step's (issue 17's ported section ran stable to Courant 7, its error
    #: first order in the step: tests/data/cfd/moving/record_ported.py pimple).
    max_courant: float = 1.0
    #: PIMPLE outer correctors a step (1: PISO).  More iterate each step's coupling of
    #: pressure, velocity and energy, which is what lets the step grow past Courant 1
    #: (issue 17's cost control): raise ``max_courant`` with it, and judge the result
    #: by the chamber pressures against a run at Courant below 1.
    outer_correctors: int = 1
    #: Fields written every this many key frames (0: at the end only), on the frame
    #: times, where the grid is known exactly: the chambers' pressures are taken from the
    #: grid's own topology there (:mod:`.moving_chambers`).
    write_every_frames: int = 0
    #: Mass of the closed domain, or of the ported one less what its ports let through
    #: (:func:`mass_balance`): relative change allowed over the run (issue 17's 1e-4
    #: over a revolution).
    mass_tol: float = 1e-4
    timeout_s: float | None = None


@dataclass(frozen=True)
class Built:
    cells: int
    chambers: tuple  # slot numbers with a zone
    seals: tuple  # (a, b) slot pairs with a sealing faceZone
    gap_cells: int
    duration: float
    interpolation: dict  # :func:`.moving_section.interpolation_error`
    wall_velocity: dict  # imposed (:func:`.moving_walls.check`) and the grid's sliding
    ports: tuple = ()  # the port patches, empty when closed


def _frame_name(t: float) -> str:
    return "0" if t == 0.0 else f"{t:.12g}"


def _ends(xy, end):
    return np.full(len(xy), ENDS), {ENDS: "wall"}


def section_zones(s: MovingSection, grid, phi: float) -> ChamberZones:
    """The chambers of the grid at outer angle ``phi`` by the O-grid's own topology
    (:func:`.machine_zones.chamber_zones`), slot s (1..N, N the outer rotor's lobes)
    holding the chamber of machine age ``phi + s * period`` modulo a turn (a chamber
    lives less than a turn: one slot, one chamber; past the first period the newborn
    chamber's own slot is negative)."""
    n = int(round(2.0 * math.pi / float(s.pair.period)))
    z = chamber_zones(s.pair, [grid, grid], np.array([0.0, s.depth]), phi,
                      Sweep("straight", s.depth))

    def fold(slot):
        return (slot - 1) % n + 1

    cell_slot = z.cell_slot.copy()
    on = cell_slot != NONE
    cell_slot[on] = fold(cell_slot[on])
    return ChamberZones(cell_slot, tuple(sorted({fold(c) for c in z.slots})),
                        {fold(c): a for c, a in z.ages.items()})


def chamber_cells(s: MovingSection, grid, phi: float) -> tuple[dict, np.ndarray]:
    """({slot: cells} without the gap columns, the gap columns' cells) of the grid at
    outer angle ``phi``: the chambers of :func:`section_zones`."""
    return _cells(s, grid, section_zones(s, grid, phi))


def _cells(s: MovingSection, grid, zones: ChamberZones) -> tuple[dict, np.ndarray]:
    p = grid.points
    length = np.linalg.norm(p[:, -1] - p[:, 0], axis=1)
    # a cell column spans node columns i and i + 1: a gap column if either is short
    short = np.minimum(length, np.roll(length, -1)) <= GAP_COLUMN_RATIO * s.gap
    gap_cell = np.repeat(short, grid.cells_across)  # cell (i, j) is i * rows + j
    cells = {c: np.flatnonzero((zones.cell_slot == c) & ~gap_cell) for c in zones.slots}
    return {k: v for k, v in cells.items() if v.size}, gap_cell


def _zones(s: MovingSection, grid, mesh) -> tuple[dict, dict, int]:
    """(cellZones by slot, "gaps" included; sealing faces by slot pair; gap cells) at the
    start angle: chambers without their gap columns, the gap columns, the faces between
    chambers (:func:`.machine_zones.seal_faces`)."""
    pts, faces, owner, nei, patches = mesh
    zones = section_zones(s, grid, s.start)
    cell_zones, gap_cell = _cells(s, grid, zones)
    cell_zones["gaps"] = np.flatnonzero(gap_cell)
    return cell_zones, seal_faces(zones, owner, nei), int(gap_cell.sum())


def _write_frames(case_dir: Path, s: MovingSection, grids, patches) -> None:
    base = grids[0].points.reshape(-1, 2)
    boundary = "".join(f"    {name} {{ type calculated; }}\n" for name in patches)
    for t, g in zip(s.frame_times, grids, strict=True):
        d = g.points.reshape(-1, 2) - base
        d = np.concatenate([d, d])  # both planes of the slab move alike
        rows = "\n".join(f"({a:.17g} {b:.17g} 0)" for a, b in d)
        folder = case_dir / _frame_name(float(t))
        folder.mkdir(parents=True, exist_ok=True)
        (folder / FIELD).write_text(
            HEADER.format(cls="pointVectorField", obj=FIELD).replace(
                'location    "constant/polyMesh";\n', "")
            + f"\ndimensions [0 1 0 0 0 0 0];\ninternalField nonuniform List<vector> "
            f"{len(d)}\n(\n{rows}\n);\nboundaryField\n{{\n{boundary}}}\n")


def write_case(s: MovingSection, case_dir: Path, controls: RunControls = RunControls()
               ) -> tuple[Plan, Built]:
    """Write the case into ``case_dir`` (see the module docstring) and return its plan
    (checkMesh, the solver) and what the judge needs.  Every key frame and the motion
    between them are checked before the first file is written: a degenerate frame is a
    CaseError and nothing is written."""
    grids, error = checked_frames(s)
    mesh = build_polymesh([grids[0], grids[0]], np.array([0.0, s.depth]),
                          moving_ports.end_patches if s.ports else _ends)
    by_slot, seals, gap_cells = _zones(s, grids[0], mesh)
    cell_zones = {k if k == "gaps" else slot_name(k): v for k, v in by_slot.items()}
    case_dir = Path(case_dir)
    write_mesh(case_dir, mesh)
    write_zones(case_dir, cell_zones, {seal_name(a, b): v for (a, b), v in seals.items()})
    patches = [p[0] for p in mesh[4]]
    _write_frames(case_dir, s, grids, patches)
    walls = _write_walls(s, case_dir, grids, mesh, controls.steps_per_frame)
    slots = tuple(k for k in by_slot if k != "gaps")
    ports = moving_ports.PATCHES if s.ports else ()
    _write_dicts(s, case_dir, controls, [slot_name(c) for c in slots],
                 [seal_name(a, b) for a, b in seals], ports)
    cells = int(mesh[2].max()) + 1
    _write_fields(s, case_dir, cells, cell_zones, patches)
    # One cell thick: checkMesh's aspect ratio is the depth over the smallest in-plane
    # size (10 mm over the 2304 x 9 grid's 0.7 um cells: 1.5e4), and no face lies across
    # the depth to suffer it; the in-plane ratio is the O-grid's own check at every
    # key frame (QualityLimits), so checkMesh's flag is not the judge here.
    plan = Plan(setup=(Step(("checkMesh",), then=functools.partial(
        judge_check_mesh, expected_cells=cells, max_aspect_ratio=math.inf)),),
        solve=Step((SOLVER,), timeout_s=controls.timeout_s))
    return plan, Built(cells, slots, tuple(seals), gap_cells, s.duration, error,
                       {**walls, "grid_sliding": wall_velocity_check(s, grids)}, ports)


def _rotor(s: MovingSection, patch: str):
    rotor = s.pair.rotors[1 if patch == "innerRotor" else 0]
    return float(rotor.speed_ratio) * s.omega_outer, rotor.axis


def _write_walls(s: MovingSection, case_dir: Path, grids, mesh, steps: int) -> dict:
    """Each rotor patch's wall-velocity samples (:mod:`.moving_walls`) into
    ``constant/boundaryData``, and their check at every step against the mesh's swept
    areas and omega x r."""
    frames = [g.points.reshape(-1, 2) for g in grids]
    dt = s.duration / s.frames / steps
    out = {}
    for patch in ROTORS:
        edges = moving_walls.wall_edges(mesh, patch)
        omega, axis = _rotor(s, patch)
        times, values = moving_walls.wall_samples(frames, s.frame_times, edges, dt, omega,
                                                  axis)
        centres = np.column_stack([0.5 * (frames[0][edges[:, 0]] + frames[0][edges[:, 1]]),
                                   np.full(len(edges), 0.5 * s.depth)])
        moving_walls.write_boundary_data(case_dir, patch, centres, times, values)
        out[patch] = moving_walls.check(frames, s.frame_times, edges, dt, omega, axis, steps)
    return out


def _write_dicts(s: MovingSection, case_dir: Path, c: RunControls, chambers: list,
                 seals: list, ports: tuple = ()) -> None:
    def fo(kind, region, op, fields, name=None):
        return field_value(kind, region, op, fields, write_control="timeStep",
                           write_interval=1, name=name)

    # CourantNo first: function objects run in order, and the Co maxima read its field.
    functions: dict[str, Any] = {"Co": {"type": "CourantNo", "libs": ["fieldFunctionObjects"],
                                        "executeControl": "timeStep",
                                        "writeControl": "none"}}
    functions["Co_gaps"] = fo("volFieldValue", "cellZone", "max", ["Co"], "gaps")
    functions["Co_all"] = fo("volFieldValue", "all", "max", ["Co"])
    functions["mass"] = fo("volFieldValue", "all", "volIntegrate", ["rho"])
    functions |= {f"p_{z}": fo("volFieldValue", "cellZone", "volAverage", ["p"], z)
                  for z in chambers}
    functions |= {f"flow_{z}": fo("surfaceFieldValue", "faceZone", "sum", ["phi"], z)
                  for z in seals}
    functions |= {f"port_{z}": fo("surfaceFieldValue", "patch", "sum", ["phi"], z)
                  for z in ports}
    system, constant = case_dir / "system", case_dir / "constant"
    frame_dt = s.duration / s.frames
    write_dict(system / "controlDict", control_dict(
        SOLVER, start_from="startTime", end_time=s.duration,
        delta_t=frame_dt / c.steps_per_frame, time_step={"adjustTimeStep": False},
        write_control="runTime", purge_write=0,
        write_interval=frame_dt * c.write_every_frames if c.write_every_frames else s.duration,
        time_precision=12, run_time_modifiable=False, functions=functions))
    lin_up = ("Gauss", "linearUpwind", "limited")
    schemes = fv_schemes("Euler", {
        "div(phi,U)": lin_up, "div(phi,e)": lin_up, "div(phi,K)": ("Gauss", "linear"),
        "div(phiv,p)": ("Gauss", "linear"), "div(meshPhi,p)": ("Gauss", "linear"),
        "div(phid,p)": ("Gauss", "upwind")})
    # the O-grid reaches ~70 deg of non-orthogonality next to the sealing lines: limit
    # the correction there (as the frozen-angle machine case does)
    schemes["laplacianSchemes"] = {"default": ("Gauss", "linear", "limited", 0.5)}
    schemes["snGradSchemes"] = {"default": ("limited", 0.5)}
    write_dict(system / "fvSchemes", schemes)
    fine = {"solver": "PBiCGStab", "preconditioner": "DILU", "tolerance": 1e-12,
            "relTol": 0.0}
    write_dict(system / "fvSolution", {
        "solvers": {
            '"rho.*"': {"solver": "diagonal"},
            # tight: the closed domain's mass is the run's check, and the pressure
            # equation's residual is what it is conserved to
            "p": {**fine, "relTol": 0.01}, "pFinal": fine,
            '"(U|e)"': {**fine, "relTol": 0.01}, '"(U|e)Final"': fine,
            # no interior points (every patch prescribes its own): cheap, kept exact
            '"cellDisplacement.*"': {"solver": "PCG", "preconditioner": "DIC",
                                      "tolerance": 1e-12, "relTol": 0.0},
        },
        "PIMPLE": {"momentumPredictor": True, "nOuterCorrectors": c.outer_correctors,
                   "nCorrectors": 2, "nNonOrthogonalCorrectors": 1, "transonic": True,
                   "correctPhi": False},
    })
    write_dict(constant / "dynamicMeshDict", {
        "dynamicFvMesh": "dynamicMotionSolverFvMesh",
        "motionSolverLibs": ['"libfvMotionSolvers.so"'],
        "solver": "displacementLaplacian",
        "displacementLaplacianCoeffs": {"diffusivity": "uniform"}})
    write_dict(constant / "thermophysicalProperties", thermophysical_properties(s.gas))
    write_dict(constant / "turbulenceProperties", turbulence_properties("laminar"))


def _write_fields(s: MovingSection, case_dir: Path, cells: int, cell_zones: dict,
                  patches: list) -> None:
    zero = case_dir / "0"
    p, T, U = _start_state(s, cells, cell_zones)
    grad = {name: {"type": "zeroGradient"} for name in patches}
    ends = moving_ports.boundary_fields(s.ports, s.p0, s.T0) if s.ports else {
        "p": {}, "T": {}, "U": {ENDS: {"type": "slip"}}}
    write_field(zero / "p", (1, -1, -2), p, grad | ends["p"])
    write_field(zero / "T", (0, 0, 0, 1), T, grad | ends["T"])
    u0 = np.zeros(3)
    # the samples are the faces' own centres: "nearest" maps each onto its face
    walls = {"type": "timeVaryingMappedFixedValue", "mapMethod": "nearest",
             "setAverage": False, "value": u0}
    write_field(zero / "U", (0, 1, -1), U, vector=True, boundary={
        **{r: walls for r in ROTORS}, **ends["U"]})
    motion = {"type": "uniformInterpolatedDisplacement", "field": FIELD,
              "interpolationScheme": "linear", "value": u0}
    write_field(zero / "pointDisplacement", (0, 1), u0, {name: motion for name in patches},
                vector=True, point=True)


def _start_state(s: MovingSection, cells: int, cell_zones: dict):
    """(p, T, U) of the cells at the start: ``initial_fields`` whole, else p0 and T0 with
    the named chambers' own values."""
    if s.initial_fields is not None:
        f = s.initial_fields
        p, T, U = (np.asarray(f[k], float) for k in ("p", "T", "U"))
        if p.shape != (cells,) or T.shape != (cells,) or U.shape != (cells, 3):
            raise CaseError(f"the start fields hold {p.size} cells, the grid {cells}: "
                            "not the same grid")
        return p, T, U
    p, T = np.full(cells, s.p0), np.full(cells, s.T0)
    for values, field_ in ((s.initial_p, p), (s.initial_T, T)):
        for slot, value in (values or {}).items():
            if slot_name(slot) in cell_zones:
                field_[cell_zones[slot_name(slot)]] = value
    # uniform where nothing varies: a closed run's files stay what they always were
    return p, (T if s.initial_T else s.T0), np.zeros(3)


def case_key(s: MovingSection, controls: RunControls) -> str:
    key = {
        "pair": s.pair.digest(), "gap": s.gap, "spec": s.spec.key(), "start": s.start,
        "span": s.span, "frames": s.frames, "omega": s.omega_outer, "depth": s.depth,
        "p0": s.p0, "T0": s.T0, "gas": asdict(s.gas),
        "initial_p": sorted((int(k), float(v)) for k, v in (s.initial_p or {}).items()),
        "controls": {k: v for k, v in asdict(controls).items()
                     if k != "outer_correctors" or v != 1}}  # PISO runs keep their keys
    if s.initial_T:  # keys of runs without them stay what they were
        key["initial_T"] = sorted((int(k), float(v)) for k, v in s.initial_T.items())
    if s.initial_fields is not None:
        key["initial_fields"] = hashlib.sha256(b"".join(
            np.ascontiguousarray(s.initial_fields[k], float).tobytes()
            for k in ("p", "T", "U"))).hexdigest()
    if s.ports:  # a closed section keeps the key it always had
        key["ports"] = s.ports.key()
    return foam_case.digest(key)


def run_moving_section(s: MovingSection, case_dir: Path,
                       controls: RunControls = RunControls(), *, reuse: bool = True,
                       launch=None) -> MovingRun:
    """Build, run and judge ``s`` in ``case_dir`` (:func:`.foam_case.run_case`: built in a
    temporary folder, renamed into place once judged, reused by key; a failed run kept
    with its log tail).  A grid or motion that cannot be made raises CaseError."""
    def build(folder: Path):
        try:
            return write_case(s, folder, controls)
        except CaseError:
            shutil.rmtree(folder, ignore_errors=True)  # nothing half-written stays
            raise

    def judged(folder, built, values: Mapping[str, Any], elapsed, failure):
        return judge(folder, built, controls, elapsed, failure)

    return foam_case.run_case(
        case_dir, case_key(s, controls), build, judged, MovingRun.from_json, reuse=reuse,
        label="moving section", launch=launch,
        summary=lambda r: (f"{r.status} {r.message}, {r.cells} cells, {r.time_steps} steps, "
                           f"mass drift {r.mass_drift:.1e}"
                           + (f", balance {r.mass_balance:.1e}" if r.port_flow else "")
                           + ", gap Courant "
                           f"{r.max_gap_courant:.3g}, {r.run_time_s:.1f} s"))
