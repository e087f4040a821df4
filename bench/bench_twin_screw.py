"""Run time against error of the twin-screw geometry as the angle resolution grows.

Seed 004's 4/6 machine on two profiles, the pin-cycloid of examples/twin_screw_4_6.toml
and the circular rack of examples/twin_screw_export.toml: per points per lobe period of
the chamber curves (the section table runs twice as fine, TwinScrewPair), the time of
the geometry figures and the chamber table, and the errors against a reference at 192
points per period computed in the same run: of the largest chamber volume, of Pi_max,
and of the chamber's tip and interlobe sealing lines (each kind summed over its lines,
as functions of the angle: the largest difference from the reference's lines at the
same angles, over the reference's largest value), with the order each line error
shows against the previous resolution.  Target (issue 13): geometry figures and table
of a 4/6 pair at 1e-4 relative error in under 1 s.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.summary import chamber_table, geometry_figures
from rotorflow.workflow.case import load_case

REPO = Path(__file__).resolve().parents[1]
RESOLUTIONS = (24, 48, 96)
REFERENCE = 192
TARGET_TIME_S = 1.0
TARGET_ERROR = 1e-4


def _lines(lines, kind):
    return sum(x for (name, d), x in lines.items() if name.startswith(kind) and d > 0)


def _case(case, ppp, table=True):
    """(wall, CPU) time of `rotorflow geometry` and the chamber table at ``ppp`` from
    scratch (the CPU time is the one to compare on a shared machine)."""
    t0, c0 = time.perf_counter(), time.process_time()
    case = dataclasses.replace(case, pair=dataclasses.replace(case.pair))  # no caches
    m = SweptMachine(case.pair, case.sweep(None), ppp)
    figures = geometry_figures(case, m)
    if table:
        chamber_table(case, m)
    times = (time.perf_counter() - t0, time.process_time() - c0)
    return times, m, (figures["chamber_volume_max_m3"], figures["Pi_max"])


def _line_error(m, ref, kind):
    here = _lines(m.track_lines, kind)
    there = _lines(ref.track_lines_at(m.curves.phi), kind)
    return float(np.abs(here - there).max() / there.max())


#: (profile label, case file) benched.
CASES = (("pin-cycloid", "twin_screw_4_6.toml"), ("circular", "twin_screw_export.toml"))


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for label, name in CASES:
        rows += _profile_rows(label, load_case(REPO / "examples" / name))
    with (results_dir / "twin_screw.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows


def _profile_rows(label: str, case) -> list[dict]:
    _, ref, ref_values = _case(case, REFERENCE, table=False)
    rows = []
    for ppp in RESOLUTIONS:
        (dt, cpu), m, values = _case(case, ppp)
        err = [abs(v / r - 1) for v, r in zip(values, ref_values, strict=True)]
        err += [_line_error(m, ref, kind) for kind in ("tip", "interlobe")]
        row = {"profile": label, "points_per_period": ppp, "time_s": dt, "cpu_s": cpu,
               "err_V_max": err[0], "err_Pi_max": err[1], "err_tip_lines": err[2],
               "err_interlobe_lines": err[3]}
        prev = rows[-1] if rows else None
        for kind in ("tip", "interlobe"):
            key = f"err_{kind}_lines"
            row[f"order_{kind}_lines"] = (math.log(prev[key] / row[key])
                                          / math.log(ppp / prev["points_per_period"])
                                          if prev else float("nan"))
        row["meets_target"] = cpu < TARGET_TIME_S and max(err) < TARGET_ERROR
        rows.append(row)
    return rows
