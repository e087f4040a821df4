"""The chamber table: what the geometry hands to the quasi-1D model.

One working chamber is followed from its birth to its death against the outer-rotor
angle ``angle_rad`` (0 at birth; a table whose grid cannot start on the birth, the
twin screw's, starts at the node before it, a small negative angle of volume 0).
Every other chamber of the machine is the same chamber shifted by whole lobe periods
``2*pi/lobes_outer``: the chamber one period older is the *next* (leading) neighbour,
one period younger the *previous* (trailing) one.  Everything is SI.

CSV columns (one row per angle, uniform spacing):

    angle_rad            outer-rotor angle since chamber birth
    volume_m3            chamber volume
    dVdangle_m3_rad      dV/d(angle)
    area_lp_m2           chamber cross-section lying in the low-pressure end plane (z = 0)
    area_hp_m2           chamber cross-section lying in the high-pressure end plane (z = L)
    seal_next_m          sealing-line length shared with the next (older) chamber
    seal_prev_m          sealing-line length shared with the previous (younger) chamber
    seal_lp_face_m       rotor-tip length along which the chamber meets the low-pressure
                         end plate (leaks across the end-face clearance to suction)
    seal_hp_face_m       same on the high-pressure end plate (leaks to/from discharge)
    seal_next{d}_m       (optional, d >= 2) sealing line shared with the chamber d periods
    seal_prev{d}_m       older / younger: where the neighbouring space's own chamber has
                         died (is not yet born) there, the line faces the chamber a
                         revolution younger (older), and across the fillet contacts the
                         chamber a revolution apart (seed 001's paths C22, C31, C11, C12)
    (any other name)     a column of the family's own leakage paths (``columns``)

The leakage paths are declared by the machine family with the table (``leakage_paths``,
records :class:`LeakagePath`): each names its kind, the chamber or plenum it joins, the
column it reads and, where the family knows it, its own clearance and flow model.  The
quasi-1D model builds its flow network from these records alone.

The JSON side-car (same stem, ``.json``) carries the scalars: ``lobes_outer``,
``period_rad`` (= 2*pi/lobes_outer), ``speed_ratio_outer_per_driven``, ``volume_max_m3``,
``angle_volume_max_rad``, ``swept_volume_m3`` (per outer-rotor revolution), ``length_m``,
``diameter_m`` and ``machine``, and the path declarations ``leakage_paths`` (a list of
objects with the fields of :class:`LeakagePath`).  A side-car written before the
declarations existed gets the internal-gear set (:func:`internal_gear_paths`).

Gas loads.  For each rotor NAME of the pair (``rotor_names``, reference rotor first;
``speed_ratios``: each rotor's signed angular speed over the reference rotor's) the
table carries the columns

    force_NAME_x_m2, force_NAME_y_m2   force of the fluid on rotor NAME per unit chamber
                                       pressure, fixed frame (N/Pa = m2)
    torque_NAME_m3                     torque of the fluid on rotor NAME about its own
                                       axis per unit pressure, counter-clockwise positive

and the per-rotor scalars ``rotor_scalars`` (absent where undefined):
``end_area_NAME_m2``, the rotor's transverse section at the high-pressure end (the end
face the discharge pressure acts on), and ``axial_per_torque_NAME_per_m``, the axial
force of the fluid on the rotor's flanks per unit of the fluid's torque on it (1/m,
+z from the low- to the high-pressure end); defined for constant lead (straight: 0).
A table without these two (older side-cars, one-chamber test tables) has no gas loads.
``groove_area_NAME_m2`` and ``groove_gyration_NAME_m``: the transverse area of the
grooves of a rotor whose material lies inside its profile (its tip circle less its
section) and their radius of gyration about its axis (straight and helical sweeps), for
the angular momentum of the liquid they carry.

Oil films.  ``oil_films`` (optional) lists the rotor surfaces that shear an oil film
against the casing, each naming the leakage path whose clearance it has
(:mod:`.films`: a tip film's radial deficits, a face film's polar moment); the quasi-1D
model turns them into a viscous loss when oil is injected.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from .films import film_from_dict

COLUMNS = (
    "angle_rad",
    "volume_m3",
    "dVdangle_m3_rad",
    "area_lp_m2",
    "area_hp_m2",
    "seal_next_m",
    "seal_prev_m",
    "seal_lp_face_m",
    "seal_hp_face_m",
)

# Kinds of leakage path.  The quasi-1D model treats every kind alike (a flow area between
# two nodes); the kind is what a case file's [leakage.<kind>] section addresses, so a
# family with a new kind of gap adds its name here.
LEAKAGE_KINDS = ("interlobe", "tip", "blow-hole", "end-face", "port")
PLENA = ("suction", "discharge")
# What a path's column measures: a sealing-line length (m; flow area = gap x length) or
# an orifice area (m2; flow area as it stands, whatever the gap).
MEASURES = ("length", "area")


@dataclass(frozen=True)
class LeakagePath:
    """One leakage path of the table's chamber, as the machine family declares it.

    ``name``: unique within the table (figures and ``[leakage.paths.<name>]`` use it).
    ``kind``: one of LEAKAGE_KINDS.  ``target``: the chamber ``target`` periods older
    (negative: younger), or the plenum "suction" / "discharge"; the source is always the
    table's own chamber.  A chamber target that does not exist at an instant is the space
    it will be or was: not yet born, open to suction; already discharged, the discharge.
    ``column``: the table column the path reads, the path seen from the table's chamber.
    ``mirror``: (chamber targets only) the column holding the same path seen from the
    target chamber, read at the target's age; where both chambers exist the two views
    are averaged, where one does not the other view serves alone.
    ``measure``: "length" (column in m: a sealing line, flow area gap x length) or "area"
    (column in m2: an orifice such as a blow-hole; the gap does not enter).
    ``gap_m``, ``model``: the family's own clearance and flow model of this path; None
    takes the case's [leakage] section.  ``moving_wall``: a rotor surface runs along the
    path from the older into the younger chamber and, with [leakage] wall_motion, drags
    gas with it.  ``report``: the key of the figure ``leakage_kg_s`` its gross flow adds
    to (None: its name).
    """

    name: str
    kind: str
    target: int | str
    column: str
    mirror: str | None = None
    measure: str = "length"
    gap_m: float | None = None
    model: str | None = None
    moving_wall: bool = False
    report: str | None = None

    def __post_init__(self):
        where = f"leakage path {self.name!r}"
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"{where}: the name must be a non-empty string")
        if self.kind not in LEAKAGE_KINDS:
            raise ValueError(f"{where}: kind {self.kind!r} is not one of "
                             f"{', '.join(LEAKAGE_KINDS)}")
        chamber = isinstance(self.target, int) and not isinstance(self.target, bool)
        if not (chamber and self.target != 0) and self.target not in PLENA:
            raise ValueError(f"{where}: target {self.target!r} is neither a chamber offset "
                             f"(a non-zero integer) nor one of {', '.join(PLENA)}")
        if self.mirror is not None and not chamber:
            raise ValueError(f"{where}: only a path to a chamber has a mirror column")
        if self.measure not in MEASURES:
            raise ValueError(f"{where}: measure {self.measure!r} is not one of "
                             f"{', '.join(MEASURES)}")
        if self.gap_m is not None and not self.gap_m > 0:
            raise ValueError(f"{where}: gap_m must be positive, got {self.gap_m!r}")
        if self.moving_wall and not chamber:
            raise ValueError(f"{where}: only a path between chambers has moving walls")

    @property
    def to_chamber(self) -> bool:
        return self.target not in PLENA

    @property
    def report_key(self) -> str:
        return self.name if self.report is None else self.report

    @property
    def columns(self) -> tuple[str, ...]:
        return (self.column,) if self.mirror is None else (self.column, self.mirror)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> LeakagePath:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown:
            raise ValueError(f"leakage path {d.get('name')!r}: unknown field(s) "
                             f"{', '.join(unknown)}")
        return cls(**d)


def far_column(offset: int) -> str:
    """Column name of the sealing line to the chamber ``offset`` periods away (|d| >= 2)."""
    return f"seal_{'next' if offset > 0 else 'prev'}{abs(offset)}_m"


def track_column(track: str, offset: int) -> str:
    """Column name of a family's further sealing line (a section track) to the chamber
    ``offset`` periods away."""
    return f"seal_{track.replace('#', '_')}{'+' if offset > 0 else '-'}{abs(offset)}_m"


def opening_column(name: str, offset: int) -> str:
    """Column name of a family's orifice (a section opening swept into an area, such as
    the twin screw's blow-hole) to the chamber ``offset`` periods away."""
    return f"area_{name}{'+' if offset > 0 else '-'}{abs(offset)}_m2"


def internal_gear_paths(far_offsets: Iterable[int] = ()) -> tuple[LeakagePath, ...]:
    """The leakage paths of an internal-gear (pin-generated) machine's table: the
    sealing lines to the chambers one period older and younger (one line seen from both
    sides), the end faces to suction (low-pressure plate) and to discharge (high-pressure
    plate), and the lines to the chambers |d| >= 2 periods away whose columns
    ``far_offsets`` lists.

    All report as before: the sealing lines together as "interlobe", the faces as
    "lp_face" and "hp_face".  (A figure per far line would need an accumulator per line
    in the integrated state, which changes the step control of every existing case.)  The
    far lines carry no wall drag, as before: whether the fillet contacts a revolution
    apart see the rotor's drag as the neighbours' lines do is not settled.
    """
    paths = [
        LeakagePath("interlobe+1", "interlobe", 1, "seal_next_m", mirror="seal_prev_m",
                    moving_wall=True, report="interlobe"),
        LeakagePath("lp-face", "end-face", "suction", "seal_lp_face_m", report="lp_face"),
        LeakagePath("hp-face", "end-face", "discharge", "seal_hp_face_m", report="hp_face"),
    ]
    far = set(far_offsets)
    for d in sorted({abs(x) for x in far if abs(x) >= 2}):
        if d in far:  # the line seen from the younger chamber, and from the older if given
            mirror = far_column(-d) if -d in far else None
            paths.append(LeakagePath(f"interlobe+{d}", "interlobe", d, far_column(d),
                                     mirror=mirror, report="interlobe"))
        else:
            paths.append(LeakagePath(f"interlobe-{d}", "interlobe", -d, far_column(-d),
                                     report="interlobe"))
    return tuple(paths)


@dataclass(frozen=True)
class ChamberTable:
    """Columns as arrays (see the module docstring) plus the scalars of the side-car."""

    angle_rad: np.ndarray
    volume_m3: np.ndarray
    dVdangle_m3_rad: np.ndarray
    area_lp_m2: np.ndarray
    area_hp_m2: np.ndarray
    seal_next_m: np.ndarray
    seal_prev_m: np.ndarray
    seal_lp_face_m: np.ndarray
    seal_hp_face_m: np.ndarray
    lobes_outer: int
    speed_ratio_outer_per_driven: float
    length_m: float
    diameter_m: float
    machine: str = "internal-gear"
    seal_far: dict[int, np.ndarray] = field(default_factory=dict)
    """Sealing lines to chambers more than one period away, keyed by the signed offset."""
    leakage_paths: tuple[LeakagePath, ...] | None = None
    """The declared leakage paths; None: the internal-gear set for these columns."""
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    """The family's own path columns, beyond the fixed and the far ones, by name, and
    the gas-load columns (see the module docstring)."""
    rotor_names: tuple[str, ...] = ()
    """The pair's rotors, reference first; () when the table carries no gas loads."""
    speed_ratios: tuple[float, ...] = ()
    """Signed angular speed of each rotor over the reference rotor's."""
    rotor_scalars: dict[str, float] = field(default_factory=dict)
    """end_area_NAME_m2, axial_per_torque_NAME_per_m where defined."""
    oil_films: tuple = ()
    """The rotor surfaces that shear an oil film against the casing (:mod:`.films`)."""
    port_timing: dict[str, float] = field(default_factory=dict)
    """The geometry's port timing, where its port areas follow one
    (:func:`..ports.port_timing`): ``suction_close_rad``, ``discharge_open_rad`` (ages)
    and the ``volume_ratio`` and ``early_opening_rad`` it was made for; the quasi-1D model
    reads it rather than re-deriving it ({}: none, the model derives its own)."""
    port_areas: bool = True
    """False: the area columns were not computed (zeros): a table for ideal ports, which
    follow the port timing alone (:func:`..summary.chamber_table`); the quasi-1D model
    refuses it for nozzle ports and it is never written."""

    @property
    def paths(self) -> tuple[LeakagePath, ...]:
        """The leakage paths: as declared, or the internal-gear set."""
        if self.leakage_paths is None:
            return internal_gear_paths(self.seal_far)
        return tuple(self.leakage_paths)

    def column(self, name: str) -> np.ndarray:
        """A column by its CSV name; KeyError if the table has none of that name."""
        if name in COLUMNS:
            return getattr(self, name)
        m = _FAR.fullmatch(name)
        if m and int(m.group(2)) >= 2:
            d = int(m.group(2)) * (1 if m.group(1) == "next" else -1)
            if d in self.seal_far:
                return self.seal_far[d]
        if name in self.columns:
            return self.columns[name]
        raise KeyError(name)

    def seal_to(self, offset: int) -> np.ndarray:
        """Sealing line to the chamber ``offset`` periods older (negative: younger)."""
        if offset == 1:
            return self.seal_next_m
        if offset == -1:
            return self.seal_prev_m
        return self.seal_far.get(offset, np.zeros_like(self.angle_rad))

    @property
    def period_rad(self) -> float:
        return 2.0 * math.pi / self.lobes_outer

    @property
    def volume_max_m3(self) -> float:
        return float(np.max(self.volume_m3))

    @property
    def angle_volume_max_rad(self) -> float:
        return float(self.angle_rad[int(np.argmax(self.volume_m3))])

    @property
    def swept_volume_m3(self) -> float:
        return self.lobes_outer * self.volume_max_m3

    def scalars(self) -> dict:
        return {
            "machine": self.machine,
            "lobes_outer": self.lobes_outer,
            "period_rad": self.period_rad,
            "speed_ratio_outer_per_driven": self.speed_ratio_outer_per_driven,
            "volume_max_m3": self.volume_max_m3,
            "angle_volume_max_rad": self.angle_volume_max_rad,
            "swept_volume_m3": self.swept_volume_m3,
            "length_m": self.length_m,
            "diameter_m": self.diameter_m,
            "rotor_names": list(self.rotor_names),
            "speed_ratios": list(self.speed_ratios),
            **self.rotor_scalars,
        }


_FAR = re.compile(r"seal_(next|prev)(\d+)_m")
_ROTOR_SCALAR = re.compile(
    r"(end_area_\w+_m2|axial_per_torque_\w+_per_m|groove_area_\w+_m2|groove_gyration_\w+_m)")


def write(table: ChamberTable, csv_path: Path) -> None:
    """Write ``csv_path`` and its ``.json`` side-car (callers make the folder atomic)."""
    if not table.port_areas:
        raise ValueError("a chamber table without its port areas is not written")
    csv_path = Path(csv_path)
    far = sorted(table.seal_far, key=lambda d: (abs(d), -d))
    names = list(COLUMNS) + [far_column(d) for d in far] + list(table.columns)
    data = np.column_stack([getattr(table, c) for c in COLUMNS]
                           + [table.seal_far[d] for d in far] + list(table.columns.values()))
    np.savetxt(csv_path, data, delimiter=",", header=",".join(names), comments="", fmt="%.12e")
    side = table.scalars()
    side["leakage_paths"] = [p.to_dict() for p in table.paths]
    if table.oil_films:
        side["oil_films"] = [f.to_dict() for f in table.oil_films]
    if table.port_timing:
        side["port_timing"] = dict(table.port_timing)
    csv_path.with_suffix(".json").write_text(json.dumps(side, indent=2) + "\n")


def read(csv_path: Path) -> ChamberTable:
    """Read a table written by :func:`write`; a missing file or column, or a malformed
    path declaration, raises ValueError."""
    csv_path = Path(csv_path)
    side = csv_path.with_suffix(".json")
    if not csv_path.is_file():
        raise ValueError(f"chamber table not found: {csv_path}")
    if not side.is_file():
        raise ValueError(f"chamber table side-car not found: {side}")
    with csv_path.open() as fh:
        header = fh.readline().strip().split(",")
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise ValueError(f"chamber table {csv_path} lacks column(s): {', '.join(missing)}")
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
    cols = {c: data[:, header.index(c)] for c in COLUMNS}
    far, extra = {}, {}
    for i, name in enumerate(header):
        m = _FAR.fullmatch(name)
        if m and int(m.group(2)) >= 2:
            far[int(m.group(2)) * (1 if m.group(1) == "next" else -1)] = data[:, i]
        elif name not in COLUMNS:
            extra[name] = data[:, i]
    meta = json.loads(side.read_text())
    paths = None
    if "leakage_paths" in meta:  # older side-cars: None, the internal-gear set
        try:
            paths = tuple(LeakagePath.from_dict(p) for p in meta["leakage_paths"])
        except (TypeError, ValueError, AttributeError) as exc:
            raise ValueError(f"chamber table side-car {side}: {exc}") from None
    per_rotor = {k: float(v) for k, v in meta.items() if _ROTOR_SCALAR.fullmatch(k)}
    try:
        films = tuple(film_from_dict(f) for f in meta.get("oil_films", ()))
    except (TypeError, ValueError, AttributeError) as exc:
        raise ValueError(f"chamber table side-car {side}: {exc}") from None
    return ChamberTable(
        **cols,
        lobes_outer=int(meta["lobes_outer"]),
        speed_ratio_outer_per_driven=float(meta["speed_ratio_outer_per_driven"]),
        length_m=float(meta["length_m"]),
        diameter_m=float(meta["diameter_m"]),
        machine=str(meta.get("machine", "internal-gear")),
        seal_far=far,
        leakage_paths=paths,
        columns=extra,
        rotor_names=tuple(str(n) for n in meta.get("rotor_names", ())),
        speed_ratios=tuple(float(x) for x in meta.get("speed_ratios", ())),
        rotor_scalars=per_rotor,
        oil_films=films,
        port_timing={str(k): float(v) for k, v in meta.get("port_timing", {}).items()},
    )


__all__ = ["COLUMNS", "LEAKAGE_KINDS", "ChamberTable", "LeakagePath", "internal_gear_paths",
           "opening_column",
           "read", "write", "asdict"]
