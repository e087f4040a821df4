"""Both rotors of a pair placed for export, with the clearance applied, and the analytic
volumes every exported solid is checked against."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from ..curves import Clearance, offset_profile, region_volume, sample_polygon
from ..machine import SweptMachine
from ..polygons import check_simple
from ..summary import build_machine
from .settings import Export
from .surface import SweptSurface

#: Relative volume error an STL or STEP solid may show (the issue's acceptance).
VOLUME_RTOL = 1e-4


@dataclass(frozen=True)
class Assembly:
    """Both rotors' flanks placed in the machine frame at the export angle."""

    machine: SweptMachine
    settings: Export
    outer: SweptSurface
    inner: SweptSurface
    bore_radius: float
    volume_ratio: float = 2.0
    #: explicit [operating] port angles since birth (radians), None: from the table
    suction_close: float | None = None
    discharge_open: float | None = None

    @property
    def analytic(self) -> dict:
        sw = self.machine.sweep
        v_out = region_volume(self.outer.curve, sw)
        v_in = region_volume(self.inner.curve, sw)
        casing = math.pi * self.bore_radius ** 2 * sw.scale_squared_integral
        return {"casing_m3": casing, "outer_m3": casing - v_out, "inner_m3": v_in,
                "fluid_core_m3": v_out - v_in}


def assemble(case, settings: Export, machine: SweptMachine | None = None) -> Assembly:
    """Profiles with the clearance applied and checked, placed at the export angle.

    Written for a pair whose first rotor encloses the second (material outside, as the
    internal gear's outer rotor): ``outer`` and ``inner`` are those two rotors."""
    m = machine or build_machine(case)
    pair, sweep = m.pair, m.sweep
    ring, core = pair.rotors[0], pair.rotors[1]
    if ring.material_inside or not core.material_inside:
        raise CaseError(f"solids of a {pair.family} pair are not written yet: the export "
                        "needs a first rotor that encloses the second")
    clearance = Clearance(settings.clearance_m)
    outer, inner = ring.profile, core.profile
    if settings.clearance_on == "outer":
        outer = offset_profile(outer, clearance, +1)
    else:
        inner = offset_profile(inner, clearance, -1)
    tol = settings.tolerance_m
    for curve in (outer, inner):
        check_simple(sample_polygon(curve, tol), f"{curve.name} rotor profile")
    bore = pair.casing_bores(None if settings.bore_diameter_m is None
                             else 0.5 * settings.bore_diameter_m)[0][1]
    if bore <= outer.radius_max + tol:
        raise CaseError(f"bore_diameter_mm = {2e3 * bore:g} must exceed the outer rotor's "
                        f"profile diameter {2e3 * outer.radius_max:.4f} mm")
    phi = settings.fluid_angle_rad
    op = case.raw.get("operating", {}) if hasattr(case, "raw") else {}

    def angle(key):
        v = op.get(key)
        return None if v is None else math.radians(float(v))

    return Assembly(
        machine=m,
        settings=settings,
        outer=SweptSurface(outer, sweep, ring.speed_ratio * phi, ring.speed_ratio, ring.axis),
        inner=SweptSurface(inner, sweep, core.speed_ratio * phi, core.speed_ratio, core.axis),
        bore_radius=bore,
        volume_ratio=float(getattr(case, "volume_ratio", 2.0)),
        suction_close=angle("suction_close_deg"),
        discharge_open=angle("discharge_open_deg"),
    )


def rel_error(a: float, b: float) -> float:
    return abs(a / b - 1.0) if b else abs(a)


def check_volume(name: str, volume: float, analytic: float) -> None:
    if rel_error(volume, analytic) > VOLUME_RTOL:
        raise RuntimeError(f"{name}: volume {volume:.9g} m^3 differs from the analytic "
                           f"{analytic:.9g} m^3 by {rel_error(volume, analytic):.2e}")


def chamber_sum(machine: SweptMachine, phi: float) -> float:
    """Sum of the volumes of all chambers present at reference angle phi (chamber table)."""
    period = machine.pair.period
    cur = machine.curves
    k0 = math.floor((cur.phi[0] - phi) / period) - 1
    k1 = math.ceil((cur.phi[-1] - phi) / period) + 1
    angles = phi + period * np.arange(k0, k1 + 1)
    return float(machine.volume_at(angles).sum())
