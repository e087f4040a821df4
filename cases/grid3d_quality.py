"""Quality of a stacked structured O-grid (3D hexahedra), by OpenFOAM's definitions.

The 2D measures of :mod:`.ogrid_quality` judge one section; a stack of sections
(:mod:`.polymesh`) is judged here on its hexahedra, with ``primitiveMeshTools``'
formulas (v1912) so the figures can be set against checkMesh's:

* a face's centre and area vector from the triangles fanned about its point average;
* a cell's centre from the pyramids its faces make with the average of its face centres;
* non-orthogonality: the angle between an internal face's area vector and the line
  joining its cells' centres; skewness: ``faceSkewness`` (internal faces) and
  ``boundaryFaceSkewness`` (boundary faces), as in :mod:`.ogrid_quality`.

Nodes are ``X[k, i, j]``: layer k, column i (periodic), row j (0 on the inner wall).
Each measure is also returned per face family (``i``: between columns, ``j``: between
rows, ``k``: between layers), with the location of its worst face, which is what tells
a construction where it fails.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ogrid_quality import BOUNDARY_FLOOR, INTERNAL_FLOOR

#: OpenFOAM's VSMALL, added where it adds it.
VSMALL = 1.0e-300


def _face(p):
    """Centres and area vectors of quads p (..., 4, 3), OpenFOAM's triangle fan."""
    c0 = p.mean(-2)
    q = np.roll(p, -1, axis=-2)
    n = np.cross(q - p, c0[..., None, :] - p)
    a = np.linalg.norm(n, axis=-1)
    c = p + q + c0[..., None, :]
    centre = (a[..., None] * c).sum(-2) / (3.0 * a.sum(-1)[..., None])
    return centre, 0.5 * n.sum(-2)


def _quads(X):
    """The six faces of every hex as quads (k, i, j, 4, 3), outward normals."""
    Xi = np.roll(X, -1, axis=1)
    a, b = X[:-1], Xi[:-1]  # layer k: (i, j), (i+1, j)
    c, d = X[1:], Xi[1:]  # layer k + 1
    faces = {
        # j- (inner side) and j+ (outer side)
        "j-": np.stack([a[:, :, :-1], c[:, :, :-1], d[:, :, :-1], b[:, :, :-1]], -2),
        "j+": np.stack([a[:, :, 1:], b[:, :, 1:], d[:, :, 1:], c[:, :, 1:]], -2),
        # i- and i+ (columns i and i + 1)
        "i-": np.stack([a[:, :, :-1], a[:, :, 1:], c[:, :, 1:], c[:, :, :-1]], -2),
        "i+": np.stack([b[:, :, :-1], d[:, :, :-1], d[:, :, 1:], b[:, :, 1:]], -2),
        # k- and k+ (layers k and k + 1)
        "k-": np.stack([a[:, :, :-1], b[:, :, :-1], b[:, :, 1:], a[:, :, 1:]], -2),
        "k+": np.stack([c[:, :, :-1], c[:, :, 1:], d[:, :, 1:], d[:, :, :-1]], -2),
    }
    return faces


def cell_centres(X):
    """(k, i, j, 3) cell centres and (k, i, j) volumes, OpenFOAM's pyramid sum."""
    faces = _quads(X)
    cf = {key: _face(q) for key, q in faces.items()}
    est = sum(c for c, _ in cf.values()) / 6.0
    vol = np.zeros(est.shape[:-1])
    acc = np.zeros_like(est)
    for c, s in cf.values():
        # The orientation of each quad above is outward for a right-handed stack; the
        # sign cancels in the centre (vol and acc share it) but not in the volume.
        v = np.abs(np.sum(s * (c - est), -1))
        vol += v
        acc += v[..., None] * (0.75 * c + 0.25 * est)
    return acc / vol[..., None], vol / 3.0


@dataclass(frozen=True)
class FaceStats:
    max_non_orthogonality_deg: float
    max_skewness: float
    #: (k, i, j) of the face with the largest skewness (its owner cell) and of the face
    #: with the largest non-orthogonality.
    worst_skew_at: tuple
    worst_non_orth_at: tuple


@dataclass(frozen=True)
class Quality3D:
    cells: int
    volume: float
    min_volume: float
    max_non_orthogonality_deg: float
    max_skewness: float
    by_family: dict  # "i", "j", "k", "wall" -> FaceStats

    def row(self) -> str:
        fam = ", ".join(f"{k}: {v.max_non_orthogonality_deg:.1f} deg/{v.max_skewness:.2f}"
                        for k, v in self.by_family.items())
        return (f"cells {self.cells}, non-orth max {self.max_non_orthogonality_deg:.1f} deg, "
                f"skewness {self.max_skewness:.3g} ({fam})")


def _internal(cf, sf, c_own, c_nei, pts):
    d = c_nei - c_own
    d_len = np.linalg.norm(d, axis=-1)
    cos = np.abs(np.sum(sf * d, -1)) / (np.linalg.norm(sf, axis=-1) * d_len)
    non_orth = np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
    cpf = cf - c_own
    sv = cpf - (np.sum(sf * cpf, -1) / (np.sum(sf * d, -1) + VSMALL))[..., None] * d
    return non_orth, _skew(sv, cf, pts, INTERNAL_FLOOR * d_len)


def _skew(sv, cf, pts, floor):
    length = np.linalg.norm(sv, axis=-1)
    hat = sv / (length[..., None] + VSMALL)
    extent = np.abs(np.sum(hat[..., None, :] * (pts - cf[..., None, :]), -1)).max(-1)
    return length / np.maximum(floor + VSMALL, extent)


def _stats(no, sk) -> FaceStats:
    ks = np.unravel_index(int(np.nanargmax(sk)), sk.shape)
    kn = np.unravel_index(int(np.nanargmax(no)), no.shape) if no is not None else ks
    return FaceStats(float(np.nanmax(no)) if no is not None else 0.0, float(np.nanmax(sk)),
                     tuple(int(v) for v in ks), tuple(int(v) for v in kn))


def measure3d(X: np.ndarray) -> Quality3D:
    """Quality of the hexahedra between the stacked node layers X (layers+1, columns,
    rows+1, 3)."""
    C, V = cell_centres(X)
    faces = _quads(X)
    fam = {}
    # Between rows j and j + 1: the j+ face of (k, i, j).
    q = faces["j+"][:, :, :-1]
    cf, sf = _face(q)
    fam["j"] = _stats(*_internal(cf, sf, C[:, :, :-1], C[:, :, 1:], q))
    # Between columns i and i + 1 (periodic): the i+ face of (k, i, j).
    q = faces["i+"]
    cf, sf = _face(q)
    fam["i"] = _stats(*_internal(cf, sf, C, np.roll(C, -1, axis=1), q))
    if X.shape[0] > 2:
        q = faces["k+"][:-1]
        cf, sf = _face(q)
        fam["k"] = _stats(*_internal(cf, sf, C[:-1], C[1:], q))
    walls, where = [], []
    for key, sel in (("j-", (slice(None), slice(None), slice(0, 1))),
                     ("j+", (slice(None), slice(None), slice(-1, None))),
                     ("k-", (slice(0, 1),)), ("k+", (slice(-1, None),))):
        q = faces[key][sel]
        cf, sf = _face(q)
        c = C[sel]
        n = sf / np.linalg.norm(sf, axis=-1)[..., None]
        cpf = cf - c
        d = np.sum(n * cpf, -1)[..., None] * n
        sk = _skew(cpf - d, cf, q, BOUNDARY_FLOOR * np.linalg.norm(d, axis=-1))
        walls.append(float(sk.max()))
        where.append((key,) + tuple(int(v) for v in np.unravel_index(int(sk.argmax()), sk.shape)))
    w = int(np.argmax(walls))
    fam["wall"] = FaceStats(0.0, walls[w], where[w], where[w])
    return Quality3D(
        cells=int(V.size), volume=float(V.sum()), min_volume=float(V.min()),
        max_non_orthogonality_deg=max(f.max_non_orthogonality_deg for f in fam.values()),
        max_skewness=max(f.max_skewness for f in fam.values()), by_family=fam)


def stack_nodes(sections, z) -> np.ndarray:
    """X (layers+1, columns, rows+1, 3) of sections stacked at heights z."""
    return np.stack([np.concatenate([s.points, np.full(s.points.shape[:2] + (1,), zk)], -1)
                     for s, zk in zip(sections, z, strict=True)])
