"""What the frozen-angle 3D machine case writes besides its dictionaries: face sets for the
port patches, the createPatch dictionary, and the zones (chambers, sealing lines).

OpenFOAM's zone files are written directly (the cells and faces are ours, numbered by
:mod:`.polymesh`); the ports become patches through stock ``createPatch`` from face sets,
which moves boundary faces only, so the internal faces the sealing zones name keep their
numbers (checked after the conversion by :func:`check_internal_faces`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

from .foam_files import write_dict

_HEADER = """FoamFile
{{
    version     2.0;
    format      ascii;
    class       {cls};
    location    "{location}";
    object      {obj};
}}
"""


def _labels(values) -> str:
    v = np.asarray(values, dtype=np.int64)
    return f"{v.size}\n(\n" + "\n".join(map(str, v.tolist())) + "\n)\n"


def write_face_set(case_dir: Path, name: str, faces) -> Path:
    path = Path(case_dir) / "constant" / "polyMesh" / "sets" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_HEADER.format(cls="faceSet", location="constant/polyMesh/sets", obj=name)
                    + "\n" + _labels(faces))
    return path


def write_create_patch(case_dir: Path, sets: dict) -> Path:
    """system/createPatchDict: one ``patch`` per {name: face set}."""
    return write_dict(Path(case_dir) / "system" / "createPatchDict", {
        "pointSync": False,
        "patches": [{"name": name, "patchInfo": {"type": "patch"}, "constructFrom": "set",
                     "set": face_set} for name, face_set in sets.items()],
    })


def write_cell_zones(case_dir: Path, zones: dict) -> Path:
    """constant/polyMesh/cellZones from {name: cell labels}."""
    body = [f"{name}\n{{\n    type cellZone;\ncellLabels List<label> {_labels(cells)};\n}}"
            for name, cells in zones.items()]
    return _write_zones(case_dir, "cellZones", "regIOobject", body)


def write_face_zones(case_dir: Path, zones: dict) -> Path:
    """constant/polyMesh/faceZones from {name: (face labels, flip)}."""
    body = []
    for name, (faces, flip) in zones.items():
        flips = np.asarray(flip, dtype=int)
        body.append(f"{name}\n{{\n    type faceZone;\nfaceLabels List<label> "
                    f"{_labels(faces)};\nflipMap List<bool> {_labels(flips)};\n}}")
    return _write_zones(case_dir, "faceZones", "regIOobject", body)


def _write_zones(case_dir: Path, obj: str, cls: str, body: list[str]) -> Path:
    path = Path(case_dir) / "constant" / "polyMesh" / obj
    path.write_text(_HEADER.format(cls=cls, location="constant/polyMesh", obj=obj) + "\n"
                    + f"{len(body)}\n(\n" + "\n".join(body) + "\n)\n")
    return path


def read_labels(path: Path) -> np.ndarray:
    """A labelList file as OpenFOAM writes it (ASCII; header, count, parenthesised)."""
    text = Path(path).read_text()
    body = text[text.index("(", text.index("}")) + 1: text.rindex(")")]
    return np.array(body.split(), dtype=np.int64)


def check_internal_faces(case_dir: Path, owner: np.ndarray, neighbour: np.ndarray) -> None:
    """Raise unless the mesh's internal faces are still ours (same owner and neighbour in
    the same order) after a conversion step."""
    mesh = Path(case_dir) / "constant" / "polyMesh"
    nei = read_labels(mesh / "neighbour")
    own = read_labels(mesh / "owner")[:nei.size]
    if not (np.array_equal(nei, neighbour) and np.array_equal(own, owner[:neighbour.size])):
        raise CaseError(f"{case_dir}: createPatch renumbered the internal faces; the sealing "
                        "zones would name the wrong faces")
