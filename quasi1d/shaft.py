"""Shaft figures of a converged cycle: gas loads per rotor, mechanical loss, shaft power.

Added to the performance figures (:mod:`.performance`), which keep their meaning (the
efficiencies there are indicated):

    shaft_power_W               indicated power + mechanical loss, at the driven shaft
    mechanical_loss_W           bearing and seal friction (:mod:`.mechanical`)
    adiabatic_efficiency_shaft  mass flow * isentropic work / shaft power
    loads                       per rotor (``rotors``): radial gas force mean and max (N),
                                axial gas force mean and max |F| (N; None where undefined)
                                and, after seed 004, its end-face part and the flanks'
                                mean,
                                shaft torque mean, min, max (N m; the rotor's torque on the
                                gas, counter-clockwise positive) and its sign changes per
                                lobe period (seed 004: a rotor whose gas torque changes
                                sign rattles in its timing gear), bearing loss (W); and
                                ``power_balance_error``: |mean sum omega_r T_r / indicated
                                power - 1|
    mechanical                  bearing bore used, seal loss, what is not modelled

All None when the chamber table carries no gas loads (:func:`.loads.has_loads`).
"""

from __future__ import annotations

import math

import numpy as np

from .loads import GasLoads, RotorLoads, gas_loads
from .mechanical import Mechanical, mechanical_loss
from .result import SimulationResult

SHAFT_KEYS = ("shaft_power_W", "mechanical_loss_W", "adiabatic_efficiency_shaft", "loads",
              "mechanical")


def sign_changes(x: np.ndarray) -> int:
    """Sign changes of a periodic sequence (exact zeros skipped; the wrap-around counts)."""
    s = np.sign(x)
    s = s[s != 0]
    if s.size < 2:
        return 0
    return int(np.count_nonzero(s != np.roll(s, 1)))


def rotor_figures(loads: GasLoads, r: RotorLoads) -> dict:
    radial = r.radial
    return {
        "radial_force_N_mean": loads.mean(radial),
        "radial_force_N_max": float(radial.max()),
        "axial_force_N_mean": None if r.axial is None else loads.mean(r.axial),
        "axial_force_N_max_abs": None if r.axial is None else float(np.abs(r.axial).max()),
        # seed 004's split: the end faces' part, and the flanks' (the gas force where the
        # chambers meet the rotor) as the rest
        "axial_end_force_N": r.axial_end,
        "axial_flank_force_N_mean": None if r.axial is None
        else loads.mean(r.axial) - r.axial_end,
        "torque_Nm_mean": loads.mean(r.torque),
        "torque_Nm_min": float(r.torque.min()),
        "torque_Nm_max": float(r.torque.max()),
        "torque_sign_changes": sign_changes(r.torque),
    }


def shaft_figures(result: SimulationResult, table, mech: Mechanical) -> tuple[dict, GasLoads]:
    """The figures of SHAFT_KEYS for ``result`` and the loads they came from."""
    loads = gas_loads(result, table)
    if loads is None:
        return dict.fromkeys(SHAFT_KEYS), None
    model = result.solution.model
    op = model.op
    omega_driven = 2.0 * math.pi * op.speed_rpm / 60.0
    loss = mechanical_loss(loads, mech, float(table.diameter_m), omega_driven,
                           oil=op.oil_mass_ratio > 0.0)
    fig = result.figures
    shaft = fig["indicated_power_W"] + loss.total_W
    eta = fig["adiabatic_efficiency"]
    rotors = {r.name: {**rotor_figures(loads, r), "bearing_loss_W": loss.bearings_W[r.name]}
              for r in loads.rotors}
    return {
        "shaft_power_W": shaft,
        "mechanical_loss_W": loss.total_W,
        # eta_shaft = mdot w_is / P_shaft = eta_indicated * P_indicated / P_shaft
        "adiabatic_efficiency_shaft": None if eta is None or shaft <= 0.0
        else eta * fig["indicated_power_W"] / shaft,
        "loads": {"power_balance_error": loads.power_balance_error, "rotors": rotors},
        "mechanical": {"bearing_bore_m": loss.bore_m, "seal_loss_W": loss.seal_W,
                       "not_modelled": list(loss.not_modelled)},
    }, loads
