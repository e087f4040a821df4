"""Chambers and sealing lines of a stacked O-grid: cellZones and faceZones (issue 16).

In every section a sealing gap is a run of columns where the rotors are within
``NARROW`` clearances of each other; the column line of least width in the run is its
contact.  Contacts of neighbouring sections that lie within ``MAX_SHIFT`` columns of
each other are one sealing line; between the two sections the line cuts the faces
between columns on the lower section's contact line and, for the cells between the two
contacts' columns, the faces between the layers (a staircase that follows the line as
it moves round).  The cells left connected once those faces are cut are the chambers
(connected components of the cell graph); the cut faces of each sealing line are its
faceZone.  Where a contact appears or vanishes between sections its line ends, and the
chambers on either side join around the end, as the gas does.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .polymesh import HEADER

#: A column narrower than this many clearances is in a sealing gap.
NARROW = 1.5
#: Most columns a contact moves between neighbouring sections and is still the same
#: sealing line (a contact moves with the rotors' surfaces, a few columns per layer).
MAX_SHIFT = 32


@dataclass(frozen=True)
class Zones:
    chamber: np.ndarray  # chamber number of every cell (polyMesh order)
    seals: dict  # sealing line number -> polyMesh numbers of its internal faces


def contacts(X: np.ndarray, gap: float) -> list[np.ndarray]:
    """Column lines of the contacts in each section of the stack X (sections, columns,
    rows + 1, 3)."""
    width = np.linalg.norm(X[:, :, -1] - X[:, :, 0], axis=-1)
    out = []
    for w in width:
        narrow = w < NARROW * gap
        if narrow.all() or not narrow.any():
            out.append(np.zeros(0, int))
            continue
        start = int(np.argmin(narrow))  # a wide column: runs do not straddle it
        idx = (start + np.arange(len(w))) % len(w)
        runs, current = [], []
        for i in idx:
            if narrow[i]:
                current.append(i)
            elif current:
                runs.append(current)
                current = []
        if current:
            runs.append(current)
        out.append(np.array([r[int(np.argmin(w[r]))] for r in runs], int))
    return out


def _between(a: int, b: int, columns: int) -> np.ndarray:
    """Cell columns from line a up to line b (the shorter way round)."""
    d = (b - a) % columns
    if d > columns // 2:
        a, d = b, columns - d
    return (a + np.arange(d)) % columns


def find_zones(X: np.ndarray, gap: float, mesh: tuple) -> Zones:
    """The chambers and sealing lines of the stack X whose polyMesh is ``mesh``
    (:func:`.polymesh.build_polymesh`)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    _, _, owner, nei, _ = mesh
    layers, columns, rows = X.shape[0] - 1, X.shape[1], X.shape[2] - 1
    n = layers * columns * rows
    cuts = contacts(X, gap)
    cell = np.arange(n).reshape(layers, columns, rows)
    cut_pairs = []  # (cell a, cell b, sealing line)
    line_of = {}  # (section, contact index) -> sealing line
    lines = 0
    for k in range(layers):
        here, there = cuts[k], cuts[k + 1]
        for m, c in enumerate(here):
            if (k, m) not in line_of:
                line_of[k, m] = lines
                lines += 1
            s = line_of[k, m]
            # Faces between columns c - 1 and c in cell layer k.
            cut_pairs += [(cell[k, c - 1, j], cell[k, c, j], s) for j in range(rows)]
            if not len(there) or k + 1 == layers:
                continue
            d = np.abs((there - c + columns // 2) % columns - columns // 2)
            t = int(np.argmin(d))
            if d[t] > MAX_SHIFT:
                continue
            line_of.setdefault((k + 1, t), s)
            for i in _between(c, int(there[t]), columns):
                cut_pairs += [(cell[k, i, j], cell[k + 1, i, j], s) for j in range(rows)]
    key = owner[:len(nei)].astype(np.int64) * n + nei
    cut = np.asarray(cut_pairs, np.int64).reshape(-1, 3)
    a, b = np.minimum(cut[:, 0], cut[:, 1]), np.maximum(cut[:, 0], cut[:, 1])
    face = np.searchsorted(key, a * n + b)
    keep = np.ones(len(nei), bool)
    keep[face] = False
    own = owner[:len(nei)][keep]
    graph = coo_matrix((np.ones(len(own)), (own, nei[keep])), shape=(n, n))
    _, chamber = connected_components(graph, directed=False)
    seals = {int(s): np.unique(face[cut[:, 2] == s]) for s in np.unique(cut[:, 2])}
    return Zones(chamber, seals)


def write_zones(case_dir: Path, zones: Zones) -> dict:
    """``constant/polyMesh/cellZones`` (chamber<n>) and ``faceZones`` (seal<n>, flip
    maps all false: a zone's flux is positive from the faces' owners to neighbours);
    returns the zones' names and sizes."""
    d = Path(case_dir) / "constant" / "polyMesh"
    chambers = {f"chamber{c}": np.nonzero(zones.chamber == c)[0]
                for c in range(int(zones.chamber.max()) + 1)}
    seals = {f"seal{s}": f for s, f in zones.seals.items()}

    def labels(v):
        return f"List<label> {len(v)}(" + " ".join(map(str, v.tolist())) + ")"

    with open(d / "cellZones", "w") as fh:
        fh.write(HEADER.format(cls="regIOobject", obj="cellZones"))
        fh.write(f"\n{len(chambers)}\n(\n")
        for name, cells in chambers.items():
            fh.write(f"{name}\n{{\n    type cellZone;\n    cellLabels {labels(cells)};\n}}\n")
        fh.write(")\n")
    with open(d / "faceZones", "w") as fh:
        fh.write(HEADER.format(cls="regIOobject", obj="faceZones"))
        fh.write(f"\n{len(seals)}\n(\n")
        for name, faces in seals.items():
            flips = f"List<bool> {len(faces)}(" + " ".join("0" * len(faces)) + ")"
            fh.write(f"{name}\n{{\n    type faceZone;\n    faceLabels {labels(faces)};\n"
                     f"    flipMap {flips};\n}}\n")
        fh.write(")\n")
    return {**{k: len(v) for k, v in chambers.items()}, **{k: len(v) for k, v in seals.items()}}
