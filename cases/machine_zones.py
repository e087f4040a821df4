"""Chambers, sealing lines and ports on a stacked structured grid of the machine (issue 16).

The 3D grid of :mod:`.polymesh` stacks O-grid sections: layer k holds the planar pair at
section angle ``phi - twist(z_k)`` (the sweep law, :mod:`..geometry.machine`).  This
module names what a steady run at machine angle ``phi`` must report on:

* **Chambers.**  The working chamber of slot s (machine age ``phi + s * period``) has at
  height z the planar chamber section at ``phi + s * period - twist(z)``, the polygons
  of the family's :meth:`chamber_polygons` (the same ones the ports and the chamber
  table are built from).  A column of cells in layer k belongs to the slot whose section
  holds its middle cell; the columns in a sealing gap (whose middle lies in no section)
  take the nearest labelled column's slot, so the cut between two chambers falls inside
  their gap, where any cut carries the same steady flow.  Cells of one slot form the
  cellZone ``chamber<s>``.
* **Sealing lines.**  Every internal face between cells of two different slots, whether
  it crosses a gap inside a layer or between layers (the sealing line is a helix, so it
  crosses layers), is in the faceZone of that pair of slots, ``seal<a>_<b>`` with
  a < b, oriented from the younger slot a into the older b: its summed flux is the net
  flow from a to b through the lines between them.
* **Ports.**  The end faces whose centres lie in the suction region (z = 0) or the
  discharge region (z = L) of :func:`..geometry.ports.ports`, in the machine frame, are
  the patches ``suction`` and ``discharge`` (:func:`end_labels`, which
  :func:`.polymesh.build_polymesh` calls as it writes the end faces, so the mesh has its
  port patches from the start and no face is renumbered after the zones are cut); the
  rest of both plates is the wall ``endPlates``.

Labels are per (column, row, layer) and per cell in :mod:`.polymesh`'s numbering; the
zones are written straight into ``constant/polyMesh`` (:func:`write_zones`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

from .polymesh import HEADER

PORTS = ("suction", "discharge")
#: The label of a cell or column in no chamber.  Slots run negative too (the chamber of
#: age phi + s period, s < 0, past the first period), so "none" is no slot's number.
NONE = np.iinfo(np.int64).min


@dataclass(frozen=True)
class ChamberZones:
    """Slot of every cell (:data:`NONE`: none; polymesh numbering), and the slots
    present."""

    cell_slot: np.ndarray  # (cells,)
    slots: tuple[int, ...]
    ages: dict  # slot -> machine age (rad)

    def cells_of(self, slot: int) -> np.ndarray:
        return np.flatnonzero(self.cell_slot == slot)


def inside(polygons, xy: np.ndarray) -> np.ndarray:
    """Points of ``xy`` inside ``polygons`` by the even-odd rule over all of them (a
    region's holes are polygons of their own, as Clipper returns them)."""
    from matplotlib.path import Path as MplPath

    hit = np.zeros(len(xy), dtype=bool)
    for poly in polygons:
        hit ^= MplPath(np.asarray(poly)).contains_points(xy)
    return hit


def _fill_nearest(label: np.ndarray) -> np.ndarray:
    """Unlabelled entries (:data:`NONE`) of a periodic sequence take the nearest labelled
    one's label (ties to the lower index)."""
    n = label.size
    have = np.flatnonzero(label != NONE)
    if have.size == 0:
        return label
    idx = np.arange(n)
    # distance to each labelled index on the circle, nearest wins
    d = np.abs(idx[:, None] - have[None, :])
    d = np.minimum(d, n - d)
    return label[have[np.argmin(d, axis=1)]]


def column_slots(pair, sections, z, phi: float, sweep) -> tuple[np.ndarray, dict]:
    """(labels (columns, layers), ages): the slot of every column of every layer.
    Layer k's cells lie between sections k and k + 1; a column's label is taken at the
    middle height, from the middle of its cell column's centre line."""
    period = float(pair.period)
    layers = len(sections) - 1
    columns = sections[0].columns
    zm = 0.5 * (np.asarray(z[:-1]) + np.asarray(z[1:]))
    twist = np.asarray(sweep.twist(zm), dtype=float)
    # A conical stack's section at z is the unit pair's scaled about the outer axis
    # (:func:`.polymesh.helical_stack`): label it in the unit pair's frame.
    scale = np.array([float(sweep.scale(v)) for v in zm])
    # A planar chamber lives less than one turn of the outer rotor (N1 periods) and the
    # section at z is that of the age ``- twist(z)``: every slot whose section can be
    # alive somewhere on the rotor lies in this range (the rest return no polygon).
    # (found at the equivalent angle of the first period, so the range does not move
    # with phi; slot s there is slot s - shift at phi)
    turn = int(np.ceil(2.0 * np.pi / period))
    candidates = range(-turn - 1, turn + int(np.ceil(float(twist.max(initial=0.0)) / period)) + 2)
    shift = math.floor(phi / period)
    base = phi - shift * period
    labels = np.full((columns, layers), NONE, dtype=np.int64)
    ages = {}
    for k in range(layers):
        mid = 0.5 * (sections[k].points + sections[k + 1].points)  # (columns, rows+1, 2)
        j = mid.shape[1] // 2
        centre = 0.25 * (mid[:, j - 1] + mid[:, j] + np.roll(mid[:, j - 1], -1, 0)
                         + np.roll(mid[:, j], -1, 0)) if mid.shape[1] > 2 else \
            0.5 * (mid[:, 0] + np.roll(mid[:, 0], -1, 0))
        lab = np.full(columns, NONE, dtype=np.int64)
        for s in candidates:
            polys = pair.chamber_polygons(base + s * period - twist[k])
            if not polys:
                continue
            hit = inside(polys, centre / scale[k]) & (lab == NONE)
            if hit.any():
                lab[hit] = s - shift
                ages[s - shift] = phi + (s - shift) * period
        labels[:, k] = _fill_nearest(lab)
    if not ages:
        raise CaseError("no working chamber found on the grid (angle outside every "
                        "chamber's life?)")
    return labels, ages


def chamber_zones(pair, sections, z, phi: float, sweep) -> ChamberZones:
    """The cellZones of the chambers (see the module docstring)."""
    labels, ages = column_slots(pair, sections, z, phi, sweep)
    columns, layers = labels.shape
    rows = sections[0].cells_across
    # polymesh numbering: cell(i, j, k) = k * columns * rows + i * rows + j
    per_cell = np.repeat(labels.T[:, :, None], rows, axis=2).reshape(-1)
    return ChamberZones(per_cell, tuple(sorted(ages)), ages)


def seal_faces(zones: ChamberZones, owner: np.ndarray, neighbour: np.ndarray) -> dict:
    """faceZones of the sealing lines: {(a, b): (faces, flip)}, a < b two slots; ``flip``
    True where the face's normal (owner -> neighbour) points from b into a, so that
    flux * (1 - 2 flip) summed is the flow from a to b."""
    n_int = len(neighbour)
    so = zones.cell_slot[owner[:n_int]]
    sn = zones.cell_slot[neighbour]
    cut = np.flatnonzero((so != sn) & (so != NONE) & (sn != NONE))
    out = {}
    lo, hi = np.minimum(so[cut], sn[cut]), np.maximum(so[cut], sn[cut])
    for a, b in sorted(set(zip(lo.tolist(), hi.tolist(), strict=True))):
        sel = cut[(lo == a) & (hi == b)]
        out[(a, b)] = (sel, so[sel] == b)
    return out


def end_labels(ports):
    """The end-face namer :func:`.polymesh.build_polymesh` takes: on the low-pressure
    plate (z = 0) the faces whose centre lies in the suction port ``ports[0]`` are the
    patch ``suction``, on the high-pressure one those in the discharge port ``ports[1]``
    ``discharge``, the rest of both plates the wall ``endPlates``.  ``ports``: each a
    list of polygons in the machine frame (even-odd, as Clipper returns a region)."""

    def name(xy: np.ndarray, end: str):
        port = PORTS[0] if end == "lp" else PORTS[1]
        region = ports[0] if end == "lp" else ports[1]
        names = np.where(inside(region, xy), port, "endPlates")
        return names, {port: "patch", "endPlates": "wall"}

    return name


def _labels(values) -> str:
    v = np.asarray(values, dtype=np.int64)
    return f"{v.size}\n(\n" + "\n".join(map(str, v.tolist())) + "\n)\n"


def write_zones(case_dir: Path, cell_zones: dict, face_zones: dict) -> None:
    """``constant/polyMesh/cellZones`` from {name: cell labels} and ``faceZones`` from
    {name: (face labels, flip)}, in the polyMesh numbering the zones were cut in."""
    cells = [f"{name}\n{{\n    type cellZone;\ncellLabels List<label> {_labels(c)};\n}}"
             for name, c in cell_zones.items()]
    faces = [f"{name}\n{{\n    type faceZone;\nfaceLabels List<label> {_labels(f)};\n"
             f"flipMap List<bool> {_labels(np.asarray(flip, dtype=int))};\n}}"
             for name, (f, flip) in face_zones.items()]
    mesh = Path(case_dir) / "constant" / "polyMesh"
    for obj, body in (("cellZones", cells), ("faceZones", faces)):
        (mesh / obj).write_text(HEADER.format(cls="regIOobject", obj=obj) + "\n"
                                + f"{len(body)}\n(\n" + "\n".join(body) + "\n)\n")
