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
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

from ..curves import sample_polygon
from . import csvfile, dxf, ply, stl
from .assembly import Assembly, assemble, check_volume, rel_error
from .cloud import cloud
from .fluid import write_fluid
from .settings import Export
from .solids import (
    TriMesh,
    check_sections,
    flank_to_tolerance,
    rotor_mesh,
    validate_mesh,
)
from .surface import min_horizontal_normal

log = logging.getLogger(__name__)

#: Share of the narrowest normal gap each fluid flank may deviate: two flanks each
#: within 0.45 of the gap leave 10 % of it open.
FLUID_GAP_SHARE = 0.45
def export(case, settings: Export, out: Path) -> dict:
    """Write the requested files into ``out`` (an existing, empty folder); the manifest."""
    t_start = time.perf_counter()
    out = Path(out)
    if settings.wants("fluid") and not min(settings.clearance_m) > 0.0:
        raise CaseError("the fluid domain needs clearance_um > 0 everywhere: with no gap the "
                        "chambers touch along the sealing lines and it is not a solid")
    asm = assemble(case, settings)
    if settings.wants("cutter"):  # fail before building anything else
        from .cutter import default_setup

        default_setup(asm.machine.pair, asm.machine.sweep, settings.cutter_setting_angle_rad,
                      settings.cutter_centre_distance_m)
    manifest = _manifest(case, asm, settings)
    files, timing = manifest["files"], manifest["timing_s"]
    timing["profiles_s"] = time.perf_counter() - t_start
    if settings.wants("stl") or settings.wants("fluid"):
        _meshes(case, asm, out, manifest)
    if settings.wants("step"):
        t0 = time.perf_counter()
        log.info("%s: STEP solids", case.name)
        files.update(_step(out, asm, asm.analytic))
        timing["step_s"] = time.perf_counter() - t0
    _machining(asm, out, manifest)
    if settings.wants("cutter"):
        t0 = time.perf_counter()
        log.info("%s: form cutter", case.name)
        files.update(_cutter(out, asm, settings.units, settings.unit_scale))
        timing["cutter_s"] = time.perf_counter() - t0
    for name, entry in files.items():
        entry["bytes"] = (out / name).stat().st_size
    timing["total_s"] = time.perf_counter() - t_start
    (out / "export.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return manifest


def _manifest(case, asm: Assembly, settings: Export) -> dict:
    """export.json before any file is written: frames, tolerances, analytic volumes."""
    sweep = asm.machine.sweep
    inner_axis = [float(c) for c in asm.inner.centre]
    return {
        "case": case.name,
        "units": settings.units,
        "frame": "machine: outer axis on z, low-pressure face at z = 0, pin 0 on +y at "
                 "outer angle 0; rotors placed at fluid_angle_rad (STL, STEP, clouds)",
        "profile_frame": "each rotor's own frame at z = 0 and angle 0 (outer: origin O1, "
                         "inner: origin O2), clearance included (DXF, CSV profiles)",
        "tolerance_m": settings.tolerance_m,
        "clearance_m": list(settings.clearance_m),
        "clearance_on": settings.clearance_on,
        "fluid_angle_rad": settings.fluid_angle_rad,
        "bore_radius_m": asm.bore_radius,
        "inner_axis_m": [[*inner_axis, 0.0],
                         [*(float(sweep.scale(sweep.length)) * c for c in inner_axis),
                          sweep.length]],
        "analytic_volumes_m3": asm.analytic,
        "files": {},
        "timing_s": {},
    }


def _meshes(case, asm: Assembly, out: Path, manifest: dict) -> None:
    """The flank grids, then the rotor STLs and the fluid domain asked for."""
    settings, files, timing = asm.settings, manifest["files"], manifest["timing_s"]
    scale, fluid = settings.unit_scale, settings.wants("fluid")
    analytic = asm.analytic
    t0 = time.perf_counter()
    tol_mesh = settings.tolerance_m
    if fluid:
        c_min = min(settings.clearance_m)
        nxy = min(min_horizontal_normal(asm.outer), min_horizontal_normal(asm.inner))
        tol_mesh = min(tol_mesh, FLUID_GAP_SHARE * c_min * nxy)
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
        files["fluid.stl"] = write_fluid(out / "fluid.stl", asm, go, gi, dev_o, dev_i, scale)
        timing["fluid_s"] = time.perf_counter() - t0


def _machining(asm: Assembly, out: Path, manifest: dict) -> None:
    """Profiles (CSV, DXF) and point clouds (CSV, PLY) asked for."""
    settings, files = asm.settings, manifest["files"]
    scale, unit, tol = settings.unit_scale, settings.units, settings.tolerance_m
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
        manifest["timing_s"]["clouds_s"] = time.perf_counter() - t0


def _write_stl(path: Path, mesh: TriMesh, scale: float, analytic: float,
               deviation: dict | None) -> dict:
    check = validate_mesh(mesh.vertices, mesh.faces, path.name)
    check_volume(path.name, check["manifold3d_volume"], analytic)
    stl.write(path, mesh.vertices, mesh.faces, scale, header=f"rotorflow {path.stem}")
    entry = {
        "triangles": check["triangles"],
        "volume_m3": check["manifold3d_volume"],
        "analytic_volume_m3": analytic,
        "volume_rel_error": rel_error(check["manifold3d_volume"], analytic),
        "genus": check["manifold3d_genus"],
    }
    if deviation is not None:
        entry["max_deviation_m"] = deviation["max"]
        entry["deviation_m"] = {k: deviation[k] for k in ("vertices", "edge_midpoints",
                                                          "centroids")}
        entry["measured_points"] = deviation["points"]
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
        check_volume(path.name, chk.volume_m3, analytic[key])
        files[path.name] = {
            "solids": chk.volumes,
            "faces": chk.faces,
            "closed": chk.closed,
            "volume_m3": chk.volume_m3,
            "occ_volume_m3": chk.occ_volume_m3,
            "analytic_volume_m3": analytic[key],
            "volume_rel_error": rel_error(chk.volume_m3, analytic[key]),
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
