"""Performance figures of a converged cycle (seed 003: mass flow, indicated and specific
power, volumetric, adiabatic and isothermal efficiency; seed 001 Table 4).

Definitions (per lobe period = one chamber's cycle, t_P = period / omega_outer):

    mass_flow_kg_s              net mass drawn from the suction plenum / t_P
    suction_volume_flow_L_min   mass flow / suction density, in L/min
    indicated_power_W           work done on the gas, -sum of p dV over all chambers, / t_P
    specific_power_J_kg         indicated power / mass flow
    volumetric_efficiency       mass per cycle / (suction density * V at suction closing):
                                the trapped volume, seed 001's "suction volume" (30 cc)
    adiabatic_efficiency        mass flow * isentropic work (p_suc, T_suc -> p_dis) / power
    isothermal_efficiency       mass flow * isothermal work at T_suc / power; None for a
                                condensable fluid whose isotherm from suction reaches the
                                saturation line before p_dis (every refrigeration point:
                                the reversible isothermal path would condense the vapour,
                                a condenser's work, not a compressor's; and a wet suction)
    discharge_temperature_K     temperature of the delivered gas at its mean enthalpy (None,
                                with a warning, outside the chambers' range: the fixed
                                discharge plenum's artefact, :mod:`.result`)
    suction_return_enthalpy_W   (no oil or liquid) the enthalpy the gas flowing back into the
                                suction plenum carries above the suction's own, lost there
                                (power = delivered enthalpy rise + this - heat to the gas)
    discharge_quality           its vapour mass fraction (CoolProp fluids: 1 superheated,
                                None above the critical pressure)
    discharge_mixture_temperature_K  (oil injected) the delivered gas and oil mixed to one
                                temperature (what a thermometer in the discharge line of an
                                oil-flooded machine reads); None without oil
    leakage_kg_s                gross flow (|mdot| integrated) per report key of the
                                chamber table's leakage paths (a path's name unless it
                                declares a key); the internal gear's: "interlobe" (every
                                sealing line between chambers), "lp_face" and "hp_face"
                                (across the low- and the high-pressure end face)
    oil_flow_kg_s               net oil supplied: injected at suction closing, less what
                                leaks into the suction plenum (over a periodic cycle the
                                oil delivered); liquid_flow_kg_s instead where a liquid is
                                drawn in with the gas (gas_volume_fraction < 1: a
                                multiphase pump's water is no oil)
    evaporated_kg_s             (a volatile liquid, :mod:`.humid`) the liquid evaporated
                                into the gas, net (negative: the vapour condensed)
    discharge_vapour_fraction   the delivered gas's vapour mass fraction
    oil_leakage_kg_s            gross oil flow per report key, as leakage_kg_s: the oil
                                that leaks with the gas as a homogeneous mixture
                                ([leakage] mixture, :mod:`.oil`); 0 where the leakage
                                carries gas only or no oil is injected;
                                liquid_leakage_kg_s where a liquid is drawn in

Figures that are undefined (no net delivery) are None so that the JSON stays valid.
"""

from __future__ import annotations

import math

from .cycle import CycleSolution
from .fluids import suction_given
from .network import ACC_H_DIS, ACC_H_SUC, ACC_M_DIS, ACC_M_SUC, ACC_Q, ACC_W


def liquid_name(op) -> str:
    """What the figures call the liquid the model carries: "liquid" where it is drawn in
    with the gas (a multiphase pump), else "oil" (injected, or none)."""
    return "liquid" if op.gas_volume_fraction < 1.0 else "oil"


def figures(sol: CycleSolution) -> dict:
    model = sol.model
    geo, op, fl = model.geo, model.op, model.fluid
    a = model.acc(sol.run.y[0])
    liquid = liquid_name(op)
    t_period = geo.period / geo.omega_outer
    mdot = a[ACC_M_SUC] / t_period
    power = a[ACC_W] / t_period
    rho_s = model.suc.rho
    delivered = mdot > 0
    wet = suction_given(op)  # a wet suction's quality (real fluids)
    w_is = fl.work_isentropic(op.p_suction_Pa, op.T_suction_K, op.p_discharge_Pa, **wet)
    w_it = fl.work_isothermal(op.p_suction_Pa, op.T_suction_K, op.p_discharge_Pa, **wet)
    # the delivered gas's composition, with a volatile liquid's vapour (.humid)
    w_dis = (a[model.acc_cols.vap_out] / a[ACC_M_DIS],) if model.vapour and a[ACC_M_DIS] > 0 \
        else ()
    if a[ACC_M_DIS] > 0:
        T_dis = float(fl.T_ph(op.p_discharge_Pa, a[ACC_H_DIS] / a[ACC_M_DIS], *w_dis))
    else:
        T_dis = None

    def ratio(num, den):
        return float(num / den) if delivered and den > 0 else None

    out = {
        "mass_flow_kg_s": float(mdot),
        "suction_volume_flow_L_min": float(mdot / rho_s * 60e3),
        "indicated_power_W": float(power),
        "specific_power_J_kg": ratio(power, mdot),
        "volumetric_efficiency": float(a[ACC_M_SUC] / (rho_s * geo.v_trapped)),
        "adiabatic_efficiency": ratio(mdot * w_is, power),
        "isothermal_efficiency": None if w_it is None else ratio(mdot * w_it, power),
        "discharge_temperature_K": T_dis,
        "discharge_mixture_temperature_K": _mixture_T(model, a, T_dis, w_dis),
        "heat_to_gas_W": float(a[ACC_Q] / t_period),
        f"{liquid}_flow_kg_s": float(a[model.acc_cols.oil_m_in] / t_period),
        "leakage_kg_s": {key: float(a[model.acc_cols.leak(key)] / t_period)
                         for key in model.acc_cols.leak_keys},
        f"{liquid}_leakage_kg_s": _oil_leakage(model, a, t_period),
        "cycles": int(sol.cycles),
        "converged": bool(sol.converged),
        "mass_balance_error": float(sol.mass_closure),
        "energy_balance_error": float(sol.energy_closure),
        "chambers": int(model.n),
        "speed_outer_rpm": float(geo.omega_outer * 60.0 / (2.0 * math.pi)),
        "trapped_volume_m3": float(geo.v_trapped),
        "suction_close_deg": math.degrees(geo.suction_close),
        "discharge_open_deg": math.degrees(geo.discharge_open),
        "fluid": op.fluid,
    }
    if not model.oil and not model.vapour:
        # What the gas flowing back into the suction plenum carries above the suction's
        # own enthalpy: the plenum is held at its state, so this leaves the machine there
        # (it is why the indicated power exceeds the delivered gas's enthalpy rise).
        out["suction_return_enthalpy_W"] = float(
            (a[ACC_M_SUC] * model.suc.h - a[ACC_H_SUC]) / t_period)
    if hasattr(fl, "quality_ph") and a[ACC_M_DIS] > 0:
        # (a wet discharge's temperature is its saturation temperature: the quality says
        # how wet)
        out["discharge_quality"] = fl.quality_ph(op.p_discharge_Pa, a[ACC_H_DIS] / a[ACC_M_DIS])
    if model.vapour:
        c = model.acc_cols
        out["evaporated_kg_s"] = float(a[c.evaporated] / t_period)
        out["discharge_vapour_fraction"] = float(w_dis[0]) if w_dis else None
    if not sol.converged:
        out["message"] = sol.message
    return out


def _oil_leakage(model, a, t_period) -> dict:
    c = model.acc_cols
    return {key: float(a[c.oil_leak(key)] / t_period) if c.oil_leaks else 0.0
            for key in c.leak_keys}


def _mixture_T(model, a, T_gas, w=()):
    """Delivered gas (at T_gas, cp from the fluid) and oil (its delivered enthalpy,
    c_oil T) brought to one temperature by their heat balance."""
    op, c = model.op, model.acc_cols
    if not model.oil or T_gas is None or a[c.oil_m_out] <= 0 or a[ACC_M_DIS] <= 0:
        return None
    fl = model.fluid
    h_lo = fl.state_pT(op.p_discharge_Pa, T_gas - 0.5, *w)[2]
    h_hi = fl.state_pT(op.p_discharge_Pa, T_gas + 0.5, *w)[2]
    cg = float(h_hi - h_lo) * a[ACC_M_DIS]
    co = op.oil_cp_J_kgK * a[c.oil_m_out]
    # the delivered liquid's enthalpy, less its p v (at the discharge pressure), over c
    T_oil = model.liquid_datum_K + (a[c.oil_h_out] - model.op.p_discharge_Pa
                                    * model.inv_rho_liquid * a[c.oil_m_out]) / co
    return float((cg * T_gas + co * T_oil) / (cg + co))
