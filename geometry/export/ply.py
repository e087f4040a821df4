"""Point clouds with unit normals as binary little-endian PLY (double x, y, z, nx, ny, nz)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def write(path: Path, pts, nrm, scale: float, comment: str = "rotorflow") -> None:
    n = len(pts)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment {comment}\n"
        f"element vertex {n}\n"
        "property double x\nproperty double y\nproperty double z\n"
        "property double nx\nproperty double ny\nproperty double nz\n"
        "end_header\n"
    )
    data = np.hstack([pts * scale, nrm]).astype("<f8")
    with Path(path).open("wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(data.tobytes())


def read(path: Path) -> np.ndarray:
    raw = Path(path).read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    head = raw[:end].decode("ascii").splitlines()
    n = int(next(s.split()[2] for s in head if s.startswith("element vertex")))
    return np.frombuffer(raw, dtype="<f8", count=6 * n, offset=end).reshape(n, 6)
