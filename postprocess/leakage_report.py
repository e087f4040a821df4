"""The ``cfd.leakage`` stage's outputs: the error tables of every leakage model against the
CFD points, the fitted flow coefficient and its plot (:func:`write_report`), and its part
of the HTML report (:func:`report_section`)."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path

import numpy as np

from rotorflow.quasi1d.calibrated import DEFAULT_INERTIAL, FlowCoefficientFit

from .leakage import LeakagePoint, Model, compare, fit_flow_coefficient


def write_report(
    points: Sequence[LeakagePoint],
    out_dir: Path,
    models: Mapping[str, Model],
    *,
    features: Sequence[str] = DEFAULT_INERTIAL,
) -> dict:
    """Fit the flow coefficient and compare every model with the CFD points.

    The fit ("cfd-calibrated") uses every point, with the wall-drag term when some walls
    move; its left-out errors are reported for static and moving walls apart.  Where
    there are both, the static form fitted to the static points alone
    ("cfd-calibrated-static", the correlation without its wall term) is compared too,
    which shows what the wall motion does to a correlation that ignores it.  Writes
    ``leakage_errors.csv``, ``leakage_errors.md``, ``flow_coefficient.json`` and
    ``flow_coefficient.png``; returns the summary figures.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fit = fit_flow_coefficient(points, features)
    fit.save(out_dir / "flow_coefficient.json")
    fitted = {"cfd-calibrated": fit.model()}
    static = [p for p in points if p.wall_speed_m_s == 0]
    if fit.wall != 0.0 and len(static) > len(features) + 2:
        fitted["cfd-calibrated-static"] = fit_flow_coefficient(static, features,
                                                               wall=False).model()
    table = compare(points, {**models, **fitted})
    table.write_csv(out_dir / "leakage_errors.csv")
    loo = fit.leave_out_summary()
    lines = [f"\ncfd-calibrated: w = {fit.wall:.4g}; left-out prediction error:"]
    for name in ("all", "static", "moving"):
        s = loo[name]
        if s["points"]:
            lines.append(f"- {name} walls: max {s['max']:.1%}, RMS {s['rms']:.1%} over "
                         f"{s['points']} points")
    (out_dir / "leakage_errors.md").write_text(table.markdown() + "\n".join(lines) + "\n")
    _plot_fit(points, fit, out_dir / "flow_coefficient.png")
    return {
        "models": [asdict(s) for s in table.summary()],
        "fit": {"inertial_features": fit.inertial_features, "inertial": fit.inertial,
                "viscous": fit.viscous, "wall": fit.wall,
                "leave_out_max_error": loo["all"]["max"],
                "leave_out_rms_error": loo["all"]["rms"],
                "leave_out": loo},
    }


def _plot_fit(points: Sequence[LeakagePoint], fit: FlowCoefficientFit, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    cd = np.array([p.flow_coefficient for p in points])
    pred = np.array([fit.flow_coefficient(p.reynolds, p.pressure_ratio, p.length_over_gap,
                                          p.wall_speed_ratio) for p in points])
    re = np.array([p.reynolds for p in points])
    pr = np.array([p.pressure_ratio for p in points])
    moving = np.array([p.wall_speed_m_s != 0 for p in points])
    sc = ax.scatter(re[~moving], cd[~moving], c=np.log(pr[~moving]), marker="o", label="CFD")
    ax.scatter(re[moving], cd[moving], c="k", marker="x", label="CFD, moving walls")
    ax.scatter(re, pred, facecolors="none", edgecolors="r", marker="s", label="fit")
    fig.colorbar(sc, ax=ax, label="ln(pressure ratio)")
    ax.set_xscale("log")
    ax.set_xlabel("Re = ideal mass flow per depth / mu")
    ax.set_ylabel("flow coefficient Cd")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _largest(values) -> float:
    v = np.asarray([x for x in values if x is not None], dtype=float)
    return float(np.max(v)) if len(v) and np.all(np.isfinite(v)) else math.nan


def report_section(artifact: Path, report_dir: Path, case):
    """The ``cfd.leakage`` stage's part of the HTML report: mesh studies (failed runs
    named with their reasons), the error table of each model and the fitted Cd."""
    from rotorflow.postprocess.report import Section, esc, figure, table

    artifact = Path(artifact)
    body = []
    studies = json.loads((artifact / "studies.json").read_text())
    failed = [s for s in studies if not s["ok"]]
    if failed:
        body.append("<p class='warn'>Failed runs, left out of the comparison and the fit: "
                    + "; ".join(esc(f"{s['name']}: {', '.join(s['failures'])}") for s in failed)
                    + "</p>")
    body.append(table(
        ["point", "mesh convergence", "observed order", "default mesh vs extrapolated",
         "extrapolated kg/s/m", "largest inlet/outlet imbalance", "run time s (3 meshes)"],
        [[s["name"], s["kind"], s["order"], s["default_error"], s["extrapolated_kg_s_m"],
          _largest(s.get("imbalance", [])), float(np.sum(s.get("run_time_s", [math.nan])))]
         for s in studies],
        ["failed" if not s["ok"] else "" for s in studies]))
    errors = artifact / "leakage_errors.csv"
    if errors.is_file():
        with errors.open() as fh:
            rows = list(csv.DictReader(fh))
        models = [k[: -len("_error")] for k in rows[0] if k.endswith("_error")]
        body.append(table(["point", "Re", "PR", "L/h", "wall speed m/s", "CFD Cd"]
                          + [f"{m} error" for m in models],
                          [[r["point"], float(r["reynolds"]), float(r["pressure_ratio"]),
                            float(r["L_over_h"]), float(r.get("wall_speed_m_s", 0.0)),
                            float(r["cfd_Cd"])]
                           + [float(r[f"{m}_error"]) for m in models] for r in rows]))
        body.append(f"<pre>{esc((artifact / 'leakage_errors.md').read_text())}</pre>")
    if (artifact / "flow_coefficient.png").is_file():
        name = "cfd_leakage_flow_coefficient.png"
        (Path(report_dir) / name).write_bytes((artifact / "flow_coefficient.png").read_bytes())
        body.append(figure(name, "Flow coefficient: CFD and the fitted correlation"))
    if (artifact / "flow_coefficient.json").is_file():
        fit = FlowCoefficientFit.load(artifact / "flow_coefficient.json")
        body.append(f"<p>Fitted correlation ({esc(fit.definitions)}): inertial "
                    f"{esc(dict(zip(fit.inertial_features, fit.inertial, strict=True)))}, "
                    f"viscous b = {fit.viscous:.4g}, wall drag w = {fit.wall:.4g}.</p>")
    return Section("CFD: leakage through clearance gaps", "".join(body))
