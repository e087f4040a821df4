"""Cost per revolution against accuracy of the section with its rotors turning (issue 17).

The section of tests/data/cfd/moving (the default pair at 100 um, a slab 10 mm deep,
closed, gas at rest at 1 bar at 13 deg, 2500 rpm) is turned SPAN_DEG on three grids
refined by 2 in both directions (columns x cells across the gap: 256 x 2, 512 x 4,
1024 x 8) with the time step halved with the cell size (the gap's Courant number held),
and on the middle grid with the step halved twice more.  What is compared: each
chamber's pressure change over the span, from the grid's own topology at the last frame
(:func:`.moving_chambers.topology_pressures`); the reference of each study is its
Richardson extrapolation (observed order, :mod:`.postprocess.richardson`), and a run's
error is the largest difference over the chambers as a share of the largest change.

The cost per revolution is each run's solver time over the span, scaled to 360 deg, and
the key frames' build time scaled the same way (both on one core: the section is 2D and
small; a cluster would run frames and solver side by side).  Needs OpenFOAM; without it
nothing is measured and the log says why.  ~7 min on one core.

What it measures is the start-up from rest over a few degrees, where the chambers'
pressures change by 2-17 kPa; the recorded lobe-period run (tests/data/cfd/moving) is on
the middle grid at 192 steps per 0.25-deg frame.
"""

from __future__ import annotations

import csv
import logging
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from rotorflow.cases import foam
from rotorflow.cases.moving_case import RunControls, run_moving_section
from rotorflow.cases.moving_chambers import topology_pressures
from rotorflow.cases.moving_section import MovingSection
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.postprocess.richardson import richardson

from .plots import time_error_plot

log = logging.getLogger(__name__)

START_DEG = 13.0
SPAN_DEG = 4.0
FRAMES_PER_DEG = 4  # key frames every 0.25 deg, as the recorded lobe-period run
OMEGA = 2500.0 * 2.0 * math.pi / 60.0  # outer rotor, rad/s
GAP = 100e-6
#: (columns, cells across the gap, steps per key frame): the grid study holds the gap's
#: Courant number (steps double as the cells halve), the time-step study is the middle grid.
GRIDS = ((256, 2, 32), (512, 4, 64), (1024, 8, 128))
STEPS = ((512, 4, 64), (512, 4, 128), (512, 4, 256))
#: Guide lines of the plot (1 % in one CPU hour per revolution): not an issue target.
GUIDE = (1.0, 0.01)


def section(columns: int, across: int) -> MovingSection:
    return MovingSection(examples()["table1"], GAP, OGridSpec(columns=columns,
                                                              cells_across_gap=across),
                         math.radians(START_DEG), math.radians(SPAN_DEG),
                         int(round(SPAN_DEG * FRAMES_PER_DEG)), OMEGA)


def measure(columns: int, across: int, steps: int, root: Path) -> dict:
    """One run: its cost and each chamber's pressure change over the span."""
    s = section(columns, across)
    folder = root / f"c{columns}x{across}-s{steps}"
    t0 = time.perf_counter()
    run = run_moving_section(s, folder, RunControls(steps_per_frame=steps), reuse=False)
    wall = time.perf_counter() - t0
    row = {"columns": columns, "cells_across": across, "steps_per_frame": steps,
           "cells": run.cells, "status": run.status, "time_steps": run.time_steps,
           "solver_s": run.run_time_s, "frames_s": wall - run.run_time_s,
           "max_courant": run.max_courant, "mass_drift": run.mass_drift}
    scale = 360.0 / SPAN_DEG
    row["solver_s_per_rev"] = row["solver_s"] * scale
    row["frames_s_per_rev"] = row["frames_s"] * scale
    row["dp"] = {}
    if run.ok:
        p = topology_pressures(s, folder)["p"]
        row["dp"] = {c: v[-1] - s.p0 for c, v in p.items() if np.isfinite(v[-1])}
    else:
        log.warning("bench_cfd_moving: %s %s\n%s", folder.name, run.message, run.log_tail)
    return row


def study_errors(rows: list[dict], key: str) -> dict:
    """Set row[key]: the largest chamber's difference from the study's extrapolation as a
    share of the largest pressure change.  Returns the observed order per chamber."""
    chambers = sorted(set.intersection(*(set(r["dp"]) for r in rows)), key=int)
    refs, orders = {}, {}
    for c in chambers:
        r = richardson([row["dp"][c] for row in rows], 2.0)
        refs[c], orders[c] = r.extrapolated, r.order
    swing = max(abs(v) for v in refs.values())
    for row in rows:
        row[key] = max(abs(row["dp"][c] - refs[c]) for c in chambers) / swing
    return orders


def run(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    if not foam.is_available():
        log.warning("bench_cfd_moving: OpenFOAM not installed (make openfoam); nothing measured")
        return []
    with tempfile.TemporaryDirectory() as tmp:
        grid = [measure(*g, Path(tmp)) for g in GRIDS]
        steps = [grid[1]] + [measure(*g, Path(tmp)) for g in STEPS[1:]]
    rows = grid + steps[1:]
    if all(r["status"] == "completed" for r in rows):
        for name, study in (("grid", grid), ("time_step", steps)):
            orders = study_errors(study, f"{name}_error")
            log.info("bench_cfd_moving: %s study, observed orders %s", name,
                     {c: round(p, 2) for c, p in orders.items()})
    else:
        log.warning("bench_cfd_moving: failed runs, no errors computed")
    errors = ["grid_error", "time_step_error"]
    keys = [k for k in rows[0] if k != "dp" and k not in errors] + errors
    with (results_dir / "cfd_moving.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    series = [(f"{label} study", [r["solver_s_per_rev"] / 3600.0 for r in study],
               [r[key] for r in study], style)
              for label, key, study, style in (("grid", "grid_error", grid, "o-"),
                                               ("time-step", "time_step_error", steps, "s--"))
              if all(key in r for r in study)]
    if series:
        time_error_plot(results_dir / "cfd_moving.png", series, GUIDE,
                        xlabel="solver CPU hours per revolution (one core)",
                        ylabel="chamber pressure change: error / largest change",
                        title=f"moving section, {GAP * 1e6:g} um, {SPAN_DEG:g} deg turned")
    return [{k: r.get(k) for k in keys} for r in rows]
