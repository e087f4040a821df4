"""Case B: pressure in a chamber that is compressed while it leaks, with OpenFOAM.

One working chamber of an internal-gear machine is followed through its compression
phase, from suction closing to discharge opening, as a 2D section (one cell thick):

* **Scaling.**  The slab's depth D is a representative sealing-line length L_s (by
  default the mean, over the compression phase, of the lines across which the chamber
  leaks toward suction: ``seal_prev_m + seal_lp_face_m`` of the chamber table).  Then
  the gap's flow area is h_min x D = gap x L_s, which is the leakage area the quasi-1D
  model gives those lines, and the chamber's area A(t) = V(t) / D makes its volume the
  table's V(t).
* **Geometry.**  A rectangular chamber (square at the start) whose top wall is a piston,
  and case A's rotor-tip gap (minimum gap h from ``[leakage] gap_um``) opening from the
  bottom wall into a plenum at suction pressure (the gap's outlet, a static-pressure
  boundary); see :mod:`rotorflow.cases.chamber_mesh`.  The chamber's area is reduced by
  the gap's area upstream of its throat, so that the gas upstream of the throat (the
  control volume of the quasi-1D chamber) has exactly the table's volume.
* **Motion.**  Time is angle over the outer rotor's angular speed, t = (theta -
  theta_sc) / omega_outer.  The piston's displacement d(t) = (V(t) - V(0)) / (D W) is a
  table in time; ``dynamicMotionSolverFvMesh`` with the stock ``displacementInterpolation``
  solver moves every point by linear interpolation in y between two face zones made by
  topoSet: the piston (the table) and a line of faces at the top of the chamber's fixed
  lower part (zero), so the cells around the opening, the gap and the outlet never move
  and the structured block above is squeezed uniformly.  (``displacementLaplacian`` on
  the whole chamber squeezed the unstructured cells near the opening too: their
  non-orthogonality rose from 30 to 52 deg and the run diverged late in the compression.)
* **Flow.**  rhoPimpleFoam, laminar, perfect gas with Sutherland viscosity, adiabatic
  walls; at rest at suction pressure and temperature at the start.
* **Outputs.**  Function objects sample, every ``sample_deg`` of rotor angle: the
  chamber zone's volume average of p and T (``volFieldValue``, cellZone ``chamber``
  made by gmshToFoam from gmsh's physical volume: cell zones keep their orientation,
  only face zones come flipped), its integrals of p and rho (chamber volume = integral
  of p / average of p; chamber mass), the mass in the whole domain and the mass flow
  out through the outlet.

:func:`run_chamber_case` builds the case in a temporary folder, runs it, judges it
(end time reached, mass conserved, chamber volume as prescribed) and renames the folder
into place with ``result.json``.  A crashed or diverged run is kept with its log tail
and is never compared.  :func:`run_stage` is the workflow's ``cfd.chamber`` stage.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError, ExternalRunError
from rotorflow.postprocess import chamber_compare as cc
from rotorflow.quasi1d.perfect_gas import PerfectGas

from . import foam
from .chamber_mesh import ChamberDomain, ChamberMeshSpec, build_foam_mesh, patch_types
from .gap_case import RESULT_LOG_LINES, looks_diverged, thermophysical_properties
from .gap_mesh import GapWalls, rotor_tip_gap

log = logging.getLogger(__name__)

SOLVER = "rhoPimpleFoam"

#: Version of the case this module writes: bump it when dictionaries or judgement change,
#: so that stored results of older cases are recomputed rather than reused.
CASE_FORMAT = 1

#: Default radius of the two convex walls of the rotor-tip gap: the radius of case A's
#: matrix points (MatrixPoint.radius_mm), so that its fitted correlation applies.
TIP_RADIUS_M = 0.02

#: Points of the piston's displacement table per degree of rotor angle.  The volume
#: curve is smooth on that scale: linear interpolation between 0.1 deg samples departs
#: from it by ~1e-7 of the volume.
VOLUME_SAMPLES_PER_DEG = 10


@dataclass(frozen=True)
class Compression:
    """The chamber's compression phase: volume against outer-rotor angle, and the gas."""

    angle_rad: tuple[float, ...]
    """Outer-rotor angles since the chamber's birth, from suction closing to discharge
    opening (increasing)."""
    volume_m3: tuple[float, ...]
    omega_outer_rad_s: float
    p_suction_Pa: float
    T_suction_K: float
    seal_length_m: float
    """The slab's depth: the sealing-line length the gap stands for."""
    gap_m: float
    """Minimum gap; 0: a sealed chamber."""
    tip_radius_m: float = TIP_RADIUS_M
    gas: PerfectGas = field(default_factory=PerfectGas)

    def __post_init__(self) -> None:
        a, v = np.asarray(self.angle_rad), np.asarray(self.volume_m3)
        if a.ndim != 1 or a.shape != v.shape or len(a) < 2:
            raise CaseError("compression: angle and volume must be equal-length 1D sequences")
        if np.any(np.diff(a) <= 0) or np.any(v <= 0) or not np.all(np.isfinite(v)):
            raise CaseError("compression: angles must increase and volumes be positive")
        if min(self.omega_outer_rad_s, self.p_suction_Pa, self.T_suction_K,
               self.seal_length_m) <= 0 or self.gap_m < 0:
            raise CaseError("compression: speed, pressure, temperature, sealing length must "
                            "be > 0 and the gap >= 0")

    @property
    def duration_s(self) -> float:
        return (self.angle_rad[-1] - self.angle_rad[0]) / self.omega_outer_rad_s

    def time_s(self, angle_rad) -> np.ndarray:
        return (np.asarray(angle_rad, dtype=float) - self.angle_rad[0]) / self.omega_outer_rad_s

    def angle_of(self, time_s) -> np.ndarray:
        return self.angle_rad[0] + np.asarray(time_s, dtype=float) * self.omega_outer_rad_s

    def volume_curve(self) -> cc.VolumeCurve:
        return cc.VolumeCurve(np.asarray(self.angle_rad), np.asarray(self.volume_m3),
                              self.omega_outer_rad_s)

    def walls(self) -> GapWalls | None:
        return None if self.gap_m == 0 else rotor_tip_gap(self.gap_m, self.tip_radius_m)

    def limited_to(self, end_deg: float) -> Compression:
        """The same compression stopped ``end_deg`` after its start (for short runs)."""
        a = np.asarray(self.angle_rad)
        end = a[0] + math.radians(end_deg)
        if not a[0] < end <= a[-1]:
            raise CaseError(f"end_deg {end_deg} lies outside the compression phase")
        keep = a < end - 1e-12
        angles = np.append(a[keep], end)
        vol = np.append(np.asarray(self.volume_m3)[keep], np.interp(end, a, self.volume_m3))
        return replace(self, angle_rad=tuple(angles), volume_m3=tuple(vol))


@dataclass(frozen=True)
class TransientControls:
    """Time stepping, sampling and what a finished run must satisfy."""

    max_courant: float = 1.0
    """Largest cell Courant number (rhoPimpleFoam's adjustable time step)."""
    max_dt_s: float = 2.0e-6
    """Upper bound of the time step on the default mesh (divided by the mesh refinement):
    a twentieth of the chamber's acoustic time W/c (~40 us), so the pressure in the
    chamber stays uniform as it is in the quasi-1D model; the leakage flow's Courant
    number takes over below it once the gap flow is fast."""
    first_dt_s: float = 1.0e-9
    outer_correctors: int = 1
    """PISO (one outer corrector): outer iterations without under-relaxation made the
    gap's flow unstable at these time steps."""
    correctors: int = 3
    """Pressure correctors: with 2 the splitting error let noise grow in the gap's
    smallest cells (acoustic Courant number ~15) on the refined mesh; 3 keeps it still."""
    sample_deg: float = 0.5
    """Rotor angle between samples of the function objects."""
    mass_tol: float = 1.0e-3
    """Largest |mass now + mass out - mass at start| / mass at start: finite volumes
    conserve mass to the linear solvers' tolerance, far below this."""
    volume_tol: float = 1.0e-3
    """Largest relative difference between the chamber zone's volume and the prescribed
    one: the motion is exact, so anything above round-off means the zones or the table
    are wrong."""
    timeout_s: float | None = 900.0


@dataclass(frozen=True)
class ChamberCase:
    """Everything that defines one chamber run."""

    compression: Compression
    mesh: ChamberMeshSpec = field(default_factory=ChamberMeshSpec)
    controls: TransientControls = field(default_factory=TransientControls)

    def refined(self, factor: float) -> ChamberCase:
        return replace(self, mesh=self.mesh.refined(factor))

    @property
    def with_gap(self) -> bool:
        return self.compression.gap_m > 0

    def domain(self) -> ChamberDomain:
        """Square at the start; its area less the gap's area upstream of the throat."""
        c = self.compression
        walls = c.walls()
        area = c.volume_m3[0] / c.seal_length_m - upstream_gap_area(walls)
        side = math.sqrt(area)
        return ChamberDomain(side, side, c.seal_length_m, walls)

    def key(self) -> str:
        """A digest of everything that determines the result (reuse of finished runs)."""
        payload = {"format": CASE_FORMAT, "compression": asdict(self.compression),
                   "mesh": asdict(self.mesh), "controls": asdict(self.controls)}
        text = json.dumps(payload, sort_keys=True, allow_nan=True)
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def description(self) -> dict[str, Any]:
        """What the comparison needs to know of the case (``case.json``)."""
        c, d = self.compression, self.domain()
        walls = c.walls()
        return {
            "angle_rad": list(c.angle_rad),
            "volume_m3": list(c.volume_m3),
            "omega_outer_rad_s": c.omega_outer_rad_s,
            "p_suction_Pa": c.p_suction_Pa,
            "T_suction_K": c.T_suction_K,
            "seal_length_m": c.seal_length_m,
            "gap_m": c.gap_m,
            "gap_length_m": walls.narrow_length() if walls is not None else 0.0,
            "tip_radius_m": c.tip_radius_m,
            "gas": asdict(c.gas),
            "gamma": c.gas.gamma,
            "R_J_kgK": c.gas.R,
            "width_m": d.width_m,
            "height_m": d.height_m,
            "depth_m": d.depth_m,
            "upstream_gap_area_m2": upstream_gap_area(walls),
            "gap_flow_area_m2": d.gap_flow_area_m2,
            "mesh": asdict(self.mesh),
            "controls": asdict(self.controls),
        }


def upstream_gap_area(walls: GapWalls | None) -> float:
    """Area of the gap between its inlet and its throat (m2 of the 2D section)."""
    if walls is None:
        return 0.0
    x = np.linspace(walls.x_inlet, walls.throat_x, 2001)
    return float(np.trapezoid(walls.gap(x), x))


# --- building a case from a chamber table ------------------------------------------------


def seal_length_to_suction(table, start_rad: float, end_rad: float) -> float:
    """Mean over [start, end] of the sealing lines toward suction: the previous (younger)
    chamber's line and the low-pressure end face's."""
    a = np.asarray(table.angle_rad)
    lines = np.asarray(table.seal_prev_m) + np.asarray(table.seal_lp_face_m)
    x = np.linspace(start_rad, end_rad, 1001)
    return float(np.mean(np.interp(x, a, lines)))


def compression_from_table(table, operating, leakage, *, seal_length_m: float | None = None,
                           tip_radius_m: float = TIP_RADIUS_M,
                           samples_per_deg: int = VOLUME_SAMPLES_PER_DEG) -> Compression:
    """The compression phase of ``table`` at ``operating`` with ``leakage``'s gap.

    ``table``: a ChamberTable; ``operating``/``leakage``: quasi-1D ``Operating`` and
    ``Leakage``.  Suction closing and discharge opening follow the quasi-1D model's rules
    (:func:`rotorflow.quasi1d.chamber.prepare`), and the volume is its Hermite curve.
    """
    from rotorflow.quasi1d.chamber import prepare

    if operating.fluid != "air":
        raise CaseError(f"the chamber CFD case models air as a perfect gas, not "
                        f"{operating.fluid}")
    geo = prepare(table, operating.volume_ratio, operating.suction_close_rad,
                  operating.discharge_open_rad, operating.speed_rpm, 1e-3)
    span_deg = math.degrees(geo.discharge_open - geo.suction_close)
    n = max(2, int(math.ceil(span_deg * samples_per_deg)) + 1)
    angles = np.linspace(geo.suction_close, geo.discharge_open, n)
    seal = seal_length_m if seal_length_m is not None else seal_length_to_suction(
        table, geo.suction_close, geo.discharge_open)
    gas = operating.constant_cp_gas
    return Compression(
        angle_rad=tuple(float(a) for a in angles),
        volume_m3=tuple(float(v) for v in geo.volume(angles)),
        omega_outer_rad_s=geo.omega_outer,
        p_suction_Pa=operating.p_suction_Pa,
        T_suction_K=operating.T_suction_K,
        seal_length_m=seal,
        gap_m=leakage.gap_m if leakage.model != "none" else 0.0,
        tip_radius_m=tip_radius_m,
        gas=gas,
    )


# --- dictionaries -------------------------------------------------------------------------

_FUNCTION_OBJECTS = {
    # name: (type, region type, region name, operation, fields)
    "chamberAverage": ("volFieldValue", "cellZone", "chamber", "volAverage", ["p", "T"]),
    "chamberIntegral": ("volFieldValue", "cellZone", "chamber", "volIntegrate", ["p", "rho"]),
    "domainMass": ("volFieldValue", "all", None, "volIntegrate", ["rho"]),
    "outletFlow": ("surfaceFieldValue", "patch", "outlet", "sum", ["phi"]),
}


def sample_interval_s(case: ChamberCase) -> float:
    """Time between samples: about ``sample_deg`` of rotor angle, a whole fraction of the
    run so that the last sample falls on its end (discharge opening)."""
    c = case.compression
    span_deg = math.degrees(c.angle_rad[-1] - c.angle_rad[0])
    return c.duration_s / max(1, math.ceil(span_deg / case.controls.sample_deg - 1e-9))


def _function_objects(case: ChamberCase) -> dict[str, Any]:
    interval = sample_interval_s(case)
    out = {}
    for name, (kind, region, region_name, operation, fields) in _FUNCTION_OBJECTS.items():
        if region_name == "outlet" and not case.with_gap:
            continue
        entry: dict[str, Any] = {
            "type": kind,
            "libs": ["fieldFunctionObjects"],
            "writeControl": "adjustableRunTime",  # the time step is cut to hit each sample
            "writeInterval": interval,
            "log": False,
            "writeFields": False,
            "regionType": region,
            "operation": operation,
            "fields": fields,
        }
        if region_name is not None:
            entry["name"] = region_name
        out[name] = entry
    return out


def _control_dict(case: ChamberCase) -> dict[str, Any]:
    c, ctl = case.compression, case.controls
    return {
        "application": SOLVER,
        "startFrom": "startTime",
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": c.duration_s,
        "deltaT": ctl.first_dt_s,
        "adjustTimeStep": True,
        "maxCo": ctl.max_courant,
        # Refined with the mesh: at a fixed time step the acoustic Courant number of the
        # smallest cells (near the opening and in the gap) grows with refinement, and at
        # ~15 the split pressure-velocity coupling lets noise grow in them.
        "maxDeltaT": ctl.max_dt_s / case.mesh.refinement,
        "writeControl": "adjustableRunTime",
        "writeInterval": c.duration_s,  # only the final fields; the tables are the output
        "purgeWrite": 0,
        "writeFormat": "ascii",
        "writePrecision": 10,
        "writeCompression": False,
        "timeFormat": "general",
        "timePrecision": 12,
        "runTimeModifiable": False,
        "functions": _function_objects(case),
    }


def _fv_schemes() -> dict[str, Any]:
    lin_up = ("Gauss", "linearUpwind", "limited")
    return {
        "ddtSchemes": {"default": "Euler"},
        "gradSchemes": {"default": ("Gauss", "linear"),
                        "limited": ("cellLimited", "Gauss", "linear", 1)},
        "divSchemes": {
            "default": "none",
            "div(phi,U)": lin_up,
            "div(phi,e)": lin_up,
            "div(phi,K)": ("Gauss", "linear"),
            "div(phiv,p)": ("Gauss", "linear"),
            "div(meshPhi,p)": ("Gauss", "linear"),
            "div(phid,p)": ("Gauss", "upwind"),
            "div(((rho*nuEff)*dev2(T(grad(U)))))": ("Gauss", "linear"),
        },
        "laplacianSchemes": {"default": ("Gauss", "linear", "corrected")},
        "interpolationSchemes": {"default": "linear"},
        "snGradSchemes": {"default": "corrected"},
    }


def _fv_solution(controls: TransientControls, p_ref: float) -> dict[str, Any]:
    fine = {"solver": "PBiCGStab", "preconditioner": "DILU", "tolerance": 1e-10, "relTol": 0.0}
    return {
        "solvers": {
            '"rho.*"': {"solver": "diagonal"},
            # A Krylov solver: on these small meshes with gap cells 50:1 it converges in
            # tens of iterations where GAMG took hundreds.  1e-9 (normalised residual):
            # mass is conserved to ~1e-6 over a compression.
            "p": {"solver": "PBiCGStab", "preconditioner": "DILU", "tolerance": 1e-9,
                  "relTol": 0.01},
            "pFinal": {"solver": "PBiCGStab", "preconditioner": "DILU", "tolerance": 1e-9,
                       "relTol": 0.0},
            '"(U|e)"': {**fine, "relTol": 0.01},
            '"(U|e)Final"': fine,
        },
        "PIMPLE": {
            "momentumPredictor": True,
            "nOuterCorrectors": controls.outer_correctors,
            "nCorrectors": controls.correctors,
            "nNonOrthogonalCorrectors": 0,
            # The gap's flow reaches the speed of sound: the transonic pressure equation.
            "transonic": True,
            "correctPhi": False,
        },
    }


#: Names of the face zones that carry the motion (made by topoSet, see _write_motion).
PISTON_ZONE, FIXED_ZONE = "pistonZone", "fixedZone"


def _dynamic_mesh_dict() -> dict[str, Any]:
    # displacementInterpolation: each point moves by the linear interpolation, in its y,
    # between the displacements of the face zones below and above it (tables in time);
    # below the lowest zone it interpolates from zero, so the fixed zone at y = ys keeps
    # everything under it (the opening's cells, the gap, the outlet) still, and the block
    # between it and the piston is squeezed uniformly.  No equation is solved.
    return {
        "dynamicFvMesh": "dynamicMotionSolverFvMesh",
        "motionSolver": "displacementInterpolation",
        "solver": "displacementInterpolation",
        "displacementInterpolationCoeffs": {
            "interpolationTables": [[PISTON_ZONE, "piston"], [FIXED_ZONE, "fixed"]],
        },
    }


def piston_table(case: ChamberCase) -> list[list]:
    """The piston's displacement against time: [[t, [0, d, 0]], ...] (d <= 0)."""
    c = case.compression
    d = case.domain()
    t = c.time_s(c.angle_rad)
    disp = (np.asarray(c.volume_m3) - c.volume_m3[0]) / (c.seal_length_m * d.width_m)
    return [[float(ti), [0.0, float(di), 0.0]] for ti, di in zip(t, disp, strict=True)]


def _write_table(path: Path, rows: list[list]) -> None:
    from foamlib import FoamFile

    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    with FoamFile(path) as f:
        f["FoamFile"] = {"version": 2.0, "format": "ascii", "class": "scalarVectorTable",
                         "location": '"constant/tables"', "object": path.name}
        f[None] = rows


def _write_motion(case_dir: Path, case: ChamberCase, fixed_height: float) -> None:
    """Motion tables, and the two face zones (topoSet): the piston patch and the faces on
    the line y = fixed_height between the fixed and the moving part of the chamber."""
    constant = case_dir / "constant"
    foam.write_dict(constant / "dynamicMeshDict", _dynamic_mesh_dict())
    table = piston_table(case)
    _write_table(constant / "tables" / "piston", table)
    _write_table(constant / "tables" / "fixed", [[row[0], [0.0, 0.0, 0.0]] for row in table])
    d = case.domain()
    eps = 1e-6 * d.height_m  # far below any cell, far above round-off
    big = 10.0 * (d.width_m + d.height_m + d.depth_m)
    foam.write_dict(case_dir / "system" / "topoSetDict", {"actions": [
        {"name": "pistonFaces", "type": "faceSet", "action": "new", "source": "patchToFace",
         "sourceInfo": {"patch": "piston"}},
        {"name": PISTON_ZONE, "type": "faceZoneSet", "action": "new",
         "source": "setToFaceZone", "sourceInfo": {"faceSet": "pistonFaces"}},
        {"name": "fixedFaces", "type": "faceSet", "action": "new", "source": "boxToFace",
         "sourceInfo": {"box": (np.array([-big, fixed_height - eps, -big]),
                                np.array([big, fixed_height + eps, big]))}},
        {"name": FIXED_ZONE, "type": "faceZoneSet", "action": "new",
         "source": "setToFaceZone", "sourceInfo": {"faceSet": "fixedFaces"}},
    ]})
    foam.run(case_dir, "topoSet")
    counts = _face_zone_sizes(case_dir)
    nx = foam.patch_face_counts(case_dir)["piston"]
    if counts.get(PISTON_ZONE) != nx or counts.get(FIXED_ZONE) != nx:
        raise foam.MeshCheckError(
            f"motion face zones in {case_dir} have {counts} faces; both should have the "
            f"piston's {nx}")


def _face_zone_sizes(case_dir: Path) -> dict[str, int]:
    from foamlib import FoamFile

    zones = FoamFile(case_dir / "constant" / "polyMesh" / "faceZones")[None]
    out = {}
    for name, entry in zones:
        labels = entry["faceLabels"]
        if isinstance(labels, tuple) and labels and isinstance(labels[0], str):
            labels = labels[1]  # ("List<label>", [...]) as foamlib reads a typed list
        out[name] = len(labels)
    return out


def _write_fields(case_dir: Path, case: ChamberCase) -> None:
    from foamlib import FoamFieldFile

    c = case.compression
    zero = case_dir / "0"
    walls = [name for name, kind in patch_types(case.with_gap).items() if kind == "wall"]
    empty = {"frontAndBack": {"type": "empty"}}

    def boundary(wall: dict, outlet: dict) -> dict:
        out = {name: wall for name in walls}
        if case.with_gap:
            out["outlet"] = outlet
        return {**out, **empty}

    foam.write_field(zero / "p", (1, -1, -2), c.p_suction_Pa, boundary(
        {"type": "zeroGradient"}, {"type": "fixedValue", "value": c.p_suction_Pa}))
    foam.write_field(zero / "T", (0, 0, 0, 1), c.T_suction_K, boundary(
        {"type": "zeroGradient"},
        {"type": "inletOutlet", "inletValue": c.T_suction_K, "value": c.T_suction_K}))
    zero_u = np.zeros(3)
    foam.write_field(zero / "U", (0, 1, -1), zero_u, vector=True, boundary=boundary(
        {"type": "movingWallVelocity", "value": zero_u},
        {"type": "inletOutlet", "inletValue": zero_u, "value": zero_u}))

    # Read by the motion solver but not used by displacementInterpolation (the tables are).
    fixed = {"type": "fixedValue", "value": np.zeros(3)}
    disp = {name: fixed for name in walls}
    if case.with_gap:
        disp["outlet"] = fixed
    disp.update(empty)
    path = zero / "pointDisplacement"
    path.unlink(missing_ok=True)
    with FoamFieldFile(path) as f:
        f["FoamFile"] = {"version": 2.0, "format": "ascii", "class": "pointVectorField",
                         "location": '"0"', "object": "pointDisplacement"}
        f["dimensions"] = FoamFieldFile.DimensionSet(0, 1, 0, 0, 0, 0, 0)
        f["internalField"] = np.zeros(3)
        f["boundaryField"] = disp


def write_case(case: ChamberCase, case_dir: Path) -> tuple[foam.MeshQuality, int]:
    """Write the full OpenFOAM case into ``case_dir`` (mesh included); return checkMesh's
    verdict and the number of gap cells."""
    case_dir = Path(case_dir)
    system, constant = case_dir / "system", case_dir / "constant"
    foam.write_dict(system / "controlDict", _control_dict(case))
    foam.write_dict(system / "fvSchemes", _fv_schemes())
    foam.write_dict(system / "fvSolution", _fv_solution(case.controls,
                                                        case.compression.p_suction_Pa))
    mesh, quality = build_foam_mesh(case_dir, case.domain(), case.mesh)
    _write_motion(case_dir, case, mesh.fixed_height_m)
    foam.write_dict(constant / "thermophysicalProperties",
                    thermophysical_properties(case.compression.gas))
    foam.write_dict(constant / "turbulenceProperties", {"simulationType": "laminar"})
    _write_fields(case_dir, case)
    (case_dir / "case.json").write_text(json.dumps(case.description(), indent=1) + "\n")
    return quality, mesh.cells_gap


# --- running and judging ------------------------------------------------------------------


@dataclass(frozen=True)
class ChamberResult:
    """What a chamber run produced.  Use only results with :attr:`ok`."""

    status: str
    """'completed', 'inconsistent' (a mass or volume check failed), 'incomplete' (stopped
    before the end), 'diverged' or 'crashed'."""
    message: str
    end_angle_deg: float
    """Rotor angle the run reached (since the chamber's birth)."""
    samples: int
    mass_error: float
    """max |m(t) + mass out until t - m(0)| / m(0) over the run."""
    volume_error: float
    """max |V_zone(t) / V_prescribed(t) - 1| of the chamber zone over the run."""
    final_pressure_Pa: float
    run_time_s: float
    time_steps: int
    cells: int
    cells_gap: int
    mesh_refinement: float
    max_aspect_ratio: float = math.nan
    max_non_orthogonality_deg: float = math.nan
    log_tail: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "completed"

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2, allow_nan=True) + "\n"

    @classmethod
    def from_json(cls, text: str) -> ChamberResult:
        return cls(**json.loads(text))


def load_result(case_dir: Path) -> ChamberResult | None:
    path = Path(case_dir) / "result.json"
    return ChamberResult.from_json(path.read_text()) if path.is_file() else None


class _Progress:
    def __init__(self, duration: float, progress: Callable[[float], None] | None) -> None:
        self.duration, self.progress, self.steps = duration, progress, 0

    def __call__(self, t: float) -> None:
        self.steps += 1
        if self.progress is not None:
            self.progress(min(1.0, t / self.duration))


def run_chamber_case(case: ChamberCase, case_dir: Path, *,
                     progress: Callable[[float], None] | None = None,
                     reuse: bool = True) -> ChamberResult:
    """Build and run one chamber case in ``case_dir``; return (and store) its result.

    Built in ``<case_dir>.tmp`` and renamed to ``case_dir`` once judged, with
    ``result.json``, ``case.json`` and ``case.key``; with ``reuse`` a folder whose key
    matches is not run again (failed results are kept, never retried silently).
    ``progress`` receives the fraction of the compression done.  Mesh problems raise
    (CaseError, MeshCheckError); solver failures give a failed result.
    """
    case_dir = Path(case_dir)
    foam.check_case_path(case_dir)
    key = case.key()
    if reuse and (case_dir / "case.key").is_file() and (case_dir / "result.json").is_file():
        if (case_dir / "case.key").read_text().strip() == key:
            log.info("chamber case %s: reusing the stored result", case_dir.name)
            return ChamberResult.from_json((case_dir / "result.json").read_text())
    tmp = case_dir.with_name(case_dir.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    quality, cells_gap = write_case(case, tmp)
    start = time.monotonic()
    failure = ""
    counter = _Progress(case.compression.duration_s, progress)
    try:
        foam.run(tmp, SOLVER, timeout_s=case.controls.timeout_s, on_time=counter)
    except ExternalRunError as exc:
        failure = str(exc)
    elapsed = time.monotonic() - start
    steps = _count_steps(tmp / f"log.{SOLVER}")
    result = judge(tmp, case, quality, cells_gap, elapsed, steps, failure)
    (tmp / "result.json").write_text(result.to_json())
    (tmp / "case.key").write_text(key + "\n")
    if case_dir.exists():
        shutil.rmtree(case_dir)
    tmp.rename(case_dir)
    log.info("chamber case %s: %s at %.1f deg, p_end %.4g Pa, mass error %.1e, volume error "
             "%.1e, %d steps, %.1f s", case_dir.name, result.status, result.end_angle_deg,
             result.final_pressure_Pa, result.mass_error, result.volume_error,
             result.time_steps, result.run_time_s)
    return result


def _count_steps(log_path: Path) -> int:
    if not log_path.is_file():
        return 0
    with log_path.open("rb") as fh:
        return sum(1 for line in fh if line.startswith(b"Time = "))


def judge(case_dir: Path, case: ChamberCase, quality: foam.MeshQuality, cells_gap: int,
          elapsed: float, steps: int, failure: str) -> ChamberResult:
    """The result of a finished (or failed) run, from its tables."""
    log_path = case_dir / f"log.{SOLVER}"
    c, ctl = case.compression, case.controls
    status, message = ("crashed", failure) if failure else ("", "")
    end_deg = mass_err = vol_err = p_end = math.nan
    samples = 0
    try:
        hist = cc.read_history(case_dir, c.volume_curve())
        samples = len(hist.time_s)
        end_deg = float(np.degrees(hist.angle_rad[-1]))
        p_end = float(hist.p_Pa[-1])
        mass_err = hist.mass_error()
        vol_err = hist.volume_error()
        if not failure:
            status, message = _assess(hist, c, ctl, mass_err, vol_err)
    except ExternalRunError as exc:
        if not failure:
            status, message = "crashed", str(exc)
    if status == "crashed" and looks_diverged(foam.log_tail(log_path, 60)):
        status = "diverged"
    return ChamberResult(
        status=status,
        message=message.splitlines()[0] if message else "",
        end_angle_deg=end_deg,
        samples=samples,
        mass_error=mass_err,
        volume_error=vol_err,
        final_pressure_Pa=p_end,
        run_time_s=elapsed,
        time_steps=steps,
        cells=quality.cells,
        cells_gap=cells_gap,
        mesh_refinement=case.mesh.refinement,
        max_aspect_ratio=quality.max_aspect_ratio,
        max_non_orthogonality_deg=quality.max_non_orthogonality_deg,
        log_tail="" if status == "completed" else foam.log_tail(log_path, RESULT_LOG_LINES),
    )


def _assess(hist: cc.ChamberHistory, c: Compression, ctl: TransientControls,
            mass_err: float, vol_err: float) -> tuple[str, str]:
    if not (np.all(np.isfinite(hist.p_Pa)) and np.all(hist.p_Pa > 0)):
        return "diverged", "non-finite or negative chamber pressure"
    end = c.angle_rad[-1]
    if hist.angle_rad[-1] < end - 0.5 * math.radians(ctl.sample_deg):
        return "incomplete", (f"stopped at {math.degrees(hist.angle_rad[-1]):.2f} deg, before "
                              f"{math.degrees(end):.2f} deg")
    if not mass_err <= ctl.mass_tol:
        return "inconsistent", f"mass not conserved: error {mass_err:.2e} > {ctl.mass_tol:g}"
    if not vol_err <= ctl.volume_tol:
        return "inconsistent", (f"chamber volume off the prescribed curve by {vol_err:.2e} > "
                                f"{ctl.volume_tol:g}")
    return "completed", ""


# --- the workflow stage -------------------------------------------------------------------

#: The case file's section for this stage, and its keys.
SECTION = "cfd_chamber"
CHAMBER_KEYS = ("seal_length_mm", "tip_radius_mm", "refinement", "end_deg", "sample_deg",
                "max_courant", "runs_dir", "flow_coefficient")


@dataclass(frozen=True)
class ChamberSettings:
    """The ``[cfd_chamber]`` section: what the chamber run may change from its defaults."""

    seal_length_m: float | None = None
    """Slab depth; None: the mean sealing-line length toward suction (see the module)."""
    tip_radius_m: float = TIP_RADIUS_M
    refinement: float = 1.0
    end_deg: float | None = None
    """Stop this many degrees after suction closing (None: at discharge opening)."""
    sample_deg: float = TransientControls.sample_deg
    max_courant: float = TransientControls.max_courant
    runs_dir: str | None = None
    """Where runs live (relative to the case file); None: inside the stage's folder."""
    flow_coefficient: str | None = None
    """A fitted correlation (flow_coefficient.json) for the "cfd-calibrated" model; None:
    the cfd.leakage stage's when it ran."""

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> ChamberSettings:
        if not isinstance(d, dict):
            raise CaseError(f"[{SECTION}] of {where} must be a table")
        unknown = sorted(set(d) - set(CHAMBER_KEYS))
        if unknown:
            raise CaseError(f"unknown key(s) {', '.join(unknown)} in [{SECTION}] of {where}")

        def number(key: str, default):
            if key not in d:
                return default
            v = d[key]
            if isinstance(v, bool) or not isinstance(v, int | float) or not v > 0:
                raise CaseError(f"key '{key}' in [{SECTION}] of {where} must be a positive "
                                f"number, got {v!r}")
            return float(v)

        def text(key: str) -> str | None:
            v = d.get(key)
            if v is not None and not isinstance(v, str):
                raise CaseError(f"key '{key}' in [{SECTION}] of {where} must be a string")
            return v

        seal = number("seal_length_mm", None)
        return cls(
            seal_length_m=None if seal is None else 1e-3 * seal,
            tip_radius_m=1e-3 * number("tip_radius_mm", 1e3 * TIP_RADIUS_M),
            refinement=number("refinement", 1.0),
            end_deg=number("end_deg", None),
            sample_deg=number("sample_deg", TransientControls.sample_deg),
            max_courant=number("max_courant", TransientControls.max_courant),
            runs_dir=text("runs_dir"),
            flow_coefficient=text("flow_coefficient"),
        )


def case_from_settings(table, operating, leakage, settings: ChamberSettings) -> ChamberCase:
    """The chamber case a case file asks for."""
    comp = compression_from_table(table, operating, leakage,
                                  seal_length_m=settings.seal_length_m,
                                  tip_radius_m=settings.tip_radius_m)
    if settings.end_deg is not None:
        comp = comp.limited_to(settings.end_deg)
    controls = TransientControls(max_courant=settings.max_courant,
                                 sample_deg=settings.sample_deg)
    return ChamberCase(comp, controls=controls).refined(settings.refinement)


def _resolve(path: str, case_path: Path) -> Path:
    p = Path(path)
    return p if p.is_absolute() else Path(case_path).parent / p


def _load_fit(ctx, settings: ChamberSettings):
    """The correlation for "cfd-calibrated": the section's file, else the cfd.leakage
    stage's; None (with a warning) when there is none or it does not load."""
    from rotorflow.quasi1d.calibrated import FlowCoefficientFit

    if settings.flow_coefficient is not None:
        path = _resolve(settings.flow_coefficient, ctx.case_path)
    elif "cfd.leakage" in ctx.inputs:
        path = ctx.inputs["cfd.leakage"] / "flow_coefficient.json"
    else:
        log.warning("no fitted flow coefficient: the chamber is compared without the "
                    "cfd-calibrated model")
        return None
    try:
        return FlowCoefficientFit.load(path)
    except (OSError, ValueError, KeyError) as exc:
        log.warning("cannot load the fitted flow coefficient %s (%s): compared without the "
                    "cfd-calibrated model", path, exc)
        return None


def run_stage(ctx) -> dict:
    """Workflow stage ``cfd.chamber``: the chamber run and its comparison.

    Reads ``[operating]``, ``[leakage]`` and ``[cfd_chamber]`` (see
    :class:`ChamberSettings`), and the chamber table from the ``table`` stage when it is
    upstream (else computes it).  Writes into ``ctx.out``: ``chamber_result.json`` (the
    run's status, checks and, for a failed run, its log tail) and, for a completed run,
    ``chamber_comparison.json``, ``chamber_pressure.csv`` and ``chamber_pressure.png``
    (:func:`rotorflow.postprocess.chamber_compare.write_comparison`); always
    ``chamber_figures.json``, the flat scalars it returns (status, run time, max and RMS
    difference per model, the closest model).  A failed run is recorded, never compared.
    """
    from rotorflow.quasi1d import Leakage, Operating

    raw, where = ctx.raw, str(ctx.case_path)
    settings = ChamberSettings.from_section(raw.get(SECTION, {}), where)
    if "operating" not in raw:
        raise CaseError(f"the chamber CFD case needs an [operating] section in {where}")
    operating = Operating.from_section(raw["operating"], where)
    leakage = Leakage.from_section(raw.get("leakage", {}), where)
    if "table" in ctx.inputs:
        from rotorflow.geometry import table as chamber_table_io

        tab = chamber_table_io.read(ctx.input("table") / "chamber_table.csv")
    else:
        from rotorflow.geometry.summary import chamber_table

        tab = chamber_table(ctx.case)
    case = case_from_settings(tab, operating, leakage, settings)
    runs = (_resolve(settings.runs_dir, ctx.case_path) if settings.runs_dir
            else ctx.out / "runs")
    run_dir = runs / f"chamber-r{settings.refinement:g}"
    result = run_chamber_case(case, run_dir)
    _write_json(ctx.out / "chamber_result.json", asdict(result))
    figures: dict[str, Any] = {"status": result.status, "run_time_s": result.run_time_s,
                               "cells": result.cells}
    if not result.ok:
        log.warning("chamber run %s %s: %s", run_dir, result.status, result.message)
        figures["message"] = result.message
        _write_json(ctx.out / "chamber_figures.json", figures)
        return figures
    history, comparison = cc.compare_run(run_dir, leakage, _load_fit(ctx, settings))
    checks = {"mass_error": result.mass_error, "volume_error": result.volume_error,
              "run_time_s": result.run_time_s, "time_steps": result.time_steps,
              "cells": result.cells}
    summary = cc.write_comparison(comparison, history, ctx.out, checks)
    for d in summary["models"]:
        figures[f"rms_Pa[{d['model']}]"] = d["rms_Pa"]
        figures[f"max_abs_Pa[{d['model']}]"] = d["max_abs_Pa"]
    figures["closest_model"] = summary["closest_model"]
    _write_json(ctx.out / "chamber_figures.json", figures)
    return figures


def _write_json(path: Path, data: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, allow_nan=True) + "\n")
    tmp.replace(path)
