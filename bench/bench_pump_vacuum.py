"""Seed 003's vacuum pump (Table 2) through the quasi-1D model: every row, its errors
against the table and the run time (postprocess/pump_validation.py,
examples/screw_pump_vacuum.toml).  Output: results_dir/pump_vacuum.csv.

    python -m bench.bench_pump_vacuum                 # every row, table on stdout
    python -m bench.bench_pump_vacuum --rows 0.01,0.39
    python -m bench.bench_pump_vacuum --fit           # re-fit the one coefficient
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_validation as pv
from rotorflow.workflow.case import case_from_raw, load_toml


def pump_table(case_path: Path = pv.EXAMPLE):
    """(raw case, chamber table): the geometry is built once, for every row."""
    raw = load_toml(case_path)
    case = case_from_raw(raw, case_path)
    return raw, chamber_table(case, build_machine(case))


def _rows(want: str | None) -> list[pv.Row]:
    rows = pv.read_table()
    if not want:
        return rows
    ps = [float(x) for x in want.split(",")]
    return [r for r in rows if any(abs(r.p_suction_bar - p) < 1e-9 for p in ps)]


def run(results_dir: Path, rows: list[pv.Row] | None = None,
        case: Path = pv.EXAMPLE) -> list[dict]:
    """Every row (or ``rows``), written to pump_vacuum.csv with the wall and CPU time."""
    t0, c0 = time.perf_counter(), time.process_time()
    res = pv.run(rows or pv.read_table(), *pump_table(case), str(case))
    summary = record(results_dir / "pump_vacuum.csv", res, t0, c0)
    return [{**summary, "eta_v_rising": pv.rising([r["eta_v_model"] for r in res])}]


def record(path: Path, res: list[dict], t0: float, c0: float) -> dict:
    """Write a pump table's rows to ``path``; the summary of their errors and targets
    with the wall and CPU time since t0, c0."""
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(res[0]))
        w.writeheader()
        w.writerows(res)
    predicted = [r for r in res if r["predicted"]]
    return {"rows": len(res), "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
            "max_eta_v_error": max(abs(r["eta_v_error"]) for r in predicted),
            "max_power_error": max(abs(r["power_error"]) for r in predicted),
            "eta_v_met": sum(r["eta_v_ok"] for r in predicted),
            "power_met": sum(r["power_ok"] for r in predicted),
            "predicted": len(predicted)}


def read_record(path: Path) -> list[dict]:
    """The rows :func:`record` wrote, numbers and flags typed back."""
    with open(path, newline="") as f:
        return [{k: (v == "True" if v in ("True", "False") else float(v))
                 for k, v in r.items()} for r in csv.DictReader(f)]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", help="suction pressures (bar), comma separated; default all")
    ap.add_argument("--case", type=Path, default=pv.EXAMPLE)
    ap.add_argument("--results", type=Path, default=Path(__file__).parent / "results")
    ap.add_argument("--fit", action="store_true",
                    help=f"only fit the blow-hole coefficient on the {pv.FITTED} bar row")
    a = ap.parse_args(argv)
    if a.fit:
        raw, table = pump_table(a.case)
        row = next(r for r in pv.read_table() if abs(r.p_suction_bar - pv.FITTED) < 1e-9)
        print(f"blow-hole coefficient fitted on {pv.FITTED} bar: "
              f"{pv.fit_coefficient(raw, table, row, where=str(a.case))}")
        return
    summary = run(a.results, _rows(a.rows), a.case)[0]
    res = read_record(a.results / "pump_vacuum.csv")
    print(pv.format_report(res))
    print(summary)


if __name__ == "__main__":
    main()
