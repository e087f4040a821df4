"""Stress test of the chamber model with a volatile liquid (water in air, quasi1d/humid.py).

Seeded random points on synthetic sin^2 chamber tables (4-7 lobes, 5 cc - 0.5 L): air of
constant cp at 0.5-2 bar and 0-40 C, relative humidity 0-1, pressure ratio 1.5-10, speed
1000-12000 rpm, nozzle gaps 5-100 um leaking the gas-water mixture; half the points
inject water (0.1-5 kg per kg of air at 5-90 C), half draw it in with the gas (gas
volume fraction from 1 - 0.7 / vi, short of a hydraulic lock, to 0.99); the water's
exchange time constant 1-100 ms.  Every point must converge; NaN, a negative gas,
liquid or vapour mass, or a non-positive pressure or temperature anywhere along the
converged cycle counts as a failure, and so does an exception.  Target: zero failures.

Measured (seed 20261129, 60 points, 2026-11-29, 2 cores shared with another job): 60
converged, none invalid, no errors; 39 evaporate on balance, 21 condense; balances within
9.4e-8; median 0.88 s a point (numpy: the liquid cases are not compiled), the slowest
39.5 s (water drawn in at a gas volume fraction of 0.73, tau 1.8 ms: the stiffest
exchange).  It found a defect on its way: the cycle's first guess put a discharging
chamber's whole liquid in its shrinking volume and stopped small machines with "the
liquid fills the chamber before the discharge opens" (quasi1d/events.initial_state).
Rerun 2026-11-30 with three jobs on the 2 cores: 59 converged; the slowest point (37,
the one above) stopped at the 60-s budget after 6 periods (61.7 s alone on the idle
machine).  Its batch periods carry 61 states through ros23 (15 s each), its chord
periods the state alone (0.7 s); a chord period that cut the residual 2x brought the
batch back (quasi1d/cycle.py CHORD_GAIN), and that batch ran out the budget.  Since
(2026-11-30, cycle._chord_pays: chord periods go on while they reach CHORD_GAIN sooner
than a batch would): 60 converged, none invalid, the slowest 42.3 s (point 37 39.5 s,
6 periods, balances 1e-11 / 1.5e-10), median 0.80 s (another job on the other core).
Output: bench/results/humid_stress.csv.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports
from rotorflow.quasi1d.chamber import prepare
from rotorflow.quasi1d.cycle import solve
from rotorflow.quasi1d.fluids import make_fluid
from rotorflow.quasi1d.model import build
from rotorflow.quasi1d.result import make_result
from rotorflow.quasi1d.synthetic import scaled_table

from .bench_quasi1d import _write_csv, attempt, classify
from .bench_real_fluid import _defects, _logu

POINTS = 60
SEED = 20261129
NUMERICS = Numerics(max_cycles=40)


def stress_point(rng: np.random.Generator) -> dict:
    """One random humid-air point with water injected or drawn in, and its machine."""
    vr = float(rng.uniform(1.2, 4.0))
    injected = bool(rng.random() < 0.5)
    return {"p_suction_bar": float(rng.uniform(0.5, 2.0)), "pressure_ratio": _logu(rng, 1.5, 10.0),
            "T_suction_K": float(rng.uniform(273.15, 313.15)), "humidity": float(rng.random()),
            "volume_ratio": vr, "speed_rpm": _logu(rng, 1000.0, 12000.0),
            "gap_um": _logu(rng, 5.0, 100.0), "lobes": int(rng.integers(4, 8)),
            "v_max_m3": _logu(rng, 5e-6, 5e-4), "injected": injected,
            "water_ratio": _logu(rng, 0.1, 5.0) if injected else 0.0,
            "T_water_K": float(rng.uniform(278.15, 363.15)) if injected else None,
            "gas_volume_fraction": 1.0 if injected else float(rng.uniform(1.0 - 0.7 / vr, 0.99)),
            "tau_ms": _logu(rng, 1.0, 100.0)}


def _operating(pt: dict) -> Operating:
    d = {"p_suction_bar": pt["p_suction_bar"],
         "p_discharge_bar": pt["p_suction_bar"] * pt["pressure_ratio"],
         "T_suction_K": pt["T_suction_K"], "speed_rpm": pt["speed_rpm"],
         "volume_ratio": pt["volume_ratio"], "heat_capacity": "constant",
         "liquid_volatile": "Water", "suction_relative_humidity": pt["humidity"],
         "oil_cp_J_kgK": 4180.0, "oil_time_constant_ms": pt["tau_ms"]}
    if pt["injected"]:
        d.update(oil_mass_ratio=pt["water_ratio"], T_oil_K=pt["T_water_K"])
    else:
        d.update(gas_volume_fraction=pt["gas_volume_fraction"], liquid_density_kg_m3=998.0)
    return Operating.from_section(d, "stress")


def _liquid_defects(res) -> list[str]:
    """Liquid or vapour mass of a live slot below minus rtol times its chamber's content
    (gas mass times the larger of 1 and the liquid ratio) along the converged cycle.  A
    newborn chamber's liquid, which only leakage brings before the water enters at
    suction closing, sits at zero within the integration's error: -1.9e-13 kg in a
    chamber of 5.3e-8 kg of gas was seen; a sign error would show at the content's scale."""
    sol = res.solution
    model, n = sol.model, sol.model.n
    th, ys = np.asarray(sol.run.trace_theta), np.asarray(sol.run.trace_y)
    alive = th[:, None] + model.geo.period * np.arange(n) <= model.geo.death * (1 + 1e-12)
    tol = NUMERICS.rtol * ys[:, :n] * max(1.0, model.liquid_ratio)
    return [f"{what} mass negative" for what, b in (("liquid", 2), ("vapour", 4))
            if np.any((ys[:, b * n:(b + 1) * n] + tol)[alive] < 0.0)]


def run_point(pt: dict) -> dict:
    out = dict(pt)

    def run():
        op = _operating(pt)
        table = scaled_table(pt["v_max_m3"], pt["lobes"])
        geo = prepare(table, op.volume_ratio, None, None, op.speed_rpm, NUMERICS.vanish_fraction)
        leak = Leakage(gap_m=pt["gap_um"] * 1e-6, model="nozzle", coefficient=1.0)
        return make_result(solve(build(geo, make_fluid(op, geo.v_max / geo.v_discharge), op,
                                       leak, Ports("ideal")), NUMERICS))

    res = attempt(out, run)
    if res is None:
        return out
    f = res.figures
    out.update(cycles=f["cycles"], volumetric_efficiency=f["volumetric_efficiency"],
               indicated_power_W=f["indicated_power_W"],
               evaporated_kg_s=f["evaporated_kg_s"],
               discharge_vapour_fraction=f["discharge_vapour_fraction"],
               mass_balance_error=f["mass_balance_error"],
               energy_balance_error=f["energy_balance_error"])
    return classify(out, res, _defects(res) + _liquid_defects(res))


def run(results_dir: Path, n: int = POINTS, seed: int = SEED) -> list[dict]:
    rng = np.random.default_rng(seed)
    rows = [run_point(stress_point(rng)) for _ in range(n)]
    results_dir.mkdir(parents=True, exist_ok=True)
    _write_csv(results_dir / "humid_stress.csv", rows)
    status = [r["status"] for r in rows]
    times = np.array([r["time_s"] for r in rows])
    summary = {"points": n, "converged": status.count("converged"),
               "failures": n - status.count("converged"),
               "median_s": float(np.median(times)), "max_s": float(np.max(times)),
               "evaporating": sum(1 for r in rows if r.get("evaporated_kg_s", 0) > 0)}
    print(summary)
    for r in rows:
        if r["status"] != "converged":
            print(r["status"], r.get("message", ""), {k: r[k] for k in
                  ("injected", "pressure_ratio", "gap_um", "tau_ms", "speed_rpm")})
    return rows


if __name__ == "__main__":
    run(Path(__file__).resolve().parent / "results")
