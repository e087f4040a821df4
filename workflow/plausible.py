"""Every number of a case file checked once, where the case is read: representable,
finite, and inside a plausible range for its key.

The settings classes check what a key must satisfy to mean anything (a positive gap, a
volume ratio of at least 1); this module checks what it must satisfy to be what a user
of this field meant.  A value outside its range is almost always a unit slip (a
pressure in Pa in a _bar key, a temperature in Celsius in a _K key, a length in metres
in a _mm or _um key) or a typo of a few orders of magnitude, and some of those make a
run explode in time (a hundred lobes, ten thousand degrees of wrap).  A deliberate
extreme is accepted by naming the key, not by accident::

    [plausibility]
    accept = ["operating.T_suction_K"]   # a helium cold compressor

An accepted key is still checked for being a finite, representable number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from rotorflow.errors import CaseError

SECTION = "plausibility"


@dataclass(frozen=True)
class Range:
    """A closed plausible range, with the unit shown and a hint for each side."""

    low: float
    high: float
    unit: str = ""
    below: str = ""  # the likely slip when a value lies below ``low``
    above: str = ""


#: Absolute pressures [bar]: from the ultimate pressure of rough-vacuum screw pumps
#: (1e-3 mbar) to twice the highest-pressure rotary machines' 1000 bar.
PRESSURE_BAR = Range(1e-6, 2000.0, "bar", "below any rough-vacuum pump's ultimate pressure",
                     "was it given in Pa?")
#: Temperatures [K]: 50 K is below every working fluid a rotary compressor handles but
#: helium and hydrogen; 1500 K is above what any rotor material survives.
TEMPERATURE_K = Range(50.0, 1500.0, "K", "was it given in Celsius?",
                      "above what any rotor material survives")
#: Machine sizes [mm]: rotors from a 1 mm micro machine to 10 m.
SIZE_MM = Range(1.0, 10000.0, "mm", "was it given in metres?", "was it given in um?")
#: Other lengths [mm] (seal lands, fillet and tip radii, mesh spacings).
LENGTH_MM = Range(1e-3, 10000.0, "mm", "was it given in metres?", "was it given in um?")
#: Clearances and tolerances [um]: from the best grinding (0.1 um) to 2 mm, four times
#: the largest clearances of dry vacuum screw pumps (0.2-0.5 mm); beyond it a machine
#: is an orifice between its plena (a 5 mm gap turned the CRC.60's delivery negative).
GAP_UM = Range(0.1, 2000.0, "um", "was it given in metres or mm?", "was it given in nm?")
#: Rotor angles [deg]: wraps and timings of up to ten turns (multi-turn pump rotors
#: have three or four).
ANGLE_DEG = Range(-3600.0, 3600.0, "deg", "", "was it given in some other unit?")
#: Keys whose lower side the settings check themselves, with the meaning in the message
#: ("lambda must be greater than 1", "volume_ratio must be at least 1"): no lower range.
OWN_LOW = -1e9
WRAP_DEG = Range(OWN_LOW, 3600.0, "deg", "", "more than ten turns of wrap")
#: Shaft speeds [rpm]: a cycle longer than 6 s is heat exchange, not compression; above
#: 100,000 rpm no positive-displacement rotor holds together.
SPEED_RPM = Range(10.0, 1e5, "rpm", "a turn takes over 6 s", "beyond any rotor's burst speed")
#: Flow and discharge coefficients: a nozzle passes at most its isentropic flow.
COEFFICIENT = Range(1e-3, 1.0, "", "a path that passes nothing is not a leakage path",
                    "more than an isentropic nozzle passes")

#: Ranges of keys by section and key (checked first), then by key in any section.
BY_KEY: dict[str, Range] = {
    "machine.lobes_outer": Range(OWN_LOW, 12, "lobes", "", "no gerotor has so many lobes"),
    "machine.lobes_male": Range(OWN_LOW, 10, "lobes", "", "no screw rotor has so many lobes"),
    "machine.lobes_female": Range(OWN_LOW, 12, "lobes", "", "no screw rotor has so many lobes"),
    "machine.lambda": Range(OWN_LOW, 10.0, "", "", "the pin circle would dwarf the rotor"),
    "machine.sigma": Range(OWN_LOW, 10.0, "", "", "the pin would dwarf the rotor"),
    "machine.tip_radius_mm": LENGTH_MM,
    "machine.fillet_apex_diameter_mm": SIZE_MM,
    "sweep.wrap_bar": Range(OWN_LOW, 10.0, "", "", "more than ten chamber lives of wrap"),
    "sweep.lead_ratio": Range(1e-2, 1e2, "", "the lead would vanish", "the lead would be flat"),
    "operating.volume_ratio": Range(OWN_LOW, 20.0, "", "",
                                    "beyond any positive-displacement machine's built-in ratio"),
    "operating.speed_rpm": SPEED_RPM,
    "operating.heat_transfer_W_m2K": Range(0.0, 1e5, "W/m2K", "",
                                           "beyond even boiling heat transfer"),
    "operating.oil_mass_ratio": Range(0.0, 100.0, "kg oil/kg gas", "",
                                      "more liquid than any flooded or multiphase machine"),
    "operating.oil_time_constant_ms": Range(1e-3, 1e3, "ms", "", "was it given in us?"),
    "operating.cp_J_kgK": Range(100.0, 20000.0, "J/kgK", "was it given in kJ/kgK?", ""),
    "operating.oil_cp_J_kgK": Range(100.0, 10000.0, "J/kgK", "was it given in kJ/kgK?", ""),
    "operating.molar_mass_g_mol": Range(1.0, 1000.0, "g/mol", "was it given in kg/mol?", ""),
    "operating.discharge_early_opening_deg": Range(-360.0, 360.0, "deg", "", ""),
    "leakage.zeta": Range(0.0, 100.0, "", "", "a loss coefficient no gap has"),
    "leakage.viscosity_Pa_s": Range(1e-7, 10.0, "Pa s", "", "was it given in cP or cSt?"),
    "operating.liquid_viscosity_Pa_s": Range(1e-5, 10.0, "Pa s", "",
                                             "was it given in cP or cSt?"),
    # a liquid drawn in: from liquefied gases (propane 500 kg/m3) to brines and muds
    "operating.liquid_density_kg_m3": Range(300.0, 3000.0, "kg/m3", "was it given in g/cm3?",
                                            "denser than any pumped liquid but a metal"),
    "operating.liquid_cp_J_kgK": Range(100.0, 10000.0, "J/kgK", "was it given in kJ/kgK?", ""),
    "numerics.rtol": Range(1e-12, 1e-2, "", "below round-off", "no digit of the answer is sure"),
    "numerics.atol": Range(0.0, 1e-2, "", "", "no digit of the answer is sure"),
    "numerics.cycle_rtol": Range(1e-14, 1e-2, "", "below round-off", "the cycle is not periodic"),
    "numerics.balance_tol": Range(1e-14, 1e-1, "", "below round-off", "no balance is checked"),
    "numerics.max_cycles": Range(1, 1000, "cycles", "", "a budget of hours"),
    "numerics.max_steps": Range(100, 1e8, "steps", "no cycle resolves in so few steps",
                                "a budget of hours"),
    "numerics.max_seconds": Range(0.1, 1e5, "s", "", "a budget of more than a day"),
    "mechanical.bearing_mu_radial": Range(0.0, 0.5, "", "", "beyond dry sliding friction"),
    "mechanical.bearing_mu_axial": Range(0.0, 0.5, "", "", "beyond dry sliding friction"),
    "mechanical.seal_torque_Nm": Range(0.0, 1e4, "Nm", "", ""),
    "mechanical.oil_density_kg_m3": Range(500.0, 2000.0, "kg/m3", "was it given in g/cm3?", ""),
    "export.cloud_spacing_mm": LENGTH_MM,
    "cfd.wall_speed_m_s": Range(0.0, 500.0, "m/s", "", "beyond any rotor's tip speed"),
}
#: Ranges by the unit suffix a key's name ends with, where no key's own range applies.
BY_SUFFIX: dict[str, Range] = {
    "_bar": PRESSURE_BAR,
    "_K": TEMPERATURE_K,
    "_um": GAP_UM,
    "_cSt": Range(0.5, 1e5, "mm2/s", "thinner than water", "was it given in mm2/s x 1000?"),
    "wrap_outer_deg": WRAP_DEG,
    "_deg": ANGLE_DEG,
    "_mm": SIZE_MM,
    "_rpm": SPEED_RPM,
    "coefficient": COEFFICIENT,
}
#: Any other number: representable and of a magnitude some key could mean.
ANY = Range(-1e9, 1e9, "", "", "")
#: Keys whose machine sizes are lengths of parts rather than of a whole rotor.
PART_MM = ("land_mm", "radius_mm", "port_depth_mm", "seal_length_mm", "gap_mm", "layer_mm")


def range_of(section: str, key: str) -> Range:
    """The plausible range of ``key`` in ``[section]`` (nested tables are named by their
    top section: [leakage.tip] reads as [leakage])."""
    if f"{section}.{key}" in BY_KEY:
        return BY_KEY[f"{section}.{key}"]
    if key.startswith("wrap_") and key.endswith("_deg"):
        return WRAP_DEG
    if key.endswith(PART_MM):
        return LENGTH_MM
    for suffix, rng in BY_SUFFIX.items():
        if key.endswith(suffix):
            return rng
    return ANY


def _numbers(table: dict, path: tuple[str, ...]):
    """(path, key, value) of every number in a table, nested tables and lists included."""
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _numbers(value, (*path, key))
        elif isinstance(value, list):
            for v in value:
                if isinstance(v, int | float) and not isinstance(v, bool):
                    yield path, key, v
        elif isinstance(value, int | float) and not isinstance(value, bool):
            yield path, key, value


def _accepted(data: dict, where: str) -> set[str]:
    section = data.get(SECTION, {})
    if not isinstance(section, dict) or set(section) - {"accept"}:
        raise CaseError(f"[{SECTION}] of {where} takes one key, accept = [\"section.key\", ...]")
    accept = section.get("accept", [])
    if not isinstance(accept, list) or not all(isinstance(k, str) for k in accept):
        raise CaseError(f"accept in [{SECTION}] of {where} must be a list of \"section.key\"")
    return set(accept)


def check_plausible(data: dict, path: Path | str) -> None:
    """Raise a one-line CaseError for the first number of ``data`` (a parsed case file)
    that is not representable, not finite, or outside its key's plausible range."""
    where = str(path)
    accept = _accepted(data, where)
    for name, table in data.items():
        if name in (SECTION, "optimise") or not isinstance(table, dict):
            continue  # [optimise] bounds are checked against the variables they set
        for inner, key, value in _numbers(table, (name,)):
            full = ".".join((*inner, key))
            at = f"in [{'.'.join(inner)}] of {where}"
            try:
                x = float(value)
            except OverflowError:
                raise CaseError(f"{key} {at} is too large for a number: "
                                f"{str(value)[:12]}...") from None
            if not math.isfinite(x):
                raise CaseError(f"{key} {at} must be finite, got {value!r}")
            if full in accept or f"{name}.{key}" in accept:
                continue
            _check_range(f"{key} = {x:g} {at}", full, x, range_of(name, key))
    _check_beside_suction(data.get("operating"), where, accept)


#: The machine's other temperatures against its suction's: a wall or an injected oil
#: below half the suction's absolute temperature is a Celsius slip (80 C for 80 K: the
#: absolute range, from 50 K, lets it through; it ran, the wall cooling the gas to an
#: eta_v of 1.4), a deliberate one a cryogenic rig's, accepted by name.
BESIDE_SUCTION = ("T_wall_K", "T_oil_K")


def _check_beside_suction(op, where: str, accept: set[str]) -> None:
    if not isinstance(op, dict) or not isinstance(op.get("T_suction_K"), int | float):
        return
    ts = float(op["T_suction_K"])
    for key in BESIDE_SUCTION:
        x = op.get(key)
        if (isinstance(x, int | float) and not isinstance(x, bool) and 0.0 < x < 0.5 * ts
                and f"operating.{key}" not in accept):
            raise CaseError(f"{key} = {x:g} in [operating] of {where} is below half of "
                            f"T_suction_K = {ts:g} K: was it given in Celsius? (a "
                            f"deliberate value: [{SECTION}] accept = [\"operating.{key}\"])")


def _check_range(label: str, full: str, x: float, rng: Range) -> None:
    unit = f" {rng.unit}" if rng.unit else ""
    if rng.low <= x <= rng.high:
        return
    if x <= 0.0 < rng.low:  # a sign or a zero, not a unit: nothing to accept
        raise CaseError(f"{label} must be positive")
    side, bound, hint = (("below", rng.low, rng.below) if x < rng.low
                         else ("above", rng.high, rng.above))
    why = f": {hint}" if hint else ""
    raise CaseError(f"{label} is {side} {bound:g}{unit}{why} "
                    f"(a deliberate value: [{SECTION}] accept = [\"{full}\"])")
