"""Run time against error of the twin-screw geometry as the angle resolution grows.

Seed 004's 4/6 machine (examples/twin_screw_4_6.toml): per points per lobe period of
the chamber curves (the section table runs twice as fine, TwinScrewPair), the time of
the geometry figures and the chamber table, and the errors of the largest chamber
volume, Pi_max and the largest tip and interlobe sealing-line lengths against a
reference at 192 points per period computed in the same run.  Target (issue 13):
geometry figures and table of a 4/6 pair at 1e-4 relative error in under 1 s.
"""

from __future__ import annotations

import csv
import dataclasses
import time
from pathlib import Path

from rotorflow.geometry.forces import power_split
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.summary import chamber_table
from rotorflow.workflow.case import load_case

REPO = Path(__file__).resolve().parents[1]
RESOLUTIONS = (24, 48, 96)
REFERENCE = 192
TARGET_TIME_S = 1.0
TARGET_ERROR = 1e-4


def _lines(m, kind):
    return sum(x.max() for (name, d), x in m.track_lines.items()
               if name.startswith(kind) and d > 0)


def _case(case, ppp, table=True):
    t0 = time.perf_counter()
    pair = dataclasses.replace(case.pair)  # nothing cached from another resolution
    m = SweptMachine(pair, case.sweep(None), ppp)
    split = power_split(m, case.volume_ratio, case.driven)
    if table:
        chamber_table(dataclasses.replace(case, pair=pair), m)
    values = (m.volume_max, split.pi_max, _lines(m, "tip"), _lines(m, "interlobe"))
    return time.perf_counter() - t0, values


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    case = load_case(REPO / "examples" / "twin_screw_4_6.toml")
    _, ref = _case(case, REFERENCE, table=False)
    rows = []
    for ppp in RESOLUTIONS:
        dt, val = _case(case, ppp)
        err = [abs(v / r - 1) for v, r in zip(val, ref, strict=True)]
        rows.append({"points_per_period": ppp, "time_s": dt, "err_V_max": err[0],
                     "err_Pi_max": err[1], "err_tip_lines": err[2],
                     "err_interlobe_lines": err[3],
                     "meets_target": dt < TARGET_TIME_S and max(err) < TARGET_ERROR})
    with (results_dir / "twin_screw.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows
