"""Seed 003's vacuum pump (its Table 2) against the quasi-1D model, row by row.

Table 2 lists, at 3001 rpm and suction 0.01 to 0.39 bar, the delivered flow, the
volumetric efficiency, the power and the adiabatic efficiency of a 1-1 screw vacuum pump
whose geometry the seed does not give.  The pump is therefore chosen beforehand in
``examples/screw_pump_vacuum.toml`` (its comments give the reasons); one coefficient of
that file is fitted on one row (:data:`FITTED`, named in the file), and every other row
is a prediction of :func:`rotorflow.quasi1d.simulate` on the same chamber table, the
suction pressure the only input that changes.

The comparison is the table's own: eta_v = delivered flow / displacement (the flow over
eta_v is 6.247 m3/min in every row), the model's ``volumetric_efficiency`` (delivered
mass over suction density times trapped volume); power = shaft power, the model's
``shaft_power_W`` (indicated plus bearing losses), since a dry pump's table gives one
power.  Targets (issue 14): |eta_v error| <= 0.05 absolute and |power error| <= 15 % on
every predicted row, and the table's trend, eta_v rising with suction pressure.

    python -m bench.bench_pump_vacuum [--rows 0.01,0.11,0.39] [--fit]
"""

from __future__ import annotations

import copy
import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path

from scipy.optimize import brentq

from rotorflow.quasi1d import case_settings, simulate

ROOT = Path(__file__).resolve().parent.parent
REFERENCE = ROOT / "tests" / "data" / "reference" / "screw_pump_vacuum.csv"
EXAMPLE = ROOT / "examples" / "screw_pump_vacuum.toml"
#: The row the example's one fitted coefficient was fitted on (suction pressure, bar):
#: it is reported but is no prediction, and the targets are not checked on it.
FITTED = 0.11
#: Issue 14's targets on every predicted row.
ETA_V_TOL = 0.05  # absolute
POWER_TOL = 0.15  # relative


@dataclass(frozen=True)
class Row:
    p_suction_bar: float
    speed_rpm: float
    flow_m3_min: float
    eta_v: float
    power_kW: float


def read_table(path: Path = REFERENCE) -> list[Row]:
    with open(path, newline="") as f:
        return [Row(float(r["p_suction_bar"]), float(r["speed_rpm"]), float(r["flow_m3_min"]),
                    float(r["eta_v"]), float(r["power_kW"])) for r in csv.DictReader(f)]


def predict(raw: dict, table, row: Row, where: str = str(EXAMPLE)) -> dict:
    """The model at the row's suction pressure and speed, all else as in the case."""
    return point(raw, table, where, p_suction_bar=row.p_suction_bar, speed_rpm=row.speed_rpm)


def point(raw: dict, table, where: str, **operating) -> dict:
    """The model's figures of the case with its [operating] keys updated by ``operating``
    (on the chamber table ``table``, built once for every row of a pump's table)."""
    raw = copy.deepcopy(raw)
    raw["operating"].update(operating)
    op, leak, ports, numerics, mech = case_settings(raw, where)
    t0 = time.process_time()
    fig = simulate(table, op, leak, ports, numerics, mech).figures
    return {"eta_v": fig["volumetric_efficiency"], "power_kW": fig["shaft_power_W"] / 1e3,
            "indicated_kW": fig["indicated_power_W"] / 1e3,
            "flow_m3_min": fig["suction_volume_flow_L_min"] / 1e3,
            "T_discharge_K": fig["discharge_temperature_K"], "converged": fig["converged"],
            "mass_balance_error": fig["mass_balance_error"],
            "energy_balance_error": fig["energy_balance_error"],
            "leakage_kg_s": fig["leakage_kg_s"], "mass_flow_kg_s": fig["mass_flow_kg_s"],
            "liquid_leakage_kg_s": fig.get("liquid_leakage_kg_s"),
            "liquid_flow_kg_s": fig.get("liquid_flow_kg_s"),
            "cpu_s": time.process_time() - t0}


def fit_coefficient(raw: dict, table, row: Row, lo: float = 1e-4, hi: float = 1.0,
                    where: str = str(EXAMPLE)) -> float:
    """The blow-holes' flow coefficient ([leakage.blow-hole] coefficient) that gives the
    row's eta_v: the example's one fitted coefficient.  eta_v falls as the coefficient
    rises (more gas back through the holes), so a bracket in log c and Brent's method;
    3 significant figures (the table's eta_v has 3)."""
    def miss(log_c: float) -> float:
        r = copy.deepcopy(raw)
        r["leakage"].setdefault("blow-hole", {})["coefficient"] = 10.0 ** log_c
        return predict(r, table, row, where)["eta_v"] - row.eta_v

    x = brentq(miss, math.log10(lo), math.log10(hi), xtol=1e-4)
    return float(f"{10.0 ** x:.3g}")


def compare(rows: list[Row], preds: list[dict], fitted: float = FITTED) -> list[dict]:
    """Per row: measured, model, errors (eta_v absolute, power relative) and whether the
    row is a prediction (every row but the fitted one) and meets the targets."""
    out = []
    for r, p in zip(rows, preds, strict=True):
        d_eta = p["eta_v"] - r.eta_v
        d_pow = p["power_kW"] / r.power_kW - 1.0
        predicted = abs(r.p_suction_bar - fitted) > 1e-9
        out.append({"p_suction_bar": r.p_suction_bar, "eta_v_table": r.eta_v,
                    "eta_v_model": p["eta_v"], "eta_v_error": d_eta,
                    "power_kW_table": r.power_kW, "power_kW_model": p["power_kW"],
                    "indicated_kW_model": p["indicated_kW"], "power_error": d_pow,
                    "T_discharge_K": p["T_discharge_K"], "predicted": predicted,
                    "eta_v_ok": abs(d_eta) <= ETA_V_TOL, "power_ok": abs(d_pow) <= POWER_TOL,
                    "converged": p["converged"], "cpu_s": p["cpu_s"]})
    return out


def rising(values: list[float]) -> bool:
    """The trend test on the model: strictly rising from row to row.  (Table 2's own
    eta_v dips once, 0.806 -> 0.801 at 0.11 -> 0.13 bar, and steps up at 0.15 bar: the
    table's trend is read as rising overall, the model's is asked to rise at every step.)"""
    return all(b > a for a, b in zip(values, values[1:], strict=False))


def run(rows: list[Row], raw: dict, table, where: str = str(EXAMPLE)) -> list[dict]:
    """Every row through the model on one chamber table (the case's, built by the caller:
    the case file is the workflow's to read, bench/bench_pump_vacuum.py:pump_table)."""
    return compare(rows, [predict(raw, table, r, where) for r in rows])


def format_report(res: list[dict]) -> str:
    head = (f"{'p_s bar':>8} {'eta_v tab':>9} {'model':>7} {'err':>7} {'P tab kW':>9} "
            f"{'model':>7} {'err %':>7}  role")
    lines = [head]
    for r in res:
        role = "predicted" if r["predicted"] else "FITTED"
        flag = "" if not r["predicted"] or (r["eta_v_ok"] and r["power_ok"]) else "  miss"
        lines.append(f"{r['p_suction_bar']:8.2f} {r['eta_v_table']:9.3f} {r['eta_v_model']:7.3f} "
                     f"{r['eta_v_error']:+7.3f} {r['power_kW_table']:9.3f} "
                     f"{r['power_kW_model']:7.3f} {100 * r['power_error']:+7.1f}  {role}{flag}")
    eta = [r["eta_v_model"] for r in res]
    lines.append(f"model eta_v rising at every step: {rising(eta)}")
    return "\n".join(lines)
