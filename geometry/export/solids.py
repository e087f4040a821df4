"""Rotor solids and the fluid domain as closed triangle meshes, exact to a tolerance.

A rotor flank is the swept surface of :mod:`.surface`. The flank is meshed on a
structured (u, z) grid: profile samples from a chordal tolerance, z levels from the
curvature of the helices ``u = const``, and the quad diagonal that deviates less.
Second-order error model: along u the chord sag is kappa h_u^2 / 8, along z it is |S_zz
. n| h_z^2 / 8, and the diagonal adds the twist term omega twist' s h_u h_z / 4; each
gets a share of the tolerance.

Vertices are then moved along the surface normal by the mean deviation of their
triangles (the edge-midpoint rule is exact for the quadratic error), so that chords
cut the surface instead of lying on one side of it: the volume error drops from first
to second order in the tolerance and the largest deviation from ~tol to ~2/3 tol.
Cap rows move within their plane.  Every vertex, edge midpoint and facet centroid is
then measured against the analytic surface (Gauss-Newton foot points), and the mesh is
rebuilt finer if any is farther than the tolerance.

Meshes are indexed (shared vertices), closed, consistently oriented (outward normals)
and checked as they are (every directed edge paired with its reverse, and manifold3d's
own checks; trimesh's too on request); nothing is ever merged or repaired.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..curves import sample
from ..polygons import check_simple
from .casing import ring_size
from .surface import SweptSurface, foot_points

log = logging.getLogger(__name__)

#: The sampling is designed for DESIGN_FACTOR * tol before the normal shift, which
#: brings the largest deviation to about 2/3 of that; measured, and refined by
#: REFINE_FACTOR (at most MAX_REBUILDS times) if the measurement exceeds tol.
DESIGN_FACTOR = 1.3
REFINE_FACTOR = 0.75
MAX_REBUILDS = 4
#: After the first Gauss-Newton step (which leaves each distance within ~1e-3 of its
#: converged value), only points within this fraction of the largest keep iterating.
FOCUS = 0.8


# ---------------------------------------------------------------------- the flank grid
@dataclass(frozen=True)
class FlankGrid:
    """Structured flank mesh: vertices (nz, nu, 3), triangles on the flattened grid."""

    surface: SweptSurface = field(repr=False)
    u: np.ndarray
    z: np.ndarray
    vertices: np.ndarray = field(repr=False)
    triangles: np.ndarray = field(repr=False)  # (m, 3) into vertices.reshape(-1, 3)
    params: np.ndarray = field(repr=False)  # (nz, nu, 2): (u, z) of each vertex
    tol: float = 0.0

    @property
    def shape(self):
        return self.vertices.shape[:2]

    def measure(self) -> dict:
        """Largest distance to the analytic flank of vertices, edge midpoints, centroids."""
        return measure_flank(self)


def _closed_u(u, n):
    return np.append(u, u[0] + n)


def build_flank(surface: SweptSurface, tol: float, design: float = DESIGN_FACTOR) -> FlankGrid:
    """The structured mesh of one flank, normal-shifted, for the tolerance ``tol``."""
    td = tol * design
    twisted = surface.sweep.wrap != 0.0
    if twisted:
        levels = surface.z_levels(0.5 * td)
        h_max = surface.u_step_limit(levels, td)
        u = sample(surface.curve, 0.5 * td, h_max)
    else:
        levels = np.array([0.0, surface.length])
        u = sample(surface.curve, td)
    n = surface.curve.n
    nz, nu = len(levels), len(u)
    uu = _closed_u(u, n)
    U, Z = np.meshgrid(u, levels)
    V = surface.point(U, Z)
    N = surface.normal(U, Z)
    # Midpoint samples of every edge: along u, along z, and of each quad (both diagonals).
    um = 0.5 * (uu[:-1] + uu[1:])
    zm = 0.5 * (levels[:-1] + levels[1:])
    Mu = surface.point(*np.meshgrid(um, levels))  # (nz, nu)
    Mz = surface.point(*np.meshgrid(u, zm))  # (nz-1, nu)
    Mc = surface.point(*np.meshgrid(um, zm))  # (nz-1, nu)
    Vn = np.roll(V, -1, axis=1)  # neighbour i+1 (wraps)
    Nn = np.roll(N, -1, axis=1)

    def signed(mid, a, b, na, nb):
        nrm = na + nb
        nrm /= np.linalg.norm(nrm, axis=-1)[..., None]
        return np.sum((mid - 0.5 * (a + b)) * nrm, -1)

    du = signed(Mu, V, Vn, N, Nn)  # (nz, nu)
    dz = signed(Mz, V[:-1], V[1:], N[:-1], N[1:])  # (nz-1, nu)
    nq = N[:-1] + Nn[:-1] + N[1:] + Nn[1:]
    d1 = signed(Mc, V[:-1], Vn[1:], nq, nq)  # diagonal (j,i)-(j+1,i+1)
    d2 = signed(Mc, Vn[:-1], V[1:], nq, nq)  # diagonal (j,i+1)-(j+1,i)
    main = np.abs(d1) <= np.abs(d2)

    idx = np.arange(nz * nu).reshape(nz, nu)
    a, b = idx[:-1], np.roll(idx, -1, axis=1)[:-1]
    c, d = np.roll(idx, -1, axis=1)[1:], idx[1:]
    # main diagonal a-c: (a, b, c), (a, c, d); other diagonal b-d: (a, b, d), (b, c, d)
    t1 = np.where(main[..., None], np.stack([a, b, c], -1), np.stack([a, b, d], -1))
    t2 = np.where(main[..., None], np.stack([a, c, d], -1), np.stack([b, c, d], -1))
    tris = np.concatenate([t1.reshape(-1, 3), t2.reshape(-1, 3)])
    # Mean deviation of each triangle = mean of its edge-midpoint deviations.
    dd = np.where(main, d1, d2)
    dzn = np.roll(dz, -1, axis=1)
    # t1 edges: u-edge at row j, then (main) z-edge at i+1 / (other) the diagonal ...
    m1 = np.where(main, (du[:-1] + dzn + dd) / 3.0, (du[:-1] + dd + dz) / 3.0)
    m2 = np.where(main, (dd + du[1:] + dz) / 3.0, (dzn + du[1:] + dd) / 3.0)
    mean = np.concatenate([m1.ravel(), m2.ravel()])
    flat = V.reshape(-1, 3)
    e1 = flat[tris[:, 1]] - flat[tris[:, 0]]
    e2 = flat[tris[:, 2]] - flat[tris[:, 0]]
    area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=-1)
    num = np.zeros(nz * nu)
    den = np.zeros(nz * nu)
    for k in range(3):
        np.add.at(num, tris[:, k], area * mean)
        np.add.at(den, tris[:, k], area)
    shift = (num / np.maximum(den, 1e-300)).reshape(nz, nu)
    # Move within the section plane so that the normal displacement is `shift`.
    nxy = N[..., :2]
    hn = np.linalg.norm(nxy, axis=-1)
    V = V.copy()
    V[..., :2] += (shift / hn ** 2)[..., None] * nxy
    params = np.stack([U, Z], -1)
    return FlankGrid(surface, u, levels, V, tris, params, tol)


def measure_flank(grid: FlankGrid) -> dict:
    """Largest distances (upper bounds) of the mesh's vertices, edge midpoints and facet
    centroids from the analytic flank, each started from its own (u, z)."""
    surf = grid.surface
    V = grid.vertices.reshape(-1, 3)
    P = grid.params.reshape(-1, 2).copy()
    n = surf.curve.n
    tri = grid.triangles
    # Unwrap u across the seam so that parameter averages stay on the right piece.
    ut = P[tri, 0]
    ref = ut[:, :1]
    ut = np.where(ut - ref > 0.5 * n, ut - n, np.where(ref - ut > 0.5 * n, ut + n, ut))
    zt = P[tri, 1]
    # Only the largest distance is wanted: points far below it stop early (FOCUS).
    out = {"vertices": float(foot_points(surf, V, P[:, 0], P[:, 1], focus=FOCUS).max())}
    cen = V[tri].mean(1)
    out["centroids"] = float(foot_points(surf, cen, ut.mean(1), zt.mean(1), focus=FOCUS).max())
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    ue = np.concatenate([ut[:, [0, 1]], ut[:, [1, 2]], ut[:, [2, 0]]])
    ze = np.concatenate([zt[:, [0, 1]], zt[:, [1, 2]], zt[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, first = np.unique(key[:, 0] * (len(V) + 1) + key[:, 1], return_index=True)
    mid = V[edges[first]].mean(1)
    out["edge_midpoints"] = float(foot_points(surf, mid, ue[first].mean(1),
                                              ze[first].mean(1), focus=FOCUS).max())
    out["max"] = max(out.values())
    out["points"] = int(len(V) + len(cen) + len(first))
    return out


# ---------------------------------------------------------------------- closed meshes
@dataclass(frozen=True)
class TriMesh:
    """An indexed triangle mesh (metres), outward-oriented when closed."""

    vertices: np.ndarray
    faces: np.ndarray
    name: str = ""

    @cached_property
    def volume(self) -> float:
        v = self.vertices[self.faces]
        return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)


def validate_mesh(vertices, faces, name: str, with_trimesh: bool = False) -> dict:
    """Closed, consistently wound 2-manifold with positive volume, checked on the mesh as
    given (nothing merged or repaired): every directed edge appears once and its
    reverse once, and manifold3d accepts the mesh (status NoError); trimesh's watertight
    and winding tests too with ``with_trimesh`` (slower; the tests use it on the files
    read back)."""
    import manifold3d

    faces = np.asarray(faces)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]).astype(np.int64)
    nv = len(vertices) + 1
    fwd = np.sort(e[:, 0] * nv + e[:, 1])
    rev = e[:, 1] * nv + e[:, 0]
    unique_directed = bool(np.all(np.diff(fwd) > 0))
    pos = np.minimum(np.searchsorted(fwd, rev), len(fwd) - 1)
    paired = bool(np.all(fwd[pos] == rev))
    mesh = manifold3d.Mesh64(vert_properties=np.ascontiguousarray(vertices, dtype=np.float64),
                             tri_verts=np.ascontiguousarray(faces, dtype=np.uint64))
    man = manifold3d.Manifold(mesh)
    status = str(man.status())
    out = {
        "edges_paired": paired and unique_directed,
        "manifold3d_status": status,
        "manifold3d_volume": float(man.volume()),
        "manifold3d_genus": int(man.genus()),
        "triangles": int(len(faces)),
    }
    ok = out["edges_paired"] and status.endswith("NoError") and out["manifold3d_volume"] > 0.0
    if with_trimesh:
        import trimesh

        tm = trimesh.Trimesh(vertices=vertices, faces=faces, process=False, validate=False)
        out["trimesh_watertight"] = bool(tm.is_watertight)
        out["trimesh_winding_consistent"] = bool(tm.is_winding_consistent)
        out["trimesh_volume"] = float(tm.volume)
        ok = ok and out["trimesh_watertight"] and out["trimesh_winding_consistent"]
    if not ok:
        raise RuntimeError(f"{name} mesh is not a closed oriented manifold: {out}")
    return out


def _triangulate(polygons):
    import manifold3d

    return np.asarray(manifold3d.triangulate([np.ascontiguousarray(p[:, :2]) for p in polygons]),
                      dtype=np.int64)


def _cap(rings, offsets, top: bool):
    """Cap triangles over rings (each ccw for an outer boundary, cw for a hole)."""
    tri = _triangulate(rings)
    glob = np.concatenate([off + np.arange(len(r)) for r, off in zip(rings, offsets, strict=True)])
    tri = glob[tri]
    return tri if top else tri[:, ::-1]


def rotor_mesh(flank: FlankGrid, bore_radius: float | None, tol: float, name: str) -> TriMesh:
    """Closed rotor: the flank, the end caps, and (outer rotor) the bore cylinder."""
    nz, nu = flank.shape
    V = flank.vertices.reshape(-1, 3)
    tris = flank.triangles
    bottom, top = flank.vertices[0], flank.vertices[-1]
    off_bottom, off_top = 0, (nz - 1) * nu
    if bore_radius is None:  # inner rotor: material inside the profile
        caps = [_cap([bottom], [off_bottom], False), _cap([top], [off_top], True)]
        faces = np.concatenate([tris] + caps)
        return TriMesh(V, faces, name)
    # outer rotor: material between the profile and the bore
    sw = flank.surface.sweep
    # The bore is a cylinder (a cone when scaled): straight generators, so its two end
    # rings are exact; the ring is sized at the larger (z = 0) end.
    m, r = ring_size(bore_radius, tol)
    a = 2.0 * math.pi * np.arange(m) / m
    circle = np.stack([np.cos(a), np.sin(a)], -1) * r
    ring0 = np.concatenate([circle, np.zeros((m, 1))], -1)
    ring1 = np.concatenate([circle * float(sw.scale(sw.length)), np.full((m, 1), sw.length)], -1)
    base = len(V)
    Vall = np.concatenate([V, ring0, ring1])
    i = np.arange(m)
    j = (i + 1) % m
    b0, b1 = base + i, base + j
    t0, t1 = base + m + i, base + m + j
    bore = np.concatenate([np.stack([b0, b1, t1], -1), np.stack([b0, t1, t0], -1)])
    # The flank faces point into the fluid for the outer rotor: reverse them.
    flank_faces = tris[:, ::-1]
    cap0 = _cap_with_hole(ring0, base, bottom, off_bottom, top=False)
    cap1 = _cap_with_hole(ring1, base + m, top, off_top, top=True)
    faces = np.concatenate([flank_faces, bore, cap0, cap1])
    return TriMesh(Vall, faces, name)


def _cap_with_hole(outer, outer_off, hole, hole_off, top: bool):
    """Annulus cap: ``outer`` ring (ccw) with the ccw polygon ``hole`` cut out."""
    return _cap_with_holes(outer, outer_off, [(hole, hole_off)], top)


def _cap_with_holes(outer, outer_off, holes, top: bool):
    """Cap: ``outer`` ring (ccw) with the ccw polygons ``holes`` ((ring, offset), ...)
    cut out."""
    import manifold3d

    pts = [np.ascontiguousarray(outer[:, :2])]
    glob = [outer_off + np.arange(len(outer))]
    for hole, off in holes:
        pts.append(np.ascontiguousarray(hole[::-1, :2]))
        glob.append(off + np.arange(len(hole))[::-1])
    tri = np.asarray(manifold3d.triangulate(pts), dtype=np.int64)
    tri = np.concatenate(glob)[tri]
    return tri if top else tri[:, ::-1]


def fluid_mesh(wall, holes, name: str = "fluid") -> TriMesh:
    """Space inside ``wall`` (a flank grid or casing tube whose triangles point out of
    the region it encloses: the internal gear's outer flank, the twin screw's bores)
    less the flank grids ``holes`` (rotors with their material inside), z in [0, L]."""
    parts = [wall, *holes]
    sizes = [g.vertices.shape[0] * g.vertices.shape[1] for g in parts]
    offs = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int)
    V = np.concatenate([g.vertices.reshape(-1, 3) for g in parts])
    faces = [wall.triangles] + [h.triangles[:, ::-1] + off
                                for h, off in zip(holes, offs[1:], strict=True)]
    for top in (False, True):
        rows = [(g.vertices.shape[0] - 1 if top else 0) for g in parts]
        rings = [(g.vertices[j], off + j * g.vertices.shape[1])
                 for g, j, off in zip(parts, rows, offs, strict=True)]
        faces.append(_cap_with_holes(rings[0][0], rings[0][1], rings[1:], top))
    return TriMesh(V, np.concatenate(faces), name)


def check_sections(flank: FlankGrid, what: str) -> None:
    """The cap polygons must be simple (a folded offset or profile shows here)."""
    for j in (0, len(flank.z) - 1):
        check_simple(flank.vertices[j, :, :2], f"{what} section at z = {flank.z[j] * 1e3:.3f} mm")


def flank_to_tolerance(surface: SweptSurface, tol: float) -> tuple[FlankGrid, dict]:
    """A flank mesh whose measured deviation is within ``tol``: built for the design
    estimate, measured, and rebuilt finer (REFINE_FACTOR) until it passes."""
    design = DESIGN_FACTOR
    for attempt in range(MAX_REBUILDS + 1):
        grid = build_flank(surface, tol, design)
        meas = grid.measure()
        meas["rebuilds"] = attempt
        if meas["max"] <= tol:
            return grid, meas
        log.info("%s flank deviates %.3g um > %.3g um: rebuilding finer", surface.curve.name,
                 meas["max"] * 1e6, tol * 1e6)
        design *= REFINE_FACTOR
    raise RuntimeError(f"{surface.curve.name} flank does not reach {tol * 1e6:.3g} um "
                       f"after {MAX_REBUILDS} refinements (measured {meas['max'] * 1e6:.3g} um)")
