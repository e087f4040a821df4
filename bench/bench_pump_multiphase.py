"""Seed 003's multiphase pump (Table 1) through the quasi-1D model: every row, its errors
against the table and the run time (postprocess/pump_multiphase.py,
examples/screw_pump_multiphase.toml).  Output: results_dir/pump_multiphase.csv.

    python -m bench.bench_pump_multiphase                  # every row, table on stdout
    python -m bench.bench_pump_multiphase --rows 4:1501,14:2101
    python -m bench.bench_pump_multiphase --fit            # re-fit the one value
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from rotorflow.postprocess import pump_multiphase as pm

from .bench_pump_vacuum import pump_table, read_record, record


def _rows(want: str | None) -> list[pm.Row]:
    rows = pm.read_table()
    if not want:
        return rows
    keys = {tuple(float(v) for v in w.split(":")) for w in want.split(",")}
    return [r for r in rows if r.key in keys]


def run(results_dir: Path, rows: list[pm.Row] | None = None,
        case: Path = pm.EXAMPLE) -> list[dict]:
    """Every row (or ``rows``), written to pump_multiphase.csv with the CPU time."""
    t0, c0 = time.perf_counter(), time.process_time()
    res = pm.run(rows or pm.read_table(), *pump_table(case), str(case))
    return [{**record(results_dir / "pump_multiphase.csv", res, t0, c0), **pm.trends(res)}]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", help="rows as p_d:rpm, comma separated; default all")
    ap.add_argument("--case", type=Path, default=pm.EXAMPLE)
    ap.add_argument("--results", type=Path, default=Path(__file__).parent / "results")
    ap.add_argument("--fit", action="store_true",
                    help=f"only fit the gas volume fraction on the {pm.FITTED} row")
    a = ap.parse_args(argv)
    if a.fit:
        raw, table = pump_table(a.case)
        row = next(r for r in pm.read_table() if r.key == pm.FITTED)
        print(f"gas volume fraction fitted on {pm.FITTED}: "
              f"{pm.fit_gas_volume_fraction(raw, table, row, where=str(a.case))}")
        return
    summary = run(a.results, _rows(a.rows), a.case)[0]
    res = read_record(a.results / "pump_multiphase.csv")
    print(pm.format_report(res))
    print(summary)


if __name__ == "__main__":
    main()
