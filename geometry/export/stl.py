"""Binary STL: write an indexed mesh, read one back as an indexed mesh.

Binary STL stores every facet with its own three single-precision vertices and a
facet normal; reading merges vertices that are bit-identical in single precision,
which restores the shared vertices of a mesh that was indexed when written (distinct
vertices of rotorflow meshes are micrometres apart, far above float32 resolution).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

_DTYPE = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def write(path: Path, vertices: np.ndarray, faces: np.ndarray, scale: float = 1.0,
          header: str = "rotorflow") -> None:
    """Write ``vertices * scale`` (metres times scale) and ``faces`` (outward, ccw)."""
    v = np.asarray(vertices, dtype=np.float64)[faces] * scale
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=-1), 1e-300)[:, None]
    rec = np.zeros(len(faces), dtype=_DTYPE)
    rec["normal"] = n
    rec["v"] = v
    with Path(path).open("wb") as fh:
        fh.write(header.encode("ascii", "replace")[:80].ljust(80, b" "))
        fh.write(np.uint32(len(faces)).tobytes())
        fh.write(rec.tobytes())


def read(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertices float64, faces) with bit-identical float32 vertices merged."""
    data = Path(path).read_bytes()
    n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
    if len(data) != 84 + n * _DTYPE.itemsize:
        raise ValueError(f"{path}: size does not match {n} facets of binary STL")
    rec = np.frombuffer(data, dtype=_DTYPE, count=n, offset=84)
    flat = np.ascontiguousarray(rec["v"].reshape(-1, 3))
    key = flat.view(np.dtype((np.void, 12))).ravel()
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    return flat[first].astype(np.float64), inverse.reshape(-1, 3).astype(np.int64)
