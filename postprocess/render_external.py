"""Pictures of a pair of external rotors side by side (the twin screw): both rotors as
capped solids, and the low-pressure end plane with the bores, chambers and rotors.

The internal gear's pictures (:mod:`.render`) show the outer rotor cut open in its bore;
rotors that each hold their material inside their profile stand in intersecting bores
instead, and are drawn whole.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

WINDOW = (1000, 800)
COLOURS = ("#4c72b0", "#dd8452", "#55a868")
FLUID_COLOUR = "#e8eef7"
CAMERA_DIRECTION = (1.0, -1.6, 0.0)


def render_external(pv, case, surfaces, folder: Path, wrap_deg: float) -> list[Path]:
    from .render import _cap

    meshes = []
    for (pts, centre), colour in zip(surfaces, COLOURS, strict=False):
        from .render import _flank

        parts = [_flank(pv, pts)]
        for ring in (pts[0], pts[-1]):
            parts.append(_cap(pv, ring, np.array([centre[0], centre[1], ring[0, 2]])))
        meshes.append((pv.merge(parts), colour))
    files = [_rotors(pv, case, meshes, wrap_deg, folder / "rotors.png"),
             _section(pv, case, surfaces, folder / "section.png")]
    log.info("rendered %s", ", ".join(p.name for p in files))
    return files


def _rotors(pv, case, meshes, wrap_deg, path: Path) -> Path:
    pair = case.pair
    span = max(np.hypot(*r.axis) for r in pair.rotors) + pair.diameter
    plotter = pv.Plotter(off_screen=True, window_size=WINDOW)
    plotter.set_background("white")
    for mesh, colour in meshes:
        plotter.add_mesh(mesh, color=colour, smooth_shading=True, split_sharp_edges=True,
                         specular=0.3)
    lobes = "/".join(str(r.lobes) for r in pair.rotors)
    plotter.add_text(f"{case.name}: {pair.family} {lobes}, {case.sweep_kind}, wrap "
                     f"{wrap_deg:.1f} deg ({pair.rotors[0].name})", font_size=10,
                     color="black")
    mid = np.mean([r.axis for r in pair.rotors], axis=0)
    cx, cy, _ = CAMERA_DIRECTION
    plotter.camera_position = [(mid[0] + 1.6 * cx * span, mid[1] + 1.6 * cy * span,
                                1.6 * case.length + 0.5 * span),
                               (mid[0], mid[1], 0.45 * case.length), (0.0, 0.0, 1.0)]
    plotter.enable_anti_aliasing("ssaa")
    plotter.screenshot(str(path))
    plotter.close()
    return path


def _section(pv, case, surfaces, path: Path) -> Path:
    from .render import _cap

    pair = case.pair
    d = pair.diameter
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 700))
    plotter.set_background("white")
    for (cx, cy), radius in pair.casing_bores():
        plotter.add_mesh(pv.Disc(center=(cx, cy, -2e-3 * d), inner=0.0, outer=radius,
                                 c_res=180), color=FLUID_COLOUR, lighting=False)
    for (pts, centre), colour in zip(surfaces, COLOURS, strict=False):
        ring = pts[0]
        plotter.add_mesh(_cap(pv, ring, np.array([centre[0], centre[1], 0.0])), color=colour,
                         lighting=False)
        line = pv.lines_from_points(np.vstack([ring, ring[:1]]) + [0, 0, 1e-3 * d])
        plotter.add_mesh(line, color="black", line_width=2)
    plotter.add_text("low-pressure end plane: bores (light), rotors", font_size=9,
                     color="black")
    plotter.view_xy()
    plotter.enable_parallel_projection()
    plotter.camera.parallel_scale = 0.5 * max(
        max(abs(c[0]) + r for c, r in pair.casing_bores()), d)
    plotter.screenshot(str(path))
    plotter.close()
    return path
