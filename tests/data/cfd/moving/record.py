"""Re-record the moving section's lobe-period run and its quasi-1D comparison (issue 17).

    .venv/bin/python tests/data/cfd/moving/record.py [RUNS_DIR] [STEPS_PER_FRAME]

(needs OpenFOAM; about 8 min of key frames and 15-20 min of solver on one core at 192
steps per frame).  The default pair of examples/default.toml at 100 um, 512 x 4 cells,
a slab 10 mm deep, turned one lobe period (60 deg of the outer rotor, 2500 rpm) from 13
deg, key frames every 0.25 deg, fields written every 0.5 deg; the chambers' pressures
from the grid's topology at those angles (:func:`.moving_chambers.topology_pressures`)
against the closed-section quasi-1D model under each leakage model.  Writes
``lobe_100um.json`` next to this file (``lobe_100um_s<STEPS>.json`` for another step);
a run that is not "completed" is written with its status and log tail and no comparison.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

from rotorflow.cases.moving_case import RunControls, run_moving_section
from rotorflow.cases.moving_chambers import comparison_record
from rotorflow.cases.moving_section import MovingSection
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.workflow.case import load_toml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
CASE = ROOT / "examples" / "default.toml"
FIT = ROOT / "tests" / "data" / "cfd" / "chamber" / "flow_coefficient.json"
MODELS = ("nozzle", "fanno", "cfd-calibrated")
#: 192 steps per 0.25 deg frame keeps the Courant number below 1 over the period (at 64
#: it reached 2.1 near 70 deg, where the chamber before top dead centre leaks hardest).
STEPS = 192


def main(runs: Path, steps: int = STEPS) -> Path:
    s = MovingSection(examples()["table1"], 100e-6, OGridSpec(columns=512, cells_across_gap=4),
                      math.radians(13.0), math.radians(60.0), 240,
                      2500.0 * 2.0 * math.pi / 60.0)
    t0 = time.perf_counter()
    folder = runs / f"moving-lobe-100um-s{steps}"
    run = run_moving_section(s, folder, RunControls(steps_per_frame=steps,
                                                    write_every_frames=2))
    out = HERE / ("lobe_100um.json" if steps == STEPS else f"lobe_100um_s{steps}.json")
    if run.ok:
        rec = comparison_record(s, run, folder, load_toml(CASE), CASE, MODELS, FIT)
    else:
        rec = {"cfd": {"status": run.status, "message": run.message,
                       "log_tail": run.log_tail}}
    rec["cfd"]["steps_per_frame"] = steps
    rec["cfd"]["wall_clock_s"] = time.perf_counter() - t0
    out.write_text(json.dumps(rec, indent=1, allow_nan=True) + "\n")
    return out


if __name__ == "__main__":
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("build/moving"),
               int(sys.argv[2]) if len(sys.argv) > 2 else STEPS))
