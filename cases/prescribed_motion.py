"""Prescribed non-rigid mesh motion in stock OpenFOAM v1912: the route for moving rotors.

Stock v1912 has no solver that reads a whole mesh's point positions at each time. Its
``uniformInterpolatedDisplacement`` point condition reads pre-computed displacement
fields (``field``, a pointVectorField) from the time folders where they exist and
interpolates them linearly in time. On a mesh one cell thick whose every boundary patch,
front and back included, carries that condition, every point is a boundary point, so
the motion solver (``displacementLaplacian``) has no interior point to solve for and the
mesh follows the prescription exactly (issue 17: verify that first).

:func:`verify` builds a small such mesh with blockMesh, prescribes a displacement that
is non-rigid in space (it shears and stretches the cells) and linear in time between
key frames, runs ``moveDynamicMesh`` and returns the largest distance between the
points OpenFOAM wrote and the prescribed ones, relative to the mesh size.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import foam

#: Key-frame times of the check, and the times moveDynamicMesh writes (between them:
#: linear interpolation of a displacement linear in time is exact, so any difference
#: there is the route's, not the interpolation's).
KEY_TIMES = (0.0, 0.5, 1.0)
STEP = 0.25
#: Cells of the check mesh (one cell thick).
CELLS = (6, 5)
THICKNESS = 0.1

_HEADER = ("FoamFile\n{{\n    version 2.0;\n    format ascii;\n    class {cls};\n"
           "    object {obj};\n}}\n")
_POINT = re.compile(r"\(\s*([-+\d.eE]+)\s+([-+\d.eE]+)\s+([-+\d.eE]+)\s*\)")


def displacement(points: np.ndarray, t: float) -> np.ndarray:
    """The prescribed motion: shear and stretch, zero at the origin, linear in time."""
    x, y = points[:, 0], points[:, 1]
    return t * np.stack([0.1 * x * y + 0.05 * y, 0.05 * x * x - 0.02 * y, 0.0 * x], axis=1)


def _write(path: Path, cls: str, obj: str, body: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_HEADER.format(cls=cls, obj=obj) + body)


def read_points(path: Path) -> np.ndarray:
    """The points of an ASCII polyMesh ``points`` file."""
    text = path.read_text()
    body = text[text.index("}") + 1:]
    return np.array(_POINT.findall(body), dtype=float)


def write_case(case: Path, layers: int = 1) -> None:
    """The check case: controlDict, blockMeshDict, schemes, the motion solver and the
    point condition on every patch."""
    _write(case / "system" / "controlDict", "dictionary", "controlDict",
           f"application moveDynamicMesh;\nstartFrom startTime;\nstartTime 0;\n"
           f"stopAt endTime;\nendTime {KEY_TIMES[-1]};\ndeltaT {STEP};\n"
           "writeControl timeStep;\nwriteInterval 1;\nwriteFormat ascii;\n"
           "writePrecision 17;\ntimeFormat general;\ntimePrecision 6;\n"
           "runTimeModifiable false;\n")
    nx, ny = CELLS
    _write(case / "system" / "blockMeshDict", "dictionary", "blockMeshDict",
           "convertToMeters 1;\nvertices ((0 0 0) (1 0 0) (1 1 0) (0 1 0) "
           f"(0 0 {THICKNESS}) (1 0 {THICKNESS}) (1 1 {THICKNESS}) (0 1 {THICKNESS}));\n"
           f"blocks (hex (0 1 2 3 4 5 6 7) ({nx} {ny} {layers}) simpleGrading (1 1 1));\n"
           "boundary (walls { type wall; faces ((0 3 2 1) (4 5 6 7) (0 1 5 4) (1 2 6 5) "
           "(2 3 7 6) (3 0 4 7)); });\n")
    _write(case / "system" / "fvSchemes", "dictionary", "fvSchemes",
           "ddtSchemes { default Euler; }\ngradSchemes { default Gauss linear; }\n"
           "divSchemes { default none; }\nlaplacianSchemes { default Gauss linear corrected; }\n"
           "interpolationSchemes { default linear; }\nsnGradSchemes { default corrected; }\n")
    _write(case / "system" / "fvSolution", "dictionary", "fvSolution",
           "solvers { \"cellDisplacement.*\" { solver PCG; preconditioner DIC; tolerance 1e-12; "
           "relTol 0; } }\n")
    _write(case / "constant" / "dynamicMeshDict", "dictionary", "dynamicMeshDict",
           "dynamicFvMesh dynamicMotionSolverFvMesh;\n"
           "motionSolverLibs (\"libfvMotionSolvers.so\");\nsolver displacementLaplacian;\n"
           "displacementLaplacianCoeffs { diffusivity uniform; }\n")
    _write(case / "0" / "pointDisplacement", "pointVectorField", "pointDisplacement",
           "dimensions [0 1 0 0 0 0 0];\ninternalField uniform (0 0 0);\n"
           "boundaryField { walls { type uniformInterpolatedDisplacement; "
           "field wantedDisplacement; interpolationScheme linear; value uniform (0 0 0); } }\n")


def write_key_frames(case: Path, points: np.ndarray) -> None:
    """The prescribed displacement at every key-frame time, as pointVectorFields."""
    for t in KEY_TIMES:
        d = displacement(points, t)
        rows = "\n".join(f"({a:.17g} {b:.17g} {c:.17g})" for a, b, c in d)
        _write(case / f"{t:g}" / "wantedDisplacement", "pointVectorField", "wantedDisplacement",
               f"dimensions [0 1 0 0 0 0 0];\ninternalField nonuniform List<vector> {len(d)}\n"
               f"(\n{rows}\n);\nboundaryField {{ walls {{ type calculated; }} }}\n")


def verify(case: Path, layers: int = 1) -> dict:
    """Run the check in ``case``; the largest point error at each written time, relative
    to the cell size, and the largest overall. ``layers`` > 1 gives the mesh interior
    points, which the Laplacian motion solver places (the negative control: the
    prescribed x^2 term is not harmonic, so they miss)."""
    case = Path(case)
    write_case(case, layers)
    foam.run(case, "blockMesh")
    points = read_points(case / "constant" / "polyMesh" / "points")
    write_key_frames(case, points)
    foam.run(case, "moveDynamicMesh")
    h = 1.0 / max(CELLS)
    errors = {}
    for k in range(1, int(round(KEY_TIMES[-1] / STEP)) + 1):
        t = k * STEP
        moved = read_points(case / f"{t:g}" / "polyMesh" / "points")
        want = points + displacement(points, t)
        errors[t] = float(np.max(np.linalg.norm(moved - want, axis=1))) / h
    return {"errors": errors, "max_error": max(errors.values()), "points": len(points)}
