"""The [export] section of a case file: which solids and machining files to build.

Keys (lengths in the unit their name carries; the dataclass holds SI):

``formats`` (required)
    any of ``"stl"`` (outer.stl, inner.stl), ``"fluid"`` (fluid.stl), ``"step"``
    (outer.step, inner.step), ``"dxf"`` (outer_profile.dxf, inner_profile.dxf), ``"csv"``
    (the profiles and the point clouds as CSV), ``"ply"`` (the point clouds as PLY),
    ``"cutter"`` (inner_cutter.csv: the form-cutter profile of the inner rotor).
    Nothing that is not named is built.
``tolerance_um`` = 5
    largest distance of any STL vertex, edge midpoint or facet centroid, and of any
    profile chord, from the analytic surface.  5 um: the scale of the clearances.
``clearance_um`` = 0
    rotor-to-rotor clearance as a transverse normal offset of one profile: one number
    (uniform), or a list of values at equally spaced fractions of each lobe's arc
    length (from the centre of the pin, or the root of an inner lobe), joined by a
    periodic cubic spline.  The fluid domain needs a positive clearance.
``clearance_on`` = "outer"
    the profile that is offset: "outer" (into the outer rotor: always valid up to the
    pin radius) or "inner" (into the inner rotor: invalid where its convex radius is
    smaller than the clearance, which at sigma_bar = 1 is everywhere near the tip).
``fluid_angle_deg`` = 0
    outer-rotor angle of the assembly; the rotors and the fluid domain are written in
    the machine frame at this angle (outer axis on z, low-pressure face at z = 0).
``bore_diameter_mm``
    outside diameter of the outer rotor (= the casing bore); default 1.25 D.
``port_depth_mm``
    depth of the port pockets cut into the end plates (fluid domain); default 0.1 D,
    0 for none.
``cutter_setting_angle_deg``, ``cutter_centre_distance_mm``
    tool-axis setting angle (from the plane normal to the rotor axis) and distance
    between the tool and rotor axes of the form cutter; defaults: the inner rotor's
    helix angle at its pitch radius, and the outer diameter D.
``cloud_spacing_mm`` = 1
    spacing of the inspection point clouds along the profile and along z.
``units`` = "mm"
    length unit of every file written ("mm" or "m"); STEP is always in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rotorflow.errors import CaseError

FORMATS = ("stl", "fluid", "step", "dxf", "csv", "ply", "cutter")
KEYS = ("formats", "tolerance_um", "clearance_um", "clearance_on", "fluid_angle_deg",
        "bore_diameter_mm", "port_depth_mm", "cutter_setting_angle_deg",
        "cutter_centre_distance_mm", "cloud_spacing_mm", "units")
#: A tolerance above this is no longer a tolerance of a rotor of any size here.
TOLERANCE_MAX_UM = 1000.0


def _where(where: str) -> str:
    return f"[export] of {where}"


def _num(d: dict, key: str, where: str, default=None, *, positive=False, nonnegative=False):
    if key not in d:
        return default
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise CaseError(f"key '{key}' in {_where(where)} must be a number, got {v!r}")
    if not math.isfinite(v):
        raise CaseError(f"key '{key}' in {_where(where)} must be finite, got {v!r}")
    if positive and not v > 0:
        raise CaseError(f"key '{key}' in {_where(where)} must be positive, got {v!r}")
    if nonnegative and v < 0:
        raise CaseError(f"key '{key}' in {_where(where)} must not be negative, got {v!r}")
    return float(v)


def _choice(d: dict, key: str, where: str, choices, default):
    v = d.get(key, default)
    if not isinstance(v, str) or v not in choices:
        allowed = ", ".join(f'"{c}"' for c in choices)
        raise CaseError(f"key '{key}' in {_where(where)} must be one of {allowed}, got {v!r}")
    return v


@dataclass(frozen=True)
class Export:
    formats: tuple[str, ...]
    tolerance_m: float = 5e-6
    clearance_m: tuple[float, ...] = (0.0,)
    clearance_on: str = "outer"
    fluid_angle_rad: float = 0.0
    bore_diameter_m: float | None = None
    port_depth_m: float | None = None
    cutter_setting_angle_rad: float | None = None
    cutter_centre_distance_m: float | None = None
    cloud_spacing_m: float = 1e-3
    units: str = "mm"

    @property
    def unit_scale(self) -> float:
        """Multiplier from metres to the file unit."""
        return 1e3 if self.units == "mm" else 1.0

    def wants(self, fmt: str) -> bool:
        return fmt in self.formats

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> Export:
        if not isinstance(d, dict):
            raise CaseError(f"{_where(where)} must be a table")
        for k in d:
            if k not in KEYS:
                raise CaseError(f"unknown key '{k}' in {_where(where)}")
        if "formats" not in d:
            raise CaseError(f"missing key 'formats' in {_where(where)}")
        fm = d["formats"]
        if not isinstance(fm, list) or not fm or not all(isinstance(f, str) for f in fm):
            raise CaseError(f"key 'formats' in {_where(where)} must be a non-empty list of "
                            f"strings, got {fm!r}")
        for f in fm:
            if f not in FORMATS:
                allowed = ", ".join(f'"{c}"' for c in FORMATS)
                raise CaseError(f"unknown format {f!r} in 'formats' of {_where(where)} "
                                f"(one of {allowed})")
        if len(set(fm)) != len(fm):
            raise CaseError(f"key 'formats' in {_where(where)} names a format twice")
        tol = _num(d, "tolerance_um", where, 5.0, positive=True)
        if tol > TOLERANCE_MAX_UM:
            raise CaseError(f"key 'tolerance_um' in {_where(where)} must be at most "
                            f"{TOLERANCE_MAX_UM:g}, got {tol:g}")
        cl = d.get("clearance_um", 0.0)
        if isinstance(cl, list):
            if not cl:
                raise CaseError(f"key 'clearance_um' in {_where(where)} must not be an empty list")
            values = []
            for i, v in enumerate(cl):
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise CaseError(f"key 'clearance_um' in {_where(where)}: entry {i} must be "
                                    f"a number, got {v!r}")
                if v < 0:
                    raise CaseError(f"key 'clearance_um' in {_where(where)}: entry {i} must not "
                                    f"be negative, got {v!r}")
                values.append(float(v) * 1e-6)
            clearance = tuple(values)
        else:
            clearance = (_num(d, "clearance_um", where, 0.0, nonnegative=True) * 1e-6,)
        angle = _num(d, "cutter_setting_angle_deg", where)
        if angle is not None and not -89.0 <= angle <= 89.0:
            raise CaseError(f"key 'cutter_setting_angle_deg' in {_where(where)} must lie in "
                            f"[-89, 89], got {angle:g}")
        bore = _num(d, "bore_diameter_mm", where, positive=True)
        depth = _num(d, "port_depth_mm", where, nonnegative=True)
        centre = _num(d, "cutter_centre_distance_mm", where, positive=True)
        return cls(
            formats=tuple(fm),
            tolerance_m=tol * 1e-6,
            clearance_m=clearance,
            clearance_on=_choice(d, "clearance_on", where, ("outer", "inner"), "outer"),
            fluid_angle_rad=math.radians(_num(d, "fluid_angle_deg", where, 0.0)),
            bore_diameter_m=None if bore is None else bore * 1e-3,
            port_depth_m=None if depth is None else depth * 1e-3,
            cutter_setting_angle_rad=None if angle is None else math.radians(angle),
            cutter_centre_distance_m=None if centre is None else centre * 1e-3,
            cloud_spacing_m=_num(d, "cloud_spacing_mm", where, 1.0, positive=True) * 1e-3,
            units=_choice(d, "units", where, ("mm", "m"), "mm"),
        )
