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

from . import planar

#: A section vertex this close to a rotor's surface (per centre distance) lies on it: the
#: families' polygons lie within their chord error (1e-6) and the twin screw's grown
#: rotors (2e-6) of the true surfaces; vertices of a bore or a cut line lie farther off
#: except at the corners.
ON_ROTOR = 2e-5
#: Chord tolerance (per centre distance) of the profiles the vertices are told against.
PROFILE_TOL = 5e-6
#: Where a vertex lies within the chord error of two rotors' profiles (a film), each
#: profile is resampled this many times finer between its nearest sample's neighbours
#: (chord error 1/FILM_REFINE^2 of PROFILE_TOL, 1.5e-9 m on the 4/6 pairs).
FILM_REFINE = 16
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
    #: whether its first and its last point are a contact with the other rotor (the
    #: section's own, :func:`chains`), not a vertex of the section
    contact_ends: tuple = (False, False)


class Surfaces:
    """The rotors' surfaces of a pair, to tell which one a section vertex lies on."""

    def __init__(self, pair):
        from scipy.spatial import cKDTree

        from .curves import sample

        axes = [np.asarray(r.axis, dtype=float) for r in pair.rotors]
        self.size = max(math.dist(axes[0], axes[-1]), 1e-2 * pair.diameter)
        self.film_deficit = pair.film_deficit
        self.rotors = []
        self.profiles = [r.profile for r in pair.rotors]
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

    def outside(self, k: int, points, psi) -> np.ndarray:
        """Signed distance of each point (fixed frame) to rotor k's true profile placed
        at each reference angle ``psi`` (positive outside it): the nearest sample's
        edges resampled FILM_REFINE times finer (chord error 1.5e-9 m on the 4/6 pairs,
        below the twin screw's growth)."""
        axis, ratio, u, p, tree, n = self.rotors[k][:6]
        x = planar.rotate(np.asarray(points, dtype=float) - axis,
                          -ratio * np.asarray(psi, dtype=float))
        _, j = tree.query(x)
        lo = u[j] - np.mod(u[j] - u[j - 1], n)
        hi = u[j] + np.mod(u[(j + 1) % len(u)] - u[j], n)
        grid = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, 2 * FILM_REFINE + 1)
        q = self.profiles[k].point(np.mod(grid, n).ravel()).reshape(*grid.shape, 2)
        a, ab = q[:, :-1], np.diff(q, axis=1)
        xa = x[:, None] - a
        t = np.clip(np.einsum("vek,vek->ve", xa, ab)
                    / np.maximum(np.einsum("vek,vek->ve", ab, ab), 1e-300), 0.0, 1.0)
        d = np.linalg.norm(xa - t[..., None] * ab, axis=-1)
        e = np.argmin(d, axis=1)
        v = np.arange(len(x))
        side = np.sign(ab[v, e, 0] * xa[v, e, 1] - ab[v, e, 1] * xa[v, e, 0])
        return -side * d[v, e] * self._turning(k)

    def _turning(self, k: int) -> float:
        """+1 where rotor k's sampled profile runs counter-clockwise, else -1."""
        memo = self.__dict__.setdefault("_senses", {})
        if k not in memo:
            memo[k] = 1.0 if area(self.rotors[k][3]) > 0.0 else -1.0
        return memo[k]

    def classify(self, ring: np.ndarray, psi: float):
        """(rotor or -1, profile parameter) of each vertex of ``ring`` at angle psi."""
        dist = np.full((len(self.rotors), len(ring)), np.inf)
        pars = np.zeros_like(dist)
        nearest = np.zeros(dist.shape, dtype=int)  # the sample next to each foot
        frames = []
        for k, (axis, ratio, u, p, tree, n, _, reach) in enumerate(self.rotors):
            x = rotate(ring - axis, -ratio * psi)
            frames.append(x)
            # Only vertices within an edge of a sample can lie on the surface.
            dk, j = tree.query(x, distance_upper_bound=reach)
            near = np.nonzero(np.isfinite(dk))[0]
            if not len(near):
                continue
            x, j = x[near], j[near]
            nearest[k, near] = j
            # The two edges at the nearest sample, from it back (row 0) and on (row 1),
            # at once; the edge on where it is strictly nearer.
            ia = np.stack([j - 1, j]) % len(p)
            ib = (ia + 1) % len(p)
            a, ab = p[ia], p[ib] - p[ia]
            xa = x - a
            t = np.clip((xa[..., 0] * ab[..., 0] + xa[..., 1] * ab[..., 1])
                        / (ab[..., 0] * ab[..., 0] + ab[..., 1] * ab[..., 1]), 0.0, 1.0)
            foot = a + t[..., None] * ab - x
            d = np.hypot(foot[..., 0], foot[..., 1])
            ua, ub = u[ia], u[ib]
            ub = np.where(ub < ua, ub + n, ub)
            on = (d[1] < d[0]).astype(int)
            v = np.arange(len(near))
            dist[k, near] = d[on, v]
            pars[k, near] = np.mod(ua + t * (ub - ua), n)[on, v]
        self._films(dist, pars, nearest, frames)
        k = np.argmin(dist, axis=0)
        v = np.arange(len(ring))
        on = dist[k, v] < ON_ROTOR * self.size
        return np.where(on, k, -1), np.where(on, pars[k, v], 0.0)

    def _films(self, dist, pars, nearest, frames):
        """Where two rotors' sampled profiles lie about as near a vertex (a film between
        the rotors thinner than the samples' chord error), its distances and parameters
        are taken again on each profile resampled FILM_REFINE times finer about its
        nearest sample, in place.  The circular 4/6 pair's conformal arcs leave a film
        under PROFILE_TOL (0.4 um) for ~0.3 mm behind their contact: told by the chords,
        that stretch of one side went to the other rotor, whose piece then folded round
        the chamber's tip, and every band's corner there lagged the tip (the strips
        between the corners' paths and the tip's, 1e-3 of the largest discharge area
        at 48 samples per period)."""
        if len(dist) < 2:
            return
        two = np.sort(dist, axis=0)[:2]
        amb = np.nonzero((two[0] < ON_ROTOR * self.size)
                         & (two[1] < two[0] + 2.0 * PROFILE_TOL * self.size))[0]
        if not len(amb):
            return
        f = np.linspace(0.0, 1.0, 2 * FILM_REFINE + 1)
        for k, profile in enumerate(self.profiles):
            sel = amb[np.isfinite(dist[k, amb])]
            if not len(sel):
                continue
            u, n = self.rotors[k][2], self.rotors[k][5]
            j = nearest[k, sel]
            lo = u[j] - np.mod(u[j] - u[j - 1], n)
            hi = u[j] + np.mod(u[(j + 1) % len(u)] - u[j], n)
            grid = lo[:, None] + (hi - lo)[:, None] * f  # (vertices, 2 FILM_REFINE + 1)
            q = profile.point(np.mod(grid, n).ravel()).reshape(*grid.shape, 2)
            a, ab = q[:, :-1], np.diff(q, axis=1)
            x = frames[k][sel][:, None]
            t = np.clip(np.einsum("vek,vek->ve", x - a, ab)
                        / np.maximum(np.einsum("vek,vek->ve", ab, ab), 1e-300), 0.0, 1.0)
            d = np.linalg.norm(a + t[..., None] * ab - x, axis=-1)
            e = np.argmin(d, axis=1)
            v = np.arange(len(sel))
            dist[k, sel] = d[v, e]
            pars[k, sel] = np.mod(grid[v, e] + t[v, e] * (grid[v, e + 1] - grid[v, e]), n)


def rotate(points, angle):
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def turn(points, angles):
    """points (m, 2) turned by each of angles (n,): (n, m, 2)."""
    return planar.rotate(points, np.asarray(angles)[:, None])


def area(ring) -> float:
    """Signed area of a closed ring (counter-clockwise positive)."""
    x, y = ring[:, 0], ring[:, 1]
    # (each vertex's successor by slices: np.roll costs more than a small ring's sum)
    x2, y2 = np.concatenate([x[1:], x[:1]]), np.concatenate([y[1:], y[:1]])
    return 0.5 * float(np.sum(x * y2 - y * x2))


def chains(ring, cls, par, periods, index, contacts=None, reach=0.0) -> list[Chain]:
    """The runs of ``ring``'s vertices on one rotor (``cls``: :meth:`Surfaces.classify`),
    each a :class:`Chain` of ring ``index``; ``periods``: each profile's parameter range.
    A run's end that meets another rotor's run is carried on to the nearest of
    ``contacts`` within ``reach`` (the section's own: where the true surfaces touch, not
    where the grown polygons meet)."""
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
        ends = [False, False]
        if contacts:
            pts, s, ends = _to_contacts(pts, s, cls[(r[0] - 1) % m], cls[(r[-1] + 1) % m], k,
                                        np.asarray(contacts, dtype=float), reach)
        if s[-1] < s[0]:
            s, pts, ends = s[::-1], pts[::-1], ends[::-1]
        out.append(Chain(k, pts, float(s[0]), float(s[-1]), index, s, tuple(ends)))
    return out


def _to_contacts(pts, s, before, after, k, contacts, reach):
    """(points, parameters, whether each end is a contact) of a run of rotor k whose
    ring neighbours are rotors ``before`` and ``after`` (-1: none): each end that meets
    the other rotor's run carried on to the nearest of ``contacts`` within ``reach``
    (its parameter the end's: no piece matching goes by it).  A contact nearer the
    run's other end is that end's: a sliver's end on the cusp line (the other rotor's
    run beyond a few microns of cut line) would be carried back to the sliver's own
    contact and the run closed on itself (the circular 4/6 pair's sliver born 116 deg
    after its chamber, within CONTACT_REACH of its contact for its first 0.006 rad:
    the bands of such runs left 0.05 mm2 of its sweep out at 3072 samples a period)."""
    ends = [False, False]
    tips = pts[[0, -1]]
    for end, nb in ((0, before), (-1, after)):
        if nb < 0 or nb == k:
            continue
        d = np.linalg.norm(contacts - pts[end], axis=1)
        j = int(np.argmin(d))
        if d[j] >= reach or d[j] == 0.0:
            continue
        if np.linalg.norm(contacts[j] - tips[end + 1]) < d[j]:  # the other end's
            continue
        if end == 0:
            pts, s = np.vstack([contacts[j], pts]), np.r_[s[0], s]
        else:
            pts, s = np.vstack([pts, contacts[j]]), np.r_[s, s[-1]]
        ends[end] = True
    return pts, s, ends
