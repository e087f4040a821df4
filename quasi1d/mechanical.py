"""Mechanical losses at the shafts: rolling-bearing friction under the gas loads and the
shaft seal, from published coefficients, not fitted to any measured compressor.

Bearings (SKF, Rolling bearings catalogue, chapter "Friction", section "Estimating the
frictional moment", Table 1 "Constant coefficient of friction mu for open bearings"):

    M = 0.5 * mu * P * d            (M friction moment, P bearing load, d bore diameter)

valid, says SKF, for a bearing load P ~ 0.1 C, good lubrication and normal operation.
Per rotor, as screw compressors are usually built:
* two radial bearings, cylindrical roller bearings with a cage, mu = 0.0011 (Table 1,
  F_a ~ 0), each carrying half the rotor's radial gas force (the gas load taken as
  centred between them);
* one thrust bearing, a single-row angular contact ball bearing, mu = 0.0020 (Table 1),
  carrying the whole axial gas force (flanks plus end faces, :mod:`.loads`).
M is linear in P, so the mean moment over a period is that of the mean |load|; its power
is M |omega_r|: Coulomb friction, linear in speed at given loads.  A rotor whose axial
load the table leaves undefined (conical rotors) gets no thrust-bearing term, and the
figures list it under ``not_modelled``.

The bore d is a design choice, not a coefficient: ``bearing_bore_mm`` in the case.  Its
default, BORE_FRACTION_DEFAULT of the machine diameter, is a placeholder sizing with no
source; the figures report the bore used.

Shaft seal: one seal where the driven shaft leaves the casing, a constant friction
torque ``seal_torque_Nm``.  Default 0 (no seal modelled): SKF's radial shaft seal pages
give lip-seal friction only as a diagram of power loss against shaft diameter and speed,
which is not transcribed here; take the torque from the seal maker's data.

Injected liquid (a compressor's oil, a multiphase pump's liquid): the rotors set it
turning.  It enters the grooves from the suction port without swirl and leaves them at
the discharge turning with the rotor, so by Euler's turbomachinery equation (torque =
mass flow x the angular momentum per kg it leaves with; e.g. Dixon & Hall, Fluid
Mechanics and Thermodynamics of Turbomachinery, ch. 1) the shaft gives it

    P = m_l sum_r s_r omega_r^2 k_r^2

(:func:`liquid_acceleration_W`): k_r the radius of gyration of rotor r's grooves about
its axis (the liquid spread over the groove's section, as the homogeneous chamber model
has it), s_r the share of the liquid rotor r carries, its grooves' share of the volume
swept, A_r |omega_r| / sum A |omega|.  Half of P is the kinetic energy the liquid
leaves with, half is lost in the impact as it is taken up; nothing is taken as
recovered at the discharge.  Not modelled: the liquid's drag in the grooves (churning)
and a swirl it enters with.  It needs the rotors' grooves in the table
(``groove_area_NAME_m2``, ``groove_gyration_NAME_m``: rotors with their material inside
their profile, twin screws); without them the figures list it under ``not_modelled``.

Injected oil: its viscous shear in the rotor-casing clearances is :mod:`.oil_film`'s,
from the oil's datasheet viscosities given here (``oil_viscosity_40C_cSt``,
``oil_viscosity_100C_cSt``, ``oil_density_kg_m3``); without them, or on a table that
declares no oil films, the figures list it under ``not_modelled``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from .settings import _check_keys, _number

#: SKF Rolling bearings catalogue, Friction, Table 1: cylindrical roller bearings with a
#: cage (F_a ~ 0).
MU_CYLINDRICAL_ROLLER = 0.0011
#: Same table: angular contact ball bearings, single row.
MU_ANGULAR_CONTACT_SINGLE_ROW = 0.0020
#: Placeholder bearing bore over the machine diameter, used without ``bearing_bore_mm``:
#: no source; an order of magnitude for the journal of a rotor of that diameter.
BORE_FRACTION_DEFAULT = 0.3
#: Density of a mineral compressor oil at its working temperature (kg/m3); ISO VG 32-68
#: mineral oils are 0.85-0.88 at 15 C and lose ~0.6 kg/m3 per K.
OIL_DENSITY = 850.0
#: Radial bearings per rotor, sharing its radial gas load equally.
RADIAL_BEARINGS = 2


@dataclass(frozen=True)
class Mechanical:
    """The [mechanical] section: bearing and seal friction (SI inside)."""

    bearing_mu_radial: float = MU_CYLINDRICAL_ROLLER
    bearing_mu_axial: float = MU_ANGULAR_CONTACT_SINGLE_ROW
    bearing_bore_m: float | None = None  # None: BORE_FRACTION_DEFAULT * machine diameter
    seal_torque_Nm: float = 0.0
    oil_viscosity_40C_cSt: float | None = None  # None: no oil-film loss
    oil_viscosity_100C_cSt: float | None = None
    oil_density_kg_m3: float = OIL_DENSITY

    KEYS = ("bearing_mu_radial", "bearing_mu_axial", "bearing_bore_mm", "seal_torque_Nm",
            "oil_viscosity_40C_cSt", "oil_viscosity_100C_cSt", "oil_density_kg_m3")

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> Mechanical:
        s = "mechanical"
        _check_keys(d, cls.KEYS, s, where)
        bore = d.get("bearing_bore_mm")
        nu = [None if d.get(k) is None else _number(d, k, s, where, positive=True)
              for k in ("oil_viscosity_40C_cSt", "oil_viscosity_100C_cSt")]
        if (nu[0] is None) != (nu[1] is None):
            raise CaseError(f"[{s}] of {where}: give both oil_viscosity_40C_cSt and "
                            "oil_viscosity_100C_cSt, or neither")
        if nu[0] is not None and nu[1] >= nu[0]:
            raise CaseError(f"[{s}] of {where}: oil_viscosity_100C_cSt ({nu[1]}) must be "
                            f"below oil_viscosity_40C_cSt ({nu[0]}): oil thins as it warms")
        return cls(
            bearing_mu_radial=_number(d, "bearing_mu_radial", s, where, MU_CYLINDRICAL_ROLLER,
                                      nonnegative=True),
            bearing_mu_axial=_number(d, "bearing_mu_axial", s, where,
                                     MU_ANGULAR_CONTACT_SINGLE_ROW, nonnegative=True),
            bearing_bore_m=None if bore is None else 1e-3 * _number(
                d, "bearing_bore_mm", s, where, positive=True),
            seal_torque_Nm=_number(d, "seal_torque_Nm", s, where, 0.0, nonnegative=True),
            oil_viscosity_40C_cSt=nu[0],
            oil_viscosity_100C_cSt=nu[1],
            oil_density_kg_m3=_number(d, "oil_density_kg_m3", s, where, OIL_DENSITY,
                                      positive=True),
        )

    @property
    def oil_viscosity_given(self) -> bool:
        return self.oil_viscosity_40C_cSt is not None

    def bore(self, diameter_m: float) -> float:
        return BORE_FRACTION_DEFAULT * diameter_m if self.bearing_bore_m is None \
            else self.bearing_bore_m


@dataclass(frozen=True)
class MechanicalLoss:
    bearings_W: dict  # per rotor: radial plus thrust bearings
    seal_W: float
    bore_m: float
    not_modelled: tuple[str, ...]

    @property
    def total_W(self) -> float:
        return float(sum(self.bearings_W.values()) + self.seal_W)


def mechanical_loss(loads, mech: Mechanical, diameter_m: float, omega_driven: float
                    ) -> MechanicalLoss:
    """Bearing and seal losses (W) under ``loads`` (:class:`.loads.GasLoads`) with the
    driven shaft at ``omega_driven`` (rad/s)."""
    d = mech.bore(diameter_m)
    bearings, missing = {}, []
    for r in loads.rotors:
        omega = abs(r.speed_ratio * loads.omega_ref)
        per_bearing = loads.mean(r.radial) / RADIAL_BEARINGS
        moment = RADIAL_BEARINGS * 0.5 * mech.bearing_mu_radial * per_bearing * d
        if r.axial is None:
            missing.append(f"thrust bearing of {r.name}: axial gas load undefined (variable "
                           "lead or tapered rotor)")
        else:
            moment += 0.5 * mech.bearing_mu_axial * loads.mean(np.abs(r.axial)) * d
        bearings[r.name] = float(moment * omega)
    return MechanicalLoss(bearings, float(mech.seal_torque_Nm * abs(omega_driven)), d,
                          tuple(missing))


def liquid_acceleration_W(flow_kg_s: float, loads, scalars: dict) -> float | None:
    """The power that turns ``flow_kg_s`` of injected liquid up to the rotors' speed
    (module docstring), ``loads`` giving the rotors and their speeds, ``scalars`` the
    table's per-rotor scalars; None where a rotor's grooves are not in them."""
    grooves = []
    for r in loads.rotors:
        area = scalars.get(f"groove_area_{r.name}_m2")
        radius = scalars.get(f"groove_gyration_{r.name}_m")
        if area is None or radius is None:
            return None
        grooves.append((area, radius, abs(r.speed_ratio * loads.omega_ref)))
    swept = sum(a * w for a, _, w in grooves)
    if swept <= 0.0:
        return 0.0
    return float(flow_kg_s * sum(a * w * (w * k) ** 2 for a, k, w in grooves) / swept)
