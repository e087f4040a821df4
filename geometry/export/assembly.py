"""The rotors of a pair placed for export, with the clearances applied, the casing, and
the analytic volumes every exported solid is checked against.

Any family: each rotor is a :class:`Part` by its name with its material side, and the
casing is the pair's bores (:mod:`.casing`).  A rotor with its material outside its
profile (the internal gear's outer rotor) fills its bore and is the fluid's outer wall;
otherwise (the twin screw) each rotor turns in its own bore, grown by the tip
clearance, and the union of the bores is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from ..curves import sample_polygon
from ..machine import SweptMachine
from ..offsets import Clearance, offset_profile, region_volume
from ..polygons import check_simple
from ..summary import build_machine
from .casing import largest_radius, union_area
from .settings import Export
from .surface import SweptSurface

#: Relative volume error an STL or STEP solid may show (the issue's acceptance).
VOLUME_RTOL = 1e-4
#: A bore is a rotor's own when its centre is the rotor's axis to this distance [m].
AXIS_MATCH = 1e-12


@dataclass(frozen=True)
class Part:
    """One rotor's flank placed in the machine frame at the export angle."""

    name: str
    surface: SweptSurface
    material_inside: bool
    #: a rotor with its material outside its profile: its outside radius (the bore)
    outside_radius: float | None = None

    @property
    def curve(self):
        return self.surface.curve


@dataclass(frozen=True)
class Assembly:
    """The rotors, the casing's bores ((centre, radius), ... at z = 0) and the ports'
    timing of one export."""

    machine: SweptMachine
    settings: Export
    parts: tuple[Part, ...]
    bores: tuple
    clearance_on: str
    #: radial gap of each rotor to its own bore (None: the casing is a rotor's outside)
    tip_clearance: float | None = None
    volume_ratio: float = 2.0
    #: explicit [operating] port angles since birth (radians), None: from the table
    suction_close: float | None = None
    discharge_open: float | None = None
    early_opening: float = 0.0

    @property
    def wall(self) -> Part | None:
        """The rotor that encloses the others (its material outside), if any."""
        return next((p for p in self.parts if not p.material_inside), None)

    @property
    def holes(self) -> tuple[Part, ...]:
        """The rotors with their material inside: holes through the fluid domain."""
        return tuple(p for p in self.parts if p.material_inside)

    @property
    def analytic(self) -> dict:
        sw = self.machine.sweep
        casing = union_area(self.bores) * sw.scale_squared_integral
        out = {"casing_m3": casing}
        enclosed = {}
        for p in self.parts:
            enclosed[p.name] = region_volume(p.curve, sw)
            out[f"{p.name}_m3"] = enclosed[p.name] if p.material_inside \
                else casing - enclosed[p.name]
        wall = self.wall
        core = enclosed[wall.name] if wall is not None else casing
        for p in self.holes:
            core -= enclosed[p.name]
        out["fluid_core_m3"] = core
        return out

    @property
    def zero_clearance_core_area(self) -> float:
        """Section area of the fluid core without any clearance: the chamber table's."""
        wall = self.wall
        area = wall.surface.base.area if wall is not None else self.machine.pair.working_area
        return area - sum(p.surface.base.area for p in self.holes)


def _offset(rotor, clearance: Clearance, others: list[str]):
    """The clearance offset into the rotor's material, or a one-line CaseError."""
    try:
        return offset_profile(rotor.profile, clearance, -1 if rotor.material_inside else 1)
    except CaseError as err:
        head = str(err).split("; apply")[0]
        hint = " or ".join(f'"{n}"' for n in others)
        raise CaseError(f"{head}; apply the clearance to another rotor (clearance_on = "
                        f"{hint}) or make it smaller") from None


def _checked_names(pair, settings: Export) -> str:
    """The rotor the clearance goes on; every rotor name the settings use exists."""
    names = [r.name for r in pair.rotors]
    listed = ", ".join(f'"{n}"' for n in names)
    on = settings.clearance_on or names[0]
    if on not in names:
        raise CaseError(f"clearance_on = {on!r} names no rotor of the {pair.family} pair "
                        f"(one of {listed})")
    for n in sorted(settings.per_rotor_names()):
        if n not in names:
            raise CaseError(f"the cutter settings name {n!r}, no rotor of the {pair.family} "
                            f"pair (one of {listed})")
    return on


def _bores(pair, settings: Export, curves: dict, tol: float):
    """(bores, tip clearance): the enclosing rotor's outside, or one bore per rotor."""
    ring = [r for r in pair.rotors if not r.material_inside]
    if ring:
        if settings.tip_clearance_m is not None:
            raise CaseError(f"tip_clearance_um does not apply to the {pair.family} pair: its "
                            f"casing is the {ring[0].name} rotor's outside (bore_diameter_mm)")
        bores = pair.casing_bores(None if settings.bore_diameter_m is None
                                  else 0.5 * settings.bore_diameter_m)
        bore, curve = bores[0][1], curves[ring[0].name]
        if bore <= curve.radius_max + tol:
            raise CaseError(f"bore_diameter_mm = {2e3 * bore:g} must exceed the {curve.name} "
                            f"rotor's profile diameter {2e3 * curve.radius_max:.4f} mm")
        return tuple(bores), None
    if settings.bore_diameter_m is not None:
        raise CaseError(f"bore_diameter_mm does not apply to the {pair.family} pair: each rotor "
                        "turns in its own bore; set tip_clearance_um")
    tip = settings.tip_clearance_m
    tip = min(settings.clearance_m) if tip is None else tip
    out = []
    for centre, _ in pair.casing_bores():
        rotor = next((r for r in pair.rotors
                      if math.dist(r.axis, centre) <= AXIS_MATCH), None)
        if rotor is None:
            raise CaseError(f"a bore of the {pair.family} casing has no rotor on its axis")
        out.append((tuple(centre), largest_radius(curves[rotor.name]) + tip))
    return tuple(out), tip


def assemble(case, settings: Export, machine: SweptMachine | None = None) -> Assembly:
    """Profiles with the clearance applied and checked, placed at the export angle."""
    m = machine or build_machine(case)
    pair, sweep = m.pair, m.sweep
    on = _checked_names(pair, settings)
    clearance = Clearance(settings.clearance_m)
    tol = settings.tolerance_m
    curves = {}
    for r in pair.rotors:
        others = [o.name for o in pair.rotors if o.name != r.name]
        curves[r.name] = _offset(r, clearance, others) if r.name == on else r.profile
    for name, curve in curves.items():
        what = f"{curve.name} rotor profile"
        if name == on and max(settings.clearance_m) > 0.0:
            # (an offset folds where the profile turns sharper than the clearance: at a
            # sharp corner, such as the trochoidal pump profile's, at any clearance)
            um = ", ".join(f"{c * 1e6:g}" for c in settings.clearance_m)
            what += f" offset by clearance_um = {um}"
        check_simple(sample_polygon(curve, tol), what)
    bores, tip = _bores(pair, settings, curves, tol)
    phi = settings.fluid_angle_rad
    parts = []
    for r in pair.rotors:
        outside = None if r.material_inside else next(
            b for c, b in bores if math.dist(c, r.axis) <= AXIS_MATCH)
        surf = SweptSurface(curves[r.name], sweep, r.speed_ratio * phi, r.speed_ratio, r.axis)
        parts.append(Part(r.name, surf, r.material_inside, outside))
    op = case.raw.get("operating", {}) if hasattr(case, "raw") else {}

    def angle(key):
        v = op.get(key)
        return None if v is None else math.radians(float(v))

    return Assembly(
        machine=m, settings=settings, parts=tuple(parts), bores=bores, clearance_on=on,
        tip_clearance=tip,
        volume_ratio=float(getattr(case, "volume_ratio", 2.0)),
        suction_close=angle("suction_close_deg"),
        discharge_open=angle("discharge_open_deg"),
        early_opening=angle("discharge_early_opening_deg") or 0.0,
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
