"""Chamber pressure of the ideal 0D cycle, net rotor loads and the power split.

Seed 000 sections 4.3-4.5: ideal gas, adiabatic compression, no leakage, no port
losses and matched discharge, so the pressure of a chamber follows from its volume
alone.  Torques here are those the rotors exert on the fluid (what a shaft supplies),
the opposite of the fluid's torques in :class:`~.machine.ChamberCurves`.  Written for
any family: rotor r turns at ``speed_ratio[r]`` times the reference rotor (rotor 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .machine import SweptMachine
from .scalar import periodic_peak

#: Isentropic exponent of seed 000's ideal adiabatic cycle ("an ideal gas with gamma =
#: 1.4", section 4.3).  An assumption of that cycle, not a gas model: the quasi-1D model
#: takes its gas from rotorflow.quasi1d (which geometry must not import: quasi1d imports
#: geometry.table).
IDEAL_CYCLE_GAMMA = 1.4


def adiabatic_pressure(volume, eps_v: float, p_suction: float = 1.0e5,
                       gamma: float = IDEAL_CYCLE_GAMMA, p_discharge: float | None = None,
                       opening: int | None = None):
    """Pressure along a chamber's life: suction, adiabatic compression, discharge.

    Suction at ``p_suction`` until the volume peaks; then ``p (V_max/V)^gamma`` until
    the volume has fallen by the built-in ratio ``eps_v``; then the discharge pressure,
    by default ``p_suction eps_v^gamma`` (matched compression) to the end.  Given
    ``p_discharge``, the chamber takes that pressure where it opens (over- or
    under-compression, a sudden equalisation): at sample ``opening`` if given, else
    where its volume has fallen by ``eps_v`` (with ``eps_v = 1``, a pump without
    internal compression, the discharge pressure reaches the chamber at ``opening``).
    """
    v = np.asarray(volume, dtype=float)
    k = int(np.argmax(v))
    v_max = v[k]
    p_dis = p_suction * eps_v**gamma
    p = np.full_like(v, p_suction)
    tail = v[k:]
    # Past the built-in ratio the chamber is at discharge pressure; only compute the
    # adiabatic law where the volume is still above V_max / eps_v (no overflow near 0).
    compressing = tail > v_max / eps_v
    comp = np.full_like(tail, p_dis)
    comp[compressing] = p_suction * (v_max / tail[compressing]) ** gamma
    p[k:] = np.minimum(comp, p_dis)
    if p_discharge is not None:
        if opening is None:
            opening = k + int(np.argmin(compressing)) if not compressing.all() else len(v)
        p[opening:] = p_discharge
    return p


def cycle_work(volume_max: float, eps_v: float, p_suction: float, gamma: float = IDEAL_CYCLE_GAMMA):
    """Indicated work per chamber and cycle, seed 000 Eq. 17."""
    p_dis = p_suction * eps_v**gamma
    return gamma / (gamma - 1.0) * (p_dis * volume_max / eps_v - p_suction * volume_max)


@dataclass(frozen=True)
class PowerSplit:
    phi: np.ndarray  # one lobe period of reference-rotor angle
    torque: np.ndarray  # (n, rotors) net shaft torque of each rotor on the fluid [N m]
    force: np.ndarray  # (n, rotors, 2) net force of the fluid on each rotor [N]
    power_ratio: np.ndarray  # (n, rotors) P_r / P_in
    rotor_names: tuple[str, ...]
    mean_power_per_omega1: float  # sum of speed_ratio_r T_r, mean
    cycle_power_per_omega1: float  # W_cyc N1 / (2 pi), Eq. 18
    driven: str
    pi_max: float

    @property
    def power_balance_error(self) -> float:
        return abs(self.mean_power_per_omega1 / self.cycle_power_per_omega1 - 1.0)


def _fold(phi, torque, force, pressure, per_period: int):
    """Sum the loads of every chamber present (Eq. 16) over one lobe period.

    Chamber k lags the first by k periods; on a period-aligned grid a period is exactly
    ``per_period`` samples, so shifting is indexing.
    """
    n = len(phi)
    reps = -(-n // per_period)
    pad = reps * per_period - n

    def fold(x):
        x = np.concatenate([x, np.zeros((pad,) + x.shape[1:])])
        return x.reshape((reps, per_period) + x.shape[1:]).sum(0)

    return (phi[:per_period], fold(pressure[:, None] * torque),
            fold(pressure[:, None, None] * force))


def net_loads(machine: SweptMachine, pressure: np.ndarray):
    """(phi, torque (n, rotors), force (n, rotors, 2)): the net fluid torques and forces
    on every rotor over one lobe period, for a pressure given on the chamber-curve grid."""
    c = machine.curves
    return _fold(c.phi, c.torque, c.force, pressure, machine.points_per_period)


def _opening(machine: SweptMachine, phi: np.ndarray, volume: np.ndarray) -> int:
    """Sample of ``phi`` at which a chamber without internal compression opens to the
    discharge (:func:`.ports.port_timing`): the end of its transport plateau, where its
    leading section reaches the discharge plate, or its volume maximum if it has none."""
    life, wrap = machine.life_2d, machine.sweep.wrap
    if life < wrap:
        return int(np.searchsorted(phi - machine.section.phi_i, wrap - 1e-9 * wrap))
    return int(np.argmax(volume))


def power_split(
    machine: SweptMachine,
    eps_v: float,
    driven: str = "auto",
    p_suction: float = 1.0e5,
    gamma: float = IDEAL_CYCLE_GAMMA,
    p_discharge: float | None = None,
) -> PowerSplit:
    """Seed 000 Eqs. 17-22: power balance, power ratios, driven rotor and Pi_max.

    ``p_discharge``: the discharge plenum's pressure where it differs from the matched
    one (:func:`adiabatic_pressure`); a pump without internal compression (``eps_v =
    1``) needs it, and its chamber takes it where it opens (:func:`_opening`), so that
    its cycle work is ``(p_discharge - p_suction) V_max``."""
    if eps_v == 1.0 and p_discharge is None:
        raise ValueError("a volume ratio of 1 compresses nothing: the power split needs "
                         "the discharge pressure")
    # Loads on the fine section grid: the power ratios have kinks (a chamber starting
    # to discharge), so their maximum is taken where the loads are sampled finely.
    fine = machine.loads
    c = machine.curves
    opens = ((None, None) if eps_v != 1.0 else
             (_opening(machine, fine.phi, fine.volume), _opening(machine, c.phi, c.volume)))
    p = adiabatic_pressure(fine.volume, eps_v, p_suction, gamma, p_discharge, opens[0])
    # Gauge pressure: a uniform pressure loads no rotor, so only p - p_suction matters,
    # and leaving it out keeps the sums free of cancellation.
    phi, tq, force = _fold(fine.phi, fine.torque, fine.force, p - p_suction,
                           machine.points_per_period * machine.section_refinement)
    shaft = -tq
    rotors = machine.pair.rotors
    power = np.stack([r.speed_ratio * shaft[:, i] for i, r in enumerate(rotors)], 1)
    p_in = power.sum(1)
    ratio = power / p_in[:, None]
    # Eq. 18 with the cycle work of the chamber's own p-V loop; for a conjugate pair
    # (no clearance volume) it equals the closed form of Eq. 17 (see tests).
    p_c = adiabatic_pressure(c.volume, eps_v, p_suction, gamma, p_discharge, opens[1])
    w = -float(np.trapezoid((p_c - p_suction) * c.dvolume, c.phi))
    cycle = w * rotors[0].lobes / (2.0 * math.pi)
    names = tuple(r.name for r in rotors)
    if driven == "auto":
        driven = names[int(np.argmax(ratio.max(0)))]
    if driven not in names:
        raise ValueError(f"driven rotor {driven!r} is none of {names}")
    # Pi_max (seed 000 Eq. 22): the largest share of the input power that passes through
    # a rotor that is not driven, i.e. through the gearing contact; the maximum over the
    # period located between the samples (:func:`.scalar.periodic_peak`).
    idle = np.abs(np.delete(ratio, names.index(driven), axis=1))
    pi_max = max(periodic_peak(idle[:, j])[1] for j in range(idle.shape[1]))
    return PowerSplit(
        phi=phi,
        torque=shaft,
        force=force,
        power_ratio=ratio,
        rotor_names=names,
        mean_power_per_omega1=float(np.mean(p_in)),
        cycle_power_per_omega1=cycle,
        driven=driven,
        pi_max=float(pi_max),
    )
