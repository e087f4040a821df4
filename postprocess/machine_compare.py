"""The ``cfd.machine`` stage's comparison: the frozen-angle 3D CFD of the whole machine on
three grids, Richardson-extrapolated, against the quasi-1D model's frozen state under
each leakage model (issue 16).

Quantities, per angle: each closed chamber's volume-averaged pressure, the net flow
between each pair of chambers (a sealing path: the lines between the two, all of them;
those between two chambers open to ports too, which carry the machine's leakage from
discharge to suction as much as any), and the machine's total leakage (discharge plenum
to suction plenum).  Each is extrapolated from the three grids with the observed order
(:mod:`.richardson`); a quantity whose grids oscillate or diverge is compared on the
finest grid and says so.  Each also gets the quick estimate of the coarse and medium
grids alone (:func:`.richardson.two_grid`, at the formal second order) and, where the
fine grid ran, that estimate's error against the three-grid value; a study run on two
grids (``grids = 2``) is compared against the quick estimate.  The error of a model is
``model / CFD - 1`` (the pressures absolute, so a 1 % error is 1 % of the chamber's
pressure).

Inputs are plain dicts (the stage's ``angles.json``), so this module is tested without
OpenFOAM.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from .richardson import richardson, two_grid

#: A sealing path carrying less than this share of the total leakage on every grid is
#: not compared: its relative error is noise (a pair of chambers that touch at a few
#: stray faces, or two chambers at one pressure).
MIN_PATH_SHARE = 0.02

KINDS = ("pressure", "path", "leakage")


def _rich(values, ratio: float) -> dict:
    quick = two_grid(values[:2], ratio)
    if len(values) == 2:
        return {"convergence": "two-grid", "order": quick.order,
                "extrapolated": quick.extrapolated, "uncertainty": quick.uncertainty,
                "level_errors": [*quick.relative_errors(), math.nan],
                "two_grid": quick.extrapolated, "two_grid_error": math.nan}
    r = richardson(values, ratio)
    return {"convergence": r.kind, "order": r.order, "extrapolated": r.extrapolated,
            "uncertainty": r.uncertainty,
            "level_errors": list(r.relative_errors()),
            "two_grid": quick.extrapolated,
            "two_grid_error": quick.extrapolated / r.extrapolated - 1.0}


def quantities(angle: dict) -> list[dict]:
    """The compared quantities of one angle (``angle``: the stage's record, three (or two)
    ``runs`` coarse to fine, each with chamber_p, seals, leakage_kg_s; ``models``: per model its
    pressures, pairs and total; ``closed``: the closed slots), each with its CFD values,
    extrapolation and model values."""
    runs, ratio = angle["runs"], angle["ratio"]
    closed = [int(s) for s in angle["closed"]]
    models = angle["models"]
    out = []

    def add(kind, name, cfd, model_values):
        row = {"angle_deg": angle["angle_deg"], "kind": kind, "name": name,
               "cfd": [float(v) for v in cfd] + [math.nan] * (3 - len(cfd)),
               **_rich(cfd, ratio)}
        row["models"] = {m: float(v) for m, v in model_values.items()}
        out.append(row)

    for s in closed:
        add("pressure", f"chamber {s}", [r["chamber_p"][str(s)] for r in runs],
            {m: d["pressures"][str(s)] for m, d in models.items()})
    total = [r["leakage_kg_s"] for r in runs]
    seals = [{(int(a), int(b)): float(f) for a, b, f in r["seals"]} for r in runs]
    pairs = sorted({p for sd in seals for p in sd})
    for a, b in pairs:
        cfd = [sd.get((a, b), 0.0) for sd in seals]
        if max(abs(v) / t for v, t in zip(cfd, total, strict=True)) < MIN_PATH_SHARE:
            continue
        add("path", f"chamber {a} -> {b}", cfd,
            {m: _pair_flow(d["pairs"], a, b) for m, d in models.items()})
    add("leakage", "total", total, {m: d["total"] for m, d in models.items()})
    return out


def _pair_flow(pairs: dict, a: int, b: int) -> float:
    return float(pairs.get(f"{a},{b}", 0.0))


def errors(rows: list[dict]) -> dict:
    """{model: {kind: [relative errors]}} over the rows."""
    out: dict = {}
    for row in rows:
        ref = row["extrapolated"]
        for m, v in row["models"].items():
            err = v / ref - 1.0 if ref != 0.0 else math.nan
            out.setdefault(m, {k: [] for k in KINDS})[row["kind"]].append(err)
    return out


def summary(rows: list[dict]) -> dict:
    """Per model the RMS and largest error of each kind and over all, and the closest
    model: the least RMS error over all compared quantities, and of each kind."""
    table = {}
    for m, by_kind in errors(rows).items():
        entry = {}
        every = []
        for kind, errs in by_kind.items():
            e = np.asarray(errs, float)
            every += errs
            entry[kind] = {"rms": float(np.sqrt(np.mean(e**2))) if e.size else math.nan,
                           "max_abs": float(np.max(np.abs(e))) if e.size else math.nan,
                           "count": int(e.size)}
        e = np.asarray(every, float)
        entry["all"] = {"rms": float(np.sqrt(np.mean(e**2))), "max_abs": float(np.max(np.abs(e))),
                        "count": int(e.size)}
        table[m] = entry
    closest = min(table, key=lambda m: table[m]["all"]["rms"]) if table else None
    # over all quantities the many sealing paths outweigh the few pressures and the one
    # total, so the closest model of each kind is named too
    by_kind = {k: min(table, key=lambda m, k=k: table[m][k]["rms"])
               for k in KINDS if table and all(table[m][k]["count"] for m in table)}
    return {"models": table, "closest_model": closest, "closest_by_kind": by_kind,
            "two_grid": _two_grid_errors(rows)}


def _two_grid_errors(rows: list[dict]) -> dict:
    """Per kind the largest error of the quick (coarse and medium) estimate against the
    three-grid extrapolation, over the quantities whose three grids converge
    monotonically (elsewhere there is no extrapolation to hold it to)."""
    out = {}
    for kind in KINDS:
        e = [abs(r["two_grid_error"]) for r in rows
             if r["kind"] == kind and r["convergence"] == "monotone"]
        out[kind] = {"max_abs": max(e) if e else math.nan, "count": len(e)}
    return out


def write(angles: list[dict], out_dir: Path) -> dict:
    """``machine_errors.csv`` (one row per quantity), ``machine_errors.md`` (the summary)
    and the summary dict it returns; ``angles``: the records of the angles whose runs
    all converged."""
    rows = [q for a in angles for q in quantities(a)]
    out_dir = Path(out_dir)
    models = sorted({m for r in rows for m in r["models"]})
    with (out_dir / "machine_errors.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["angle_deg", "kind", "quantity", "cfd_coarse", "cfd_medium", "cfd_fine",
                    "convergence", "observed_order", "cfd_extrapolated", "uncertainty",
                    "coarse_error", "medium_error", "fine_error", "two_grid",
                    "two_grid_error", *[f"{m}{s}" for m in models for s in ("", "_error")]])
        for r in rows:
            ref = r["extrapolated"]
            w.writerow([r["angle_deg"], r["kind"], r["name"], *r["cfd"], r["convergence"],
                        r["order"], ref, r["uncertainty"], *r["level_errors"],
                        r["two_grid"], r["two_grid_error"],
                        *[v for m in models for v in (r["models"][m], r["models"][m] / ref - 1)]])
    result = summary(rows)
    lines = ["| model | pressures RMS | paths RMS | total leakage RMS | all RMS | all max |",
             "| --- | --- | --- | --- | --- | --- |"]
    for m, e in result["models"].items():
        lines.append(f"| {m} | {e['pressure']['rms']:.1%} | {e['path']['rms']:.1%} | "
                     f"{e['leakage']['rms']:.1%} | {e['all']['rms']:.1%} | "
                     f"{e['all']['max_abs']:.1%} |")
    lines.append(f"\nclosest to the extrapolated CFD: {result['closest_model']}; by kind: "
                 + ", ".join(f"{k} {m}" for k, m in result["closest_by_kind"].items()))
    quick = result["two_grid"]
    lines.append("\nthe coarse and medium grids alone (two-grid Richardson at order 2) "
                 "against the three-grid extrapolation, largest error: "
                 + ", ".join(f"{k} {q['max_abs']:.2%} ({q['count']})" if q["count"]
                             else f"{k} none converges monotonically"
                             for k, q in quick.items()))
    (out_dir / "machine_errors.md").write_text("\n".join(lines) + "\n")
    (out_dir / "machine_summary.json").write_text(json.dumps(result, indent=2) + "\n")
    return result


def report_section(artifact: Path, report_dir: Path, case):
    """The ``cfd.machine`` stage's part of the HTML report: every run (failed and
    flagged ones with their reason), the error table of each model against the
    extrapolated CFD, and the closest model."""
    from .report import Section, esc, table

    artifact = Path(artifact)
    records = json.loads((artifact / "angles.json").read_text())
    body = ["<p>Frozen-angle steady 3D runs of the whole machine (rhoSimpleFoam, laminar), "
            "three grids per angle; the quasi-1D model in the same frozen state with its "
            "end-face paths sealed, as the CFD's end plates are.</p>"]
    rows, classes = [], []
    for r in records:
        for g, run in zip(r["grids"], r["runs"], strict=True):
            rows.append([r["angle_deg"], f"{g['level']} {g['label']}", run["cells"],
                         run["processes"], run["iterations"], run["run_time_s"],
                         run["leakage_kg_s"], run["imbalance"], run["status"],
                         run["message"]])
            classes.append("" if run["status"] == "converged" else "failed")
    body.append(table(["angle deg", "grid", "cells", "processes", "iterations", "wall s",
                       "leakage kg/s", "mass balance", "status", "reason"], rows, classes))
    failed = [run for r in records for run in r["runs"] if run["log_tail"]]
    for run in failed[:4]:
        body.append(f"<pre>{esc(run['log_tail'][-1500:])}</pre>")
    errors_csv = artifact / "machine_errors.csv"
    if errors_csv.is_file():
        with errors_csv.open() as fh:
            lines = list(csv.reader(fh))
        body.append(table(lines[0], [[_num(c) for c in row] for row in lines[1:]]))
        body.append(f"<pre>{esc((artifact / 'machine_errors.md').read_text())}</pre>")
    else:
        body.append("<p class='warn'>No angle has three converged runs: nothing compared."
                    "</p>")
    return Section("CFD: the whole machine at frozen angles", "".join(body))


def _num(text: str):
    try:
        return float(text)
    except ValueError:
        return text
