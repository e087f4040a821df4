"""The fluid core as a STEP solid: the casing between the end plates less the rotors.

The same B-spline flank faces as the rotors' STEP (:mod:`.step`): the enclosing rotor's
flank is the outer wall where the pair has one (internal gear), else the union of the
bores (twin screw: two ruled tubes fused by OCC, each bore scaled along a conical
sweep as the rotors are); every rotor with its material inside is a hole through it.
Each end plate is one planar face bounded by the wall's end curves with the holes'
end curves as inner loops, so the shell is built whole and no boolean touches the
flanks.  The port pockets of fluid.stl are not cut: this is the core, checked
against the analytic core volume.
"""

from __future__ import annotations

from pathlib import Path

from .assembly import Assembly
from .step import MM, _flank_faces, write_solid

#: An end curve lies in z = 0 or z = L to this distance [mm].
PLANE_TOL_MM = 1e-6


def _bore_wall(gmsh, asm: Assembly):
    """The lateral faces of the union of the bores and, per end, its boundary curves."""
    occ = gmsh.model.occ
    sw = asm.machine.sweep
    L, s1 = sw.length, float(sw.scale(sw.length))
    tubes = []
    for (cx, cy), r in asm.bores:
        c0 = occ.addCircle(cx * MM, cy * MM, 0.0, r * MM)
        c1 = occ.addCircle(s1 * cx * MM, s1 * cy * MM, L * MM, s1 * r * MM)
        vol = occ.addThruSections([occ.addWire([c0]), occ.addWire([c1])], makeSolid=True,
                                  makeRuled=True)
        tubes += [(d, t) for d, t in vol if d == 3]
    if len(tubes) > 1:
        tubes, _ = occ.fuse(tubes[:1], tubes[1:])
    occ.synchronize()
    faces = gmsh.model.getBoundary(tubes, oriented=False)
    lateral, ends = [], ([], [])
    for _, f in faces:
        box = gmsh.model.getBoundingBox(2, abs(f))
        for k, z in enumerate((0.0, L * MM)):
            if abs(box[2] - z) < PLANE_TOL_MM and abs(box[5] - z) < PLANE_TOL_MM:
                ends[k].extend(abs(c) for _, c in gmsh.model.getBoundary([(2, abs(f))],
                                                                         oriented=False))
                break
        else:
            lateral.append(abs(f))
    # Keep the lateral faces and the end curves; the tubes' own end plates go.
    occ.remove(tubes)
    occ.remove([(2, f) for _, f in faces if abs(f) not in lateral])
    return lateral, ends


def write_fluid_step(path: Path, asm: Assembly, tol: float, log_dir: Path | None = None) -> None:
    """Build the fluid core in OCC and write it to ``path`` (STEP, mm)."""
    from rotorflow.gmsh_session import gmsh_session

    with gmsh_session(Path(path).stem, log_dir=log_dir) as gmsh:
        occ = gmsh.model.occ
        if asm.wall is not None:
            faces, wall_ends = _flank_faces(gmsh, asm.wall.surface, tol)
        else:
            faces, wall_ends = _bore_wall(gmsh, asm)
        hole_ends = []
        for part in asm.holes:
            f, e = _flank_faces(gmsh, part.surface, tol)
            faces += f
            hole_ends.append(e)
        caps = []
        for k in (0, 1):
            loops = [occ.addCurveLoop(wall_ends[k])]
            loops += [occ.addCurveLoop(e[k]) for e in hole_ends]
            caps.append(occ.addPlaneSurface(loops))
        write_solid(gmsh, faces + caps, path)
