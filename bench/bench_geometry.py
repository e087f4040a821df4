"""Run time against error of the geometry engine as the angle resolution grows.

Each error is measured against a converged reference (the finest resolution, computed
in the same run): the largest chamber area A_wc, the largest chamber volume V and
Pi_max of the default case.  Target: a full case (profiles, volume curve, forces) at
1e-4 relative error in under 0.2 s.
"""

from __future__ import annotations

import csv
import time
from pathlib import Path

from rotorflow.geometry.forces import power_split
from rotorflow.geometry.machine import InternalGearMachine
from rotorflow.geometry.pin_gerotor import PinGerotor
from rotorflow.workflow.case import load_case

REPO = Path(__file__).resolve().parents[1]
POINTS = (12, 24, 48, 96, 192)
REFERENCE_POINTS = 1536


def _full_case(case, ppp):
    t0 = time.perf_counter()
    # A fresh pair: nothing cached from an earlier resolution.
    pair = PinGerotor(case.pair.lobes_outer, case.pair.lam, case.pair.sigma, case.pair.diameter)
    m = InternalGearMachine(pair, case.sweep(None), ppp)
    split = power_split(m, case.volume_ratio, case.driven)
    out = (m.section.area_max, m.volume_max, split.pi_max)
    return time.perf_counter() - t0, out


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    case = load_case(REPO / "cases" / "default.toml")
    _, ref = _full_case(case, REFERENCE_POINTS)
    rows = []
    for ppp in POINTS:
        times = []
        for _ in range(3):
            dt, val = _full_case(case, ppp)
            times.append(dt)
        rows.append({
            "points_per_period": ppp,
            "time_s": min(times),
            "err_A_wc": abs(val[0] / ref[0] - 1),
            "err_V": abs(val[1] / ref[1] - 1),
            "err_Pi_max": abs(val[2] / ref[2] - 1),
        })
    with (results_dir / "geometry.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    _plot(rows, results_dir / "geometry.png")
    return rows


def _plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for key in ("err_A_wc", "err_V", "err_Pi_max"):
        ax.loglog([r["time_s"] for r in rows], [max(r[key], 1e-16) for r in rows], "o-",
                  label=key[4:])
    ax.axvline(0.2, color="grey", ls=":")
    ax.axhline(1e-4, color="grey", ls=":")
    ax.set_xlabel("run time of a full case [s]")
    ax.set_ylabel("relative error vs converged reference")
    ax.set_title("geometry: default case")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
