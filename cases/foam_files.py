"""Writing OpenFOAM dictionaries, fields and tables with foamlib.

Every file is written whole (an existing one is replaced, not merged), header included.
What goes into the dictionaries is built by :mod:`rotorflow.cases.foam_dicts` and the
case modules; this module only writes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

FIELD_CLASSES = {
    (False, False): "volScalarField",
    (True, False): "volVectorField",
    (True, True): "pointVectorField",
}


def write_dict(path: Path, entries: Mapping[str, Any]) -> Path:
    """Write an OpenFOAM dictionary (header included) with foamlib; returns ``path``.

    Multi-word entries are tuples (``("Gauss", "linear")``), lists are OpenFOAM lists,
    nested mappings sub-dictionaries.  An existing file is replaced, not merged.
    """
    from foamlib import FoamFile

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    with FoamFile(path) as f:
        for key, value in entries.items():
            f[key] = value
    return path


def write_field(
    path: Path,
    dimensions: Sequence[float],
    internal: Any,
    boundary: Mapping,
    *,
    vector: bool = False,
    point: bool = False,
) -> Path:
    """Write a field file (``0/p``, ``0/U``, ``0/pointDisplacement``, ...) with foamlib.

    ``internal`` and the boundary ``value``/``inletValue`` entries are plain numbers or
    arrays (foamlib adds ``uniform``/``nonuniform``); other field-valued entries such as
    ``p0`` must be given as ``("uniform", x)``.  The class is set explicitly because a
    list of three scalars is indistinguishable from one vector: a volume field, scalar or
    ``vector``, or with ``point`` a point vector field (the motion solvers').
    """
    from foamlib import FoamFieldFile

    if point and not vector:
        raise ValueError("point fields are written as vectors only")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    with FoamFieldFile(path) as f:
        f["FoamFile"] = {
            "version": 2.0,
            "format": "ascii",
            "class": FIELD_CLASSES[vector, point],
            "location": f'"{path.parent.name}"',
            "object": path.name,
        }
        f["dimensions"] = FoamFieldFile.DimensionSet(*dimensions, *[0] * (7 - len(dimensions)))
        f["internalField"] = internal
        f["boundaryField"] = dict(boundary)
    return path


def write_table(path: Path, rows: list[list], location: str = "constant/tables") -> Path:
    """Write a ``scalarVectorTable`` (``[[t, [x, y, z]], ...]``: a displacement against
    time for ``displacementInterpolation``)."""
    from foamlib import FoamFile

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    with FoamFile(path) as f:
        f["FoamFile"] = {"version": 2.0, "format": "ascii", "class": "scalarVectorTable",
                         "location": f'"{location}"', "object": path.name}
        f[None] = rows
    return path


_MINIMAL_SYSTEM: dict[str, dict[str, Any]] = {
    "controlDict": {
        "application": "checkMesh",
        "startFrom": "latestTime",
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": 0,
        "deltaT": 1,
        "writeControl": "timeStep",
        "writeInterval": 1,
    },
    "fvSchemes": {
        key: {"default": "none"}
        for key in ("ddtSchemes", "gradSchemes", "divSchemes", "laplacianSchemes",
                    "interpolationSchemes", "snGradSchemes")
    },
    "fvSolution": {"solvers": {}},
}


def ensure_system_files(case_dir: Path) -> None:
    """Write stand-in ``system`` dictionaries where missing (mesh utilities read them)."""
    for name, entries in _MINIMAL_SYSTEM.items():
        path = Path(case_dir) / "system" / name
        if not path.is_file():
            write_dict(path, entries)
