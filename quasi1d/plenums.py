"""The plenums a machine works between: the suction state, and the discharge pressure
holding the gas that flows back from it.

One construction for every user: the chamber model (:mod:`.model`) and the moving CFD
section's ports (:mod:`rotorflow.cases.moving_ports`) take their plenums from here, so
that the CFD and the model it is judged against hold the same end states.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import liquid
from .fluids import suction_given
from .oil import flooded_discharge_T
from .settings import Operating


@dataclass(frozen=True)
class Plenum:
    p: float
    T: float
    rho: float
    u: float
    h: float
    kappa: float
    w: float = 0.0  # the vapour's mass fraction in the gas (a volatile liquid, .humid)


def plenums(fluid, op: Operating, T_discharge: float | None = None) -> tuple[Plenum, Plenum]:
    """(suction, discharge) plenums of an operating point: the suction state, and the
    discharge pressure holding what flows back from it (see below; at ``T_discharge``
    where given: a dry gas's delivered state, :mod:`.delivered_plenum`)."""
    if getattr(fluid, "vapour", None) is not None:
        from .humid import humid_plenums
        return humid_plenums(fluid, op)
    def plenum(p, T, **given):  # given: q or h of a two-phase real-fluid state
        rho, u, h = fluid.state_pT(p, T, **given)
        k = fluid.props(np.array([rho]), np.array([u]))[2]
        return Plenum(p, T, rho, u, h, float(np.ravel(k)[0]) if np.ndim(k) else float(k))

    wet = suction_given(op)
    suc = plenum(op.p_suction_Pa, op.T_suction_K, **wet)
    if T_discharge is not None:
        return suc, plenum(op.p_discharge_Pa, T_discharge)
    # Discharge plenum gas (what flows back) at the isentropic end state of the pressure
    # ratio: the state of gas compressed from suction without losses.
    dis_h = {}
    if hasattr(fluid, "gamma"):
        g = fluid.gamma
        Td = op.T_suction_K * op.pressure_ratio ** ((g - 1.0) / g)
    else:
        h_is = suc.h + fluid.work_isentropic(op.p_suction_Pa, op.T_suction_K,
                                             op.p_discharge_Pa, **wet)
        Td = fluid.T_ph(op.p_discharge_Pa, h_is)
        if op.fluid.startswith("CoolProp::"):  # (p, h): fixes a two-phase end state too
            dis_h = {"h": h_is}
    ratio = liquid_ratio(op, suc)
    if ratio > 0:
        Td = flooded_discharge_T(fluid, suc, op, ratio)
        dis_h = {}
        dew = discharge_dew(fluid, op)
        if dew is not None and Td <= dew:
            # Oil at or below the condensing temperature cools the mixture to below the
            # dew point: the gas over it is saturated vapour (the rest condenses into the
            # oil), not the subcooled liquid (p, T) would name, 1150-1250 kg/m3 for
            # R134a, which flowed back into the chambers and stalled the cycle.
            Td, dis_h = dew, {"q": 1.0}
    return suc, plenum(op.p_discharge_Pa, Td, **dis_h)


def discharge_dew(fluid, op: Operating) -> float | None:
    """The dew temperature at the discharge pressure of a CoolProp fluid (None: no dome
    there, or a gas law)."""
    if not op.fluid.startswith("CoolProp::"):
        return None
    from .coolprop_table import dew_temperature

    return dew_temperature(fluid.name, op.p_discharge_Pa)


def liquid_ratio(op: Operating, suc: Plenum) -> float:
    """Liquid (or oil) mass per gas mass drawn in."""
    return liquid.inlet_mass_ratio(op, suc.rho) if op.gas_volume_fraction < 1.0 \
        else op.oil_mass_ratio
