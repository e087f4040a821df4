"""From a gmsh mesh to a checked OpenFOAM mesh: the planned commands and their checks.

:func:`mesh_steps` plans the conversion of an ASCII MSH 2.2 file: ``gmshToFoam`` (then
the patch types, which gmshToFoam leaves as plain ``patch``) and ``checkMesh`` (then its
report: a failed check, or a cell count other than gmsh's, raises
:class:`MeshCheckError`).  Both case kinds put these steps at the head of their plans;
:func:`convert` drains them alone (a mesh without a case).
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from rotorflow.errors import CaseError

from .foam import Step, drain
from .foam_files import ensure_system_files


class MeshCheckError(CaseError):
    """checkMesh rejected a mesh rotorflow built; the message carries its complaints."""


@dataclass(frozen=True)
class MeshQuality:
    """What checkMesh says about a mesh."""

    cells: int
    faces: int
    points: int
    max_aspect_ratio: float
    max_non_orthogonality_deg: float
    mean_non_orthogonality_deg: float
    max_skewness: float
    failed_checks: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.failed_checks


def parse_check_mesh(text: str) -> MeshQuality:
    """Parse checkMesh's report (the log of ``checkMesh``)."""

    def number(pattern: str) -> float:
        m = re.search(pattern, text)
        return float(m.group(1)) if m else math.nan

    def count(pattern: str) -> int:  # -1 where checkMesh did not get as far as saying
        m = re.search(pattern, text)
        return int(m.group(1)) if m else -1

    failed = tuple(line.strip() for line in text.splitlines() if line.strip().startswith("***"))
    if "Mesh OK." not in text and not failed:
        failed = ("checkMesh did not report 'Mesh OK.'",)
    return MeshQuality(
        cells=count(r"\n\s*cells:\s+(\d+)"),
        faces=count(r"\n\s*faces:\s+(\d+)"),
        points=count(r"\n\s*points:\s+(\d+)"),
        max_aspect_ratio=number(r"Max aspect ratio(?: =|:) ([-+0-9.eE]+)"),
        max_non_orthogonality_deg=number(r"non-orthogonality Max: ([-+0-9.eE]+)"),
        mean_non_orthogonality_deg=number(
            r"non-orthogonality Max: [-+0-9.eE]+ average: ([-+0-9.eE]+)"
        ),
        max_skewness=number(r"Max skewness = ([-+0-9.eE]+)"),
        failed_checks=failed,
    )


#: checkMesh's flag for cells beyond its aspect-ratio threshold (1000).
HIGH_ASPECT = "***High aspect ratio cells"


def judge_check_mesh(case_dir: Path, log_path: Path, expected_cells: int | None = None,
                     max_aspect_ratio: float | None = None) -> MeshQuality:
    """checkMesh's verdict from its log: a failed check, or a cell count other than
    ``expected_cells`` (gmsh's), raises MeshCheckError quoting it.  With
    ``max_aspect_ratio`` checkMesh's high-aspect-ratio flag is the caller's limit
    instead of checkMesh's 1000 (clearance-resolving grids, whose gap cells are thin by
    design: :class:`.ogrid_quality.QualityLimits`)."""
    quality = parse_check_mesh(Path(log_path).read_text(errors="replace"))
    failed = quality.failed_checks
    if max_aspect_ratio is not None and quality.max_aspect_ratio <= max_aspect_ratio:
        failed = tuple(f for f in failed if not f.startswith(HIGH_ASPECT))
    if failed:
        raise MeshCheckError(f"checkMesh rejects the mesh in {case_dir}: " + "; ".join(failed))
    if expected_cells is not None and quality.cells != expected_cells:
        raise MeshCheckError(
            f"OpenFOAM mesh has {quality.cells} cells, gmsh made {expected_cells}, in {case_dir}"
        )
    return quality


def mesh_steps(msh_name: str, patch_types: Mapping[str, str], cells: int | None = None
               ) -> tuple[Step, Step]:
    """Convert ``msh_name`` (in the case folder) and check it: gmshToFoam, then the patch
    types; checkMesh, then its report (value: the :class:`MeshQuality`)."""
    types = dict(patch_types)
    return (
        Step(("gmshToFoam", msh_name), then=lambda case_dir, _: set_patch_types(case_dir, types)),
        Step(("checkMesh",), then=functools.partial(judge_check_mesh, expected_cells=cells)),
    )


def convert(case_dir: Path, msh_name: str, patch_types: Mapping[str, str],
            cells: int | None = None) -> MeshQuality:
    """Drain :func:`mesh_steps` in ``case_dir`` (stand-in ``system`` files where missing);
    return checkMesh's verdict."""
    ensure_system_files(case_dir)
    return drain(mesh_steps(msh_name, patch_types, cells), case_dir)["checkMesh"]


def set_patch_types(case_dir: Path, types: Mapping[str, str]) -> None:
    """Set the ``type`` of named patches in ``constant/polyMesh/boundary``.

    gmshToFoam makes every patch a plain ``patch``; walls and the empty front and back of
    a 2D mesh are set here.  A name missing from the mesh is a CaseError (boundary names
    must survive gmsh -> OpenFOAM), and so is a patch left without a type.
    """
    from foamlib import FoamFile

    path = Path(case_dir) / "constant" / "polyMesh" / "boundary"
    boundary = FoamFile(path)
    entries = list(boundary[None])
    names = [name for name, _ in entries]
    missing = sorted(set(types) - set(names))
    if missing:
        raise CaseError(
            f"mesh in {case_dir} lacks patch(es) {', '.join(missing)}; it has {', '.join(names)}"
        )
    untyped = sorted(set(names) - set(types))
    if untyped:
        raise CaseError(f"no patch type given for {', '.join(untyped)} in {case_dir}")
    new = []
    for name, entry in entries:
        entry = dict(entry)
        entry["type"] = types[name]
        entry.pop("physicalType", None)
        if types[name] == "wall":
            entry["inGroups"] = ["wall", "walls"]
        else:
            entry.pop("inGroups", None)
        new.append((name, entry))
    boundary[None] = new


def patch_face_counts(case_dir: Path) -> dict[str, int]:
    """``{patch: nFaces}`` from ``constant/polyMesh/boundary``."""
    from foamlib import FoamFile

    entries = FoamFile(Path(case_dir) / "constant" / "polyMesh" / "boundary")[None]
    return {name: int(entry["nFaces"]) for name, entry in entries}


def face_zone_sizes(case_dir: Path) -> dict[str, int]:
    """``{face zone: number of faces}`` from ``constant/polyMesh/faceZones``."""
    from foamlib import FoamFile

    zones = FoamFile(Path(case_dir) / "constant" / "polyMesh" / "faceZones")[None]
    out = {}
    for name, entry in zones:
        labels = entry["faceLabels"]
        if isinstance(labels, tuple) and labels and isinstance(labels[0], str):
            labels = labels[1]  # ("List<label>", [...]) as foamlib reads a typed list
        out[name] = len(labels)
    return out
