"""Shaft figures of a converged cycle: gas loads per rotor, mechanical loss, shaft power.

Added to the performance figures (:mod:`.performance`), which keep their meaning (the
efficiencies there are indicated):

    shaft_power_W               indicated power + mechanical loss, at the driven shaft
    mechanical_loss_W           bearing and seal friction (:mod:`.mechanical`) and, with
                                oil or a liquid injected, the oil films' shear
                                (:mod:`.oil_film`) and the liquid's acceleration to the
                                rotors' speed (:func:`.mechanical.liquid_acceleration_W`)
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
    mechanical                  bearing bore used, seal loss, the oil films' loss per
                                surface with the viscosity and film temperature used and
                                the discharge heating it would add, the liquid's
                                acceleration (W), what is not modelled

All None when the chamber table carries no gas loads (:func:`.loads.has_loads`).
"""

from __future__ import annotations

import math

import numpy as np

from .loads import GasLoads, RotorLoads, gas_loads
from .mechanical import Mechanical, liquid_acceleration_W, mechanical_loss
from .oil_film import OilFilmLoss, oil_film_loss
from .performance import liquid_name
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
    loss = mechanical_loss(loads, mech, float(table.diameter_m), omega_driven)
    fig = result.figures
    film, film_figures = _oil_films(result, table, mech, loads)
    liquid_flow = max(float(fig.get(f"{liquid_name(op)}_flow_kg_s") or 0.0), 0.0)
    lift = liquid_acceleration_W(liquid_flow, loads, table.rotor_scalars) \
        if liquid_flow > 0.0 else 0.0
    total_loss = loss.total_W + (0.0 if film is None else film.total_W) + (lift or 0.0)
    shaft = fig["indicated_power_W"] + total_loss
    eta = fig["adiabatic_efficiency"]
    rotors = {r.name: {**rotor_figures(loads, r), "bearing_loss_W": loss.bearings_W[r.name]}
              for r in loads.rotors}
    return {
        "shaft_power_W": shaft,
        "mechanical_loss_W": total_loss,
        # eta_shaft = mdot w_is / P_shaft = eta_indicated * P_indicated / P_shaft
        "adiabatic_efficiency_shaft": None if eta is None or shaft <= 0.0
        else eta * fig["indicated_power_W"] / shaft,
        "loads": {"power_balance_error": loads.power_balance_error, "rotors": rotors},
        "mechanical": {"bearing_bore_m": loss.bore_m, "seal_loss_W": loss.seal_W,
                       **film_figures, "liquid_acceleration_W": lift,
                       "not_modelled": list(loss.not_modelled) + (
                           [] if film is None else list(film.not_modelled)) + (
                           [] if lift is not None else
                           ["acceleration of the injected liquid to the rotors' speed (the "
                            "table gives no rotor grooves)"])},
    }, loads


def _oil_films(result: SimulationResult, table, mech: Mechanical, loads: GasLoads):
    """The oil films' loss (None without injected oil) and its figures."""
    model = result.solution.model
    op = model.op
    if op.oil_mass_ratio <= 0.0:
        return None, {}
    if not table.oil_films or not mech.oil_viscosity_given:
        why = ("the chamber table declares no oil films" if not table.oil_films
               else "[mechanical] gives no oil viscosities")
        return OilFilmLoss({}, math.nan, math.nan,
                           (f"viscous shear of the injected oil in the clearances ({why})",)
                           ), {}
    fig = result.figures
    T_mix = fig["discharge_mixture_temperature_K"]
    # (no delivery, no discharged mixture: the films at the injected oil's temperature)
    T_film = op.oil_temperature_K if T_mix is None else 0.5 * (op.oil_temperature_K + T_mix)
    gaps = {law.path.name: law.gap_m for law in model.laws}
    omegas = {r.name: abs(r.speed_ratio * loads.omega_ref) for r in loads.rotors}
    film = oil_film_loss(table.oil_films, gaps, omegas, float(table.length_m), mech, T_film)
    # what the shear heat would add to the discharged gas and oil, were it fed back
    fluid, p_d, T_d = model.fluid, op.p_discharge_Pa, fig["discharge_temperature_K"]
    heating = None
    if T_d is not None:
        cp_gas = fluid.state_pT(p_d, T_d + 0.5)[2] - fluid.state_pT(p_d, T_d - 0.5)[2]
        capacity = fig["mass_flow_kg_s"] * cp_gas + fig["oil_flow_kg_s"] * op.oil_cp_J_kgK
        heating = film.total_W / capacity if capacity > 0.0 else None
    return film, {
        "oil_film_W": film.by_surface_W,
        "oil_film_viscosity_Pa_s": film.viscosity_Pa_s,
        "oil_film_temperature_K": film.temperature_K,
        "oil_film_heating_K": heating,
    }
