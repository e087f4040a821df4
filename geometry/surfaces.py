"""Which rotor's surface the vertices of a section lie on (for :mod:`.footprint`).

A section's boundary runs along the rotors' surfaces and along still curves (bores, a
family's cut lines).  A vertex lies on rotor r's surface where it lies on r's profile
placed at ``speed_ratio * psi`` about r's axis (every family's frame: rotor r turns by
its speed ratio times the reference angle); the profile parameter of its foot tells
which piece of material it is, so that the same piece is found at the next angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: A section vertex this close to a rotor's surface (per centre distance) lies on it: the
#: families' polygons lie within their chord error (1e-6) and the twin screw's grown
#: rotors (2e-6) of the true surfaces; vertices of a bore or a cut line lie farther off
#: except at the corners.
ON_ROTOR = 2e-5
#: Chord tolerance (per centre distance) of the profiles the vertices are told against.
PROFILE_TOL = 5e-6
#: Chains with fewer vertices are corners, not pieces of a surface.
MIN_CHAIN = 2


@dataclass(frozen=True)
class Chain:
    """A run of a section ring's vertices on one rotor's surface, ordered the way the
    profile's parameter runs."""

    rotor: int
    points: np.ndarray  # fixed frame
    lo: float  # profile parameter at its ends (unwrapped: lo <= hi)
    hi: float
    ring: int  # index of its ring in the sample
    par: np.ndarray | None = None  # per point, unwrapped as lo .. hi


class Surfaces:
    """The rotors' surfaces of a pair, to tell which one a section vertex lies on."""

    def __init__(self, pair):
        from scipy.spatial import cKDTree

        from .curves import sample

        axes = [np.asarray(r.axis, dtype=float) for r in pair.rotors]
        self.size = max(math.dist(axes[0], axes[-1]), 1e-2 * pair.diameter)
        self.rotors = []
        for r, axis in zip(pair.rotors, axes, strict=True):
            u = sample(r.profile, PROFILE_TOL * self.size)
            p = r.profile.point(u)
            edge = float(np.max(np.linalg.norm(np.diff(p, axis=0), axis=1)))
            self.rotors.append((axis, float(r.speed_ratio), u, p, cKDTree(p),
                                float(r.profile.n), float(np.linalg.norm(p, axis=1).max()),
                                edge + ON_ROTOR * self.size))

    def move(self, points, rotor: int, dpsi: float) -> np.ndarray:
        """Points of rotor ``rotor`` after the reference rotor turns by dpsi."""
        axis, ratio = self.rotors[rotor][:2]
        return rotate(points - axis, ratio * dpsi) + axis

    def classify(self, ring: np.ndarray, psi: float):
        """(rotor or -1, profile parameter) of each vertex of ``ring`` at angle psi."""
        cls = np.full(len(ring), -1)
        par = np.zeros(len(ring))
        best = np.full(len(ring), ON_ROTOR * self.size)
        for k, (axis, ratio, u, p, tree, n, _, reach) in enumerate(self.rotors):
            x = rotate(ring - axis, -ratio * psi)
            # Only vertices within an edge of a sample can lie on the surface.
            dist, j = tree.query(x, distance_upper_bound=reach)
            near = np.nonzero(np.isfinite(dist))[0]
            if not len(near):
                continue
            x, j = x[near], j[near]
            m = len(p)
            for jj in (j - 1, j):  # the two edges at the nearest sample
                a, b = p[jj % m], p[(jj + 1) % m]
                ab = b - a
                t = np.clip(np.einsum("ij,ij->i", x - a, ab) / np.einsum("ij,ij->i", ab, ab),
                            0.0, 1.0)
                d = np.hypot(*(a + t[:, None] * ab - x).T)
                ua, ub = u[jj % m], u[(jj + 1) % m]
                ub = np.where(ub < ua, ub + n, ub)
                closer = d < best[near]
                idx = near[closer]
                cls[idx] = k
                par[idx] = np.mod(ua + t * (ub - ua), n)[closer]
                best[idx] = d[closer]
        return cls, par


def rotate(points, angle):
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def turn(points, angles):
    """points (m, 2) turned by each of angles (n,): (n, m, 2)."""
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    x, y = points[..., 0], points[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], -1)


def area(ring) -> float:
    """Signed area of a closed ring (counter-clockwise positive)."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - y * np.roll(x, -1)))


def chains(ring, cls, par, periods, index) -> list[Chain]:
    """The runs of ``ring``'s vertices on one rotor (``cls``: :meth:`Surfaces.classify`),
    each a :class:`Chain` of ring ``index``; ``periods``: each profile's parameter range."""
    m = len(ring)
    change = np.nonzero(cls != np.roll(cls, 1))[0]
    if not len(change):
        runs = [np.arange(m + 1) % m] if cls[0] >= 0 else []
    else:
        order = (np.arange(m) + change[0]) % m
        cuts = np.nonzero(np.diff(cls[order]))[0] + 1
        runs = [order[a:b] for a, b in zip(np.r_[0, cuts], np.r_[cuts, m], strict=True)]
    out = []
    for r in runs:
        k = int(cls[r[0]])
        if k < 0 or len(r) < MIN_CHAIN:
            continue
        n = periods[k]
        steps = np.remainder(np.diff(par[r]) + 0.5 * n, n) - 0.5 * n
        s = par[r[0]] + np.concatenate([[0.0], np.cumsum(steps)])
        pts = ring[r]
        if s[-1] < s[0]:
            s, pts = s[::-1], pts[::-1]
        out.append(Chain(k, pts, float(s[0]), float(s[-1]), index, s))
    return out


