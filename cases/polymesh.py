"""An OpenFOAM polyMesh from stacked structured O-grid sections (:mod:`.ogrid`).

Layer k of the mesh holds the section grid at height ``z[k]``; node (i, j) of layer k
joins node (i, j) of layer k + 1, which the O-grid's fixed numbering makes possible.
One cell thick with ``empty`` ends it is a 2D mesh; stacked by the sweep law
(:func:`helical_stack`: the section at z is the planar pair at outer angle
``phi - twist(z)``, :mod:`..geometry.sweep`) it follows the helical chambers.

Written directly (points, faces, owner, neighbour, boundary, ASCII): internal faces in
upper-triangular order (by owner, then neighbour), each oriented from its owner to its
neighbour, boundary faces outward.  Patches: ``innerRotor`` and ``outerRotor`` (walls),
``ends`` (the two end planes, ``empty`` for one layer, ``wall`` otherwise), or the end
faces named face by face (the ports, :func:`.machine_zones.end_labels`).  The heights
may be graded toward thin end layers (:func:`graded_heights`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

#: Growth of the layer height from a thin end layer (:func:`graded_heights`): the k-faces
#: between layers of unequal height keep no skewness on a uniform shear (the line of the
#: two cells' centres passes through the face centre), so a steep ratio would do; 2
#: keeps the neighbouring cells' volumes within a factor 2.
END_GROWTH = 2.0

HEADER = """FoamFile
{{
    version     2.0;
    format      ascii;
    class       {cls};
    location    "constant/polyMesh";
    object      {obj};
}}
"""


def graded_heights(length: float, layers: int, first: float | None = None,
                   growth: float = END_GROWTH) -> np.ndarray:
    """Layer heights from 0 to ``length``: ``layers`` equal layers, or with ``first`` a
    layer of that height at each end growing by ``growth`` per layer until it reaches
    the equal height (the interior then keeps ``layers`` layers of a slightly smaller
    height).  Why: an end face's boundary skewness is about the nodes' travel per unit
    height over 0.4 when its layer is tall, and that travel on a helix (1.2-1.7 m/m on
    the default machine) puts it past checkMesh's 4; a thin end layer brings it down to
    the travel across the layer over the face's own width."""
    if layers < 1:
        raise CaseError(f"layers must be at least 1, got {layers}")
    if first is None:
        return np.linspace(0.0, length, layers + 1)
    if not first > 0.0 or not growth > 1.0:
        raise CaseError("the end layer must be positive and its growth above 1")
    dz = length / layers
    ramp = [first]
    while ramp[-1] * growth < dz:
        ramp.append(ramp[-1] * growth)
    ramp = np.array(ramp)
    middle = length - 2.0 * ramp.sum()
    if not middle > 0.0:
        raise CaseError(f"end layers of {first:.3g} m growing by {growth:g} do not fit a "
                        f"length of {length:.3g} m in {layers} layers")
    steps = np.concatenate([ramp, np.full(layers, middle / layers), ramp[::-1]])
    return np.concatenate([[0.0], np.cumsum(steps)])


def helical_stack(pair, phi: float, gap: float, sweep, layers: int, spec=None,
                  end_layer: float | None = None):
    """(sections, z): the O-grid at each height of a sweep (:func:`graded_heights`:
    ``layers`` equal layers, thin ones at the ends with ``end_layer``).  The section at
    z is the planar pair at ``phi - twist(z)`` scaled by ``scale(z)`` about the outer
    axis (1 but for a conical sweep), the clearance ``gap`` the same at every height:
    the grid of the unit pair at ``gap / scale``, scaled.

    Quality against layers (default machine, 100 mm, 136 deg of wrap, 2048 x 8 at 20 um,
    :mod:`.grid3d_quality`, checkMesh agreeing): non-orthogonality 89.0 / 88.2 / 86.3 /
    85.2 deg at 17 / 34 / 68 / 92 layers (the faces between the crowded columns next to
    an anchor in a sealing gap, whose spacing changes fast with the angle: the excess
    over the helix's lean halves as the layers double); skewness 4.1-4.3 with equal
    layers (the end faces), 3.59 with 0.15 mm end layers.  92 layers and the end layers
    (1.6 million cells) pass checkMesh."""
    from dataclasses import replace

    from .ogrid import OGridSpec, make_ogrid

    z = graded_heights(sweep.length, layers, end_layer)
    z[-1] = sweep.length
    sections = []
    for zk in z:
        s = float(sweep.scale(zk))
        grid = make_ogrid(pair, phi - float(sweep.twist(zk)), gap / s, spec or OGridSpec())[0]
        sections.append(grid if s == 1.0 else replace(
            grid, points=grid.points * s,
            wall_sag=None if grid.wall_sag is None else grid.wall_sag * s))
    return sections, z


def _hexes(columns: int, rows: int, layers: int):
    """Node index of (i, j, k) and cell index of (i, j, k) as functions."""
    per_layer = columns * (rows + 1)

    def node(i, j, k):
        return k * per_layer + (i % columns) * (rows + 1) + j

    def cell(i, j, k):
        return k * columns * rows + i * rows + j

    return node, cell


def cell_number(i, j, k, columns: int, rows: int):
    """The polyMesh cell number of hex (i, j, k) of a stack."""
    return _hexes(columns, rows, 1)[1](i, j, k)


def _quad(node, i, j, k, kind):
    """The four nodes of a face of hex (i, j, k): 'j+' (toward the outer wall), 'i+'
    (toward the next column), 'k+' (toward the next layer), and the 'j-'/'k-' faces."""
    if kind == "j+":
        return [node(i, j + 1, k), node(i + 1, j + 1, k), node(i + 1, j + 1, k + 1),
                node(i, j + 1, k + 1)]
    if kind == "j-":
        return [node(i, j, k), node(i + 1, j, k), node(i + 1, j, k + 1), node(i, j, k + 1)]
    if kind == "i+":
        return [node(i + 1, j, k), node(i + 1, j + 1, k), node(i + 1, j + 1, k + 1),
                node(i + 1, j, k + 1)]
    if kind == "k+":
        return [node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1),
                node(i, j + 1, k + 1)]
    return [node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k)]


def build_polymesh(sections: list, z: np.ndarray, ends=None):
    """(points, faces, owner, neighbour, patches) of the stacked sections; ``patches`` is
    [(name, type, start, count)]; cell (i, j, k) is number k * columns * rows + i * rows
    + j (:func:`cell_number`).

    ``ends(xy, end)`` names the patch of each end face from its centre (``end`` "lp" at
    z = 0, "hp" at the top), with its type: (names, {name: type}); by default every end
    face is in ``ends``."""
    columns, rows = sections[0].columns, sections[0].cells_across
    layers = len(sections) - 1
    for s in sections:
        if s.points.shape != sections[0].points.shape:
            raise CaseError("stacked O-grid sections differ in node count")
    pts = np.concatenate([np.column_stack([s.points.reshape(-1, 2), np.full(
        columns * (rows + 1), zk)]) for s, zk in zip(sections, z, strict=True)])
    node, cell = _hexes(columns, rows, layers)
    I, J, K = np.meshgrid(np.arange(columns), np.arange(rows), np.arange(layers), indexing="ij")
    I, J, K = I.ravel(), J.ravel(), K.ravel()
    internal = []
    m = J < rows - 1
    internal.append((cell(I[m], J[m], K[m]), cell(I[m], J[m] + 1, K[m]),
                     _quad(node, I[m], J[m], K[m], "j+")))
    nxt = (I + 1) % columns
    internal.append((cell(I, J, K), cell(nxt, J, K), _quad(node, I, J, K, "i+")))
    m = K < layers - 1
    internal.append((cell(I[m], J[m], K[m]), cell(I[m], J[m], K[m] + 1),
                     _quad(node, I[m], J[m], K[m], "k+")))
    a = np.concatenate([x[0] for x in internal])
    b = np.concatenate([x[1] for x in internal])
    f = np.concatenate([np.stack(x[2], 1) for x in internal])
    own, nei = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((nei, own))
    own, nei, f = own[order], nei[order], f[order]
    centres = np.empty((len(I), 3))
    centres[cell(I, J, K)] = _cell_centres(pts, node, I, J, K)
    f = _orient(pts, f, centres[nei] - centres[own])
    groups: dict[str, list] = {}
    types: dict[str, str] = {"innerRotor": "wall", "outerRotor": "wall"}
    for side, sel, kind in (
            ("inner", J == 0, "j-"), ("outer", J == rows - 1, "j+"),
            ("lp", K == 0, "k-"), ("hp", K == layers - 1, "k+")):
        bf = np.stack(_quad(node, I[sel], J[sel], K[sel], kind), 1)
        bo = cell(I[sel], J[sel], K[sel])
        bf = _orient(pts, bf, pts[bf].mean(1) - centres[bo])
        if side in ("inner", "outer"):
            names = np.full(len(bf), f"{side}Rotor")
        elif ends is None:
            names = np.full(len(bf), "ends")
            types["ends"] = "empty" if layers == 1 else "wall"
        else:
            names, end_types = ends(pts[bf].mean(1)[:, :2], side)
            types.update(end_types)
        for name in dict.fromkeys(names.tolist()):
            m = names == name
            groups.setdefault(name, []).append((bf[m], bo[m]))
    faces, owner, patches = [f], [own], []
    start = len(f)
    for name, parts in groups.items():
        bf = np.concatenate([p[0] for p in parts])
        faces.append(bf)
        owner.append(np.concatenate([p[1] for p in parts]))
        patches.append((name, types[name], start, len(bf)))
        start += len(bf)
    return pts, np.concatenate(faces), np.concatenate(owner), nei, patches


def _cell_centres(pts, node, I, J, K):
    corners = [node(I + di, J + dj, K + dk) for di in (0, 1) for dj in (0, 1) for dk in (0, 1)]
    return np.mean([pts[c] for c in corners], axis=0)


def _orient(pts, faces, direction):
    """Reverse the faces whose normal (by their node order) points against
    ``direction``."""
    p = pts[faces]
    n = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    flip = np.sum(n * direction, 1) < 0.0
    faces = faces.copy()
    faces[flip] = faces[flip][:, ::-1]
    return faces


def write_polymesh(case_dir: Path, sections: list, z: np.ndarray, ends=None) -> dict:
    """Write ``constant/polyMesh`` of the stacked sections (``ends``: see
    :func:`build_polymesh`); returns its counts and patch sizes."""
    return write_mesh(case_dir, build_polymesh(sections, z, ends))


def write_mesh(case_dir: Path, mesh: tuple) -> dict:
    """Write ``constant/polyMesh`` from :func:`build_polymesh`'s arrays."""
    pts, faces, owner, nei, patches = mesh
    d = Path(case_dir) / "constant" / "polyMesh"
    d.mkdir(parents=True, exist_ok=True)
    n_cells = int(owner.max()) + 1

    def write(obj, cls, lines, count):
        with open(d / obj, "w") as fh:
            fh.write(HEADER.format(cls=cls, obj=obj))
            fh.write(f"\n{count}\n(\n")
            fh.write("\n".join(lines))
            fh.write("\n)\n")

    write("points", "vectorField", (f"({x:.17g} {y:.17g} {zz:.17g})" for x, y, zz in pts),
          len(pts))
    write("faces", "faceList", (f"4({a} {b} {c} {e})" for a, b, c, e in faces), len(faces))
    write("owner", "labelList", map(str, owner), len(owner))
    write("neighbour", "labelList", map(str, nei), len(nei))
    entries = []
    for name, typ, start, count in patches:
        group = "\n        inGroups    List<word> 1(wall);" if typ == "wall" else ""
        entries.append(f"    {name}\n    {{\n        type        {typ};{group}\n"
                       f"        nFaces      {count};\n        startFace   {start};\n    }}")
    with open(d / "boundary", "w") as fh:
        fh.write(HEADER.format(cls="polyBoundaryMesh", obj="boundary"))
        fh.write(f"\n{len(patches)}\n(\n" + "\n".join(entries) + "\n)\n")
    return {"points": len(pts), "faces": len(faces), "cells": n_cells,
            "internal_faces": len(nei), "patches": {p[0]: p[3] for p in patches}}


def section_thickness(grid) -> float:
    """A one-layer thickness for a 2D mesh: the mean column spacing (cells near cubic in
    the chambers; the value does not enter a 2D solution)."""
    p = grid.points[:, -1]
    return float(np.mean(np.linalg.norm(np.roll(p, -1, 0) - p, axis=1))) or math.nan
