"""Whole-process run times of the quick commands, and of a 10 x 10 performance map.

Issue 19's targets, on the default case: `rotorflow geometry CASE --json` under 0.5 s,
`rotorflow simulate CASE --json` under 1 s (each a fresh process: Python start-up,
imports, reading the case and the computation), and `rotorflow map` of 10 x 10 points
under 30 s on 2 cores with every point converged. Timings depend on the machine and its
load, so they are measured here with the load beside them, not asserted by tests.

``simulate`` runs as a user's process does: a single point stays in numpy, numba is not
imported (rotorflow.quasi1d.compiled).  Beside it, the same process with the compiled
right-hand side forced (ROTORFLOW_COMPILED=1): from numba's on-disk cache (warm), and
the first run against an empty cache (cold: numba compiles).
"""

from __future__ import annotations

import csv
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CASE = REPO / "examples" / "default.toml"
REPEATS = 7
TARGETS_S = {"geometry": 0.5, "simulate": 1.0, "simulate compiled (warm cache)": 1.0,
             "simulate compiled (cold cache)": 1.0, "map": 30.0}


def _timed(args: list[str], cwd: Path, env: dict | None = None) -> tuple[float, float]:
    """(wall, CPU) seconds of one process (CPU: user + system of the child and its own
    children, what a shared machine's load does not inflate)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", *args],
                         capture_output=True, text=True, cwd=cwd,
                         env=None if env is None else {**os.environ, **env})
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"rotorflow {args[0]} failed: {out.stderr.strip()[-400:]}")
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="bench-process-"))
    rows = []
    try:
        for command in ("geometry", "simulate"):
            rows.append(_row(command, [_timed([command, str(CASE), "--json"], work)
                                       for _ in range(REPEATS)]))
        sim = ["simulate", str(CASE), "--json"]
        cold = {"ROTORFLOW_COMPILED": "1", "NUMBA_CACHE_DIR": str(work / "numba")}
        rows.append(_row("simulate compiled (cold cache)", [_timed(sim, work, cold)]))
        rows.append(_row("simulate compiled (warm cache)",
                         [_timed(sim, work, cold) for _ in range(REPEATS)]))
        t = _timed(["map", str(CASE), "--workers", "2", "--no-progress",
                    "--build", str(work / "build")], work)
        record = json.loads((work / "build" / "map" / "default" / "map.json").read_text())
        row = _row("map", [t])
        row["points_converged"] = f"{record['converged']}/{record['points']}"
        row["met"] = row["met"] and record["converged"] == record["points"]
        rows.append(row)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    fields = sorted({k for r in rows for k in r}, key=lambda k: (k != "command", k))
    with (results_dir / "process.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    return rows


def _row(command: str, runs: list[tuple[float, float]]) -> dict:
    wall = sorted(r[0] for r in runs)
    cpu = sorted(r[1] for r in runs)
    mid = len(runs) // 2
    return {"command": command, "best_s": wall[0], "median_s": wall[mid],
            "cpu_best_s": cpu[0], "cpu_median_s": cpu[mid], "target_s": TARGETS_S[command],
            "met": wall[mid] < TARGETS_S[command], "load_1min": os.getloadavg()[0],
            "cores": os.cpu_count()}


if __name__ == "__main__":
    print(run(REPO / "bench" / "results"))
