"""`make bench`: every stage's run-time-vs-error benchmark into bench/results/."""

from __future__ import annotations

import importlib
import logging
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
MODULES = (
    "bench.bench_geometry",
    "bench.bench_twin_screw",
    "bench.bench_pump_profiles",
    "bench.bench_quasi1d",
    "bench.bench_pdsim",
    "bench.bench_real_fluid",
    "bench.bench_humid",
    "bench.bench_wet_pump",
    "bench.bench_solids",
    "bench.bench_cfd",
    "bench.bench_cfd3d",
    "bench.bench_cfd_moving",
    "bench.bench_cfd_moving_ported",
    "bench.bench_workflow",
    "bench.bench_process",
    "bench.bench_optimise",
    "bench.bench_pump_vacuum",
    "bench.bench_pump_multiphase",
)


def main() -> int:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    log = logging.getLogger("bench")
    for name in MODULES:
        try:
            mod = importlib.import_module(name)
        except ModuleNotFoundError:
            log.info("%s: not present, skipped", name)
            continue
        rows = mod.run(RESULTS)
        for row in rows or []:
            log.info("%s %s", name, row)
    return 0


if __name__ == "__main__":
    sys.exit(main())
