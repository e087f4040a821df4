"""Chamber pressure against rotor angle: the CFD run of case B against the product's
quasi-1D model.

The CFD run's history is read by :mod:`.chamber_history`; the quasi-1D side is the model
users run, :func:`rotorflow.quasi1d.simulate_transient`, on a one-chamber table made from
the case's own description (its volume curve, speed, suction state, gas, slab depth and
gap; :mod:`.chamber_model`), once per leakage model: the isentropic nozzle and Fanno flow
with their coefficients, and the CFD-calibrated correlation.  The sealed chamber in
closed form (p V^gamma constant) is drawn as a reference.

Differences are p_model(theta) - p_CFD(theta) at the CFD's samples; "max" is the largest
magnitude, "RMS" the root mean square over the samples, both also relative to the CFD
pressure rise p_CFD(end) - p_suction, the figure the leakage changes.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from rotorflow.quasi1d import Leakage

from .chamber_history import ChamberHistory, read_history, volume_curve
from .chamber_model import adiabatic_pressure, leakage_models, model_pressure

# --- comparison ---------------------------------------------------------------------------


@dataclass(frozen=True)
class PressureDifference:
    """p_model - p_CFD over the CFD's samples."""

    model: str
    max_abs_Pa: float
    rms_Pa: float
    mean_Pa: float
    max_rel_rise: float
    """max |difference| / (p_CFD(end) - p_suction)."""
    rms_rel_rise: float
    final_Pa: float
    """The difference at the last sample (discharge opening)."""


@dataclass(frozen=True)
class Comparison:
    """The CFD pressure and each model's at the CFD's samples."""

    angle_rad: np.ndarray
    p_cfd_Pa: np.ndarray
    predictions: Mapping[str, np.ndarray]
    p_suction_Pa: float
    references: Mapping[str, np.ndarray]
    """Curves drawn but not ranked (the sealed adiabatic chamber)."""

    def differences(self) -> list[PressureDifference]:
        rise = float(self.p_cfd_Pa[-1] - self.p_suction_Pa)
        out = []
        for name, p in self.predictions.items():
            d = p - self.p_cfd_Pa
            out.append(PressureDifference(
                name, float(np.max(np.abs(d))), float(np.sqrt(np.mean(d**2))),
                float(np.mean(d)), float(np.max(np.abs(d)) / rise),
                float(np.sqrt(np.mean(d**2)) / rise), float(d[-1])))
        return out

    @property
    def closest(self) -> str:
        """The model with the smallest RMS difference."""
        return min(self.differences(), key=lambda d: d.rms_Pa).model

    def summary(self) -> dict:
        return {
            "models": [asdict(d) for d in self.differences()],
            "closest_model": self.closest,
            "p_cfd_end_Pa": float(self.p_cfd_Pa[-1]),
            "p_suction_Pa": self.p_suction_Pa,
            "angle_start_deg": float(np.degrees(self.angle_rad[0])),
            "angle_end_deg": float(np.degrees(self.angle_rad[-1])),
            "samples": int(len(self.angle_rad)),
        }


def compare(history: ChamberHistory, desc: Mapping, models: Mapping[str, Leakage]
            ) -> Comparison:
    """Run the product's model of the case described by ``desc`` (its ``case.json``) with
    each of the leakage ``models`` (:func:`~.chamber_model.leakage_models`) and compare
    it with the CFD ``history``."""
    if not models:
        raise ValueError("no leakage models to compare")
    angles = history.angle_rad
    preds = {name: model_pressure(desc, leakage, angles) for name, leakage in models.items()}
    return Comparison(angles, history.p_Pa, preds, float(desc["p_suction_Pa"]),
                      {"sealed (p V^gamma const)": adiabatic_pressure(desc, angles)})


def write_comparison(comparison: Comparison, history: ChamberHistory, out_dir: Path,
                     checks: Mapping[str, float] | None = None) -> dict:
    """Write ``chamber_pressure.csv``, ``chamber_comparison.json`` and
    ``chamber_pressure.png`` into ``out_dir``; return the JSON's content."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    curves = {**comparison.predictions, **comparison.references}
    with (out_dir / "chamber_pressure.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["angle_deg", "time_s", "p_cfd_Pa", "T_cfd_K", "volume_cfd_m3",
                    *[f"p_{name}_Pa" for name in curves]])
        for i in range(len(comparison.angle_rad)):
            w.writerow([f"{math.degrees(comparison.angle_rad[i]):.6f}",
                        f"{history.time_s[i]:.9e}", f"{history.p_Pa[i]:.8g}",
                        f"{history.T_K[i]:.8g}", f"{history.volume_m3[i]:.8g}",
                        *[f"{curves[n][i]:.8g}" for n in curves]])
    summary = {**comparison.summary(), "checks": dict(checks or {})}
    text = json.dumps(summary, indent=2, allow_nan=True) + "\n"
    tmp = out_dir / "chamber_comparison.json.tmp"
    tmp.write_text(text)
    tmp.replace(out_dir / "chamber_comparison.json")
    plot_overlay(comparison, out_dir / "chamber_pressure.png")
    return summary


def plot_overlay(comparison: Comparison, path: Path) -> Path:
    """p against angle: CFD, each model, the sealed chamber; differences below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    deg = np.degrees(comparison.angle_rad)
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 1.4]})
    ax.plot(deg, comparison.p_cfd_Pa / 1e5, "k-", lw=2.2, label="CFD (rhoPimpleFoam)")
    for name, p in comparison.predictions.items():
        ax.plot(deg, p / 1e5, "--", lw=1.3, label=f"quasi-1D, {name}")
        ax2.plot(deg, (p - comparison.p_cfd_Pa) / 1e5, "--", lw=1.3, label=name)
    for name, p in comparison.references.items():
        ax.plot(deg, p / 1e5, ":", color="0.5", lw=1.2, label=name)
    ax.set_ylabel("chamber pressure (bar)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax2.axhline(0.0, color="k", lw=0.8)
    ax2.set_ylabel("model - CFD (bar)")
    ax2.set_xlabel("outer-rotor angle since chamber birth (deg)")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


# --- a finished run -----------------------------------------------------------------------


def compare_run(case_dir: Path, leakage: Leakage | None = None, fit=None
                ) -> tuple[ChamberHistory, Comparison]:
    """Read a finished chamber run and compare it with the product's model under each
    leakage model (``leakage``: the case's settings; ``fit``: the fitted correlation for
    "cfd-calibrated", or None)."""
    case_dir = Path(case_dir)
    desc = json.loads((case_dir / "case.json").read_text())
    history = read_history(case_dir, volume_curve(desc))
    return history, compare(history, desc, leakage_models(desc, leakage, fit))


def report_section(artifact: Path, report_dir: Path, case):
    """The ``cfd.chamber`` stage's part of the HTML report: the run's status and checks,
    the difference table and the p-angle overlay."""
    from rotorflow.postprocess.report import Section, esc, figure, table

    artifact = Path(artifact)
    body = []
    result_path = artifact / "chamber_result.json"
    result = json.loads(result_path.read_text()) if result_path.is_file() else {}
    if result and result.get("status") != "completed":
        body.append(f"<p class='warn'>The chamber run failed ({esc(result.get('status'))}: "
                    f"{esc(result.get('message'))}); it is not compared.</p>"
                    f"<pre>{esc(result.get('log_tail', ''))}</pre>")
    comparison = artifact / "chamber_comparison.json"
    if comparison.is_file():
        summary = json.loads(comparison.read_text())
        checks = summary.get("checks", {})
        body.append(
            f"<p>Chamber-averaged CFD pressure against rotorflow's quasi-1D model run on a "
            f"one-chamber table of the same chamber "
            f"({summary['samples']} samples, {summary['angle_start_deg']:.1f} to "
            f"{summary['angle_end_deg']:.1f} deg); closest model: "
            f"<b>{esc(summary['closest_model'])}</b>.  Mass conservation "
            f"{checks.get('mass_error', math.nan):.1e}, volume "
            f"{checks.get('volume_error', math.nan):.1e} (relative).</p>")
        body.append(table(
            ["model", "max |dp| (Pa)", "RMS dp (Pa)", "mean dp (Pa)", "max / rise",
             "RMS / rise", "dp at end (Pa)"],
            [[m["model"], m["max_abs_Pa"], m["rms_Pa"], m["mean_Pa"], m["max_rel_rise"],
              m["rms_rel_rise"], m["final_Pa"]] for m in summary["models"]]))
    if (artifact / "chamber_pressure.png").is_file():
        name = "cfd_chamber_pressure.png"
        (Path(report_dir) / name).write_bytes((artifact / "chamber_pressure.png").read_bytes())
        body.append(figure(name, "Chamber pressure against rotor angle: CFD and quasi-1D"))
    return Section("CFD: chamber compressed while it leaks", "".join(body))
