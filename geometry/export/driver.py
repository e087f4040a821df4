"""`rotorflow export`: the solids and machining files a case's [export] section asks for.

Only the formats named are built.  Every file is checked before the export counts as
done, and the figures of the checks go into ``export.json`` beside the files:

* STL (outer.stl, inner.stl, fluid.stl): closed, consistently oriented 2-manifolds
  (manifold3d and a directed-edge pairing test, never repaired); the volume against the
  analytic one; the largest distance of any vertex, edge midpoint or facet centroid of
  the flanks from the analytic flank (measured by foot points; the end faces are exact
  planes whose boundary is the flank's end row).
* The outer rotor is the material between its profile and its outside cylinder (the
  casing bore, ``bore_diameter_mm``, scaled with the section along a conical rotor).
* The fluid domain is the space inside the casing bore between the end plates, less
  both rotors at ``fluid_angle_deg``, with the suction and discharge ports
  (:mod:`.ports`) cut ``port_depth_mm`` deep into the end plates.  It needs a positive
  clearance; its flanks are meshed to a tolerance below half the narrowest gap.  Its
  volume without the ports is checked against the casing less both rotors and against
  the sum of the chamber table's volumes at that angle plus the clearance's volume.
* STEP (outer.step, inner.step): one solid per rotor, re-imported and checked.
* Profiles (CSV, DXF), point clouds (CSV, PLY), the inner rotor's form cutter (CSV and
  a JSON side-car), see :mod:`.csvfile`, :mod:`.dxf`, :mod:`.ply` and :mod:`.cutter`.

All lengths in files are in ``units`` (mm by default); export.json is SI.
"""

from __future__ import annotations

import json
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

from ..curves import Clearance, check_simple, offset_profile, region_volume, sample_polygon
from ..machine import SweptMachine
from ..summary import build_machine
from . import csvfile, dxf, ply, stl
from .cloud import cloud
from .settings import Export
from .solids import (
    SweptSurface,
    TriMesh,
    check_sections,
    flank_to_tolerance,
    fluid_mesh,
    min_horizontal_normal,
    rotor_mesh,
    validate_mesh,
)

log = logging.getLogger(__name__)

#: Default depth of the port pockets per outer diameter D.
PORT_DEPTH_FACTOR = 0.1
#: Share of the narrowest normal gap each fluid flank may deviate: two flanks each
#: within 0.45 of the gap leave 10 % of it open.
FLUID_GAP_SHARE = 0.45
#: Relative volume error an STL or STEP solid may show (the issue's acceptance).
VOLUME_RTOL = 1e-4


@dataclass(frozen=True)
class Assembly:
    """Both rotors' flanks placed in the machine frame at the export angle."""

    machine: SweptMachine
    settings: Export
    outer: SweptSurface
    inner: SweptSurface
    bore_radius: float
    volume_ratio: float = 2.0
    #: explicit [operating] port angles since birth (radians), None: from the table
    suction_close: float | None = None
    discharge_open: float | None = None

    @property
    def analytic(self) -> dict:
        sw = self.machine.sweep
        v_out = region_volume(self.outer.curve, sw)
        v_in = region_volume(self.inner.curve, sw)
        casing = math.pi * self.bore_radius ** 2 * sw.scale_squared_integral
        return {"casing_m3": casing, "outer_m3": casing - v_out, "inner_m3": v_in,
                "fluid_core_m3": v_out - v_in}


def assemble(case, settings: Export, machine: SweptMachine | None = None) -> Assembly:
    """Profiles with the clearance applied and checked, placed at the export angle.

    Written for a pair whose first rotor encloses the second (material outside, as the
    internal gear's outer rotor): ``outer`` and ``inner`` are those two rotors."""
    m = machine or build_machine(case)
    pair, sweep = m.pair, m.sweep
    ring, core = pair.rotors[0], pair.rotors[1]
    if ring.material_inside or not core.material_inside:
        raise CaseError(f"solids of a {pair.family} pair are not written yet: the export "
                        "needs a first rotor that encloses the second")
    clearance = Clearance(settings.clearance_m)
    outer, inner = ring.profile, core.profile
    if settings.clearance_on == "outer":
        outer = offset_profile(outer, clearance, +1)
    else:
        inner = offset_profile(inner, clearance, -1)
    tol = settings.tolerance_m
    for curve in (outer, inner):
        check_simple(sample_polygon(curve, tol), f"{curve.name} rotor profile")
    bore = pair.casing_bores(None if settings.bore_diameter_m is None
                             else 0.5 * settings.bore_diameter_m)[0][1]
    if bore <= outer.radius_max + tol:
        raise CaseError(f"bore_diameter_mm = {2e3 * bore:g} must exceed the outer rotor's "
                        f"profile diameter {2e3 * outer.radius_max:.4f} mm")
    phi = settings.fluid_angle_rad
    op = case.raw.get("operating", {}) if hasattr(case, "raw") else {}

    def angle(key):
        v = op.get(key)
        return None if v is None else math.radians(float(v))

    return Assembly(
        machine=m,
        settings=settings,
        outer=SweptSurface(outer, sweep, ring.speed_ratio * phi, ring.speed_ratio, ring.axis),
        inner=SweptSurface(inner, sweep, core.speed_ratio * phi, core.speed_ratio, core.axis),
        bore_radius=bore,
        volume_ratio=float(getattr(case, "volume_ratio", 2.0)),
        suction_close=angle("suction_close_deg"),
        discharge_open=angle("discharge_open_deg"),
    )


def _rel(a: float, b: float) -> float:
    return abs(a / b - 1.0) if b else abs(a)


def _check_volume(name: str, volume: float, analytic: float) -> None:
    if _rel(volume, analytic) > VOLUME_RTOL:
        raise RuntimeError(f"{name}: volume {volume:.9g} m^3 differs from the analytic "
                           f"{analytic:.9g} m^3 by {_rel(volume, analytic):.2e}")


def chamber_sum(machine: SweptMachine, phi: float) -> float:
    """Sum of the volumes of all chambers present at reference angle phi (chamber table)."""
    period = machine.pair.period
    cur = machine.curves
    k0 = math.floor((cur.phi[0] - phi) / period) - 1
    k1 = math.ceil((cur.phi[-1] - phi) / period) + 1
    angles = phi + period * np.arange(k0, k1 + 1)
    return float(machine.volume_at(angles).sum())


def export(case, settings: Export, out: Path) -> dict:
    """Write the requested files into ``out`` (an existing, empty folder); the manifest."""
    t_start = time.perf_counter()
    out = Path(out)
    fluid = settings.wants("fluid")
    c_min = min(settings.clearance_m)
    if fluid and not c_min > 0.0:
        raise CaseError("the fluid domain needs clearance_um > 0 everywhere: with no gap the "
                        "chambers touch along the sealing lines and it is not a solid")
    asm = assemble(case, settings)
    pair, sweep = asm.machine.pair, asm.machine.sweep
    inner_axis = [float(c) for c in asm.inner.centre]
    if settings.wants("cutter"):  # fail before building anything else
        from .cutter import default_setup

        default_setup(pair, sweep, settings.cutter_setting_angle_rad,
                      settings.cutter_centre_distance_m)
    scale, unit = settings.unit_scale, settings.units
    tol = settings.tolerance_m
    files: dict[str, dict] = {}
    timing: dict[str, float] = {"profiles_s": time.perf_counter() - t_start}
    analytic = asm.analytic
    manifest = {
        "case": case.name,
        "units": unit,
        "frame": "machine: outer axis on z, low-pressure face at z = 0, pin 0 on +y at "
                 "outer angle 0; rotors placed at fluid_angle_rad (STL, STEP, clouds)",
        "profile_frame": "each rotor's own frame at z = 0 and angle 0 (outer: origin O1, "
                         "inner: origin O2), clearance included (DXF, CSV profiles)",
        "tolerance_m": tol,
        "clearance_m": list(settings.clearance_m),
        "clearance_on": settings.clearance_on,
        "fluid_angle_rad": settings.fluid_angle_rad,
        "bore_radius_m": asm.bore_radius,
        "inner_axis_m": [[*inner_axis, 0.0],
                         [*(float(sweep.scale(sweep.length)) * c for c in inner_axis),
                          sweep.length]],
        "analytic_volumes_m3": analytic,
        "files": files,
        "timing_s": timing,
    }

    if settings.wants("stl") or fluid:
        t0 = time.perf_counter()
        tol_mesh = tol
        if fluid:
            nxy = min(min_horizontal_normal(asm.outer), min_horizontal_normal(asm.inner))
            tol_mesh = min(tol, FLUID_GAP_SHARE * c_min * nxy)
            manifest["fluid_gap_min_m"] = c_min * nxy
        manifest["mesh_tolerance_m"] = tol_mesh
        log.info("%s: meshing the flanks to %.3g um", case.name, tol_mesh * 1e6)
        go, dev_o = flank_to_tolerance(asm.outer, tol_mesh)
        gi, dev_i = flank_to_tolerance(asm.inner, tol_mesh)
        check_sections(go, "outer rotor")
        check_sections(gi, "inner rotor")
        timing["flanks_s"] = time.perf_counter() - t0
        if settings.wants("stl"):
            t0 = time.perf_counter()
            for name, grid, dev, bore, key in (("outer", go, dev_o, asm.bore_radius, "outer_m3"),
                                               ("inner", gi, dev_i, None, "inner_m3")):
                mesh = rotor_mesh(grid, bore, tol_mesh, name)
                files[f"{name}.stl"] = _write_stl(out / f"{name}.stl", mesh, scale,
                                                  analytic[key], dev)
            timing["stl_s"] = time.perf_counter() - t0
        if fluid:
            t0 = time.perf_counter()
            log.info("%s: fluid domain and ports", case.name)
            files["fluid.stl"] = _fluid(out / "fluid.stl", asm, go, gi, dev_o, dev_i, scale)
            timing["fluid_s"] = time.perf_counter() - t0

    if settings.wants("step"):
        t0 = time.perf_counter()
        log.info("%s: STEP solids", case.name)
        files.update(_step(out, asm, analytic))
        timing["step_s"] = time.perf_counter() - t0

    if settings.wants("dxf") or settings.wants("csv"):
        for name, curve, bore in (("outer", asm.outer.curve, asm.bore_radius),
                                  ("inner", asm.inner.curve, None)):
            poly = sample_polygon(curve, tol)
            if settings.wants("csv"):
                csvfile.write_profile_csv(out / f"{name}_profile.csv", poly, unit, scale)
                files[f"{name}_profile.csv"] = {"vertices": len(poly), "closed": True}
            if settings.wants("dxf"):
                dxf.write(out / f"{name}_profile.dxf", poly, scale, unit, bore)
                files[f"{name}_profile.dxf"] = {"vertices": len(poly), "closed": True}

    if settings.wants("csv") or settings.wants("ply"):
        t0 = time.perf_counter()
        for name, surf, inside in (("outer", asm.outer, False), ("inner", asm.inner, True)):
            pts, nrm = cloud(surf, settings.cloud_spacing_m, inside)
            if settings.wants("csv"):
                csvfile.write_cloud_csv(out / f"{name}_cloud.csv", pts, nrm, unit, scale)
                files[f"{name}_cloud.csv"] = {"points": len(pts)}
            if settings.wants("ply"):
                ply.write(out / f"{name}_cloud.ply", pts, nrm, scale,
                                          f"rotorflow {name} rotor flank, {unit}")
                files[f"{name}_cloud.ply"] = {"points": len(pts)}
        timing["clouds_s"] = time.perf_counter() - t0

    if settings.wants("cutter"):
        t0 = time.perf_counter()
        log.info("%s: form cutter", case.name)
        files.update(_cutter(out, asm, unit, scale))
        timing["cutter_s"] = time.perf_counter() - t0

    for name, entry in files.items():
        entry["bytes"] = (out / name).stat().st_size
    timing["total_s"] = time.perf_counter() - t_start
    (out / "export.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return manifest


def _write_stl(path: Path, mesh: TriMesh, scale: float, analytic: float,
               deviation: dict | None) -> dict:
    check = validate_mesh(mesh.vertices, mesh.faces, path.name)
    _check_volume(path.name, check["manifold3d_volume"], analytic)
    stl.write(path, mesh.vertices, mesh.faces, scale, header=f"rotorflow {path.stem}")
    entry = {
        "triangles": check["triangles"],
        "volume_m3": check["manifold3d_volume"],
        "analytic_volume_m3": analytic,
        "volume_rel_error": _rel(check["manifold3d_volume"], analytic),
        "genus": check["manifold3d_genus"],
    }
    if deviation is not None:
        entry["max_deviation_m"] = deviation["max"]
        entry["deviation_m"] = {k: deviation[k] for k in ("vertices", "edge_midpoints",
                                                          "centroids")}
        entry["measured_points"] = deviation["points"]
    return entry


def _fluid(path: Path, asm: Assembly, go, gi, dev_o: dict, dev_i: dict, scale: float) -> dict:
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
    _check_volume("fluid core", check["manifold3d_volume"], analytic)
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
        "core_volume_rel_error": _rel(check["manifold3d_volume"], analytic),
        "chamber_sum_m3": chambers,
        "chamber_sum_vs_analytic_rel": _rel(chambers, zero),
        "clearance_volume_m3": clearance_volume,
        "chamber_sum_rel_error": _rel(check["manifold3d_volume"], chambers + clearance_volume),
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
    _check_volume("fluid", final["manifold3d_volume"], analytic + port_volume)
    stl.write(path, verts, faces, scale, header="rotorflow fluid")
    entry.update({
        "triangles": final["triangles"],
        "volume_m3": final["manifold3d_volume"],
        "analytic_volume_m3": analytic + port_volume,
        "volume_rel_error": _rel(final["manifold3d_volume"], analytic + port_volume),
        "port_depth_m": depth,
        "genus": final["manifold3d_genus"],
    })
    return entry


def _step(out: Path, asm: Assembly, analytic: dict) -> dict:
    from .step import check_step, write_rotor_step

    files = {}
    tol = asm.settings.tolerance_m
    for name, surf, bore, key in (("outer", asm.outer, asm.bore_radius, "outer_m3"),
                                  ("inner", asm.inner, None, "inner_m3")):
        path = out / f"{name}.step"
        write_rotor_step(path, surf, tol, bore)
        chk = check_step(path, surf, tol)
        if chk.volumes != 1 or not chk.closed:
            raise RuntimeError(f"{path.name} re-imports as {chk.volumes} solids "
                               f"(closed shell: {chk.closed})")
        _check_volume(path.name, chk.volume_m3, analytic[key])
        files[path.name] = {
            "solids": chk.volumes,
            "faces": chk.faces,
            "closed": chk.closed,
            "volume_m3": chk.volume_m3,
            "occ_volume_m3": chk.occ_volume_m3,
            "analytic_volume_m3": analytic[key],
            "volume_rel_error": _rel(chk.volume_m3, analytic[key]),
            "max_deviation_m": chk.deviation_m,
        }
    return files


def _cutter(out: Path, asm: Assembly, unit: str, scale: float) -> dict:
    from .cutter import default_setup, form_cutter, round_trip

    s = asm.settings
    m = asm.machine
    setup = default_setup(m.pair, m.sweep, s.cutter_setting_angle_rad,
                          s.cutter_centre_distance_m)
    curve = asm.inner.curve
    cut = form_cutter(curve, setup, s.tolerance_m)
    path = out / "inner_cutter.csv"
    data = np.column_stack([cut.axial, cut.radius, cut.contact]) * scale
    np.savetxt(path, data, delimiter=",", comments="", fmt="%.9f",
               header=f"axial_{unit},radius_{unit},rotor_x_{unit},rotor_y_{unit},rotor_z_{unit}")
    written = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2) / scale
    rt = round_trip(curve, cut, written[:, 0], written[:, 1])
    tol = s.tolerance_m
    if rt["round_trip_max_m"] > tol:
        raise CaseError(f"the form cutter regenerates the inner rotor only to "
                        f"{rt['round_trip_max_m'] * 1e6:.3g} um (> tolerance_um): change "
                        "cutter_setting_angle_deg or cutter_centre_distance_mm")
    if rt["interference_m"] > tol:
        raise CaseError(f"the form cutter cuts {rt['interference_m'] * 1e6:.3g} um into the "
                        "inner rotor: change cutter_setting_angle_deg or "
                        "cutter_centre_distance_mm")
    side = {
        "tool_axis": "through (centre_distance, 0, 0), direction (0, cos S, sin S), rotor frame",
        "rotor_frame": "inner rotor axis on z, low-pressure face z = 0, tooth space of lobe 0 "
                       "centred on +x (profile turned by turn_rad)",
        "setting_angle_deg": math.degrees(setup.setting_angle),
        "centre_distance_m": setup.centre_distance,
        "lead_m": (2.0 * math.pi / setup.k) if setup.k else None,
        "hand": "left" if setup.k > 0 else ("straight" if setup.k == 0 else "right"),
        "turn_rad": cut.turn,
        "points": int(len(cut.u)),
        **rt,
        "tolerance_m": tol,
        "units": unit,
    }
    (out / "inner_cutter.json").write_text(json.dumps(side, indent=2) + "\n")
    return {"inner_cutter.csv": {"points": int(len(cut.u)), **rt},
            "inner_cutter.json": {}}
