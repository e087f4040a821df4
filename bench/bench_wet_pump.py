"""A CoolProp fluid pumped wet (its own liquid and vapour, homogeneous equilibrium): run
time, periods and books of n-pentane pumped from 1 to 4 bar on the 1-1 vacuum pump's
rotors (examples/screw_pump_vacuum.toml, its [operating] changed as below) at suction
qualities from 0.5 down to 0.05, where the isentrope from suction ends as subcooled
liquid and the discharging chambers condense.  Target (issue 14): every quality
converged within the default 60-s budget ([numerics] max_seconds), books to 1e-6.

Columns: the wall and CPU time of the operating point (the chamber table built once,
before), the periods and how many carried the cycle solver's perturbed batch (Newton's
Jacobian; the rest integrate the state alone), the books, indicated power and eta_v.

Measured 2026-11-30 (one process, the other core busy with a stress bench), at quality
0.5 / 0.3 / 0.2 / 0.1 / 0.05: all converged, 1.4 / 4.8 / 5.1 / 16.7 / 24.3 s, 4 / 4 / 4
/ 9 / 9 periods of which 3 / 3 / 3 / 2 / 2 carried the batch, books within 4e-8.
Before, quality 0.05 took 82 s (15 periods, 9 with the batch; the same machine): the
batch's Newton steps landed across the bubble line and never beat the first iterate,
and the state's table was read twice a right-hand side (quasi1d/cycle.py PROBE_GAIN;
quasi1d/model.py).

    python -m bench.bench_wet_pump
"""

from __future__ import annotations

import copy
import time
from pathlib import Path

import CoolProp.CoolProp as CP

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.quasi1d import case_settings, cycle, simulate
from rotorflow.workflow.case import case_from_raw, load_toml

from .bench_quasi1d import _write_csv

REPO = Path(__file__).resolve().parents[1]
CASE = REPO / "examples" / "screw_pump_vacuum.toml"
QUALITIES = (0.5, 0.3, 0.2, 0.1, 0.05)
FLUID = "n-Pentane"
P_SUCTION_BAR, P_DISCHARGE_BAR, SPEED_RPM = 1.0, 4.0, 3000.0
BUDGET_S = 60.0


def _raw(quality: float) -> dict:
    raw = copy.deepcopy(load_toml(CASE))
    T_sat = CP.PropsSI("T", "P", P_SUCTION_BAR * 1e5, "Q", quality, FLUID)
    raw["operating"].update(p_suction_bar=P_SUCTION_BAR, p_discharge_bar=P_DISCHARGE_BAR,
                            T_suction_K=round(T_sat, 2), speed_rpm=SPEED_RPM,
                            fluid=f"CoolProp::{FLUID}", suction_quality=quality)
    raw.setdefault("numerics", {})["max_seconds"] = BUDGET_S
    return raw


def run(results_dir: Path) -> list[dict]:
    case = case_from_raw(_raw(QUALITIES[0]), CASE)
    table = chamber_table(case, build_machine(case))
    batches = []
    integrate = cycle.integrate_period

    def counting(model, y0, *args, **kw):
        batches.append(y0.shape[0] > 1)
        return integrate(model, y0, *args, **kw)

    rows = []
    cycle.integrate_period = counting
    try:
        for q in QUALITIES:
            batches.clear()
            op, leak, ports, numerics, mech = case_settings(_raw(q), str(CASE))
            t0, c0 = time.perf_counter(), time.process_time()
            f = simulate(table, op, leak, ports, numerics, mech).figures
            wall = time.perf_counter() - t0
            rows.append({
                "suction_quality": q, "wall_s": round(wall, 1),
                "cpu_s": round(time.process_time() - c0, 1), "converged": f["converged"],
                "periods": f["cycles"], "batch_periods": sum(batches),
                "mass_balance_error": f["mass_balance_error"],
                "energy_balance_error": f["energy_balance_error"],
                "indicated_power_W": f["indicated_power_W"],
                "volumetric_efficiency": f["volumetric_efficiency"],
                "within_budget": f["converged"] and wall < BUDGET_S})
    finally:
        cycle.integrate_period = integrate
    _write_csv(Path(results_dir) / "wet_pump.csv", rows)
    return rows


if __name__ == "__main__":
    for row in run(Path(__file__).parent / "results"):
        print(row)
