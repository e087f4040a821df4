"""Run time against error of the quasi-1D chamber model, and its stress test.

1. Accuracy: one operating point (CRC.60-sized synthetic chamber, 1 -> 8 bar air at
   2000 rpm of the outer rotor, nozzle leakage through 5 um gaps, ideal ports), cycle
   converged, for every integrator and tolerance.  The error of mass flow and indicated
   power is taken against a tight implicit reference (Radau, rtol 1e-9) computed in the
   same run; run time is the median of repeated runs.  Target: 0.1 % in under 0.1 s.
   A second, stiff point (nozzle ports) compares the stiff-capable integrators.
2. Stress: seeded random points over pressure ratio 1.05-20, suction 0.01-10 bar, speed
   300-20000 rpm, gap 1-500 um, N1 3-7 and chamber size 1 cc - 1 L (synthetic tables
   scaled with the size and lobe count).  Every point must end converged or with a clear
   message; NaN, negative mass, pressure or temperature count as failures.  Records the
   failure count (target zero) and the run-time distribution.

Stress measured 2026-11-30 (seed 20260521, 1000 points, the compiled kernel, the other
core busy): 1000 converged, none invalid, 4864 periods in all, median 0.025 s a point,
the slowest 0.77 s.  The tree before the cycle solver's probe of the plain iteration
(quasi1d/cycle.py PROBE_GAIN) left one point (16, a leaky 7-lobe machine) at the
30-period limit in numpy (999, 4805 periods); drafts of the probe that let its period
into Newton's iteration left two (16 and 947, or 694 and 947).

Outputs in results_dir: quasi1d_accuracy.csv / .png, quasi1d_stress.csv / .png.
"""

from __future__ import annotations

import csv
import math
import statistics
import time
from pathlib import Path

import numpy as np

from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
from rotorflow.quasi1d.synthetic import scaled_table, sin2_table

ACCURACY_POINT = {"p_suction_bar": 1.0, "p_discharge_bar": 8.0, "T_suction_K": 300.0,
                  "speed_rpm": 3000.0, "volume_ratio": 4.6}
ACCURACY_LEAK = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
SWEEP = {
    "dopri5": (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7),
    "bs3": (1e-2, 1e-3, 1e-4, 1e-5, 1e-6),
    "ros23": (1e-3, 1e-4, 1e-5),
    "radau": (1e-4, 1e-6),
    "bdf": (1e-4, 1e-6),
}
STIFF_SWEEP = {"ros23": (1e-4, 1e-5), "bdf": (1e-5, 1e-7)}
REFERENCE = Numerics(integrator="radau", rtol=1e-9, atol=1e-11)
REPEATS = 5
TARGET_ERROR, TARGET_TIME = 1e-3, 0.1


def _timed(table, op, leak, ports, num, repeats):
    times, res = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = simulate(table, op, leak, ports, num)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), res


def _sweep(table, op, leak, ports, sweep, label, ref_num=REFERENCE):
    _, ref = _timed(table, op, leak, ports, ref_num, 1)
    rf = ref.figures
    rows = []
    for integ, tols in sweep.items():
        for rtol in tols:
            num = Numerics(integrator=integ, rtol=rtol, atol=rtol * 1e-2)
            slow = integ in ("radau", "bdf") or label == "stiff"
            t, res = _timed(table, op, leak, ports, num, 1 if slow else REPEATS)
            f = res.figures
            rows.append({
                "point": label, "integrator": integ, "rtol": rtol, "time_s": t,
                "err_mass_flow": abs(f["mass_flow_kg_s"] / rf["mass_flow_kg_s"] - 1.0),
                "err_power": abs(f["indicated_power_W"] / rf["indicated_power_W"] - 1.0),
                "cycles": f["cycles"], "rhs_calls": res.solution.n_rhs,
                "converged": f["converged"], "mass_balance_error": f["mass_balance_error"],
            })
    return rows, rf


def accuracy(results_dir: Path) -> list[dict]:
    table = sin2_table(rows=721)
    op = Operating.from_section(ACCURACY_POINT, "bench")
    rows, ref = _sweep(table, op, ACCURACY_LEAK, Ports("ideal"), SWEEP, "ideal-ports")
    # the reference checked by a second method: explicit dopri5 at rtol 1e-10
    cross = simulate(table, op, ACCURACY_LEAK, Ports("ideal"),
                     Numerics(integrator="dopri5", rtol=1e-10, atol=1e-12)).figures
    ref_spread = max(abs(cross["mass_flow_kg_s"] / ref["mass_flow_kg_s"] - 1),
                     abs(cross["indicated_power_W"] / ref["indicated_power_W"] - 1))
    stiff_rows, _ = _sweep(table, op, ACCURACY_LEAK, Ports("nozzle", 0.8), STIFF_SWEEP, "stiff",
                           Numerics(integrator="bdf", rtol=1e-9, atol=1e-11))
    rows += stiff_rows
    for r in rows:
        r["reference_spread"] = ref_spread
    _write_csv(results_dir / "quasi1d_accuracy.csv", rows)
    _plot_accuracy(results_dir / "quasi1d_accuracy.png", rows)
    return rows


# -- stress ------------------------------------------------------------------------------
def stress_point(rng: np.random.Generator) -> dict:
    """One random operating point and machine (log-uniform where the range spans decades)."""
    def logu(lo, hi):
        return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))

    pr = logu(1.05, 20.0)
    eps = float(np.clip(pr ** (1 / 1.4) * logu(0.8, 1.25), 1.2, 8.0))
    return {
        "pressure_ratio": pr,
        "p_suction_bar": logu(0.01, 10.0),
        "speed_rpm": logu(300.0, 20000.0),
        "gap_um": logu(1.0, 500.0),
        "lobes": int(rng.integers(3, 8)),
        "v_max_m3": logu(1e-6, 1e-3),
        "volume_ratio": eps,
    }


def attempt(out: dict, run):
    """run()'s result, its wall time in out["time_s"]; None where it raised, the failure
    recorded in ``out`` (status "error" and the message's first line), not raised."""
    t0 = time.perf_counter()
    try:
        res = run()
    except Exception as e:
        out.update(status="error", message=f"{type(e).__name__}: {e}".splitlines()[0],
                   time_s=time.perf_counter() - t0)
        return None
    out["time_s"] = time.perf_counter() - t0
    return res


def run_stress_point(pt: dict, numerics: Numerics | None = None) -> dict:
    """Simulate one stress point; classify the outcome."""
    table = scaled_table(pt["v_max_m3"], pt["lobes"])
    op = Operating.from_section({
        "p_suction_bar": pt["p_suction_bar"],
        "p_discharge_bar": pt["p_suction_bar"] * pt["pressure_ratio"],
        "T_suction_K": 300.0, "speed_rpm": pt["speed_rpm"],
        "volume_ratio": pt["volume_ratio"]}, "stress")
    leak = Leakage(gap_m=pt["gap_um"] * 1e-6, model="nozzle", coefficient=1.0)
    out = dict(pt)
    res = attempt(out, lambda: simulate(table, op, leak, Ports("ideal"),
                                        numerics or Numerics(max_cycles=30)))
    if res is None:
        return out
    f = res.figures
    c = res.chamber
    bad = []
    for key in ("p_Pa", "T_K", "m_kg"):
        v = c[key]
        if not np.all(np.isfinite(v)):
            bad.append(f"{key} not finite")
        elif np.any(v <= 0):
            bad.append(f"{key} not positive")
    numbers = [f["mass_flow_kg_s"], f["indicated_power_W"], f["mass_balance_error"],
               f["energy_balance_error"]]
    if not all(math.isfinite(x) for x in numbers):
        bad.append("figures not finite")
    out.update(cycles=f["cycles"], mass_flow_kg_s=f["mass_flow_kg_s"],
               volumetric_efficiency=f["volumetric_efficiency"],
               indicated_power_W=f["indicated_power_W"],
               mass_balance_error=f["mass_balance_error"],
               energy_balance_error=f["energy_balance_error"],
               method=res.solution.run.method)
    return classify(out, res, bad)


def classify(out: dict, res, bad: list[str]) -> dict:
    """A stress point's outcome: invalid (its defects), not converged, or converged."""
    if bad:
        out.update(status="invalid", message="; ".join(bad))
    elif not res.converged:
        out.update(status="not converged", message=res.figures.get("message", ""))
    else:
        out.update(status="converged", message="")
    return out


def stress(results_dir: Path, n: int = 1000, seed: int = 20260521) -> dict:
    rng = np.random.default_rng(seed)
    points = [stress_point(rng) for _ in range(n)]
    rows = []
    try:
        from tqdm import tqdm

        it = tqdm(points, desc="quasi1d stress", unit="pt", mininterval=5.0)
    except ImportError:  # pragma: no cover
        it = points
    for pt in it:
        rows.append(run_stress_point(pt))
    _write_csv(results_dir / "quasi1d_stress.csv", rows)
    times = np.array([r["time_s"] for r in rows])
    status = [r["status"] for r in rows]
    summary = {
        "points": n, "seed": seed,
        "converged": status.count("converged"),
        "not_converged": status.count("not converged"),
        "invalid": status.count("invalid"),
        "errors": status.count("error"),
        "time_median_s": float(np.median(times)),
        "time_p90_s": float(np.percentile(times, 90)),
        "time_max_s": float(times.max()),
        "time_total_s": float(times.sum()),
    }
    _plot_stress(results_dir / "quasi1d_stress.png", rows)
    return summary


def run(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    rows = accuracy(results_dir)
    ok = [r for r in rows if r["point"] == "ideal-ports" and r["integrator"] in ("dopri5", "bs3")
          and max(r["err_mass_flow"], r["err_power"]) < TARGET_ERROR]
    best = min(ok, key=lambda r: r["time_s"]) if ok else None
    out = [{k: r[k] for k in ("point", "integrator", "rtol", "time_s", "err_mass_flow",
                              "err_power", "cycles")} for r in rows]
    if best:
        out.append({"target": f"{TARGET_ERROR:g} error in {TARGET_TIME:g} s",
                    "fastest": f"{best['integrator']} rtol {best['rtol']:g}",
                    "time_s": best["time_s"],
                    "met": best["time_s"] < TARGET_TIME})
    out.append({"stress": stress(results_dir)})
    return out


# -- output ------------------------------------------------------------------------------
def _write_csv(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    tmp = path.with_suffix(".csv.tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    tmp.replace(path)


def _plot_accuracy(path: Path, rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, key, title in ((axes[0], "err_mass_flow", "mass flow"),
                           (axes[1], "err_power", "indicated power")):
        for (point, integ), mk in zip(sorted({(r["point"], r["integrator"]) for r in rows}),
                                      "osD^v<>ph", strict=False):
            sel = [r for r in rows if r["point"] == point and r["integrator"] == integ]
            ax.loglog([max(r[key], 1e-12) for r in sel], [r["time_s"] for r in sel],
                      marker=mk, ls="-" if point == "ideal-ports" else "--",
                      label=f"{integ} ({point})")
        ax.axvline(TARGET_ERROR, color="0.6", lw=0.8, ls=":")
        ax.axhline(TARGET_TIME, color="0.6", lw=0.8, ls=":")
        ax.set_xlabel(f"relative error of {title}")
        ax.set_title(title)
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("run time per cycle-converged point [s]")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _plot_stress(path: Path, rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    t = np.array([r["time_s"] for r in rows])
    ok = np.array([r["status"] == "converged" for r in rows])
    axes[0].hist(np.log10(t), bins=40, color="C0")
    axes[0].set_xlabel("log10 run time [s]")
    axes[0].set_ylabel("points")
    axes[0].set_title(f"{ok.sum()} of {len(rows)} converged")
    gap = np.array([r["gap_um"] for r in rows])
    spd = np.array([r["speed_rpm"] for r in rows])
    sc = axes[1].scatter(gap, spd, c=np.log10(t), s=8, cmap="viridis")
    if np.any(~ok):
        axes[1].scatter(gap[~ok], spd[~ok], marker="x", color="r", s=30, label="failed")
        axes[1].legend(fontsize=7)
    axes[1].set_xscale("log")
    axes[1].set_yscale("log")
    axes[1].set_xlabel("gap [um]")
    axes[1].set_ylabel("speed [rpm]")
    fig.colorbar(sc, ax=axes[1], label="log10 run time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
