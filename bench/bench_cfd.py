"""Run time against error of the CFD leakage mass flow as the gap mesh is refined.

Each case runs on the meshes refinement 0.5, 1 (default), 2 and 4; the reference is the
Richardson extrapolation of the three finest, computed in the same run.  Target: within
2 % of it in under 60 s per case on 2 cores.  The run time is the wall time of a whole
case: gmsh, gmshToFoam, checkMesh, set-up and rhoSimpleFoam.  Needs OpenFOAM; without it
the benchmark records nothing and says why.

The cases: the analytic parallel channel, rotor-tip gaps (laminar and turbulent), and a
gap at a sealing line of real rotors (a section point of the leakage matrix in
examples/cfd_leakage.toml, on the matrix's default section mesh, walls at the rotor surface
speeds).
"""

from __future__ import annotations

import csv
import logging
import math
import tempfile
import time
from pathlib import Path

from rotorflow.cases import foam, gap_case, gap_mesh, gap_walls
from rotorflow.cases.gap_study import OUTLET_GAP_RATIO, SectionPoint
from rotorflow.cases.leakage_stage import matrix_from_section, rotor_machine
from rotorflow.postprocess.richardson import richardson
from rotorflow.quasi1d.perfect_gas import PerfectGas

from .plots import time_error_plot

log = logging.getLogger(__name__)

REFINEMENTS = (0.5, 1.0, 2.0, 4.0)
TARGET_TIME_S = 60.0
TARGET_ERROR = 0.02

#: The leakage matrix whose section point is benchmarked, and the point: outer-rotor angle
#: 300 deg (next to the inner rotor's sharp edge, the least parabolic throat of the matrix),
#: 10 um, pressure ratio 1.2, walls at the rotor speeds: of the matrix's section points the
#: one where the walls drag most relative to the leak (laminar, Re ~ 40).
SECTION_CASE_FILE = Path(__file__).resolve().parents[1] / "examples" / "cfd_leakage.toml"
SECTION_POINT = {"rotor_angle_deg": 300.0, "gap_um": 10.0, "pressure_ratio": 1.2,
                 "moving_walls": True}


def section_point(path: Path = SECTION_CASE_FILE) -> SectionPoint:
    """The benchmarked section point, cut from the case file's machine as its matrix is."""
    from rotorflow.workflow.case import load_case

    case = load_case(path)
    points = matrix_from_section(case.raw["cfd"], str(path), rotor_machine(case))
    for p in points:
        if isinstance(p, SectionPoint) and all(getattr(p, k) == v
                                               for k, v in SECTION_POINT.items()):
            return p
    raise ValueError(f"{path}: its [cfd] matrix has no section point {SECTION_POINT}")


def cases() -> dict[str, gap_case.GapCase]:
    """Representative gaps: the analytic channel, a laminar and a turbulent rotor tip (cut
    as the leakage matrix cuts them), and a sealing-line section of the example machine
    with moving walls."""
    tip = gap_walls.rotor_tip_gap(50e-6, 0.02, outlet_gap_ratio=OUTLET_GAP_RATIO)
    tip_spec = gap_mesh.GapMeshSpec(cells_across=16, cells_along=40, along_grading=20)
    section = section_point()
    return {
        "channel-10um-PR1.005": gap_case.GapCase(
            gap_walls.parallel_channel(10e-6, 1e-3),
            gap_case.GapFlow(1.005e5, 300.0, 1e5, gas=PerfectGas(transport="const")),
            gap_mesh.GapMeshSpec(cells_across=16, cells_along=20)),
        "tip-50um-PR1.5-laminar": gap_case.GapCase(
            tip, gap_case.GapFlow(1.5e5, 300.0, 1e5), tip_spec),
        "tip-50um-PR2.5-kOmegaSST": gap_case.GapCase(
            tip, gap_case.GapFlow(2.5e5, 300.0, 1e5), tip_spec),
        (f"section-{section.rotor_angle_deg:g}deg-{section.gap_um:g}um-"
         f"PR{section.pressure_ratio:g}-{section.outer_rpm:.0f}rpm"): section.case(),
    }


def run(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    if not foam.is_available():
        log.warning("bench_cfd: OpenFOAM not installed (make openfoam); nothing measured")
        return []
    rows: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, case in cases().items():
            runs = []
            for r in REFINEMENTS:
                t0 = time.perf_counter()
                res = gap_case.run_gap_case(case.refined(r), Path(tmp) / f"{name}-{r}",
                                            reuse=False)
                runs.append((r, res, time.perf_counter() - t0))
            ok = all(res.ok for _, res, _ in runs)
            rich = richardson([res.mass_flow_kg_s_m for _, res, _ in runs[-3:]], 2.0) if ok \
                else None
            ref = rich.extrapolated if rich else math.nan
            met = [(r, wall) for r, res, wall in runs[:-1]
                   if res.ok and abs(res.mass_flow_kg_s_m / ref - 1) <= TARGET_ERROR]
            log.info("bench_cfd %s: %s", name,
                     f"within {TARGET_ERROR:.0%} from refinement {met[0][0]:g} in "
                     f"{met[0][1]:.1f} s" if met else f"no mesh within {TARGET_ERROR:.0%}")
            for r, res, wall in runs:
                rows.append({
                    "case": name,
                    "refinement": r,
                    "cells": res.cells,
                    "status": res.status,
                    "iterations": res.iterations,
                    "time_s": wall,
                    "solver_time_s": res.run_time_s,
                    "mass_flow_kg_s_m": res.mass_flow_kg_s_m,
                    "error": abs(res.mass_flow_kg_s_m / ref - 1),
                    "reference_kind": rich.kind if rich else "failed",
                    "observed_order": rich.order if rich else math.nan,
                })
    with (results_dir / "cfd.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    _plot(rows, results_dir / "cfd.png")
    return rows


def _plot(rows: list[dict], path: Path) -> None:
    series = []
    for name in dict.fromkeys(r["case"] for r in rows):
        sel = [r for r in rows if r["case"] == name and r["refinement"] != REFINEMENTS[-1]]
        series.append((name, [r["time_s"] for r in sel], [r["error"] for r in sel], "o-"))
    time_error_plot(path, series, (TARGET_TIME_S, TARGET_ERROR),
                    xlabel="wall time of one case on 2 cores [s]",
                    ylabel="|mass flow / Richardson value - 1|",
                    title="CFD leakage mass flow: meshes 0.5, 1, 2 x default", floor=1e-6)
