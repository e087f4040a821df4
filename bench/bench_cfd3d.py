"""Run time against error of the whole machine's frozen-angle 3D CFD as the grid refines
(issue 16), and the cost of one angle on 1 and 2 processes.

The case is examples/cfd_machine.toml at one of its angles: its three grids (768 x 4 x 16
layers refined by 1.5 in every direction to 1728 x 9 x 36) on 2 processes, each run
stopped by the convergence monitor of cases/machine_run.py; the reference is their
Richardson extrapolation (observed order), computed here.  Errors: the largest over the
closed chambers' volume-averaged pressures, and the total leakage.  The coarse and
medium grids run again on 1 process (the fine one would take about an hour there: its
cost is the medium's per cell and iteration, which the rows give).  One more row per
process count is the quick estimate: the coarse and medium runs' two-grid Richardson
value at the formal order 2, at the cost of both runs.  Target (issue 16): within 2 % of
the extrapolated total leakage in under 10 minutes per angle on 2 cores.
Needs OpenFOAM; without it nothing is measured and the log says why.
"""

from __future__ import annotations

import csv
import logging
import math
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from rotorflow.cases import foam
from rotorflow.cases.machine_run import Controls, run_machine_case
from rotorflow.cases.machine_setup import case_table, frozen_machine
from rotorflow.cases.machine_study import LEVELS, StudySettings
from rotorflow.cases.parallel import Decomposition
from rotorflow.postprocess.richardson import richardson, two_grid

from .plots import time_error_plot

log = logging.getLogger(__name__)

CASE_FILE = Path(__file__).resolve().parents[1] / "examples" / "cfd_machine.toml"
ANGLE_DEG = 15.0
TARGET_TIME_S = 600.0
TARGET_ERROR = 0.02
#: Grids also run on one process (the fine one would take an hour).
SERIAL_LEVELS = ("coarse", "medium")


def measure(level: str, processes: int, root: Path, *, reuse: bool = False) -> dict:
    """One run of the bench's case on grid ``level`` with ``processes``: its row."""
    from rotorflow.workflow.case import load_case

    case = load_case(CASE_FILE)
    settings = StudySettings.from_section(case.raw["cfd_machine"], str(CASE_FILE))
    grid = settings.grids()[LEVELS.index(level)]
    phi = math.radians(ANGLE_DEG)
    m = replace(frozen_machine(case, case_table(case), phi,
                               float(case.raw["leakage"]["gap_um"]) * 1e-6, grid,
                               spec=settings.spec()), moving_walls=settings.moving_walls)
    t0 = time.perf_counter()
    run = run_machine_case(m, root / f"{grid.label}-p{processes}", Controls(),
                           Decomposition(processes), reuse=reuse)
    wall = time.perf_counter() - t0
    return {"grid": level, "label": grid.label, "processes": processes, "cells": run.cells,
            "status": run.status, "iterations": run.iterations, "time_s": wall,
            "solver_time_s": run.run_time_s, "cpu_time_s": run.cpu_time_s,
            "seconds_per_iteration": run.run_time_s / max(run.iterations, 1),
            "imbalance": run.imbalance, "leakage_kg_s": run.leakage_kg_s,
            "pressures": run.pressures()}


def quick_estimate(rows: list[dict], processes: int) -> dict:
    """The row of the coarse and medium runs on ``processes`` taken together: their
    two-grid extrapolation (order 2) at the sum of their times."""
    pair = [next(r for r in rows if r["grid"] == lvl and r["processes"] == processes)
            for lvl in LEVELS[:2]]
    ratio = StudySettings.ratio
    return {"grid": "coarse+medium", "label": "two-grid", "processes": processes,
            "cells": sum(r["cells"] for r in pair), "status": "converged",
            "iterations": sum(r["iterations"] for r in pair),
            **{k: sum(r[k] for r in pair) for k in ("time_s", "solver_time_s",
                                                      "cpu_time_s")},
            "seconds_per_iteration": math.nan,
            "imbalance": max(r["imbalance"] for r in pair),
            "leakage_kg_s": two_grid([r["leakage_kg_s"] for r in pair], ratio).extrapolated,
            "pressures": {s: two_grid([r["pressures"][s] for r in pair], ratio).extrapolated
                          for s in pair[0]["pressures"]}}


def errors(rows: list[dict], closed: list[int]) -> None:
    """Each row's errors against the Richardson extrapolation of the 2-process grids."""
    ref_rows = [next(r for r in rows if r["grid"] == lvl and r["processes"] == 2)
                for lvl in LEVELS]
    ratio = StudySettings.ratio
    leak = richardson([r["leakage_kg_s"] for r in ref_rows], ratio)
    press = {s: richardson([r["pressures"][s] for r in ref_rows], ratio) for s in closed}
    for r in rows:
        r["leakage_error"] = abs(r["leakage_kg_s"] / leak.extrapolated - 1.0)
        r["pressure_error"] = max(abs(r["pressures"][s] / press[s].extrapolated - 1.0)
                                  for s in closed)
        r["leakage_order"] = leak.order
        r["leakage_convergence"] = leak.kind


def run(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    if not foam.is_available():
        log.warning("bench_cfd3d: OpenFOAM not installed (make openfoam); nothing measured")
        return []
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for level in LEVELS:
            rows.append(measure(level, 2, Path(tmp)))
        for level in SERIAL_LEVELS:
            rows.append(measure(level, 1, Path(tmp)))
    if not all(r["status"] == "converged" for r in rows):
        log.warning("bench_cfd3d: failed runs %s", [(r["label"], r["processes"], r["status"])
                                                   for r in rows if r["status"] != "converged"])
        return rows
    from rotorflow.cases.machine_setup import frozen_models, slot_of, table_origin
    from rotorflow.workflow.case import load_case

    case = load_case(CASE_FILE)
    phi = math.radians(ANGLE_DEG)
    state = frozen_models(case, case_table(case), phi, ["nozzle"])["nozzle"]
    closed = [s for s, c in zip(slot_of(state, phi, float(case.pair.period),
                                        table_origin(case)), state.closed, strict=True) if c]
    rows += [quick_estimate(rows, p) for p in (2, 1)]
    errors(rows, closed)
    angle = {p: sum(r["time_s"] for r in rows if r["processes"] == p
                    and r["grid"] in LEVELS) for p in (1, 2)}
    met = [r for r in rows if r["processes"] == 2 and r["leakage_error"] <= TARGET_ERROR]
    log.info("bench_cfd3d: one angle, three grids on 2 processes: %.0f s; %s", angle[2],
             f"{met[0]['label']} within {TARGET_ERROR:.0%} of the extrapolated leakage in "
             f"{met[0]['time_s']:.0f} s" if met else f"no grid within {TARGET_ERROR:.0%}")
    keys = [k for k in rows[0] if k != "pressures"]
    with (results_dir / "cfd3d.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    _plot(rows, results_dir / "cfd3d.png")
    return [{k: r[k] for k in keys} for r in rows]


def _plot(rows: list[dict], path: Path) -> None:
    series = []
    for procs, marker in ((2, "o-"), (1, "s--")):
        sel = [r for r in rows if r["processes"] == procs and r["grid"] in LEVELS[:2]]
        quick = [r for r in rows if r["processes"] == procs and r["grid"] not in LEVELS]
        for key, label in (("leakage_error", "total leakage"),
                           ("pressure_error", "closed-chamber pressure")):
            procs_label = f"{procs} process{'es' if procs > 1 else ''}"
            series.append((f"{label}, {procs_label}", [r["time_s"] for r in sel],
                           [r[key] for r in sel], marker))
            series.append((f"{label}, two-grid estimate, {procs_label}",
                           [r["time_s"] for r in quick], [r[key] for r in quick],
                           marker[0].replace("o", "*").replace("s", "P")))
    time_error_plot(path, series, (TARGET_TIME_S, TARGET_ERROR),
                    xlabel="wall time at one angle [s] (two-grid: both runs)",
                    ylabel="|value / Richardson value - 1|",
                    title="3D machine CFD at a frozen angle: coarse and medium grids",
                    floor=1e-6)
