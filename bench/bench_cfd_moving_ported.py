"""Cost per revolution against the time step's error of the ported section (issue 17).

The section of tests/data/cfd/moving/record_ported.py at 100 um (the default pair, a slab
10 mm deep, suction and discharge ports on its end faces, 2500 rpm, 512 x 4), started
from the quasi-1D model's periodic state at 13 deg and turned SPAN_DEG, as PISO at
STEPS steps per 0.25 deg key frame (the recorded run's 192 and 2, 4 and 8 times fewer:
Courant numbers ~0.6 to ~7).  What is compared: every chamber's pressure at the end,
from the grid's own topology; the reference is the Richardson extrapolation of the three
finest (observed order), and a run's error is its largest chamber difference from it as
a share of the pressure swing (the finest run's largest less its least chamber
pressure at the end).  Cost per revolution: the solver's time over the span scaled to
360 deg, on one core.  Needs OpenFOAM; without it nothing is measured.  ~5 min.

The grid's share of the ported run's error is the recorded study
(tests/data/cfd/moving/ported_<gap>um_grid.json): a grid twice as fine costs ~8 times a
revolution, too much for a benchmark that runs on every machine.
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
from rotorflow.cases.moving_ported import initial_state, ported_models
from rotorflow.cases.moving_ports import slab_ports
from rotorflow.cases.moving_section import MovingSection
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.postprocess.richardson import richardson
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.workflow.case import case_from_raw, load_toml

from .plots import time_error_plot

log = logging.getLogger(__name__)

REPO = Path(__file__).resolve().parents[1]
CASE = REPO / "examples" / "default.toml"
GAP, DEPTH = 100e-6, 0.01
START_DEG, SPAN_DEG, FRAMES_PER_DEG = 13.0, 4.0, 4
OMEGA = 2500.0 * 2.0 * math.pi / 60.0
STEPS = (24, 48, 96, 192)
#: Guide lines of the plot (1 % of the swing in one CPU hour a revolution): not a target.
GUIDE = (1.0, 0.01)


def _setup():
    raw, pair, gas = load_toml(CASE), examples()["table1"], PerfectGas()
    ports, _ = slab_ports(pair, DEPTH, GAP, gas, raw, CASE, case_from_raw)
    model = ported_models(raw, CASE, DEPTH, GAP, gas, ("nozzle",), case_from_raw)["nozzle"]
    p, T = initial_state(model, math.radians(START_DEG))
    return MovingSection(pair, GAP, OGridSpec(columns=512, cells_across_gap=4),
                         math.radians(START_DEG), math.radians(SPAN_DEG),
                         int(round(SPAN_DEG * FRAMES_PER_DEG)), OMEGA, depth=DEPTH,
                         p0=ports.p_suction, T0=ports.T_suction, ports=ports,
                         initial_p=p, initial_T=T)


def measure(s: MovingSection, steps: int, root: Path) -> dict:
    folder = root / f"s{steps}"
    t0 = time.perf_counter()
    run = run_moving_section(s, folder, RunControls(steps_per_frame=steps,
                                                    max_courant=math.inf), reuse=False)
    row = {"steps_per_frame": steps, "status": run.status, "cells": run.cells,
           "time_steps": run.time_steps, "solver_s": run.run_time_s,
           "frames_s": time.perf_counter() - t0 - run.run_time_s,
           "max_courant": run.max_courant, "mass_balance": run.mass_balance,
           "solver_s_per_rev": run.run_time_s * 360.0 / SPAN_DEG, "p": {}}
    if run.ok:
        got = topology_pressures(s, folder)["p"]
        row["p"] = {c: v[-1] for c, v in got.items() if np.isfinite(v[-1])}
        row["swing"] = max(row["p"].values()) - min(row["p"].values())
    else:
        log.warning("bench_cfd_moving_ported: %s %s\n%s", folder.name, run.message,
                    run.log_tail)
    return row


def errors(rows: list[dict]) -> dict:
    """Set each row's ``error``; returns the observed order per chamber (nan where the
    three finest do not converge monotonically: the finest is the reference there)."""
    chambers = sorted(set.intersection(*(set(r["p"]) for r in rows)), key=int)
    refs, orders = {}, {}
    for c in chambers:
        r = richardson([row["p"][c] for row in rows[-3:]], 2.0)
        refs[c], orders[c] = r.extrapolated, r.order
    swing = rows[-1]["swing"]
    for row in rows:
        row["error"] = max(abs(row["p"][c] - refs[c]) for c in chambers) / swing
    return orders


def run(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    if not foam.is_available():
        log.warning("bench_cfd_moving_ported: OpenFOAM not installed (make openfoam); "
                    "nothing measured")
        return []
    s = _setup()
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(s, n, Path(tmp)) for n in STEPS]
    if all(r["status"] == "completed" for r in rows):
        orders = errors(rows)
        log.info("bench_cfd_moving_ported: observed orders %s",
                 {c: round(p, 2) for c, p in orders.items()})
    keys = [k for k in rows[0] if k not in ("p", "swing")] + ["error"]
    with (results_dir / "cfd_moving_ported.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    if all("error" in r for r in rows):
        time_error_plot(results_dir / "cfd_moving_ported.png",
                        [("PISO, time step", [r["solver_s_per_rev"] / 3600.0 for r in rows],
                          [r["error"] for r in rows], "s-")], GUIDE,
                        xlabel="solver CPU hours per revolution (one core)",
                        ylabel="chamber pressure: error / cycle swing",
                        title=f"ported section, {GAP * 1e6:g} um, {SPAN_DEG:g} deg turned")
    return [{k: r.get(k) for k in keys} for r in rows]
