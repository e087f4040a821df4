"""The casing of an exported pair: its bores between the end plates.

A pair's casing is a set of parallel bores (:meth:`RotorPair.casing_bores`): one
about the internal gear's outer axis (the outer rotor's outside), one per rotor for a
twin screw (two intersecting cylinders).  The fluid domain lies inside their union;
along a conical sweep the section scales about the reference axis, bores and centres
alike (as the rotors' axes do).

The union's outline is the union of the bores' area-neutral regular polygons (each
encloses its circle's area exactly, vertices at most the tolerance outside the circle,
chords at most half of it inside): so the meshed casing keeps the analytic area to
the few chords the cusps cut, and stays within the tolerance of the true bores.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from rotorflow.errors import CaseError

#: Scan points per profile piece on which the largest radius is bracketed before it is
#: polished (a lobe's tip is far wider than 1/512 of a piece).
RADIUS_SCAN = 512


def union_area(bores) -> float:
    """Area of the union of one or two discs ``((cx, cy), r)`` (closed form)."""
    if len(bores) == 1:
        return math.pi * bores[0][1] ** 2
    if len(bores) != 2:
        raise CaseError(f"a casing of {len(bores)} bores is not supported (one or two)")
    ((x1, y1), r1), ((x2, y2), r2) = bores
    d = math.hypot(x2 - x1, y2 - y1)
    if d >= r1 + r2:
        return math.pi * (r1 * r1 + r2 * r2)
    if d <= abs(r1 - r2):
        return math.pi * max(r1, r2) ** 2
    a1 = math.acos((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1))
    a2 = math.acos((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2))
    kite = 0.5 * math.sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2))
    return math.pi * (r1 * r1 + r2 * r2) - (r1 * r1 * a1 + r2 * r2 * a2 - kite)


def ring_size(radius: float, tol: float) -> tuple[int, float]:
    """Vertex count and area-neutral radius of a circle polygon with deviation <= tol."""
    m = max(int(math.ceil(2.0 * math.pi / math.sqrt(12.0 * tol / radius))), 16)
    d = 2.0 * math.pi / m
    return m, radius * math.sqrt(d / math.sin(d))


def circle_polygon(centre, radius: float, tol: float) -> np.ndarray:
    """Area-neutral regular polygon (ccw) of a circle: deviation within ``tol``."""
    m, r = ring_size(radius, tol)
    a = 2.0 * math.pi * np.arange(m) / m
    return np.stack([centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)], -1)


def outline(bores, tol: float) -> np.ndarray:
    """The union of the bores as one counter-clockwise polygon (z = 0, metres)."""
    from manifold3d import CrossSection, FillRule, OpType

    pieces = [CrossSection([np.ascontiguousarray(circle_polygon(c, r, tol))],
                           FillRule.Positive) for c, r in bores]
    union = CrossSection.batch_boolean(pieces, OpType.Add) if len(pieces) > 1 else pieces[0]
    polys = union.to_polygons()
    if len(polys) != 1:
        raise CaseError(f"the casing bores make {len(polys)} separate regions, not one")
    poly = np.asarray(polys[0], dtype=float)
    area = 0.5 * float(np.sum(poly[:, 0] * np.roll(poly[:, 1], -1)
                              - poly[:, 1] * np.roll(poly[:, 0], -1)))
    return poly if area > 0.0 else poly[::-1]


@dataclass(frozen=True)
class Tube:
    """A ruled wall between two rings, indexed like a flank grid: vertices (2, m, 3),
    triangles pointing out of the region the rings enclose."""

    vertices: np.ndarray
    triangles: np.ndarray

    @property
    def shape(self):
        return self.vertices.shape[:2]


def casing_tube(poly: np.ndarray, sweep) -> Tube:
    """The casing wall: ``poly`` at z = 0 and scaled by scale(L) at z = L (straight
    generators: exact for the bores' cylinders and cones)."""
    m = len(poly)
    s1 = float(sweep.scale(sweep.length))
    v = np.stack([np.concatenate([poly, np.zeros((m, 1))], -1),
                  np.concatenate([poly * s1, np.full((m, 1), sweep.length)], -1)])
    i = np.arange(m)
    j = (i + 1) % m
    a, b, c, d = i, j, m + j, m + i
    tris = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)])
    return Tube(v, tris)


def largest_radius(curve) -> float:
    """The largest distance of the profile from its axis (its tip radius), polished."""
    t = np.linspace(0.0, 1.0, RADIUS_SCAN, endpoint=False)
    u = (np.arange(curve.n)[:, None] + t[None, :]).ravel()
    r = np.linalg.norm(curve.point(u), axis=-1)
    k = int(np.argmax(r))
    h = 1.0 / RADIUS_SCAN

    def neg(x):
        return -float(np.linalg.norm(curve.point(np.array([x]))[0]))

    res = minimize_scalar(neg, bounds=(u[k] - h, u[k] + h), method="bounded",
                          options={"xatol": 1e-12})
    return max(float(r[k]), -float(res.fun))
