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
(a few dozen per period); the loads are taken from that solution cut into
``TRACE_REFINEMENT`` per step by cubic Hermite interpolation of the state (its value
and right-hand side at both step ends: third order, within the integrator's own error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .result import SimulationResult, traces

#: Each accepted step of the converged period is cut into this many for the load traces.
#: The mean power is a trapezoid rule over the trace, O(h^2): on examples/default.toml
#: (24 steps per period) the plain trace leaves the power balance 2.9e-4 off, cut 16
#: times 4.5e-5 (the floor is the integrator's rtol); the extents and sign changes of the
#: torque want the finer trace more than the mean does. The interpolation costs one
#: right-hand side per step, where replaying the period cut 16 times took ~0.2 s.
TRACE_REFINEMENT = 16


@dataclass(frozen=True)
class RotorLoads:
    """The gas loads on one rotor over one lobe period (arrays against ``theta``)."""

    name: str
    speed_ratio: float  # over the reference rotor
    fx: np.ndarray  # N, fixed frame: force of the gas on the rotor
    fy: np.ndarray
    torque: np.ndarray  # N m, shaft torque: the rotor's on the gas, ccw positive
    axial: np.ndarray | None  # N, +z towards the high-pressure end; None: undefined
    #: of which on the end faces (constant: discharge less suction pressure on the
    #: rotor's section; the rest acts on the flanks, where the chambers meet the rotor)
    axial_end: float | None = None

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
    model = result.solution.model
    machine = fine_traces(result)
    theta = machine["theta_rad"]
    ks, gauge = _gauge_pressures(model, theta, machine["p_Pa"], float(table.angle_rad[-1]))
    rotors = fold(table, theta, model.geo.period, ks, gauge, model.dis.p - model.suc.p)
    return GasLoads(theta, rotors, model.geo.omega_outer,
                    float(result.figures["indicated_power_W"]))


def fold(table, theta: np.ndarray, period: float, ks: np.ndarray, gauge: np.ndarray,
         dp_end_face: float) -> tuple[RotorLoads, ...]:
    """Loads on every rotor at the angles ``theta`` from the gauge pressures (angles,
    ks) of the chambers ``ks`` periods older than the one of age theta; ``dp_end_face``:
    discharge minus suction pressure, on the rotors' high-pressure end faces."""
    a = np.asarray(table.angle_rad, float)
    ages = theta[:, None] + period * np.asarray(ks)[None, :]
    rotors = []
    for name, ratio in zip(table.rotor_names, table.speed_ratios, strict=True):
        def load(column):
            # linear in the node values, and every chamber sits at the same fraction of
            # a (period-aligned) cell: a uniform pressure cancels as on the nodes
            per_unit = np.interp(ages, a, np.asarray(table.columns[column], float),
                                 left=0.0, right=0.0)
            return (gauge * per_unit).sum(axis=1)

        fluid_torque = load(f"torque_{name}_m3")
        rotors.append(RotorLoads(name, float(ratio), load(f"force_{name}_x_m2"),
                                 load(f"force_{name}_y_m2"), -fluid_torque,
                                 *_axial(table, name, fluid_torque, dp_end_face)))
    return tuple(rotors)


def slots(birth: float, period: float, n_model: int, theta0: float, age_end: float):
    """Offsets k of every chamber that exists at some angle of a period starting at
    theta0: from ages down to 0 (before the model's birth the table's chamber already
    exists) to the table's end ``age_end`` (which may lie past the model's last slot)."""
    k0 = -int(math.ceil(birth / period))
    k1 = max(n_model, int(math.ceil((age_end - theta0) / period)) + 1)
    return np.arange(k0, k1)


def _gauge_pressures(model, theta: np.ndarray, p: np.ndarray, age_end: float):
    """Slot offsets ks (see :func:`slots`) and p - p_suction of every such chamber at
    every angle (angles, ks): the model's slots where alive, suction before birth,
    discharge after death (see the module docstring)."""
    geo = model.geo
    ks = slots(geo.birth, geo.period, p.shape[1], float(theta[0]), age_end)
    ages = theta[:, None] + geo.period * ks[None, :]
    g = np.where(ages > geo.death, model.dis.p - model.suc.p, 0.0)
    inside = (ks >= 0) & (ks < p.shape[1])
    live = np.isfinite(p)
    sub = g[:, inside]
    sub[live] = p[live] - model.suc.p
    g[:, inside] = sub
    return ks, g


def _axial(table, name: str, fluid_torque: np.ndarray, dp: float):
    """(axial gas force on the rotor, its end-face part): seed 004 separates the two.  On
    the flanks: axial_per_torque times the fluid's torque
    (:func:`rotorflow.geometry.summary._rotor_loads`); on the end faces: discharge
    pressure on the high-pressure end face, suction on the low-pressure one, pushing
    towards the suction end.  (None, None) where the table leaves either undefined."""
    k = table.rotor_scalars.get(f"axial_per_torque_{name}_per_m")
    area = table.rotor_scalars.get(f"end_area_{name}_m2")
    if k is None or area is None:
        return None, None
    return k * fluid_torque - dp * area, -dp * area


def fine_traces(result: SimulationResult) -> dict:
    """The machine traces of the converged period at TRACE_REFINEMENT times the steps:
    cubic Hermite interpolation of the state between the recorded steps of each segment,
    from the state and the right-hand side at both ends (the period's own solution: the
    derivatives its steps recorded, or one right-hand side per recorded step, instead of
    a replayed integration)."""
    sol = result.solution
    model, run = sol.model, sol.run
    th = np.asarray(run.trace_theta, float)
    ys = np.asarray(run.trace_y, float)
    fs = np.asarray(run.trace_f, float) if len(run.trace_f) == len(th) else None
    counts = [1 + len(ends) for ends in run.steps]
    if sum(counts) != len(th) or len(counts) != len(model.segments):
        return result.machine  # a trace not laid out by segment: keep the steps
    fine_t, fine_y = [], []
    first = 0
    try:
        for seg, count in zip(model.segments, counts, strict=True):
            t, y = th[first:first + count], ys[first:first + count]
            first += count
            fine_t.append(t[:1])
            fine_y.append(y[:1])
            if count < 2:
                continue
            # the integrator's own derivatives, else every recorded step's, in one call
            f = fs[first - count:first] if fs is not None else model.rhs(t, y, seg)
            h = np.diff(t)[:, None, None]
            s = np.linspace(0.0, 1.0, TRACE_REFINEMENT + 1)[1:][None, :, None]
            h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
            h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
            fine = (h00 * y[:-1, None] + h10 * h * f[:-1, None]
                    + h01 * y[1:, None] + h11 * h * f[1:, None])
            fine_t.append((t[:-1, None] + np.diff(t)[:, None] * s[..., 0]).ravel())
            fine_y.append(fine.reshape(-1, y.shape[1]))
    finally:
        model.cache.clear()
    dense = replace(run, trace_theta=list(np.concatenate(fine_t)),
                    trace_y=list(np.concatenate(fine_y)))
    return traces(replace(sol, run=dense))[0]
