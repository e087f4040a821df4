"""Off-screen pictures of a case's rotors and chambers for the report (pyvista / VTK).

The surfaces are the analytic swept flanks of :class:`rotorflow.geometry.export.solids.SweptSurface`
(the pair's rotor profiles (:mod:`rotorflow.geometry.curves`), sampled to a chordal
tolerance), evaluated on a (u, z) grid: the pictures show the case's own geometry, not
a generic drawing.

* ``rotors.png``: both rotors in 3D at outer-rotor angle 0, the outer rotor (with its
  bore, 1.25 D) cut open along the plane through the axes so that the inner rotor shows;
* ``section.png``: the low-pressure end plane (z = 0) seen along the axis: outer-rotor
  material, the working chambers (fluid) and the inner rotor.
"""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

#: Chordal tolerance of the profile samples, relative to D: 2e-4 D is a fraction of a
#: pixel at the picture sizes below.
PROFILE_TOL = 2.0e-4
#: Longest profile chord, relative to D (keeps flat stretches from becoming one facet).
PROFILE_STEP = 0.01
#: z levels per degree of outer-rotor wrap (helices look smooth at 3 degrees a facet).
LEVELS_PER_DEG = 1.0 / 3.0
#: Outer diameter of the outer rotor (the bore) drawn around the profile, relative to D.
BORE_RATIO = 1.25
WINDOW = (1000, 750)
OUTER_COLOUR = "#8fa9c4"
INNER_COLOUR = "#e39b4b"
FLUID_COLOUR = "#cfe8ff"
#: Horizontal direction from the axis towards the camera of the 3D view.
CAMERA_DIRECTION = (0.5547, -0.8321, 0.0)


def _offscreen():
    """Import pyvista for off-screen use (EGL/OSMesa when there is no X display)."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    try:
        import pyvista as pv
    except ImportError as exc:  # pragma: no cover - a dependency of the report
        raise RuntimeError("the report's pictures need pyvista (pip install pyvista)") from exc
    pv.OFF_SCREEN = True
    return pv


def _surfaces(case, wrap_outer_deg: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Flank points (nz, nu, 3) and axis of each rotor, the reference rotor first
    (``wrap_outer_deg``: the reference rotor's wrap)."""
    from rotorflow.geometry.curves import sample
    from rotorflow.geometry.export.surface import SweptSurface
    from rotorflow.geometry.sweep import Sweep

    pair = case.pair
    d = pair.diameter
    sweep = Sweep(case.sweep_kind, case.length, math.radians(wrap_outer_deg), case.scale_end,
                  case.lead_ratio)
    nz = max(2, int(math.ceil(wrap_outer_deg * LEVELS_PER_DEG)) + 1)
    z = np.linspace(0.0, case.length, nz)
    out = []
    for rotor in pair.rotors:
        prof, omega, centre = rotor.profile, rotor.speed_ratio, tuple(rotor.axis)
        u = sample(prof, PROFILE_TOL * d, PROFILE_STEP * d)
        surf = SweptSurface(prof, sweep, 0.0, omega, centre)
        pts = surf.point(u[None, :], z[:, None])  # (nz, nu, 3)
        out.append((pts, np.array(centre)))
    return out


def _flank(pv, pts):
    """Closed-in-u structured surface through the grid points (nz, nu, 3)."""
    closed = np.concatenate([pts, pts[:, :1]], axis=1)
    grid = pv.StructuredGrid(closed[..., 0], closed[..., 1], closed[..., 2])
    return grid.extract_surface(algorithm="dataset_surface")


def _fan(pv, ring, centre):
    """Disc bounded by a star-shaped ring (n, 3) around ``centre`` (3,)."""
    n = len(ring)
    pts = np.vstack([ring, centre[None, :]])
    i = np.arange(n)
    faces = np.column_stack([np.full(n, 3), i, (i + 1) % n, np.full(n, n)]).ravel()
    return pv.PolyData(pts, faces)


def _strip(pv, inner_ring, outer_ring):
    """Annulus between two rings with matching samples."""
    n = len(inner_ring)
    pts = np.vstack([inner_ring, outer_ring])
    i = np.arange(n)
    j = (i + 1) % n
    faces = np.column_stack([np.full(n, 4), i, j, n + j, n + i]).ravel()
    return pv.PolyData(pts, faces)


def _cap(pv, ring, centre):
    """Face closing a ring: a fan from ``centre`` where the ring is star-shaped about it,
    else VTK's triangulation of the polygon."""
    if _star_shaped(ring, centre):
        return _fan(pv, ring, centre)
    return pv.PolyData(ring, np.r_[len(ring), np.arange(len(ring))]).triangulate()


def _bore_ring(ring, centre, radius):
    """Points on the bore circle at the polar angles of the ring's points."""
    a = np.arctan2(ring[:, 1] - centre[1], ring[:, 0] - centre[0])
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a),
                            ring[:, 2]])


def _star_shaped(ring, centre) -> bool:
    a = np.unwrap(np.arctan2(ring[:, 1] - centre[1], ring[:, 0] - centre[0]))
    return bool(np.all(np.diff(a) > 0.0))


def render_case(case, folder: Path, wrap_outer_deg: float) -> list[Path]:
    """Write rotors.png and section.png for ``case`` into ``folder``; their paths."""
    pv = _offscreen()
    folder = Path(folder)
    if all(r.material_inside for r in case.pair.rotors):
        from .render_external import render_external

        return render_external(pv, case, _surfaces(case, wrap_outer_deg), folder,
                               wrap_outer_deg)
    outer, inner = _surfaces(case, wrap_outer_deg)
    files = [_rotors_picture(pv, case, outer, inner, wrap_outer_deg, folder / "rotors.png"),
             _section_picture(pv, case, outer, inner, folder / "section.png")]
    log.info("rendered %s", ", ".join(p.name for p in files))
    return files


def _rotor_meshes(pv, case, outer, inner):
    """The outer rotor in its bore, cut open towards the camera, and the inner rotor with
    its end faces."""
    (opts, oc), (ipts, ic) = outer, inner
    bore = 0.5 * BORE_RATIO * case.pair.diameter
    scale_z = case.scale_end if case.sweep_kind == "conical" else 1.0
    outer_parts = [_flank(pv, opts)]
    o0, o1 = opts[0], opts[-1]
    if _star_shaped(o0, oc):
        outer_parts += [_strip(pv, o0, _bore_ring(o0, oc, bore)),
                        _strip(pv, o1, _bore_ring(o1, oc, bore * scale_z))]
    cone = pv.Cylinder(center=(0, 0, 0.5 * case.length), direction=(0, 0, 1), radius=bore,
                       height=case.length, resolution=180, capping=False)
    if scale_z != 1.0:  # a conical casing: scale each ring with z
        p = cone.points.copy()
        s = 1.0 + (scale_z - 1.0) * p[:, 2] / case.length
        p[:, :2] *= s[:, None]
        cone.points = p
    outer_parts.append(cone.extract_surface(algorithm="dataset_surface"))
    # Cut away the half facing the camera so that the inner rotor shows.
    outer_mesh = pv.merge(outer_parts).clip(normal=CAMERA_DIRECTION, origin=(0.0, 0.0, 0.0))
    inner_parts = [_flank(pv, ipts)]
    for ring in (ipts[0], ipts[-1]):
        ctr = np.array([ic[0], ic[1], ring[0, 2]])
        s = 1.0 + (scale_z - 1.0) * ring[0, 2] / case.length
        ctr[:2] *= s
        inner_parts.append(_cap(pv, ring, ctr))
    return outer_mesh, pv.merge(inner_parts)


def _rotors_picture(pv, case, outer, inner, wrap_outer_deg: float, path: Path) -> Path:
    """Both rotors in 3D at outer-rotor angle 0, seen from CAMERA_DIRECTION."""
    d = case.pair.diameter
    plotter = pv.Plotter(off_screen=True, window_size=WINDOW)
    plotter.set_background("white")
    for mesh, colour in zip(_rotor_meshes(pv, case, outer, inner),
                            (OUTER_COLOUR, INNER_COLOUR), strict=True):
        plotter.add_mesh(mesh, color=colour, smooth_shading=True, split_sharp_edges=True,
                         specular=0.3)
    lobes = "/".join(str(r.lobes) for r in case.pair.rotors)
    plotter.add_text(f"{case.name}: {case.pair.family} {lobes}, "
                     f"{case.sweep_kind}, wrap {wrap_outer_deg:.1f} deg", font_size=10,
                     color="black")
    cx, cy, _ = CAMERA_DIRECTION
    plotter.camera_position = [(3.0 * cx * d, 3.0 * cy * d, 1.9 * case.length + 0.6 * d),
                               (0.0, 0.0, 0.45 * case.length), (0.0, 0.0, 1.0)]
    plotter.camera.zoom(1.5)
    plotter.enable_anti_aliasing("ssaa")
    plotter.screenshot(str(path))
    plotter.close()
    return path


def _section_picture(pv, case, outer, inner, path: Path) -> Path:
    """The low-pressure end plane seen along the axis: outer-rotor material, chambers,
    inner rotor, profiles and axes."""
    (opts, oc), (ipts, ic) = outer, inner
    d = case.pair.diameter
    plotter = pv.Plotter(off_screen=True, window_size=(800, 800))
    plotter.set_background("white")
    disc = pv.Disc(center=(0, 0, -2e-3 * d), inner=0.0, outer=0.5 * BORE_RATIO * d,
                   c_res=180)
    plotter.add_mesh(disc, color=OUTER_COLOUR, lighting=False)
    o0 = opts[0]
    ring = o0.copy()
    ring[:, 2] = -1e-3 * d
    plotter.add_mesh(_cap(pv, ring, np.array([oc[0], oc[1], ring[0, 2]])),
                     color=FLUID_COLOUR, lighting=False)
    iring = ipts[0]
    plotter.add_mesh(_cap(pv, iring, np.array([ic[0], ic[1], 0.0])), color=INNER_COLOUR,
                     lighting=False)
    for r, w in ((o0, 2), (iring, 2)):
        line = pv.lines_from_points(np.vstack([r, r[:1]]) + [0, 0, 1e-3 * d])
        plotter.add_mesh(line, color="black", line_width=w)
    plotter.add_mesh(pv.PolyData(np.array([[oc[0], oc[1], 2e-3 * d],
                                           [ic[0], ic[1], 2e-3 * d]])),
                     color="black", point_size=8, render_points_as_spheres=True)
    plotter.add_text("low-pressure end plane: outer rotor (blue), chambers (light), "
                     "inner rotor (orange)", font_size=9, color="black")
    plotter.view_xy()
    plotter.enable_parallel_projection()
    plotter.camera.parallel_scale = 0.55 * BORE_RATIO * d
    plotter.screenshot(str(path))
    plotter.close()
    return path
