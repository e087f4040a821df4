"""Run time against error of the geometry engine as the angle resolution grows.

Two resolutions: points per lobe period of the chamber curves (volume, table) and the
section-table refinement under them (the loads, hence Pi_max).  Each error is measured
against a converged reference (far finer than any row, computed in the same run): the
largest chamber area A_wc, the largest chamber volume V and Pi_max of the default case.
Target: a full case (profiles, volume curve, forces) at 1e-4 relative error in under
0.2 s.
"""

from __future__ import annotations

import csv
import dataclasses
import time
from pathlib import Path

from rotorflow.geometry.forces import power_split
from rotorflow.geometry.machine import SweptMachine
from rotorflow.workflow.case import load_case

from .plots import time_error_plot

REPO = Path(__file__).resolve().parents[1]
#: (points per period, section refinement) of each row; the library default is (96, 32).
RESOLUTIONS = ((12, 8), (24, 8), (48, 8), (48, 16), (96, 8), (96, 16), (96, 32),
               (96, 64), (192, 32))
REFERENCE = (192, 128)
TARGET_TIME_S = 0.2
TARGET_ERROR = 1e-4


def _full_case(case, ppp, refinement):
    t0 = time.perf_counter()
    # A fresh pair: nothing cached from an earlier resolution.
    pair = dataclasses.replace(case.pair)
    m = SweptMachine(pair, case.sweep(None), ppp, refinement)
    _ = m.curves.volume
    split = power_split(m, case.volume_ratio, case.driven)
    out = (m.section.area_max, m.volume_max, split.pi_max)
    return time.perf_counter() - t0, out


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    case = load_case(REPO / "examples" / "default.toml")
    _, ref = _full_case(case, *REFERENCE)
    rows = []
    for ppp, refinement in RESOLUTIONS:
        times = []
        for _ in range(3):
            dt, val = _full_case(case, ppp, refinement)
            times.append(dt)
        errors = [abs(v / r - 1) for v, r in zip(val, ref, strict=True)]
        rows.append({
            "points_per_period": ppp,
            "section_refinement": refinement,
            "time_s": min(times),
            "err_A_wc": errors[0],
            "err_V": errors[1],
            "err_Pi_max": errors[2],
            "meets_target": min(times) < TARGET_TIME_S and max(errors) < TARGET_ERROR,
        })
    with (results_dir / "geometry.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    _plot(rows, results_dir / "geometry.png")
    return rows


def _plot(rows, path):
    series = [(key[4:], [r["time_s"] for r in rows], [r[key] for r in rows], "o-")
              for key in ("err_A_wc", "err_V", "err_Pi_max")]
    time_error_plot(path, series, (TARGET_TIME_S, TARGET_ERROR),
                    xlabel="run time of a full case [s]",
                    ylabel="relative error vs converged reference",
                    title="geometry: default case", size=(6, 4))
