"""`rotorflow export`: the solids and machining files a case's [export] section asks for.

Any family, through one code path: every rotor of the pair is a part by its name
(outer/inner for the internal gear, male/female for a twin screw) with its material
side, and the casing is the pair's bores (:mod:`.assembly`).  Only the formats named
are built.  Every file is checked before the export counts as done, and the figures
of the checks go into ``export.json`` beside the files:

* STL (``<rotor>.stl``, fluid.stl): closed, consistently oriented 2-manifolds
  (manifold3d and a directed-edge pairing test, never repaired); the volume against the
  analytic one; the largest distance of any vertex, edge midpoint or facet centroid of
  the flanks from the analytic flank (measured by foot points; the end faces are exact
  planes whose boundary is the flank's end row).
* A rotor with its material inside its profile (inner, male, female) is the swept
  profile with its end caps; one with its material outside (the internal gear's outer
  rotor) is the material between its profile and its outside cylinder (the casing
  bore, ``bore_diameter_mm``, scaled with the section along a conical rotor).
* The fluid domain (:mod:`.fluid`) is the space inside the casing between the end
  plates (inside the outer rotor; inside the union of a twin screw's bores, each
  ``tip_clearance_um`` outside its rotor), less the rotors at ``fluid_angle_deg``, with
  the suction and discharge ports (:mod:`..ports`) cut ``port_depth_mm`` deep into the
  end plates.  It needs positive clearances; its flanks are meshed to a tolerance
  below half the narrowest gap.  Its volume without the ports is checked against the
  casing less the rotors and against the sum of the chamber table's volumes at that
  angle plus what the clearances open.
* STEP (``<rotor>.step``, and with the fluid domain ``fluid_core.step``, the fluid
  without the port pockets, :mod:`.step_fluid`): one solid each, re-imported and
  checked: its volume by the divergence theorem on its faces and by OpenCASCADE's own
  mass properties (what a CAD user sees in FreeCAD or gmsh) against the analytic one,
  and the rotors' faces' deviation within the tolerance.
* Profiles (CSV, DXF), point clouds (CSV, PLY), the form cutter of every rotor with its
  material inside (``<rotor>_cutter.csv`` and a JSON side-car) with its round trip,
  see :mod:`.csvfile`, :mod:`.dxf`, :mod:`.ply` and :mod:`.cutter`.

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
from .assembly import VOLUME_RTOL, Assembly, Part, assemble, check_volume, rel_error
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
#: Halvings of the flank tolerance an STL may take to hold its volume (VOLUME_RTOL).
VOLUME_REFINES = 3


def check(case, settings: Export, cutters: bool = False):
    """The assembly of ``case``'s rotors, or a CaseError for any export it cannot make
    (found before a file is written).  With ``cutters``, the form cutters are made and
    enveloped back onto their rotors too (a second or two each; `rotorflow run` asks
    before its first stage writes, `export` makes them once, as it writes them)."""
    if settings.wants("fluid") and not min(settings.clearance_m) > 0.0:
        raise CaseError("the fluid domain needs clearance_um > 0 everywhere: with no gap the "
                        "chambers touch along the sealing lines and it is not a solid")
    asm = assemble(case, settings)
    if settings.wants("fluid") and asm.tip_clearance is not None \
            and not asm.tip_clearance > 0.0:
        raise CaseError("the fluid domain needs tip_clearance_um > 0: with no gap the rotor "
                        "tips touch their bores and it is not a solid")
    if settings.wants("cutter"):
        for part in asm.holes:
            _setup(asm, part.name)
            if cutters:
                _checked_cutter(asm, part)
    return asm


def export(case, settings: Export, out: Path) -> dict:
    """Write the requested files into ``out`` (an existing, empty folder); the manifest."""
    t_start = time.perf_counter()
    out = Path(out)
    asm = check(case, settings)
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
        log.info("%s: form cutters", case.name)
        for part in asm.holes:
            files.update(_cutter(out, asm, part, settings.units, settings.unit_scale))
        timing["cutter_s"] = time.perf_counter() - t0
    for name, entry in files.items():
        entry["bytes"] = (out / name).stat().st_size
    timing["total_s"] = time.perf_counter() - t_start
    (out / "export.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return manifest


#: How each family orients its rotors at reference angle 0 (export.json's frame).
ORIENTATION = {
    "internal-gear": "pin 0 on +y",
    "twin-screw": "female axis at (C, 0), both rotors' lobe 0 as the rack generates it",
}


def _manifest(case, asm: Assembly, settings: Export) -> dict:
    """export.json before any file is written: frames, tolerances, analytic volumes."""
    sweep = asm.machine.sweep
    ref = asm.parts[0].name
    orient = ORIENTATION.get(asm.machine.pair.family, "rotors as the family places them")
    origins = ", ".join(f"{p.name}: origin O{i + 1}" for i, p in enumerate(asm.parts))
    man = {
        "case": case.name,
        "units": settings.units,
        "frame": f"machine: {ref} axis on z, low-pressure face at z = 0, {orient} at {ref} "
                 "angle 0; rotors placed at fluid_angle_rad (STL, STEP, clouds)",
        "profile_frame": f"each rotor's own frame at z = 0 and angle 0 ({origins}), "
                         "clearance included (DXF, CSV profiles)",
        "tolerance_m": settings.tolerance_m,
        "clearance_m": list(settings.clearance_m),
        "clearance_on": asm.clearance_on,
        "fluid_angle_rad": settings.fluid_angle_rad,
    }
    wall = asm.wall
    if wall is not None:  # the casing is the enclosing rotor's outside
        man["bore_radius_m"] = wall.outside_radius
    else:
        man["tip_clearance_m"] = asm.tip_clearance
        man["casing_bores_m"] = [{"centre": [float(c) for c in centre], "radius": r}
                                 for centre, r in asm.bores]
    s_end = float(sweep.scale(sweep.length))
    for p in asm.parts:
        axis = [float(c) for c in p.surface.centre]
        if any(axis):
            man[f"{p.name}_axis_m"] = [[*axis, 0.0], [*(s_end * c for c in axis),
                                                      sweep.length]]
    man.update({"analytic_volumes_m3": asm.analytic, "files": {}, "timing_s": {}})
    return man


def _meshes(case, asm: Assembly, out: Path, manifest: dict) -> None:
    """The flank grids, then the rotor STLs and the fluid domain asked for."""
    settings, files, timing = asm.settings, manifest["files"], manifest["timing_s"]
    scale, fluid = settings.unit_scale, settings.wants("fluid")
    t0 = time.perf_counter()
    tol_mesh = settings.tolerance_m
    gap = None
    if fluid:
        c_min = min(settings.clearance_m)
        nxy = min(min_horizontal_normal(p.surface) for p in asm.parts)
        gap = c_min * nxy
        tol_mesh = min(tol_mesh, FLUID_GAP_SHARE * c_min * nxy)
        if asm.tip_clearance is not None:  # the bores are walls too (radial gaps)
            sw = asm.machine.sweep
            tip = asm.tip_clearance * min(1.0, float(sw.scale(sw.length)))
            gap = min(gap, tip)
            tol_mesh = min(tol_mesh, FLUID_GAP_SHARE * tip)
        manifest["fluid_gap_min_m"] = gap
    manifest["mesh_tolerance_m"] = tol_mesh
    log.info("%s: meshing the flanks to %.3g um", case.name, tol_mesh * 1e6)
    grids, devs = {}, {}
    for p in asm.parts:
        grids[p.name], devs[p.name] = flank_to_tolerance(p.surface, tol_mesh)
        check_sections(grids[p.name], f"{p.name} rotor")
    timing["flanks_s"] = time.perf_counter() - t0
    if settings.wants("stl"):
        t0 = time.perf_counter()
        for p in asm.parts:
            analytic = asm.analytic[f"{p.name}_m3"]
            tol = tol_mesh
            mesh = rotor_mesh(grids[p.name], p.outside_radius, tol, p.name)
            # A deviation within tolerance can still miss the volume (a straight flank's
            # chords all sag one way): refine until the solid's volume holds too.
            for _ in range(VOLUME_REFINES):
                if rel_error(mesh.volume, analytic) <= VOLUME_RTOL:
                    break
                tol *= 0.5
                grids[p.name], devs[p.name] = flank_to_tolerance(p.surface, tol)
                mesh = rotor_mesh(grids[p.name], p.outside_radius, tol, p.name)
            files[f"{p.name}.stl"] = _write_stl(out / f"{p.name}.stl", mesh, scale, analytic,
                                                devs[p.name])
        timing["stl_s"] = time.perf_counter() - t0
    if fluid:
        t0 = time.perf_counter()
        log.info("%s: fluid domain and ports", case.name)
        files["fluid.stl"] = write_fluid(out / "fluid.stl", asm, grids, devs, scale, gap,
                                         tol_mesh)
        timing["fluid_s"] = time.perf_counter() - t0


def _machining(asm: Assembly, out: Path, manifest: dict) -> None:
    """Profiles (CSV, DXF) and point clouds (CSV, PLY) asked for."""
    settings, files = asm.settings, manifest["files"]
    scale, unit, tol = settings.unit_scale, settings.units, settings.tolerance_m
    if settings.wants("dxf") or settings.wants("csv"):
        for p in asm.parts:
            name = p.name
            poly = sample_polygon(p.curve, tol)
            if settings.wants("csv"):
                csvfile.write_profile_csv(out / f"{name}_profile.csv", poly, unit, scale)
                files[f"{name}_profile.csv"] = {"vertices": len(poly), "closed": True}
            if settings.wants("dxf"):
                dxf.write(out / f"{name}_profile.dxf", poly, scale, unit, p.outside_radius)
                files[f"{name}_profile.dxf"] = {"vertices": len(poly), "closed": True}
    if settings.wants("csv") or settings.wants("ply"):
        t0 = time.perf_counter()
        for p in asm.parts:
            name = p.name
            pts, nrm = cloud(p.surface, settings.cloud_spacing_m, p.material_inside)
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
    from .step_fluid import write_fluid_step

    files = {}
    tol = asm.settings.tolerance_m
    for p in asm.parts:
        path, key = out / f"{p.name}.step", f"{p.name}_m3"
        write_rotor_step(path, p.surface, tol, p.outside_radius)
        files[path.name] = _step_entry(path, check_step(path, p.surface, tol), analytic[key])
        if files[path.name]["max_deviation_m"] > tol:
            raise RuntimeError(f"{path.name}: its faces deviate "
                               f"{files[path.name]['max_deviation_m'] * 1e6:.3g} um from the "
                               f"analytic flank (tolerance {tol * 1e6:.3g} um)")
    if asm.settings.wants("fluid"):  # the core, without the port pockets of fluid.stl
        path = out / "fluid_core.step"
        write_fluid_step(path, asm, tol)
        files[path.name] = _step_entry(path, check_step(path), analytic["fluid_core_m3"])
        del files[path.name]["max_deviation_m"]  # the rotors' files measure these faces
    return files


def _step_entry(path: Path, chk, analytic: float) -> dict:
    """export.json's entry of a re-imported STEP solid, or an error: one closed solid
    whose volume, by the divergence theorem on its faces and by OpenCASCADE's own mass
    properties (what a CAD user sees), is the analytic one."""
    if chk.volumes != 1 or not chk.closed:
        raise RuntimeError(f"{path.name} re-imports as {chk.volumes} solids "
                           f"(closed shell: {chk.closed})")
    check_volume(path.name, chk.volume_m3, analytic)
    check_volume(f"{path.name} (OpenCASCADE mass properties)", chk.occ_volume_m3, analytic)
    return {
        "solids": chk.volumes,
        "faces": chk.faces,
        "closed": chk.closed,
        "volume_m3": chk.volume_m3,
        "occ_volume_m3": chk.occ_volume_m3,
        "analytic_volume_m3": analytic,
        "volume_rel_error": rel_error(chk.volume_m3, analytic),
        "occ_volume_rel_error": rel_error(chk.occ_volume_m3, analytic),
        "max_deviation_m": chk.deviation_m,
    }


def _setup(asm: Assembly, rotor: str):
    """The form-cutter setup of one rotor (its settings, else the defaults)."""
    from .cutter import default_setup

    angle, centre = asm.settings.cutter_setting(rotor)
    return default_setup(asm.machine.pair, asm.machine.sweep, angle, centre, rotor)


def _checked_cutter(asm: Assembly, part: Part) -> dict:
    """One rotor's form cutter made and enveloped back onto it, unwritten (its round
    trip, or a CaseError)."""
    from .cutter import form_cutter

    cut = form_cutter(part.curve, _setup(asm, part.name), asm.settings.tolerance_m)
    return _round_trip(asm, part, cut)


def _round_trip(asm: Assembly, part: Part, cut, axial=None, radius=None) -> dict:
    """The cutter's round trip (as written, where given), refused beyond tolerance_um."""
    from .cutter import round_trip

    name, tol = part.name, asm.settings.tolerance_m
    rt = round_trip(part.curve, cut, axial, radius)
    change = f"change cutter_setting_angle_deg or cutter_centre_distance_mm ({name})"
    if rt["round_trip_max_m"] > tol:
        raise CaseError(f"the form cutter regenerates the {name} rotor only to "
                        f"{rt['round_trip_max_m'] * 1e6:.3g} um (> tolerance_um): {change}")
    if rt["interference_m"] > tol:
        x, y = rt["interference_at_m"]
        raise CaseError(f"the form cutter cuts {rt['interference_m'] * 1e6:.3g} um into the "
                        f"{name} rotor (at radius {math.hypot(x, y) * 1e3:.4g} mm of its "
                        f"section): {change}")
    return rt


def _cutter(out: Path, asm: Assembly, part: Part, unit: str, scale: float) -> dict:
    """The form cutter of one rotor: its profile (CSV), written, read back and enveloped
    back onto the rotor (round trip), and its JSON side-car."""
    from .cutter import form_cutter

    name, curve, tol = part.name, part.curve, asm.settings.tolerance_m
    setup = _setup(asm, name)
    cut = form_cutter(curve, setup, tol)
    path = out / f"{name}_cutter.csv"
    data = np.column_stack([cut.axial, cut.radius, cut.contact]) * scale
    np.savetxt(path, data, delimiter=",", comments="", fmt="%.9f",
               header=f"axial_{unit},radius_{unit},rotor_x_{unit},rotor_y_{unit},rotor_z_{unit}")
    written = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2) / scale
    rt = _round_trip(asm, part, cut, written[:, 0], written[:, 1])
    side = {
        "tool_axis": "through (centre_distance, 0, 0), direction (0, cos S, sin S), rotor frame",
        "rotor_frame": f"{name} rotor axis on z, low-pressure face z = 0, tooth space of lobe 0 "
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
    files = {f"{name}_cutter.csv": {"points": int(len(cut.u)), **rt}}
    if asm.settings.cutter_front_angle_rad:
        rake = _rake(out, name, curve, cut, asm.settings.cutter_front_angle_rad, tol, unit,
                     scale)
        side.update(rake)
        files[f"{name}_cutter_rake.csv"] = rake
    (out / f"{name}_cutter.json").write_text(json.dumps(side, indent=2) + "\n")
    return {**files, f"{name}_cutter.json": {}}


def _rake(out: Path, name: str, curve, cut, angle: float, tol: float, unit: str,
          scale: float) -> dict:
    """The cutting edge of a disc cutter with front (rake) angle ``angle``: the tool's
    section by a plane parallel to its axis, ``d = R_max sin(angle)`` from it, through
    the tool's outermost point.  A tool circle of radius R meets the plane at
    ``s = sqrt(R^2 - d^2)`` from the plane's foot; written, read back and turned about
    the axis again (R = sqrt(s^2 + d^2)) it must regenerate the rotor as the axial
    section does."""
    from .cutter import round_trip

    d = float(np.max(cut.radius)) * math.sin(angle)
    if float(np.min(cut.radius)) <= abs(d):
        raise CaseError(f"cutter_front_angle_deg = {math.degrees(angle):g}: the rake plane, "
                        f"{abs(d) * 1e3:.4g} mm from the {name} cutter's axis, misses its "
                        f"smallest radius {np.min(cut.radius) * 1e3:.4g} mm")
    path = out / f"{name}_cutter_rake.csv"
    s = np.sqrt(cut.radius ** 2 - d * d)
    np.savetxt(path, np.column_stack([cut.axial, s]) * scale, delimiter=",", comments="",
               fmt="%.9f", header=f"axial_{unit},rake_{unit}")
    written = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2) / scale
    rt = round_trip(curve, cut, written[:, 0], np.hypot(written[:, 1], d))
    if rt["round_trip_max_m"] > tol:
        raise CaseError(f"the {name} cutter's rake-face edge regenerates the rotor only to "
                        f"{rt['round_trip_max_m'] * 1e6:.3g} um (> tolerance_um)")
    return {"front_angle_deg": math.degrees(angle), "rake_offset_m": d,
            "rake_round_trip_max_m": rt["round_trip_max_m"]}
