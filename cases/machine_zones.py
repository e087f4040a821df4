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
  discharge region (z = L) of :func:`..geometry.ports.ports`, in the machine frame.

Labels are per (column, row, layer) and per cell in :mod:`.polymesh`'s numbering.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError


@dataclass(frozen=True)
class ChamberZones:
    """Slot of every cell (-1: none; polymesh numbering), and the slots present."""

    cell_slot: np.ndarray  # (cells,)
    slots: tuple[int, ...]
    ages: dict  # slot -> machine age (rad)

    def cells_of(self, slot: int) -> np.ndarray:
        return np.flatnonzero(self.cell_slot == slot)


def _inside(polygons, xy: np.ndarray) -> np.ndarray:
    """Points of ``xy`` inside ``polygons`` by the even-odd rule over all of them (a
    region's holes are polygons of their own, as Clipper returns them)."""
    from matplotlib.path import Path as MplPath

    hit = np.zeros(len(xy), dtype=bool)
    for poly in polygons:
        hit ^= MplPath(np.asarray(poly)).contains_points(xy)
    return hit


def _fill_nearest(label: np.ndarray) -> np.ndarray:
    """Unlabelled entries (-1) of a periodic sequence take the nearest labelled one's
    label (ties to the lower index)."""
    n = label.size
    have = np.flatnonzero(label >= 0)
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
    # A planar chamber lives less than one turn of the outer rotor (N1 periods) and the
    # section at z is that of the age ``- twist(z)``: every slot whose section can be
    # alive somewhere on the rotor lies in this range (the rest return no polygon).
    turn = int(np.ceil(2.0 * np.pi / period))
    candidates = range(-turn - 1, turn + int(np.ceil(float(twist.max(initial=0.0)) / period)) + 2)
    labels = np.full((columns, layers), -1, dtype=int)
    ages = {}
    for k in range(layers):
        mid = 0.5 * (sections[k].points + sections[k + 1].points)  # (columns, rows+1, 2)
        j = mid.shape[1] // 2
        centre = 0.25 * (mid[:, j - 1] + mid[:, j] + np.roll(mid[:, j - 1], -1, 0)
                         + np.roll(mid[:, j], -1, 0)) if mid.shape[1] > 2 else \
            0.5 * (mid[:, 0] + np.roll(mid[:, 0], -1, 0))
        lab = np.full(columns, -1, dtype=int)
        for s in candidates:
            polys = pair.chamber_polygons(phi + s * period - twist[k])
            if not polys:
                continue
            hit = _inside(polys, centre) & (lab < 0)
            if hit.any():
                lab[hit] = s
                ages[s] = phi + s * period
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
    cut = np.flatnonzero((so != sn) & (so >= 0) & (sn >= 0))
    out = {}
    lo, hi = np.minimum(so[cut], sn[cut]), np.maximum(so[cut], sn[cut])
    for a, b in sorted(set(zip(lo.tolist(), hi.tolist(), strict=True))):
        sel = cut[(lo == a) & (hi == b)]
        out[(a, b)] = (sel, so[sel] == b)
    return out


def port_faces(points, faces, start: int, count: int, region, tol: float = 0.0
               ) -> np.ndarray:
    """Faces ``start .. start + count`` whose centres lie in ``region`` (polygons in the
    plane); returns the face labels."""
    label = np.arange(start, start + count)
    centres = points[faces[label]].mean(axis=1)[:, :2]
    return label[_inside(region, centres)]
