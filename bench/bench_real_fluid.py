"""Stress test of the chamber model with real refrigerants near saturation (issue 14).

Seeded random points of R134a, R290, R1234ze(E) and CO2: evaporating temperature in each
fluid's range, suction superheat 0-10 K (below 0.2 K: saturated vapour, suction_quality
1), one point in five a wet suction (quality 0.9-1, at the saturation temperature),
pressure ratio 1.5-6 (CO2's discharge capped at 140 bar, above its critical pressure),
volume ratio 0.75-1.15 times the one that reaches the discharge pressure on the suction
isentrope, speed 1000-12000 rpm, gaps 2-100 um (nozzle leakage), 4-7 lobes, 5 cc - 0.5 L
(synthetic sin^2 chamber tables).  Every point must converge; NaN, or a negative or zero
mass, pressure or temperature anywhere along the converged cycle (every traced state of
every chamber), counts as a failure, and so does an exception.  Target: zero failures.

Tables.  A table per point would cost ~1 s of CoolProp flashes a point; here each fluid
gets one table, built once, over the union of its points' reachable ranges
(:func:`rotorflow.quasi1d.coolprop_table.reachable_box`), at UNION_NODES per axis, and the
chamber model is built on it directly (:func:`rotorflow.quasi1d.model.build`; the checks
of :func:`~rotorflow.quasi1d.coolprop_fluid.tabulated` on the case's input are not needed:
the points are valid by construction).  The union's cells are up to twice as wide as a
point's own table's; every PRODUCT_EVERY-th point is also run the way a case runs
(:func:`rotorflow.quasi1d.simulate`, its own 200 x 200 table) and the relative
difference of flow and power between the two runs is recorded (it measures what the
shared table costs in accuracy).

Measured (seed 20260601, 500 points, 105 wet; 2026-11-29, after the table took the
bubble line apart, :mod:`rotorflow.quasi1d.coolprop_bubble`): 500 converged, none
invalid, no errors.  Five points (CO2 and R290) are machines that deliver nothing
(small, slow, wide gaps: the leakage exceeds the displacement, volumetric efficiency
-0.001 to -0.88); they converge in 6-26 periods.  Tables 20 s, median 0.036 s a
point with the compiled kernel (0.25 s in numpy), 22 s for the 500; the 50 product runs
agree with the shared table within 1.3e-4 in flow and power.  Again 2026-11-30, after the
cycle solver's probe of the plain iteration (quasi1d/cycle.py PROBE_GAIN): 500
converged, 1995 periods in all (2003 before, numpy), median 0.035 s a point (compiled,
the other core busy); a draft that let the probe's period into Newton's iteration
left one CO2 point (156) at the 30-period limit.

Outputs in results_dir: real_fluid_stress.csv (one row a point) and real_fluid_stress.png.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import CoolProp.CoolProp as CP
import numpy as np

from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
from rotorflow.quasi1d.chamber import prepare
from rotorflow.quasi1d.coolprop_fluid import SATURATION_T_TOLERANCE_K, TabulatedFluid
from rotorflow.quasi1d.coolprop_table import reachable_box
from rotorflow.quasi1d.cycle import solve
from rotorflow.quasi1d.model import build
from rotorflow.quasi1d.result import make_result
from rotorflow.quasi1d.synthetic import scaled_table

from .bench_quasi1d import _write_csv, attempt, classify

# evaporating temperature range (C) and discharge-pressure cap (bar) of each fluid
FLUIDS = {"R134a": (-20.0, 15.0, None), "R290": (-25.0, 10.0, None),
          "R1234ze(E)": (-15.0, 15.0, None), "CO2": (-35.0, 5.0, 140.0)}
POINTS = 500
SEED = 20260601
WET_FRACTION = 0.2
# 300 nodes a side over the union of a fluid's ranges: the union spans up to ~2x a
# point's own range in u (its ln rho span is set by the pressure margins, nearly the
# same), so its cells are at most twice as wide as the default 200 x 200 table's.
UNION_NODES = 300
PRODUCT_EVERY = 10
NUMERICS = Numerics(max_cycles=30)


def _logu(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def stress_point(rng: np.random.Generator) -> dict:
    """One random refrigerant point near saturation, and its machine."""
    name = list(FLUIDS)[int(rng.integers(len(FLUIDS)))]
    lo, hi, cap = FLUIDS[name]
    st = CP.AbstractState("HEOS", name)
    st.update(CP.QT_INPUTS, 1.0, 273.15 + rng.uniform(lo, hi))
    ps, Tsat = st.p(), st.T()
    pr = _logu(rng, 1.5, 6.0)
    pd = min(ps * pr, cap * 1e5) if cap else ps * pr
    if rng.random() < WET_FRACTION:
        q, sh = float(rng.uniform(0.9, 1.0)), 0.0
    else:
        sh = float(rng.uniform(0.0, 10.0))
        q = 1.0 if sh < 2 * SATURATION_T_TOLERANCE_K else None  # saturated vapour
    Ts = Tsat + (sh if q is None else 0.0)
    if q is None:
        st.update(CP.PT_INPUTS, ps, Ts)
    else:
        st.update(CP.PQ_INPUTS, ps, q)
    rho1, s1 = st.rhomass(), st.smass()
    st.update(CP.PSmass_INPUTS, pd, s1)
    vr = float(np.clip(st.rhomass() / rho1 * rng.uniform(0.75, 1.15), 1.2, 6.0))
    return {"fluid": name, "p_suction_bar": ps / 1e5, "p_discharge_bar": pd / 1e5,
            "T_suction_K": Ts, "superheat_K": sh, "suction_quality": q,
            "volume_ratio": vr, "speed_rpm": _logu(rng, 1000.0, 12000.0),
            "gap_um": _logu(rng, 2.0, 100.0), "lobes": int(rng.integers(4, 8)),
            "v_max_m3": _logu(rng, 5e-6, 5e-4)}


def _operating(pt: dict) -> Operating:
    d = {k: pt[k] for k in ("p_suction_bar", "p_discharge_bar", "T_suction_K", "speed_rpm",
                            "volume_ratio")}
    if pt["suction_quality"] is not None:
        d["suction_quality"] = pt["suction_quality"]
    return Operating.from_section({**d, "fluid": f"CoolProp::{pt['fluid']}"}, "stress")


def _leak(pt):
    return Leakage(gap_m=pt["gap_um"] * 1e-6, model="nozzle", coefficient=1.0)


def union_tables(points: list[dict]) -> dict:
    """One table per fluid over the union of its points' reachable ranges."""
    boxes: dict[str, list] = {}
    for pt in points:
        op = _operating(pt)
        geo = prepare(scaled_table(pt["v_max_m3"], pt["lobes"]), op.volume_ratio, None, None,
                      op.speed_rpm, NUMERICS.vanish_fraction)
        box = reachable_box(pt["fluid"], op.p_suction_Pa, op.p_discharge_Pa, op.T_suction_K,
                            pt["suction_quality"], op.T_suction_K, op.T_suction_K,
                            geo.v_max / geo.v_discharge)
        boxes.setdefault(pt["fluid"], []).append(box)
    out = {}
    for name, bx in boxes.items():
        b = np.array(bx)
        out[name] = TabulatedFluid.build(name, b[:, 0].min(), b[:, 1].max(), b[:, 2].min(),
                                         b[:, 3].max(), nodes=UNION_NODES)
    return out


def _defects(res) -> list[str]:
    """NaN or non-positive mass, pressure or temperature along the converged cycle: the
    raw masses of every slot alive by its age at every traced step (the traces hide a
    slot whose mass is not positive as inactive), and p and T of every live slot."""
    bad = []
    sol = res.solution
    model, n = sol.model, sol.model.n
    th, ys = np.asarray(sol.run.trace_theta), np.asarray(sol.run.trace_y)
    alive = th[:, None] + model.geo.period * np.arange(n) <= model.geo.death * (1 + 1e-12)
    mass = ys[:, :n][alive]
    if not np.all(np.isfinite(ys)):
        bad.append("state not finite")
    elif np.any(mass < 0):
        bad.append("mass negative")
    m = res.machine
    live = np.isfinite(m["m_kg"])
    for key in ("p_Pa", "T_K"):
        for where, v in (("chamber", res.chamber[key]), ("machine", m[key][live])):
            if not np.all(np.isfinite(v)):
                bad.append(f"{where} {key} not finite")
            elif np.any(v <= 0):
                bad.append(f"{where} {key} not positive")
    f = res.figures
    if not all(math.isfinite(f[k]) for k in ("mass_flow_kg_s", "indicated_power_W",
                                             "mass_balance_error", "energy_balance_error")):
        bad.append("figures not finite")
    return bad


def run_point(pt: dict, fluid) -> dict:
    """Simulate one point on the shared table ``fluid``; classify the outcome."""
    out = dict(pt)

    def run():
        op = _operating(pt)
        table = scaled_table(pt["v_max_m3"], pt["lobes"])
        geo = prepare(table, op.volume_ratio, None, None, op.speed_rpm,
                      NUMERICS.vanish_fraction)
        return make_result(solve(build(geo, fluid, op, _leak(pt), Ports("ideal")), NUMERICS))

    res = attempt(out, run)
    if res is None:
        return out
    f = res.figures
    bad = _defects(res)
    out.update(cycles=f["cycles"], mass_flow_kg_s=f["mass_flow_kg_s"],
               indicated_power_W=f["indicated_power_W"],
               volumetric_efficiency=f["volumetric_efficiency"],
               discharge_temperature_K=f["discharge_temperature_K"],
               mass_balance_error=f["mass_balance_error"],
               energy_balance_error=f["energy_balance_error"],
               p_min_bar=float(np.min(res.chamber["p_Pa"])) / 1e5,
               p_max_bar=float(np.max(res.chamber["p_Pa"])) / 1e5,
               T_min_K=float(np.min(res.chamber["T_K"])),
               method=res.solution.run.method)
    return classify(out, res, bad)


def product_check(pt: dict, row: dict) -> dict:
    """The point run as a case runs (its own table); relative differences to ``row``."""
    try:
        f = simulate(scaled_table(pt["v_max_m3"], pt["lobes"]), _operating(pt), _leak(pt),
                     Ports("ideal"), NUMERICS).figures
    except Exception as e:
        return {"product_status": "error",
                "product_message": f"{type(e).__name__}: {e}".splitlines()[0]}
    if row["status"] != "converged" or not f["converged"]:
        return {"product_status": "converged" if f["converged"] else "not converged"}
    return {"product_status": "converged",
            "product_diff_mass_flow": abs(f["mass_flow_kg_s"] / row["mass_flow_kg_s"] - 1),
            "product_diff_power": abs(f["indicated_power_W"] / row["indicated_power_W"] - 1)}


def stress(results_dir: Path, n: int = POINTS, seed: int = SEED) -> dict:
    rng = np.random.default_rng(seed)
    points = [stress_point(rng) for _ in range(n)]
    t0 = time.perf_counter()
    fluids = union_tables(points)
    t_tables = time.perf_counter() - t0
    rows = []
    try:
        from tqdm import tqdm

        it = tqdm(points, desc="real-fluid stress", unit="pt", mininterval=5.0)
    except ImportError:  # pragma: no cover
        it = points
    for k, pt in enumerate(it):
        row = run_point(pt, fluids[pt["fluid"]])
        if k % PRODUCT_EVERY == 0:
            row.update(product_check(pt, row))
        rows.append(row)
    _write_csv(Path(results_dir) / "real_fluid_stress.csv", rows)
    _plot(Path(results_dir) / "real_fluid_stress.png", rows)
    return summarise(rows, seed, t_tables)


def summarise(rows: list[dict], seed: int, t_tables: float) -> dict:
    status = [r["status"] for r in rows]
    times = np.array([r["time_s"] for r in rows])
    checked = [r for r in rows if "product_diff_mass_flow" in r]
    diff = [max(r["product_diff_mass_flow"], r["product_diff_power"]) for r in checked]
    return {
        "points": len(rows), "seed": seed,
        "wet": sum(r["suction_quality"] is not None for r in rows),
        "converged": status.count("converged"),
        "not_converged": status.count("not converged"),
        "invalid": status.count("invalid"), "errors": status.count("error"),
        "failures_by_fluid": {name: sum(r["status"] != "converged" for r in rows
                                        if r["fluid"] == name) for name in FLUIDS},
        "table_build_s": t_tables,
        "time_median_s": float(np.median(times)),
        "time_max_s": float(times.max()), "time_total_s": float(times.sum()),
        "product_checked": len(checked),
        "product_failures": sum(r.get("product_status") not in (None, "converged")
                                for r in rows),
        "product_diff_max": max(diff) if diff else None,
    }


def run(results_dir: Path) -> list[dict]:
    results_dir = Path(results_dir)
    results_dir.mkdir(parents=True, exist_ok=True)
    return [{"real_fluid_stress": stress(results_dir)}]


def _plot(path: Path, rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    ok = np.array([r["status"] == "converged" for r in rows])
    t = np.array([r["time_s"] for r in rows])
    for k, name in enumerate(FLUIDS):
        sel = np.array([r["fluid"] == name for r in rows])
        axes[0].hist(np.log10(t[sel]), bins=30, histtype="step", color=f"C{k}", label=name)
        pr = np.array([r["p_discharge_bar"] / r["p_suction_bar"] for r in rows])[sel]
        sh = np.array([r["superheat_K"] - (0 if r["suction_quality"] is None
                                           else 1 - r["suction_quality"]) * 100
                       for r in rows])[sel]
        axes[1].scatter(pr, sh, s=8, color=f"C{k}", label=name)
    if np.any(~ok):
        bad = [r for r, good in zip(rows, ok, strict=True) if not good]
        axes[1].scatter([r["p_discharge_bar"] / r["p_suction_bar"] for r in bad],
                        [r["superheat_K"] for r in bad], marker="x", color="r", s=40,
                        label="failed")
    axes[0].set_xlabel("log10 run time [s]")
    axes[0].set_ylabel("points")
    axes[0].set_title(f"{ok.sum()} of {len(rows)} converged")
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("pressure ratio")
    axes[1].set_ylabel("superheat [K]; wet: -100 (1 - quality)")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
