"""Re-record the moving section's lobe-period run and its quasi-1D comparison (issue 17).

    .venv/bin/python tests/data/cfd/moving/record.py [RUNS_DIR] [STEPS_PER_FRAME]
    .venv/bin/python tests/data/cfd/moving/record.py RUNS_DIR study
    .venv/bin/python tests/data/cfd/moving/record.py RUNS_DIR 20um

(needs OpenFOAM; about 8 min of key frames and 15-20 min of solver on one core at 192
steps per frame).  The default pair of examples/default.toml at 100 um, 512 x 4 cells,
a slab 10 mm deep, turned one lobe period (60 deg of the outer rotor, 2500 rpm) from 13
deg, key frames every 0.25 deg, fields written every 0.5 deg; the chambers' pressures
from the grid's topology at those angles (:func:`.moving_chambers.topology_pressures`)
against the closed-section quasi-1D model under each leakage model.  Writes
``lobe_100um.json`` next to this file (``lobe_100um_s<STEPS>.json`` for another step);
a run that is not "completed" is written with its status and log tail and no comparison.
``study``: the first 30 deg again at 288 steps per frame, its chamber pressures and their
largest difference from the 192-step run's as a share of the swing
(``dt_study_30deg.json``; ~12 min of solver).
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from rotorflow.cases.moving_case import RunControls, run_moving_section
from rotorflow.cases.moving_chambers import comparison_record, topology_pressures
from rotorflow.cases.moving_section import MovingSection
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.workflow.case import case_from_raw, load_toml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
CASE = ROOT / "examples" / "default.toml"
FIT = ROOT / "tests" / "data" / "cfd" / "chamber" / "flow_coefficient.json"
MODELS = ("nozzle", "fanno", "cfd-calibrated")
#: 192 steps per 0.25 deg frame keeps the Courant number below 1 over the period (at 64
#: it reached 2.1 near 70 deg, where the chamber before top dead centre leaks hardest).
STEPS = 192


def _record(s: MovingSection, folder: Path, steps: int, every: int, out: Path) -> Path:
    """Run ``s`` and write its comparison with the quasi-1D models (or its failure) to
    ``out``."""
    t0 = time.perf_counter()
    run = run_moving_section(s, folder, RunControls(steps_per_frame=steps,
                                                    write_every_frames=every))
    if run.ok:
        rec = comparison_record(s, run, folder, load_toml(CASE), CASE, MODELS, case_from_raw,
                                FIT)
    else:
        rec = {"cfd": {"status": run.status, "message": run.message,
                       "log_tail": run.log_tail}}
    rec["cfd"]["steps_per_frame"] = steps
    rec["cfd"]["wall_clock_s"] = time.perf_counter() - t0
    out.write_text(json.dumps(rec, indent=1, allow_nan=True) + "\n")
    return out


def main(runs: Path, steps: int = STEPS) -> Path:
    s = MovingSection(examples()["table1"], 100e-6, OGridSpec(columns=512, cells_across_gap=4),
                      math.radians(13.0), math.radians(60.0), 240,
                      2500.0 * 2.0 * math.pi / 60.0)
    out = HERE / ("lobe_100um.json" if steps == STEPS else f"lobe_100um_s{steps}.json")
    return _record(s, runs / f"moving-lobe-100um-s{steps}", steps, 2, out)


def study(runs: Path, steps: int = 288, span_deg: float = 30.0) -> Path:
    s = MovingSection(examples()["table1"], 100e-6, OGridSpec(columns=512, cells_across_gap=4),
                      math.radians(13.0), math.radians(span_deg), int(round(span_deg * 4)),
                      2500.0 * 2.0 * math.pi / 60.0)
    folder = runs / f"moving-{span_deg:g}deg-100um-s{steps}"
    run = run_moving_section(s, folder, RunControls(steps_per_frame=steps,
                                                    write_every_frames=2))
    if not run.ok:
        raise SystemExit(f"the study's run is {run.status}: {run.message}\n{run.log_tail}")
    fine = topology_pressures(s, folder)
    base = json.loads((HERE / "lobe_100um.json").read_text())["cfd"]["chambers"]
    n = len(fine["angles_deg"])
    out = {"steps_per_frame": [STEPS, steps], "span_deg": span_deg,
           "run_time_s": run.run_time_s, "mass_drift": run.mass_drift,
           "max_courant": run.max_courant, "time_steps": run.time_steps, "chambers": {}}
    for c in fine["p"]:
        a, b = np.array(base["p"][c][:n]), np.array(fine["p"][c])
        ok = np.isfinite(a) & np.isfinite(b)
        d = np.abs(a - b)[ok]
        out["chambers"][c] = {"max": float(d.max() / np.ptp(b[ok])),
                              "swing_Pa": float(np.ptp(b[ok])), "max_Pa": float(d.max())}
    out["p_288"] = fine
    path = HERE / "dt_study_30deg.json"
    path.write_text(json.dumps(out, indent=1, allow_nan=True) + "\n")
    return path


def clearance_20um(runs: Path, span_deg: float = 20.0, steps: int = 144) -> Path:
    """The real clearance: 20 um needs 1024 columns (512 leave the walls 0.89 first-cell
    heights off their chords at 20-40 deg, limit 0.5) and key frames every 0.0625 deg (at
    0.125 deg the interpolated walls are 1.74 um off, 8.7 % of the clearance, limit 5 %);
    at 96 steps per frame (the 100 um run's step halved for the finer columns) the
    gap's Courant number reached 1.37 (4,096 cells, 30,720 steps, 1,314 s: judged
    inconsistent, not recorded); 144 brought it to 0.91 (46,080 steps, 2,394 s of
    solver, 46 min with the frames on a loaded machine: ``span20deg_20um.json``).  The
    first ``span_deg`` of the lobe period (a whole period at 144: ~2 h of solver on one
    core)."""
    s = MovingSection(examples()["table1"], 20e-6, OGridSpec(columns=1024, cells_across_gap=4),
                      math.radians(13.0), math.radians(span_deg), int(round(span_deg * 16)),
                      2500.0 * 2.0 * math.pi / 60.0)
    return _record(s, runs / f"moving-{span_deg:g}deg-20um-s{steps}", steps, 8,
                   HERE / f"span{span_deg:g}deg_20um.json")


if __name__ == "__main__":
    if sys.argv[2:3] == ["20um"]:
        print(clearance_20um(Path(sys.argv[1])))
        raise SystemExit
    if sys.argv[2:3] == ["study"]:
        print(study(Path(sys.argv[1])))
        raise SystemExit
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("build/moving"),
               int(sys.argv[2]) if len(sys.argv) > 2 else STEPS))
