"""The fluid domain: the casing bore between the end plates less both rotors, with the
suction and discharge ports (:mod:`..ports`) cut into the end plates as pockets."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..polygons import check_simple
from . import stl
from .assembly import Assembly, chamber_sum, check_volume, rel_error
from .solids import fluid_mesh, validate_mesh
from .surface import min_horizontal_normal

#: Default depth of the port pockets per outer diameter D.
PORT_DEPTH_FACTOR = 0.1


def write_fluid(path: Path, asm: Assembly, go, gi, dev_o: dict, dev_i: dict, scale: float) -> dict:
    import manifold3d

    from ..ports import port_timing, ports

    gap = min(asm.settings.clearance_m) * min(min_horizontal_normal(asm.outer),
                                              min_horizontal_normal(asm.inner))
    if dev_o["max"] + dev_i["max"] >= gap:
        raise RuntimeError(f"fluid flanks deviate {1e6 * (dev_o['max'] + dev_i['max']):.3g} um "
                           f"together, more than the narrowest gap {1e6 * gap:.3g} um")
    for j, (ro, ri) in enumerate(((go.vertices[0], gi.vertices[0]),
                                  (go.vertices[-1], gi.vertices[-1]))):
        check_simple([ro[:, :2], ri[::-1, :2]], f"fluid section at the {('lp', 'hp')[j]} face")
    core = fluid_mesh(go, gi)
    check = validate_mesh(core.vertices, core.faces, "fluid core")
    analytic = asm.analytic["fluid_core_m3"]
    check_volume("fluid core", check["manifold3d_volume"], analytic)
    m = asm.machine
    phi = asm.settings.fluid_angle_rad
    chambers = chamber_sum(m, phi)
    # The chamber table is the zero-clearance pair: add what the clearance opens.
    sw = m.sweep
    zero = (asm.outer.base.area - asm.inner.base.area) * sw.scale_squared_integral
    clearance_volume = analytic - zero
    entry = {
        "core_volume_m3": check["manifold3d_volume"],
        "analytic_core_volume_m3": analytic,
        "core_volume_rel_error": rel_error(check["manifold3d_volume"], analytic),
        "chamber_sum_m3": chambers,
        "chamber_sum_vs_analytic_rel": rel_error(chambers, zero),
        "clearance_volume_m3": clearance_volume,
        "chamber_sum_rel_error": rel_error(check["manifold3d_volume"], chambers + clearance_volume),
        "max_deviation_m": max(dev_o["max"], dev_i["max"]),
    }
    solid = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(core.vertices),
        tri_verts=np.ascontiguousarray(core.faces, dtype=np.uint64)))
    depth = (asm.settings.port_depth_m if asm.settings.port_depth_m is not None
             else PORT_DEPTH_FACTOR * m.pair.diameter)
    port_volume = 0.0
    if depth > 0.0:
        timing = port_timing(m, asm.volume_ratio, asm.suction_close, asm.discharge_open)
        suction, discharge = ports(m, timing)
        prisms = []
        for region, z0, name in ((suction, -depth, "suction"), (discharge, sw.length, "discharge")):
            if region.is_empty():
                continue
            prisms.append(region.extrude(depth).translate((0.0, 0.0, z0)))
            entry[f"{name}_port_area_m2"] = float(region.area())
            port_volume += float(region.area()) * depth
        solid = manifold3d.Manifold.batch_boolean([solid, *prisms], manifold3d.OpType.Add)
        entry["port_timing_rad"] = {"suction_close": timing.suction_close,
                                    "discharge_open": timing.discharge_open,
                                    "death": timing.death}
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
        "port_depth_m": depth,
        "genus": final["manifold3d_genus"],
    })
    return entry
