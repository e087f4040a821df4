"""The fluid domain: the casing between the end plates less the rotors, with the suction
and discharge ports (:mod:`..ports`) cut into the end plates as pockets.

The casing is the enclosing rotor's flank where the pair has one (internal gear: the
space inside the outer rotor), else the union of the bores (twin screw: two
intersecting cylinders, each grown by the tip clearance); the rotors with their
material inside are holes through it.  Walls and holes are disjoint by construction
(the clearances) and meshed so that two facing walls together deviate less than the
gap between them; the caps' polygons are checked to be simple.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..polygons import check_simple
from . import stl
from .assembly import Assembly, chamber_sum, check_volume, rel_error
from .casing import casing_tube, outline
from .solids import fluid_mesh, validate_mesh

#: Default depth of the port pockets per outer diameter D.
PORT_DEPTH_FACTOR = 0.1


def _wall(asm: Assembly, grids: dict, tol: float):
    """The fluid's outer wall: the enclosing rotor's flank grid, or the casing tube."""
    wall = asm.wall
    if wall is not None:
        return grids[wall.name]
    return casing_tube(outline(asm.bores, tol), asm.machine.sweep)


def _check_gaps(asm: Assembly, devs: dict, gap: float, tol: float) -> None:
    """Two facing walls must deviate together less than the narrowest gap: the two
    largest deviations of the flanks and (when the bores are a wall) the casing
    polygon's chords, which lie at most half the tolerance inside the bores."""
    worst = sorted([d["max"] for d in devs.values()]
                   + ([0.5 * tol] if asm.wall is None else []))[-2:]
    if sum(worst) >= gap:
        raise RuntimeError(f"fluid walls deviate {1e6 * sum(worst):.3g} um together, more "
                           f"than the narrowest gap {1e6 * gap:.3g} um")


def write_fluid(path: Path, asm: Assembly, grids: dict, devs: dict, scale: float,
                gap: float, tol: float) -> dict:
    """Mesh, check and write the fluid domain; its export.json entry.  ``grids`` and
    ``devs`` hold each rotor's flank grid and measured deviation by name, ``gap`` is the
    narrowest normal gap between walls, ``tol`` the mesh tolerance."""
    import manifold3d

    _check_gaps(asm, devs, gap, tol)
    wall = _wall(asm, grids, tol)
    holes = [grids[p.name] for p in asm.holes]
    for j, face in ((0, "lp"), (-1, "hp")):
        rings = [wall.vertices[j, :, :2]] + [h.vertices[j, ::-1, :2] for h in holes]
        check_simple(rings, f"fluid section at the {face} face")
    core = fluid_mesh(wall, holes)
    check = validate_mesh(core.vertices, core.faces, "fluid core")
    analytic = asm.analytic["fluid_core_m3"]
    check_volume("fluid core", check["manifold3d_volume"], analytic)
    m = asm.machine
    chambers = chamber_sum(m, asm.settings.fluid_angle_rad)
    # The chamber table is the zero-clearance pair: add what the clearances open.
    sw = m.sweep
    zero = asm.zero_clearance_core_area * sw.scale_squared_integral
    clearance_volume = analytic - zero
    entry = {
        "core_volume_m3": check["manifold3d_volume"],
        "analytic_core_volume_m3": analytic,
        "core_volume_rel_error": rel_error(check["manifold3d_volume"], analytic),
        "chamber_sum_m3": chambers,
        "chamber_sum_vs_analytic_rel": rel_error(chambers, zero),
        "clearance_volume_m3": clearance_volume,
        "chamber_sum_rel_error": rel_error(check["manifold3d_volume"], chambers + clearance_volume),
        "max_deviation_m": max(d["max"] for d in devs.values()),
    }
    solid = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(core.vertices),
        tri_verts=np.ascontiguousarray(core.faces, dtype=np.uint64)))
    solid, port_volume = _ports(asm, solid, entry)
    mesh = solid.to_mesh64()
    verts = np.asarray(mesh.vert_properties)[:, :3].astype(np.float64)
    faces = np.asarray(mesh.tri_verts).astype(np.int64)
    final = validate_mesh(verts, faces, "fluid")
    check_volume("fluid", final["manifold3d_volume"], analytic + port_volume)
    stl.write(path, verts, faces, scale, header="rotorflow fluid")
    entry.update({
        "triangles": final["triangles"],
        "volume_m3": final["manifold3d_volume"],
        "analytic_volume_m3": analytic + port_volume,
        "volume_rel_error": rel_error(final["manifold3d_volume"], analytic + port_volume),
        "port_depth_m": entry.pop("port_depth_m"),
        "genus": final["manifold3d_genus"],
    })
    return entry


def _ports(asm: Assembly, solid, entry: dict):
    """The core with the port pockets added, and the pockets' volume."""
    import manifold3d

    from ..ports import port_timing, ports

    m, sw = asm.machine, asm.machine.sweep
    depth = (asm.settings.port_depth_m if asm.settings.port_depth_m is not None
             else PORT_DEPTH_FACTOR * m.pair.diameter)
    entry["port_depth_m"] = depth
    port_volume = 0.0
    if depth > 0.0:
        timing = port_timing(m, asm.volume_ratio, asm.suction_close, asm.discharge_open,
                             asm.early_opening)
        suction, discharge = ports(m, timing)
        prisms = []
        for region, z0, name in ((suction, -depth, "suction"), (discharge, sw.length, "discharge")):
            if region.is_empty():
                continue
            prisms.append(region.extrude(depth).translate((0.0, 0.0, z0)))
            entry[f"{name}_port_area_m2"] = float(region.area())
            port_volume += float(region.area()) * depth
        solid = manifold3d.Manifold.batch_boolean([solid, *prisms], manifold3d.OpType.Add)
        b = m.birth_age  # (since the chamber's birth, as the case gives them)
        birth, death = m.planar_life
        entry["port_timing_rad"] = {"suction_close": timing.suction_close - b,
                                    "discharge_open": timing.discharge_open - b,
                                    "death": death - birth + sw.wrap}
    return solid, port_volume
