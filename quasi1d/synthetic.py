"""Analytic chamber tables for tests and benchmarks (not a geometry engine).

The volume rises as sin^2 from zero at birth to V_max at ``angle_max`` and falls as sin^2
back to zero at ``life``; its derivative is analytic.  The end-face areas follow from
seed 000 Eq. 7 for a helical rotor of wrap Phi and length L: the chamber grows through
the low-pressure face and shrinks through the high-pressure face, so
area_lp = max(dV/dangle, 0) * Phi / L and area_hp = max(-dV/dangle, 0) * Phi / L.
The sealing line between the chamber of age a and the next older one (age a + period)
has length g(a) = seal * sin(pi (a + period) / (life + period)), positive over the
whole span in which either chamber exists, so seal_next(a) = g(a) and seal_prev(a) =
g(a - period) describe the same line from both sides.  The end-face sealing lengths are
smooth bumps: on the low-pressure plate from the volume maximum to mid-compression, on
the high-pressure plate from the maximum to death.  The table declares the internal
gear's leakage paths (interlobe+1, lp-face, hp-face); a test that wants other paths
replaces ``leakage_paths`` and adds its ``columns`` (dataclasses.replace).
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.geometry.table import ChamberTable, internal_gear_paths

CRC60_ANGLE_MAX = math.radians(220.0)  # seed 001, section 2.1
CRC60_LIFE = math.radians(907.0)
CRC60_WRAP = math.radians(547.0)  # 1.52 turns


def sin2_table(v_max=30e-6, lobes=3, angle_max=CRC60_ANGLE_MAX, life=CRC60_LIFE,
               length=0.16, diameter=0.086, wrap=CRC60_WRAP, seal=None,
               face_seal=None, speed_ratio=None, rows=1201) -> ChamberTable:
    """Chamber table with an analytic sin^2 volume curve (defaults: CRC.60-like sizes)."""
    a = np.linspace(0.0, life, rows)
    up = a <= angle_max
    s_up = 0.5 * math.pi * a / angle_max
    s_dn = 0.5 * math.pi * (life - a) / (life - angle_max)
    V = np.where(up, v_max * np.sin(s_up) ** 2, v_max * np.sin(s_dn) ** 2)
    dV = np.where(up, v_max * np.sin(2 * s_up) * 0.5 * math.pi / angle_max,
                  -v_max * np.sin(2 * s_dn) * 0.5 * math.pi / (life - angle_max))
    k = wrap / length
    period = 2.0 * math.pi / lobes
    seal = length if seal is None else seal
    face_seal = diameter / lobes if face_seal is None else face_seal

    def g(x):
        return seal * np.clip(np.sin(math.pi * (x + period) / (life + period)), 0.0, None)

    def bump(x, lo, hi):
        t = np.clip((x - lo) / (hi - lo), 0.0, 1.0)
        return np.sin(math.pi * t) ** 2

    mid = angle_max + 0.5 * (life - angle_max)
    return ChamberTable(
        angle_rad=a,
        volume_m3=V,
        dVdangle_m3_rad=dV,
        area_lp_m2=np.maximum(dV, 0.0) * k,
        area_hp_m2=np.maximum(-dV, 0.0) * k,
        seal_next_m=g(a),
        seal_prev_m=g(a - period),
        seal_lp_face_m=face_seal * bump(a, angle_max, mid),
        seal_hp_face_m=face_seal * bump(a, angle_max, life),
        lobes_outer=lobes,
        speed_ratio_outer_per_driven=(lobes - 1) / lobes if speed_ratio is None else speed_ratio,
        length_m=length,
        diameter_m=diameter,
        machine="synthetic",
        leakage_paths=internal_gear_paths(),
    )


def scaled_table(v_max: float, lobes: int, rows: int = 601) -> ChamberTable:
    """A sin^2 table of given size and lobe count with proportionate rotor dimensions:
    swept volume lobes * V_max = 0.3 of the rotor's cylinder, length 1.5 diameters, life
    360 deg + wrap with a wrap of 1.5 periods beyond one turn."""
    period = 2.0 * math.pi / lobes
    d = (lobes * v_max / (0.3 * math.pi / 4.0 * 1.5)) ** (1.0 / 3.0)
    wrap = 2.0 * math.pi * 0.75
    return sin2_table(v_max=v_max, lobes=lobes, angle_max=math.pi, life=2.0 * math.pi + wrap,
                      length=1.5 * d, diameter=d, wrap=wrap + 1.5 * period, rows=rows)
