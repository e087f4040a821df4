"""The chamber table: what the geometry hands to the quasi-1D model.

One working chamber is followed from its birth to its death against the outer-rotor
angle ``angle_rad`` (0 at birth).  Every other chamber of the machine is the same
chamber shifted by whole lobe periods ``2*pi/lobes_outer``: the chamber one period
older is the *next* (leading) neighbour, one period younger the *previous* (trailing)
one.  Everything is SI.

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

The JSON side-car (same stem, ``.json``) carries the scalars: ``lobes_outer``,
``period_rad`` (= 2*pi/lobes_outer), ``speed_ratio_outer_per_driven``, ``volume_max_m3``,
``angle_volume_max_rad``, ``swept_volume_m3`` (per outer-rotor revolution), ``length_m``,
``diameter_m`` and ``machine``.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

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
        }


def far_column(offset: int) -> str:
    """Column name of the sealing line to the chamber ``offset`` periods away (|d| >= 2)."""
    return f"seal_{'next' if offset > 0 else 'prev'}{abs(offset)}_m"


_FAR = re.compile(r"seal_(next|prev)(\d+)_m")


def write(table: ChamberTable, csv_path: Path) -> None:
    """Write ``csv_path`` and its ``.json`` side-car (callers make the folder atomic)."""
    csv_path = Path(csv_path)
    far = sorted(table.seal_far, key=lambda d: (abs(d), -d))
    names = list(COLUMNS) + [far_column(d) for d in far]
    data = np.column_stack([getattr(table, c) for c in COLUMNS]
                           + [table.seal_far[d] for d in far])
    np.savetxt(csv_path, data, delimiter=",", header=",".join(names), comments="", fmt="%.12e")
    csv_path.with_suffix(".json").write_text(json.dumps(table.scalars(), indent=2) + "\n")


def read(csv_path: Path) -> ChamberTable:
    """Read a table written by :func:`write`; a missing file or column raises ValueError."""
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
    far = {}
    for i, name in enumerate(header):
        m = _FAR.fullmatch(name)
        if m and int(m.group(2)) >= 2:
            far[int(m.group(2)) * (1 if m.group(1) == "next" else -1)] = data[:, i]
    meta = json.loads(side.read_text())
    return ChamberTable(
        **cols,
        lobes_outer=int(meta["lobes_outer"]),
        speed_ratio_outer_per_driven=float(meta["speed_ratio_outer_per_driven"]),
        length_m=float(meta["length_m"]),
        diameter_m=float(meta["diameter_m"]),
        machine=str(meta.get("machine", "internal-gear")),
        seal_far=far,
    )


__all__ = ["COLUMNS", "ChamberTable", "read", "write", "asdict"]
