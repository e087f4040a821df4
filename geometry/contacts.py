"""Contact points of a whole rotor pair against reference-rotor angle, as a table.

Rows (long format, one per contact and angle; lengths in metres, angles in degrees):
``angle_deg`` reference-rotor angle; ``kind`` the family's contact kind; ``space`` the
tooth space or chamber it bounds; ``x_m, y_m`` the point in the fixed frame;
``radius_outer_m`` and ``radius_inner_m`` its distance from the first and second rotor's
axis (a contact path's radial position on each rotor).  Families build it
(:meth:`RotorPair.contact_table`); this module holds the table and its CSV.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

COLUMNS = ("angle_deg", "kind", "space", "x_m", "y_m", "radius_outer_m", "radius_inner_m")


@dataclass(frozen=True)
class ContactTable:
    angle_deg: np.ndarray
    kind: np.ndarray  # "pin" | "fillet"
    space: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    radius_outer_m: np.ndarray
    radius_inner_m: np.ndarray

    def __len__(self) -> int:
        return len(self.angle_deg)

    def at(self, angle_deg: float) -> ContactTable:
        """The rows of one tabulated angle."""
        sel = np.isclose(self.angle_deg, angle_deg, rtol=0.0, atol=1e-9)
        return ContactTable(*(getattr(self, c)[sel] for c in COLUMNS))


def write_csv(table: ContactTable, path: Path) -> Path:
    """Write the table; a temporary file is renamed into place, so no half file is left."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(COLUMNS)
        for i in range(len(table)):
            w.writerow([f"{table.angle_deg[i]:.6g}", table.kind[i], int(table.space[i])]
                       + [f"{getattr(table, c)[i]:.9e}" for c in COLUMNS[3:]])
    os.replace(tmp, path)
    return path
