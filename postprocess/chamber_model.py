"""The quasi-1D side of the CFD chamber comparison: the CFD case as a one-chamber table,
run through the product's own model (:func:`rotorflow.quasi1d.simulate_transient`).

The CFD chamber case (:mod:`rotorflow.cases.chamber_case`) writes what it is in
``case.json``: its volume curve against outer-rotor angle, the speed, the suction state,
the gas, the slab's depth L_s (the sealing-line length the gap stands for) and the gap.
From that description :func:`one_chamber_table` makes a chamber table of one chamber:

* the volume: the CFD's samples, with dV/dangle from the cubic spline through them (the
  model's Hermite volume between the samples is then that spline: no kinks for its
  adaptive steps, and ~1e-7 of the volume from the piston's linear table);
* one leakage path, :data:`PATH` (kind "tip", the CFD's rotor-tip gap), from the chamber
  to the suction plenum, reading the column :data:`SEAL_COLUMN` = L_s, with the case's
  gap declared on it: the flow area gap x L_s the CFD's slab has;
* no port area: the chamber stays closed over the compared span (the model's port
  timing, which it requires, marks nothing);
* ``lobes_outer`` 1: the chamber is alone, and one lobe period (a revolution) holds its
  whole compression.

The chamber is born at the first sample with the suction state, as the CFD's is, and
:func:`model_pressure` integrates that single pass with the case's leakage settings
(no cycle convergence: the CFD run is one pass too).  Each leakage model compared is the
product's: "nozzle" and "fanno" with their coefficient, "cfd-calibrated" with the fitted
correlation, whose land length is the CFD gap's narrow length and whose one viscosity
is the gas's at the suction temperature (the model's viscosity is a constant).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from rotorflow.geometry.table import ChamberTable, LeakagePath
from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate_transient
from rotorflow.quasi1d.perfect_gas import PerfectGas

from .chamber_history import VolumeCurve, volume_curve

#: The one leakage path of the table, and the column it reads.
PATH = "cfd-gap"
SEAL_COLUMN = "seal_cfd_m"

#: How the single pass is integrated: the product's integrator ("auto": Dormand-Prince,
#: Rosenbrock if stiff) at a tolerance far below any difference reported (the sealed
#: chamber then follows p V^gamma to ~1e-8), so that the figures are the model's, not its
#: integration error's.
NUMERICS = Numerics(integrator="auto", rtol=1e-9, atol=1e-12)

#: Angles past the ends of the compression by less than this are its ends (the CFD's
#: sample times, written with 12 digits and turned into angles).
ANGLE_SLACK_RAD = 1e-9

#: Nozzle ports of zero area: no port flow at all (ideal ports would hold the chamber at
#: the plenum pressure while "open").
CLOSED = Ports(model="nozzle", coefficient=1.0)


def one_chamber_table(desc: Mapping) -> ChamberTable:
    """The chamber table of a CFD chamber case, from its ``case.json`` (see the module)."""
    curve = volume_curve(desc)
    a = curve.angle_rad
    zero = np.zeros_like(a)
    gap = float(desc["gap_m"])
    path = LeakagePath(PATH, "tip", "suction", SEAL_COLUMN, gap_m=gap if gap > 0 else None)
    return ChamberTable(
        angle_rad=a, volume_m3=curve.volume_m3, dVdangle_m3_rad=curve.smooth_dvdangle(a),
        area_lp_m2=zero, area_hp_m2=zero, seal_next_m=zero, seal_prev_m=zero,
        seal_lp_face_m=zero, seal_hp_face_m=zero,
        lobes_outer=1,
        speed_ratio_outer_per_driven=1.0,  # speed_rpm is the outer rotor's (operating())
        length_m=float(desc["depth_m"]),
        diameter_m=0.0,  # the wall speed; the CFD's walls do not move
        machine="cfd-chamber",
        leakage_paths=(path,),
        columns={SEAL_COLUMN: np.full_like(a, float(desc["seal_length_m"]))},
    )


def gas(desc: Mapping) -> PerfectGas:
    return PerfectGas(**desc["gas"])


def adiabatic_pressure(desc: Mapping, angle_rad) -> np.ndarray:
    """The sealed chamber in closed form: p V^gamma constant from the suction state (on
    the CFD's piston curve, linear between its samples)."""
    curve = volume_curve(desc)
    return float(desc["p_suction_Pa"]) * (curve.volume_m3[0] / curve.volume(angle_rad)) ** (
        gas(desc).gamma)


def operating(desc: Mapping) -> Operating:
    """The operating point of the single pass: the CFD's suction state, speed and gas."""
    a = volume_curve(desc).angle_rad
    g = gas(desc)
    p_s = float(desc["p_suction_Pa"])
    return Operating(
        p_suction_Pa=p_s,
        # The discharge plenum joins nothing (no path, no port area); the built-in
        # pressure of the compression keeps the model's discharge gas plausible.
        p_discharge_Pa=float(adiabatic_pressure(desc, a[-1])),
        T_suction_K=float(desc["T_suction_K"]),
        speed_rpm=float(desc["omega_outer_rad_s"]) * 60.0 / (2.0 * math.pi),
        # Port timing the model requires (birth < closing < opening < death); without
        # port area it marks nothing.
        suction_close_rad=float(a[1]), discharge_open_rad=float(a[-2]),
        heat_capacity="constant", molar_mass_kg_mol=1e-3 * g.molar_mass_kg_kmol,
        cp_J_kgK=g.cp_J_kgK,
    )


def leakage_models(desc: Mapping, leakage: Leakage | None = None, fit=None
                   ) -> dict[str, Leakage]:
    """The leakage settings compared with a run, named for the table.

    ``leakage``: the case's :class:`~rotorflow.quasi1d.Leakage` (None: its defaults).  Its
    coefficient applies to the model it names; the other model takes the default
    coefficient.  ``fit``: a fitted flow-coefficient correlation
    (:class:`~rotorflow.quasi1d.calibrated.FlowCoefficientFit`) or None.  A sealed run
    (gap 0) has the one model "sealed".
    """
    gap = float(desc["gap_m"])
    if gap == 0.0:
        return {"sealed": Leakage(model="none")}
    leakage = leakage or Leakage()
    default = Leakage()
    cd_nozzle = leakage.coefficient if leakage.model == "nozzle" else default.coefficient
    cd_fanno = leakage.coefficient if leakage.model == "fanno" else default.coefficient
    models = {
        f"nozzle (Cd={cd_nozzle:g})": Leakage(gap_m=gap, model="nozzle", coefficient=cd_nozzle),
        f"fanno (zeta={leakage.zeta:g}, Cd={cd_fanno:g})": Leakage(
            gap_m=gap, model="fanno", coefficient=cd_fanno, zeta=leakage.zeta),
    }
    if fit is not None:
        models["cfd-calibrated"] = Leakage(
            gap_m=gap, model="cfd-calibrated", correlation=fit,
            land_m=float(desc["gap_length_m"]),
            viscosity_Pa_s=gas(desc).mu(float(desc["T_suction_K"])))
    return models


def run_model(desc: Mapping, leakage: Leakage, angle_rad, numerics: Numerics = NUMERICS):
    """The product's model of the case's chamber over one pass, reported at
    ``angle_rad`` (a :class:`~rotorflow.quasi1d.TransientResult`, slot 0 the chamber)."""
    curve: VolumeCurve = volume_curve(desc)
    a = np.asarray(angle_rad, dtype=float)
    lo, hi = curve.angle_rad[0], curve.angle_rad[-1]
    if np.any(a < lo - ANGLE_SLACK_RAD) or np.any(a > hi + ANGLE_SLACK_RAD):
        raise ValueError(f"angles outside the case's compression, {lo:.6f} to {hi:.6f} rad")
    # The CFD's last sample time, turned into an angle, may pass the end by round-off.
    angles = np.clip(a, lo, hi)
    return simulate_transient(one_chamber_table(desc), operating(desc), angles, leakage,
                              CLOSED, numerics)


def model_pressure(desc: Mapping, leakage: Leakage, angle_rad) -> np.ndarray:
    """The chamber pressure of the product's model at ``angle_rad``."""
    return run_model(desc, leakage, angle_rad).p_Pa[:, 0]
