"""What a sweep leaves: ``summary.csv`` (one row per point), ``report/`` and the record
``sweep.json``, each written atomically."""

from __future__ import annotations

import csv
import os
import shutil
import uuid
from pathlib import Path

from .cache import swap_in
from .sweep_file import SweepSpec
from .sweep_points import base_value


def point_rows(spec: SweepSpec, results: dict[str, dict]) -> list[dict]:
    """One row per point in the sweep's order: its values (the base case's where the
    point sets none), its status and error, and its stages' figures."""
    rows = []
    for i, (pid, values) in enumerate(spec.points):
        r = results[pid]
        full = {p: values.get(p, base_value(spec.base_raw, p)) for p in spec.params}
        rows.append({"index": i, "point": pid, "status": r["status"], **full,
                     "seconds": r.get("seconds"), "executed": " ".join(r.get("executed", [])),
                     "error": r.get("error", ""), **r.get("figures", {})})
    return rows


def write_summary(path: Path, rows: list[dict], params: list[str]) -> Path:
    head = ["index", "point", "status", *params, "seconds", "executed", "error"]
    figs = sorted({k for r in rows for k in r} - set(head))
    tmp = path.with_name(f".tmp-{path.name}-{uuid.uuid4().hex[:8]}")
    with open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=head + figs, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})
    os.replace(tmp, path)
    return path


def write_report(folder: Path, spec: SweepSpec, rows: list[dict]) -> Path:
    """``folder/report/``, built beside it and swapped in whole."""
    from rotorflow.postprocess.report import sweep_report

    tmp = folder / f".tmp-report-{uuid.uuid4().hex[:8]}"
    try:
        sweep_report(tmp, spec.name, spec.params, spec.axes, rows)
        swap_in(tmp, folder / "report")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return folder / "report" / "index.html"


def sweep_record(spec: SweepSpec, rows: list[dict], where: str, seconds: float,
                 summary: Path, report: Path | None) -> dict:
    """The record of a run (``sweep.json``, and what ``rotorflow sweep --json`` prints)."""
    return {"sweep": str(spec.path), "base": str(spec.base), "want": spec.want,
            "params": spec.params, "axes": spec.axes, "points": len(rows), "where": where,
            "ok": sum(r["status"] == "ok" for r in rows),
            "cached": sum(r["status"] == "cached" for r in rows),
            "failed": sum(r["status"] == "failed" for r in rows),
            "seconds": round(seconds, 2), "summary": str(summary),
            "report": str(report) if report else None,
            "failures": {r["point"]: r["error"] for r in rows if r["status"] == "failed"}}
