"""Gas loads on the rotors against the reference-rotor angle, from a converged cycle.

At reference angle theta every chamber of the machine is the table's chamber at some
age theta + k * period (slot k of the model).  The fluid's load on rotor r is

    F_r(theta) = sum over k of (p_k - p_suction) * f_r(theta + k * period)

with f_r the table's force or torque column per unit pressure (``force_NAME_x_m2``,
``force_NAME_y_m2``, ``torque_NAME_m3``).  Why the gauge pressure is exact: the table's
chambers, from birth to death, cover the whole working space between the rotors, and a
uniform pressure over all of them loads no rotor (the geometry guarantees it, the
columns summed over one period's chambers are zero); so adding -p_suction everywhere
changes nothing, and the gauge form leaves out the large cancelling sums.

Assumptions, where the model has no chamber:
* ages before the model's birth (a chamber smaller than the vanishing fraction of V_max,
  open to the suction port) are at suction pressure: no gauge load;
* ages after its death (handed over to the discharge port) are at discharge pressure,
  which is also the pressure whose p V the model books as work at death;
* rotor surfaces outside the working space (the internal gear's outer rotor in its
  bore, shaft journals) sit in one uniform pressure and carry no net load.

Torques are reported as shaft torques, those the rotor exerts on the gas (minus the
fluid's torque), counter-clockwise positive, as :mod:`rotorflow.geometry.forces`: then
the power the shafts put into the gas is sum over rotors of omega_r T_r, whose mean over a
period is the indicated power (the p dV work) -- the test of this module.

Resolution.  The converged period's trace holds the integrator's accepted steps only
(a few dozen per period); the loads are taken from the same period integrated again
from the converged state along those steps each cut into ``TRACE_REFINEMENT`` (the
integrator replays the given step ends, so it is the same model at a finer output).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .integrate import IntegrationError, integrate_period
from .result import SimulationResult, traces

#: Each accepted step of the converged period is cut into this many for the load traces.
#: The mean power is a trapezoid rule over the trace, O(h^2): with ~25 steps per period
#: the plain trace leaves the power balance ~1e-2 off, cut 16 times ~4e-5 (measured on
#: examples/default.toml); and the maxima and sign changes of the torque need the
#: resolution as much.
TRACE_REFINEMENT = 16
#: Replayed methods: scipy's implicit solvers keep no step list that the Runge-Kutta
#: steppers can replay, so their periods are replayed by the linearly implicit ros23.
REPLAYABLE = ("dopri5", "bs3", "ros23")


@dataclass(frozen=True)
class RotorLoads:
    """The gas loads on one rotor over one lobe period (arrays against ``theta``)."""

    name: str
    speed_ratio: float  # over the reference rotor
    fx: np.ndarray  # N, fixed frame: force of the gas on the rotor
    fy: np.ndarray
    torque: np.ndarray  # N m, shaft torque: the rotor's on the gas, ccw positive
    axial: np.ndarray | None  # N, +z towards the high-pressure end; None: undefined

    @property
    def radial(self) -> np.ndarray:
        return np.hypot(self.fx, self.fy)


@dataclass(frozen=True)
class GasLoads:
    theta: np.ndarray  # reference-rotor angle over one lobe period (the trace's)
    rotors: tuple[RotorLoads, ...]
    omega_ref: float  # rad/s of the reference rotor
    indicated_power_W: float  # the cycle's, as the model's figures give it

    def mean(self, x: np.ndarray) -> float:
        """Mean over the period (trapezoid on the trace; repeated angles at events)."""
        span = self.theta[-1] - self.theta[0]
        return float(np.trapezoid(x, self.theta) / span)

    @property
    def power_W(self) -> float:
        """Mean power the shafts put into the gas: sum over rotors of omega_r T_r."""
        return sum(self.mean(r.torque) * r.speed_ratio * self.omega_ref for r in self.rotors)

    @property
    def power_balance_error(self) -> float | None:
        """|power from the loads / indicated power - 1|; None without indicated power."""
        if self.indicated_power_W == 0.0:
            return None
        return abs(self.power_W / self.indicated_power_W - 1.0)


def has_loads(table) -> bool:
    """The table carries the gas-load columns of every rotor it names."""
    names = getattr(table, "rotor_names", ())
    cols = getattr(table, "columns", {})
    return bool(names) and all(f"{q}_{n}_{u}" in cols for n in names
                               for q, u in (("force", "x_m2"), ("force", "y_m2"),
                                            ("torque", "m3")))


def gas_loads(result: SimulationResult, table) -> GasLoads | None:
    """The rotors' gas loads over the converged period; None if ``table`` has none."""
    if not has_loads(table):
        return None
    sol = result.solution
    model, geo = sol.model, sol.model.geo
    machine = fine_traces(result)
    theta = machine["theta_rad"]
    a = np.asarray(table.angle_rad, float)
    ks, gauge = _gauge_pressures(model, theta, machine["p_Pa"], float(a[-1]))
    ages = theta[:, None] + geo.period * ks[None, :]
    rotors = []
    for name, ratio in zip(table.rotor_names, table.speed_ratios, strict=True):
        def load(column):
            per_unit = np.interp(ages, a, np.asarray(table.columns[column], float),
                                 left=0.0, right=0.0)
            return (gauge * per_unit).sum(axis=1)

        fluid_torque = load(f"torque_{name}_m3")
        rotors.append(RotorLoads(name, float(ratio), load(f"force_{name}_x_m2"),
                                 load(f"force_{name}_y_m2"), -fluid_torque,
                                 _axial(table, name, fluid_torque, model)))
    return GasLoads(theta, tuple(rotors), geo.omega_outer, float(result.figures[
        "indicated_power_W"]))


def _k0(geo) -> int:
    """First slot offset whose chamber may exist: ages down to 0 (before the model's
    birth the table's chamber already exists, at suction pressure)."""
    return -int(math.ceil(geo.birth / geo.period))


def _gauge_pressures(model, theta: np.ndarray, p: np.ndarray, age_end: float):
    """Slot offsets ks (from _k0 to the table's end ``age_end``) and p - p_suction of
    every such chamber at every angle (angles, ks): the model's slots where alive,
    suction before birth, discharge after death (see the module docstring)."""
    geo = model.geo
    k0 = _k0(geo)
    # the table may run on past the model's last slot (the death angle)
    k1 = max(p.shape[1], int(math.ceil((age_end - theta[0]) / geo.period)) + 1)
    ks = np.arange(k0, k1)
    ages = theta[:, None] + geo.period * ks[None, :]
    g = np.where(ages > geo.death, model.dis.p - model.suc.p, 0.0)
    inside = (ks >= 0) & (ks < p.shape[1])
    live = np.isfinite(p)
    sub = g[:, inside]
    sub[live] = p[live] - model.suc.p
    g[:, inside] = sub
    return ks, g


def _axial(table, name: str, fluid_torque: np.ndarray, model) -> np.ndarray | None:
    """Axial gas force on the rotor: on the flanks (axial_per_torque times the fluid's
    torque, :func:`rotorflow.geometry.summary._rotor_loads`) plus the end faces:
    discharge pressure on the high-pressure end face, suction on the low-pressure one,
    pushing towards the suction end.  None where the table leaves either undefined."""
    k = table.rotor_scalars.get(f"axial_per_torque_{name}_per_m")
    area = table.rotor_scalars.get(f"end_area_{name}_m2")
    if k is None or area is None:
        return None
    return k * fluid_torque - (model.dis.p - model.suc.p) * area


def fine_traces(result: SimulationResult) -> dict:
    """The machine traces of the converged period at TRACE_REFINEMENT times the steps
    (the result's own traces if the period cannot be replayed)."""
    sol = result.solution
    model, run = sol.model, sol.run
    refined = []
    for seg, ends in zip(model.segments, run.steps, strict=True):
        t = np.concatenate([[seg.start], ends])
        fr = np.linspace(0.0, 1.0, TRACE_REFINEMENT + 1)[1:]
        refined.append(list((t[:-1, None] + np.diff(t)[:, None] * fr[None, :]).ravel()))
    method = run.method if run.method in REPLAYABLE else "ros23"
    atol = model.atol_scales()
    try:
        fine = integrate_period(model, sol.y_start[None], method, 1.0, atol, replay=refined,
                                record=True, force_replay=True)
    except IntegrationError:
        return result.machine
    finally:
        model.cache.clear()
        model.work.clear()
    return traces(replace(sol, run=fine))[0]
