"""Working-fluid properties in the form the chamber equations need them.

The chamber state is (mass m, internal energy U); with the volume V this gives density
rho = m/V and specific internal energy u = U/m.  Every fluid therefore answers, for
arrays of (rho, u) and without inner iteration:

    props(rho, u)  -> p, T, kappa      (kappa = rho a^2 / p, the isentropic exponent
                                        used by the nozzle formulas)
    dp(rho, u)     -> (dp/drho)_u, (dp/du)_rho   (for the ideal-port constraint)
    state(rho, u)  -> both at once, from one table lookup (the fluids that are not
                      perfect gases)

and, at a few points per run (plenum states, port events, performance figures):

    state_pT(p, T) -> rho, u, h                 (a real fluid also takes q= or h= for a
                                                two-phase state, where T fixes nothing)
    u_from_rho_p(rho, p) -> u                   (starting states of the chambers)
    isentropic(rho, u, p2) -> rho2, u2          (blow-down of the gas left in a chamber)
    fill(m, U, V, h_in, p2) -> m2, U2           (back-flow into a chamber at constant V)
    T_ph(p, h), work_isentropic(p1, T1, p2), work_isothermal(p1, T1, p2)

Three fluids, one module each:

- :class:`~.perfect_gas.PerfectGas` is closed form (u = cv T); it is also the gas of the
  CFD cases and the leakage analysis.
- :class:`~.dry_air.ThermallyPerfectGas` (dry air) has p = rho R T with cp(T): T, kappa
  and 1/cv come from a one-dimensional table in u.
- :class:`~.coolprop_fluid.TabulatedFluid` wraps a CoolProp fluid, tabulated in
  (ln rho, u), two-phase states included (the homogeneous equilibrium mixture); a wet
  suction is given by ``[operating] suction_quality``, the vapour mass fraction, with
  T_suction_K the saturation temperature at p_suction.
"""

from __future__ import annotations

from rotorflow.errors import CaseError

from .coolprop_fluid import TabulatedFluid, tabulated
from .dry_air import DRY_AIR_R, ThermallyPerfectGas, dry_air
from .perfect_gas import PerfectGas
from .settings import Operating

__all__ = ["DRY_AIR_R", "PerfectGas", "TabulatedFluid", "ThermallyPerfectGas", "dry_air",
           "make_fluid", "suction_given"]


def make_fluid(op: Operating, volume_ratio: float):
    """The fluid of an operating point: a perfect gas, dry air with cp(T), or a CoolProp
    fluid tabulated over the range the operating point can reach
    (:func:`.coolprop_table.reachable_box`), saturation dome included.  A state outside it
    is reported, not extrapolated silently.
    """
    q = op.suction_quality
    if q is not None and (not op.fluid.startswith("CoolProp::") or not 0.0 < q <= 1.0):
        raise CaseError(f"key 'suction_quality' in [operating] must lie in (0, 1] and needs a "
                        f"CoolProp fluid; got {q:g} with fluid {op.fluid!r}")
    if q is not None and op.oil_mass_ratio > 0:  # flooded_discharge_T assumes a gas
        raise CaseError("key 'suction_quality' in [operating]: a wet suction with oil "
                        "injected (oil_mass_ratio) is not modelled")
    if op.liquid_volatile is not None:
        from .vapour import humid_gas
        return humid_gas(op.constant_cp_gas if op.perfect_gas else dry_air(), op)
    if op.perfect_gas:
        return op.constant_cp_gas
    if op.fluid == "air":
        return dry_air()
    name = op.fluid.split("::", 1)[1]
    return tabulated(name, op.p_suction_Pa, op.p_discharge_Pa, op.T_suction_K,
                     op.wall_temperature_K, op.oil_temperature_K, volume_ratio, q)


def suction_given(op: Operating) -> dict:
    """What fixes the suction state besides (p, T): the quality of a wet suction (passed
    to state_pT and the work functions of a real fluid), else nothing."""
    return {} if op.suction_quality is None else {"q": op.suction_quality}
