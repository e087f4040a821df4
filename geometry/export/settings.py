"""The [export] section of a case file: which solids and machining files to build.

Keys (lengths in the unit their name carries; the dataclass holds SI):

``formats`` (required)
    any of ``"stl"`` (one solid per rotor, ``<rotor>.stl``: outer.stl and inner.stl for an
    internal gear, male.stl and female.stl for a twin screw), ``"fluid"`` (fluid.stl),
    ``"step"`` (``<rotor>.step``; with ``"fluid"`` also fluid_core.step, the fluid
    domain without the port pockets), ``"dxf"`` (``<rotor>_profile.dxf``), ``"csv"`` (the
    profiles and the point clouds as CSV), ``"ply"`` (the point clouds as PLY),
    ``"cutter"`` (``<rotor>_cutter.csv``: the form-cutter profile of every externally
    toothed rotor, i.e. every rotor with its material inside its profile: the internal
    gear's inner rotor, both twin-screw rotors).  Nothing that is not named is built.
``tolerance_um`` = 5
    largest distance of any STL vertex, edge midpoint or facet centroid, and of any
    profile chord, from the analytic surface.  5 um: the scale of the clearances.
``clearance_um`` = 0
    rotor-to-rotor clearance as a transverse normal offset of one profile: one number
    (uniform), or a list of values at equally spaced fractions of each lobe's arc
    length (from the centre of the pin, or the root of an inner lobe; from the start of
    a twin-screw lobe's first arc), joined by a periodic cubic spline.  The fluid
    domain needs a positive clearance.
``clearance_on``
    the rotor whose profile is offset, into its material, by name: "outer" or "inner"
    (internal gear), "male" or "female" (twin screw); default the reference rotor (the
    pair's first: outer, male).  Offsetting "outer" is always valid up to the pin radius;
    a rotor with its material inside folds where its convex radius of curvature is
    smaller than the clearance (the internal gear's inner rotor at sigma_bar = 1
    everywhere near the tip; the 4/6 twin screw's female at 1.2 mm, its male at 3.8 mm).
``tip_clearance_um``
    a pair whose casing is one bore per rotor (twin screw): the radial gap between each
    exported rotor (clearance included) and its bore, i.e. each bore's radius is its
    rotor's largest radius plus this gap.  Default: the smallest value of clearance_um
    (one number sets every gap, as [leakage] gap_um does).  Not for the internal gear,
    whose casing is the outer rotor's outside (bore_diameter_mm).
``fluid_angle_deg`` = 0
    reference-rotor angle of the assembly; the rotors and the fluid domain are written in
    the machine frame at this angle (reference axis on z, low-pressure face at z = 0).
``bore_diameter_mm``
    internal gear: outside diameter of the outer rotor (= the casing bore); default
    1.25 D.  Not for a pair with one bore per rotor (tip_clearance_um sets those).
``port_depth_mm``
    depth of the port pockets cut into the end plates (fluid domain); default 0.1 D,
    0 for none.
``cutter_setting_angle_deg``, ``cutter_centre_distance_mm``
    tool-axis setting angle (from the plane normal to the rotor axis; seed 004's
    helical oblique angle of the disc cutter) and distance between the tool and rotor
    axes of the form cutter: one number for every rotor cut, or an inline table by rotor
    name (``{male = 56, female = -50}``; the twin screw's rotors are of opposite hand,
    so one angle rarely suits both), rotors not named taking the defaults: the rotor's
    helix angle at its pitch radius, and the pair's diameter D.
``cutter_front_angle_deg`` = 0
    the disc cutter's front (rake) angle (seed 004): its cutting edge lies in a plane
    parallel to the tool axis at ``sin(angle)`` times the tool's largest radius from it,
    so the edge a toolmaker grinds is the tool's section by that plane, written as
    ``<rotor>_cutter_rake.csv`` (and enveloped back onto the rotor, as the axial one).
    Between -45 and 45 deg.
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
KEYS = ("formats", "tolerance_um", "clearance_um", "clearance_on", "tip_clearance_um",
        "fluid_angle_deg", "bore_diameter_mm", "port_depth_mm", "cutter_setting_angle_deg",
        "cutter_centre_distance_mm", "cutter_front_angle_deg", "cloud_spacing_mm", "units")
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


def _clearance(d: dict, where: str) -> tuple[float, ...]:
    cl = d.get("clearance_um", 0.0)
    if not isinstance(cl, list):
        return (_num(d, "clearance_um", where, 0.0, nonnegative=True) * 1e-6,)
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
    return tuple(values)


def _per_rotor(d: dict, key: str, where: str, to_si, check=None, **kind):
    """A number for every rotor, or an inline table of numbers by rotor name: SI, as a
    float or a tuple of (name, value) pairs (the names are checked against the pair)."""
    if key not in d:
        return None
    v = d[key]
    if not isinstance(v, dict):
        value = _num(d, key, where, **kind)
        if check:
            check(key, value, where)
        return to_si(value)
    if not v:
        raise CaseError(f"key '{key}' in {_where(where)} must not be an empty table")
    out = []
    for name, item in v.items():
        full = f"{key}.{name}"
        value = _num({full: item}, full, where, **kind)
        if check:
            check(full, value, where)
        out.append((str(name), to_si(value)))
    return tuple(out)


def _angle_range(key: str, angle: float, where: str) -> None:
    if not -89.0 <= angle <= 89.0:
        raise CaseError(f"key '{key}' in {_where(where)} must lie in [-89, 89], got {angle:g}")


@dataclass(frozen=True)
class Export:
    formats: tuple[str, ...]
    tolerance_m: float = 5e-6
    clearance_m: tuple[float, ...] = (0.0,)
    #: the rotor offset by the clearance; None: the pair's reference rotor
    clearance_on: str | None = None
    fluid_angle_rad: float = 0.0
    bore_diameter_m: float | None = None
    #: None: the smallest clearance (pairs with one bore per rotor only)
    tip_clearance_m: float | None = None
    port_depth_m: float | None = None
    #: one value for every rotor cut, or ((rotor name, value), ...); None: the default
    cutter_setting_angle_rad: float | tuple | None = None
    cutter_centre_distance_m: float | tuple | None = None
    cutter_front_angle_rad: float = 0.0
    cloud_spacing_m: float = 1e-3
    units: str = "mm"

    @property
    def unit_scale(self) -> float:
        """Multiplier from metres to the file unit."""
        return 1e3 if self.units == "mm" else 1.0

    def wants(self, fmt: str) -> bool:
        return fmt in self.formats

    def cutter_setting(self, rotor: str) -> tuple[float | None, float | None]:
        """(setting angle, centre distance) asked for the cutter of ``rotor`` (None:
        its default)."""
        def pick(v):
            return dict(v).get(rotor) if isinstance(v, tuple) else v

        return pick(self.cutter_setting_angle_rad), pick(self.cutter_centre_distance_m)

    def per_rotor_names(self) -> set[str]:
        """The rotor names the per-rotor tables use."""
        return {n for v in (self.cutter_setting_angle_rad, self.cutter_centre_distance_m)
                if isinstance(v, tuple) for n, _ in v}

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
        on = d.get("clearance_on")
        if on is not None and (not isinstance(on, str) or not on):
            raise CaseError(f"key 'clearance_on' in {_where(where)} must name a rotor, "
                            f"got {on!r}")
        bore = _num(d, "bore_diameter_mm", where, positive=True)
        tip = _num(d, "tip_clearance_um", where, nonnegative=True)
        depth = _num(d, "port_depth_mm", where, nonnegative=True)
        return cls(
            formats=tuple(fm),
            tolerance_m=tol * 1e-6,
            clearance_m=_clearance(d, where),
            clearance_on=on,
            fluid_angle_rad=math.radians(_num(d, "fluid_angle_deg", where, 0.0)),
            bore_diameter_m=None if bore is None else bore * 1e-3,
            tip_clearance_m=None if tip is None else tip * 1e-6,
            port_depth_m=None if depth is None else depth * 1e-3,
            cutter_setting_angle_rad=_per_rotor(d, "cutter_setting_angle_deg", where,
                                                math.radians, _angle_range),
            cutter_centre_distance_m=_per_rotor(d, "cutter_centre_distance_mm", where,
                                                lambda v: v * 1e-3, positive=True),
            cutter_front_angle_rad=math.radians(_front_angle(d, where)),
            cloud_spacing_m=_num(d, "cloud_spacing_mm", where, 1.0, positive=True) * 1e-3,
            units=_choice(d, "units", where, ("mm", "m"), "mm"),
        )


def _front_angle(d: dict, where: str) -> float:
    angle = _num(d, "cutter_front_angle_deg", where, 0.0)
    if not -45.0 < angle < 45.0:
        raise CaseError(f"key 'cutter_front_angle_deg' in {_where(where)} must lie "
                        f"strictly between -45 and 45 deg, got {angle:g}")
    return angle
