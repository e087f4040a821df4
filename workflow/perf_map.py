"""`rotorflow map CASE.toml`: a performance map of one machine over speed and pressure.

The map's grid is the driven rotor's speed against the discharge pressure (or, for
vacuum duty, the suction pressure), from the case's optional [map] section:

    [map]
    speed_rpm = [1500, 4500]      # range of the driven rotor's speed
    p_discharge_bar = [1.5, 4.0]  # or p_suction_bar = [...]: the second axis
    points = [10, 10]             # along speed, along pressure

Without [map] the map spans half to one and a half times the case's speed and its
pressure rise. A pressure range of a decade or more (vacuum duty) is spaced evenly in its
logarithm, and drawn so. The geometry does not change across a map, so the chamber table
is built once and handed to every point (scattered once to every Dask worker); each point is one
call of the product's quasi-1D model (:func:`rotorflow.quasi1d.simulate`), nothing
re-implemented. A point that fails or does not converge stays in the map as a row with
its message: the map never drops a point silently.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

#: Share of the case's speed and pressure rise that the default map spans either side.
DEFAULT_SPAN = 0.5
DEFAULT_POINTS = 10
#: A map point's balances must close to this (issue 19; the cycle's own tolerance is tighter).
BALANCE_LIMIT = 1e-6
#: Nodes a side of a map's shared CoolProp table: it spans the union of the points'
#: ranges, up to ~2x one point's, so 300 keeps its cells within the default 200-node
#: table's size (the real-fluid stress bench's reasoning; within 1.3e-4 of per-point tables).
SHARED_TABLE_NODES = 300
SECTION_KEYS = {"speed_rpm", "p_discharge_bar", "p_suction_bar", "points"}
#: A pressure axis spanning this ratio or more is spaced evenly in its logarithm.
LOG_DECADE = 10.0
#: The columns of map.csv, in order (units in the names).
COLUMNS = (
    "speed_rpm", "p_suction_bar", "p_discharge_bar", "pressure_ratio", "converged",
    "mass_flow_kg_s", "suction_volume_flow_m3_min", "indicated_power_W", "shaft_power_W",
    "specific_power_kW_per_m3_min", "volumetric_efficiency", "adiabatic_efficiency",
    "adiabatic_efficiency_shaft", "isothermal_efficiency", "discharge_temperature_K",
    "mass_balance_error", "energy_balance_error", "cycles", "seconds", "message",
)


@dataclass(frozen=True)
class MapSpec:
    """The axes of a map: speeds (driven rotor, rpm) and pressures (bar) of ``pressure``."""

    speeds: tuple[float, ...]
    pressure: str  # "p_discharge_bar" or "p_suction_bar"
    pressures: tuple[float, ...]

    @property
    def size(self) -> int:
        return len(self.speeds) * len(self.pressures)


def map_spec(raw: dict, where: str) -> MapSpec:
    """The map a parsed case asks for ([map], or the default around its operating point)."""
    section = raw.get("map", {})
    if not isinstance(section, dict):
        raise CaseError(f"[map] in {where} must be a table")
    unknown = sorted(set(section) - SECTION_KEYS)
    if unknown:
        raise CaseError(f"unknown key '{unknown[0]}' in [map] of {where} "
                        f"(known: {', '.join(sorted(SECTION_KEYS))})")
    op = raw.get("operating", {})
    for key in ("speed_rpm", "p_suction_bar", "p_discharge_bar"):
        if key not in op:
            raise CaseError(f"[operating] of {where} needs {key} for a performance map")
    if "p_discharge_bar" in section and "p_suction_bar" in section:
        raise CaseError(f"[map] of {where} maps one pressure: give p_discharge_bar or "
                        "p_suction_bar, not both")
    pressure = "p_suction_bar" if "p_suction_bar" in section else "p_discharge_bar"
    ps, pd, n = float(op["p_suction_bar"]), float(op["p_discharge_bar"]), float(op["speed_rpm"])
    rise = pd - ps
    if pressure == "p_discharge_bar":
        default_p = (ps + (1 - DEFAULT_SPAN) * rise, ps + (1 + DEFAULT_SPAN) * rise)
    else:
        default_p = (ps * (1 - DEFAULT_SPAN), ps * (1 + DEFAULT_SPAN))
    speed = _range(section, "speed_rpm", (n * (1 - DEFAULT_SPAN), n * (1 + DEFAULT_SPAN)), where)
    press = _range(section, pressure, default_p, where)
    points = section.get("points", [DEFAULT_POINTS, DEFAULT_POINTS])
    if (not isinstance(points, list) or len(points) != 2
            or not all(isinstance(k, int) and not isinstance(k, bool) and 2 <= k <= 100
                       for k in points)):
        raise CaseError(f"points in [map] of {where} must be two integers from 2 to 100 "
                        f"(along speed, along pressure), got {points!r}")
    spec = MapSpec(_linspace(*speed, points[0]), pressure, _pressures(*press, points[1]))
    if pressure == "p_discharge_bar":
        other_key, other = "p_suction_bar", ps
        bad = [p for p in spec.pressures if p <= ps]
    else:
        other_key, other = "p_discharge_bar", pd
        bad = [p for p in spec.pressures if p >= pd]
    if bad:
        raise CaseError(f"{pressure} = {bad[0]:g} in the map of {where} leaves no pressure "
                        f"rise against the case's {other_key} = {other:g}")
    return spec


def _range(section: dict, key: str, default: tuple[float, float], where: str):
    value = section.get(key, list(default))
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)):
        raise CaseError(f"{key} in [map] of {where} must be a range [low, high], got {value!r}")
    low, high = float(value[0]), float(value[1])
    if not (0.0 < low < high and math.isfinite(high)):
        raise CaseError(f"{key} in [map] of {where} must rise from a positive low to a "
                        f"finite high, got [{value[0]}, {value[1]}]")
    return low, high


def _linspace(low: float, high: float, n: int) -> tuple[float, ...]:
    return tuple(low + (high - low) * i / (n - 1) for i in range(n))


def _pressures(low: float, high: float, n: int) -> tuple[float, ...]:
    """The pressure axis: evenly spaced, or evenly in its logarithm where it spans
    LOG_DECADE or more (a vacuum map from 1 mbar to 1 bar: evenly, every point but the
    first would lie above 0.11 bar)."""
    if high / low < LOG_DECADE:
        return _linspace(low, high, n)
    return tuple(low * (high / low) ** (i / (n - 1)) for i in range(n))


def log_pressures(spec) -> bool:
    """Whether the map's pressures are spaced evenly in their logarithm."""
    p = spec.pressures
    return len(p) > 2 and p[-1] / p[0] >= LOG_DECADE


def point_raw(raw: dict, spec: MapSpec, speed: float, pressure: float) -> dict:
    """The case of one map point: the case's own sections with speed and pressure set."""
    out = copy.deepcopy(raw)
    out.pop("map", None)
    out["operating"]["speed_rpm"] = speed
    out["operating"][spec.pressure] = pressure
    return out


def shared_fluid(table, raw: dict, spec: MapSpec, where: str):
    """One CoolProp table over every state the map's points reach (the union of its four
    corners' ranges), or None for the gas models (air's table is shared per process
    already). Building a table takes ~1 s; a 10 x 10 map would build 100."""
    from rotorflow.quasi1d import case_settings
    from rotorflow.quasi1d.coolprop_fluid import TabulatedFluid, checked_box
    from rotorflow.quasi1d.simulate import chamber_of

    if not str(raw["operating"].get("fluid", "")).startswith("CoolProp::"):
        return None
    boxes = []
    for n in (spec.speeds[0],):  # the speed does not move the range
        for p in (spec.pressures[0], spec.pressures[-1]):
            op, _, _, num, _ = case_settings(point_raw(raw, spec, n, p), where)
            geo = chamber_of(table, op, num)
            boxes.append(checked_box(op.fluid.split("::", 1)[1], op.p_suction_Pa,
                                     op.p_discharge_Pa, op.T_suction_K,
                                     op.wall_temperature_K, op.oil_temperature_K,
                                     geo.v_max / geo.v_discharge, op.suction_quality))
    b = np.array(boxes)
    return TabulatedFluid.build(raw["operating"]["fluid"].split("::", 1)[1], b[:, 0].min(),
                                b[:, 1].max(), b[:, 2].min(), b[:, 3].max(),
                                nodes=SHARED_TABLE_NODES)


def run_point(table, raw: dict, where: str, fluid=None) -> dict:
    """One map point through the product's quasi-1D model: a CSV row (COLUMNS)."""
    from rotorflow.quasi1d import case_settings, simulate
    from rotorflow.quasi1d.integrate import IntegrationError

    op = raw["operating"]
    row = dict.fromkeys(COLUMNS)
    row.update(speed_rpm=float(op["speed_rpm"]), p_suction_bar=float(op["p_suction_bar"]),
               p_discharge_bar=float(op["p_discharge_bar"]), converged=False, message="")
    row["pressure_ratio"] = row["p_discharge_bar"] / row["p_suction_bar"]
    t0 = time.perf_counter()
    try:
        fig = simulate(table, *case_settings(raw, where), fluid=fluid).summary()
    except (CaseError, IntegrationError) as exc:
        row["message"] = " ".join(str(exc).split())
        row["seconds"] = time.perf_counter() - t0
        return row
    row["seconds"] = time.perf_counter() - t0
    for key in COLUMNS:
        if key in fig and key not in ("speed_rpm", "p_suction_bar", "p_discharge_bar"):
            row[key] = fig[key]
    row["suction_volume_flow_m3_min"] = fig["suction_volume_flow_L_min"] / 1000.0
    shaft, flow = fig.get("shaft_power_W"), row["suction_volume_flow_m3_min"]
    row["specific_power_kW_per_m3_min"] = (shaft / 1000.0 / flow
                                           if shaft is not None and flow and flow > 0 else None)
    balances = max(abs(fig["mass_balance_error"]), abs(fig["energy_balance_error"]))
    row["converged"] = bool(fig["converged"]) and balances <= BALANCE_LIMIT
    if not fig["converged"]:
        row["message"] = str(fig.get("message") or "cycle not converged")
    elif balances > BALANCE_LIMIT:
        row["message"] = f"balances {balances:.1e} above {BALANCE_LIMIT:g}"
    elif fig.get("warning"):
        # (a converged point that delivers nothing has empty efficiencies: say why)
        row["message"] = str(fig["warning"])
    return row
