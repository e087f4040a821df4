"""The headline of a case's report: what a designer reads first, from the quasi-1D
summary (:mod:`rotorflow.quasi1d.performance`, :mod:`rotorflow.quasi1d.shaft`).

Flow, power, specific power, efficiencies and discharge temperature, each with its unit
and rounded to four significant figures (the model is not better than that; the full
figures stay in the quasi-1D section below).  A figure the summary leaves None is shown
as "n/a" with the reason, where the summary's definitions give one.

Specific power is the shaft power per suction volume flow in kW/(m³/min), the unit of
compressor data sheets (CAGI); W per L/min is the same number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

NA = "n/a"


@dataclass(frozen=True)
class Row:
    quantity: str
    value: float | None  # in ``unit``, unrounded (None: not available)
    unit: str
    note: str = ""


def sig(v: float, figures: int = 4) -> str:
    """``v`` rounded to ``figures`` significant figures, trailing zeros kept (they say
    how many figures are meant) and no exponent for the magnitudes a headline shows."""
    if v == 0 or not math.isfinite(v):
        return f"{v:g}"
    decimals = figures - 1 - math.floor(math.log10(abs(v)))
    x = round(v, decimals)
    # Rounding can carry into a new decade (9.9996 -> 10.000): one decimal fewer.
    if x != 0 and math.floor(math.log10(abs(x))) > math.floor(math.log10(abs(v))):
        decimals -= 1
    return f"{x:.{max(decimals, 0)}f}"


def _num(v) -> float | None:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    return float(v) if math.isfinite(v) else None


def _scaled(v, factor: float) -> float | None:
    x = _num(v)
    return None if x is None else x * factor


def headline_rows(s: dict) -> list[Row]:
    """The headline's rows from a quasi-1D summary (a dict as in summary.json)."""
    delivered = (_num(s.get("mass_flow_kg_s")) or 0.0) > 0.0
    no_delivery = "no net delivery over the cycle"
    shaft = _num(s.get("shaft_power_W"))
    no_shaft = "no gas loads in the chamber table, hence no mechanical loss"
    vflow = _num(s.get("suction_volume_flow_L_min"))
    rows = [
        Row("Volume flow at suction", _scaled(vflow, 1e-3), "m³/min",
            "" if vflow is None else f"{sig(vflow)} L/min; mass flow / suction density"),
        Row("Mass flow", _num(s.get("mass_flow_kg_s")), "kg/s", "net, drawn from suction"),
        Row("Indicated power", _scaled(s.get("indicated_power_W"), 1e-3), "kW",
            "work done on the gas, −∮p dV"),
        Row("Shaft power", _scaled(shaft, 1e-3), "kW",
            no_shaft if shaft is None else
            f"indicated + mechanical loss ({sig(_num(s.get('mechanical_loss_W')) or 0.0)} W)"),
        _specific_power(shaft, _num(s.get("indicated_power_W")), vflow, delivered),
        Row("Volumetric efficiency", _scaled(s.get("volumetric_efficiency"), 100.0), "%",
            "mass per cycle / (suction density × trapped volume)"),
        Row("Isentropic efficiency, indicated", _scaled(s.get("adiabatic_efficiency"), 100.0),
            "%", "isentropic power / indicated power" if delivered else no_delivery),
        Row("Isentropic efficiency, shaft", _scaled(s.get("adiabatic_efficiency_shaft"), 100.0),
            "%", no_shaft if shaft is None else
            ("isentropic power / shaft power" if delivered else no_delivery)),
        Row("Isothermal efficiency, indicated", _scaled(s.get("isothermal_efficiency"), 100.0),
            "%", _isothermal_note(s, delivered)),
        _temperature("Discharge temperature", s.get("discharge_temperature_K"),
                     "gas at its mean delivered enthalpy", "no gas delivered"),
    ]
    if _num(s.get("discharge_mixture_temperature_K")) is not None:
        rows.append(_temperature("Discharge temperature, gas and oil mixed",
                                 s["discharge_mixture_temperature_K"], "", ""))
    if _num(s.get("discharge_quality")) is not None and s["discharge_quality"] < 1.0:
        rows.append(Row("Discharge vapour quality", _scaled(s["discharge_quality"], 100.0),
                        "%", "the delivered refrigerant is wet"))
    return rows


def _specific_power(shaft, indicated, vflow, delivered) -> Row:
    name, unit = "Specific power", "kW/(m³/min)"
    if not delivered or not vflow or vflow <= 0.0:
        return Row(name, None, unit, "no net delivery over the cycle")
    if shaft is None:
        if indicated is None:
            return Row(name, None, unit, "no power in the summary")
        return Row(name, indicated / vflow, unit,
                   "indicated power / volume flow (no shaft power in the summary)")
    # W per L/min is kW per m³/min: no factor.
    return Row(name, shaft / vflow, unit, "shaft power / volume flow at suction")


def _isothermal_note(s: dict, delivered: bool) -> str:
    if not delivered:
        return "no net delivery over the cycle"
    if s.get("isothermal_efficiency") is None:
        # quasi1d.performance: None for a condensable fluid whose isotherm from suction
        # reaches saturation below the discharge pressure.
        return ("undefined: compressing isothermally from suction would condense the "
                "fluid before the discharge pressure")
    return "isothermal power at suction temperature / indicated power"


def _temperature(name: str, kelvin, note: str, missing: str) -> Row:
    t = _num(kelvin)
    if t is None:
        return Row(name, None, "K", missing)
    celsius = f"{sig(t - 273.15)} °C"
    return Row(name, t, "K", f"{celsius}; {note}" if note else celsius)


def operating_line(s: dict, case) -> str:
    """One sentence of the operating point the headline is for (plain text)."""
    op = (getattr(case, "raw", None) or {}).get("operating", {}) or {}
    parts = []
    if s.get("fluid"):
        parts.append(str(s["fluid"]))
    if _num(op.get("p_suction_bar")) is not None:
        t = _num(op.get("T_suction_K"))
        parts.append(f"suction {op['p_suction_bar']:g} bar"
                     + (f", {t:g} K" if t is not None else ""))
    if _num(op.get("p_discharge_bar")) is not None:
        parts.append(f"discharge {op['p_discharge_bar']:g} bar")
    ref = reference_rotor(case)
    if _num(s.get("speed_outer_rpm")) is not None:
        parts.append(f"{ref} rotor {sig(s['speed_outer_rpm'])} rpm")
    driven = getattr(case, "driven", None)
    if _num(op.get("speed_rpm")) is not None and driven != ref:
        # [operating] speed_rpm is the driven rotor's; "auto" leaves its name to the
        # power split, which the summary does not carry.
        who = f"{driven} (driven)" if driven and driven != "auto" else "driven"
        parts.append(f"{who} rotor {op['speed_rpm']:g} rpm")
    return "; ".join(parts)


def reference_rotor(case) -> str:
    """The name of rotor 0, whose angle every chamber-table angle is."""
    try:
        return case.pair.rotors[0].name
    except (AttributeError, IndexError, TypeError):
        return "reference"


def headline_html(s: dict, case, esc) -> str:
    """The headline table (``id='headline'``) and its operating point."""
    body = []
    if not s.get("converged", True):
        body.append("<p class='warn'>The quasi-1D cycle did not converge: these are the "
                    "figures of its last cycle.</p>")
    line = operating_line(s, case)
    if line:
        body.append(f"<p>Operating point: {esc(line)}.</p>")
    rows = []
    for r in headline_rows(s):
        value = NA if r.value is None else sig(r.value)
        rows.append(f"<tr><th>{esc(r.quantity)}</th><td class='num'>{esc(value)}</td>"
                    f"<td>{esc(r.unit)}</td><td class='muted'>{esc(r.note)}</td></tr>")
    body.append("<table id='headline' class='headline'><tr><th>quantity</th><th>value</th>"
                f"<th>unit</th><th>basis</th></tr>{''.join(rows)}</table>")
    return "".join(body)
