"""What the chamber case writes into its folder: dictionaries, motion, fields, the mesh.

:func:`write_files` writes everything Python writes (``system``, ``constant``, ``0``,
``case.json`` and gmsh's ``chamber.msh``); the OpenFOAM commands that follow are the
chamber case's plan (:func:`rotorflow.cases.chamber_case.plan`), among them ``topoSet``,
which makes the two face zones the motion solver moves (:data:`TOPO_SET`, checked by
:func:`check_motion_zones`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from .chamber_mesh import ChamberMesh, patch_types, write_msh
from .chamber_spec import ChamberCase, TransientControls
from .foam_dicts import (
    FRONT_AND_BACK,
    control_dict,
    field_value,
    fv_schemes,
    inlet_outlet,
    thermophysical_properties,
    turbulence_properties,
)
from .foam_files import write_dict, write_field, write_table
from .foam_mesh import MeshCheckError, face_zone_sizes, patch_face_counts

SOLVER = "rhoPimpleFoam"

#: The plan's step that makes the motion's face zones (system/topoSetDict).
TOPO_SET = ("topoSet",)

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
    return {
        # adjustableRunTime: the time step is cut to hit each sample
        name: field_value(kind, region, operation, fields, write_control="adjustableRunTime",
                          write_interval=interval, name=region_name)
        for name, (kind, region, region_name, operation, fields) in _FUNCTION_OBJECTS.items()
        if region_name != "outlet" or case.with_gap
    }


def _control_dict(case: ChamberCase) -> dict[str, Any]:
    c, ctl = case.compression, case.controls
    return control_dict(
        SOLVER, start_from="startTime", end_time=c.duration_s, delta_t=ctl.first_dt_s,
        time_step={
            "adjustTimeStep": True,
            "maxCo": ctl.max_courant,
            # Refined with the mesh: at a fixed time step the acoustic Courant number of
            # the smallest cells (near the opening and in the gap) grows with refinement,
            # and at ~15 the split pressure-velocity coupling lets noise grow in them.
            "maxDeltaT": ctl.max_dt_s / case.mesh.refinement,
        },
        write_control="adjustableRunTime",
        write_interval=c.duration_s,  # only the final fields; the tables are the output
        purge_write=0, time_precision=12, run_time_modifiable=False,
        functions=_function_objects(case),
    )


def _fv_schemes() -> dict[str, Any]:
    lin_up = ("Gauss", "linearUpwind", "limited")
    return fv_schemes("Euler", {
        "div(phi,U)": lin_up,
        "div(phi,e)": lin_up,
        "div(phi,K)": ("Gauss", "linear"),
        "div(phiv,p)": ("Gauss", "linear"),
        "div(meshPhi,p)": ("Gauss", "linear"),
        "div(phid,p)": ("Gauss", "upwind"),
    })


def _fv_solution(controls: TransientControls) -> dict[str, Any]:
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


# --- motion -------------------------------------------------------------------------------

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


def _write_motion(case_dir: Path, case: ChamberCase, fixed_height: float) -> None:
    """Motion tables, and the topoSet dictionary of the two face zones: the piston patch
    and the faces on the line y = fixed_height between the fixed and the moving part of
    the chamber."""
    constant = case_dir / "constant"
    write_dict(constant / "dynamicMeshDict", _dynamic_mesh_dict())
    table = piston_table(case)
    write_table(constant / "tables" / "piston", table)
    write_table(constant / "tables" / "fixed", [[row[0], [0.0, 0.0, 0.0]] for row in table])
    d = case.domain()
    eps = 1e-6 * d.height_m  # far below any cell, far above round-off
    big = 10.0 * (d.width_m + d.height_m + d.depth_m)
    write_dict(case_dir / "system" / "topoSetDict", {"actions": [
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


def check_motion_zones(case_dir: Path, _log: Path | None = None) -> dict[str, int]:
    """After topoSet: both motion zones must hold as many faces as the piston patch."""
    counts = face_zone_sizes(case_dir)
    nx = patch_face_counts(case_dir)["piston"]
    if counts.get(PISTON_ZONE) != nx or counts.get(FIXED_ZONE) != nx:
        raise MeshCheckError(
            f"motion face zones in {case_dir} have {counts} faces; both should have the "
            f"piston's {nx}")
    return counts


# --- fields and the whole folder ----------------------------------------------------------


def _write_fields(case_dir: Path, case: ChamberCase) -> None:
    c = case.compression
    zero = case_dir / "0"
    walls = [name for name, kind in patch_types(case.with_gap).items() if kind == "wall"]

    def boundary(wall: dict, outlet: dict) -> dict:
        out = {name: wall for name in walls}
        if case.with_gap:
            out["outlet"] = outlet
        return {**out, **FRONT_AND_BACK}

    write_field(zero / "p", (1, -1, -2), c.p_suction_Pa, boundary(
        {"type": "zeroGradient"}, {"type": "fixedValue", "value": c.p_suction_Pa}))
    write_field(zero / "T", (0, 0, 0, 1), c.T_suction_K, boundary(
        {"type": "zeroGradient"}, inlet_outlet(c.T_suction_K)))
    zero_u = np.zeros(3)
    write_field(zero / "U", (0, 1, -1), zero_u, vector=True, boundary=boundary(
        {"type": "movingWallVelocity", "value": zero_u}, inlet_outlet(zero_u)))
    # Read by the motion solver but not used by displacementInterpolation (the tables are).
    fixed = {"type": "fixedValue", "value": np.zeros(3)}
    write_field(zero / "pointDisplacement", (0, 1), np.zeros(3), boundary(fixed, fixed),
                vector=True, point=True)


def write_files(case: ChamberCase, case_dir: Path) -> ChamberMesh:
    """Write what Python writes into ``case_dir``: the dictionaries, the motion, the
    initial fields, ``case.json`` (:meth:`ChamberCase.description`) and gmsh's
    ``chamber.msh``; return the gmsh mesh."""
    case_dir = Path(case_dir)
    system, constant = case_dir / "system", case_dir / "constant"
    write_dict(system / "controlDict", _control_dict(case))
    write_dict(system / "fvSchemes", _fv_schemes())
    write_dict(system / "fvSolution", _fv_solution(case.controls))
    mesh = write_msh(case.domain(), case.mesh, case_dir / "chamber.msh")
    _write_motion(case_dir, case, mesh.fixed_height_m)
    write_dict(constant / "thermophysicalProperties",
               thermophysical_properties(case.compression.gas))
    write_dict(constant / "turbulenceProperties", turbulence_properties("laminar"))
    _write_fields(case_dir, case)
    (case_dir / "case.json").write_text(json.dumps(case.description(), indent=1) + "\n")
    return mesh
