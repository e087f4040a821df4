"""A rotor flank: the swept surface of design.md, and distances to it.

    S(u, z) = R(theta(z)) (s(z) p(u) + w(u)) + s(z) C + z e_z,

with ``p`` the analytic profile (:mod:`..curves`), ``w = d c(u) n(u)`` the clearance
offset (not scaled along a conical rotor: a clearance is a gap, the same at every
section), ``C`` the rotor axis in the section plane, ``s`` the scale law and
``theta = theta0 - omega twist(z)`` (omega the rotor's speed ratio: 1 for the reference
rotor).  Foot points (Gauss-Newton) measure how far a point is from the analytic flank.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..curves import PieceCurve
from ..offsets import OffsetProfile
from ..sweep import Sweep

log = logging.getLogger(__name__)

#: Gauss-Newton iterations of the foot-point search (each converges the distance
#: bound to ~1e-3 of itself; the result is a true upper bound at any iteration).
FOOT_ITERATIONS = 8
#: Fine grid on which the z-density of the levels is integrated.
Z_GRID = 2001


def _rot(theta):
    c, s = np.cos(theta), np.sin(theta)
    return c, s


def _apply(c, s, v):
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], -1)


@dataclass(frozen=True)
class SweptSurface:
    """One rotor flank placed in the machine (fixed) frame; lengths in metres."""

    curve: PieceCurve | OffsetProfile
    sweep: Sweep
    theta0: float  # rotor turn at z = 0
    omega: float  # rotor twist per outer-rotor twist (1 outer, m21 inner)
    centre: tuple[float, float]  # rotor axis at z = 0 (scaled with s along z)

    @property
    def base(self) -> PieceCurve:
        return self.curve.base if isinstance(self.curve, OffsetProfile) else self.curve

    @property
    def length(self) -> float:
        return self.sweep.length

    def theta(self, z):
        return self.theta0 - self.omega * self.sweep.twist(z)

    def dtheta(self, z):
        return -self.omega * self.sweep.dtwist(z)

    def d2theta(self, z):
        h = 1e-6 * self.length
        zz = np.clip(np.asarray(z, dtype=float), h, self.length - h)
        return (self.dtheta(zz + h) - self.dtheta(zz - h)) / (2.0 * h)

    def evaluate(self, u, z, jacobian: bool = False, twist: bool = False):
        """S(u, z); with ``jacobian`` also S_u and S_z (analytic in z); with ``twist``
        also the cross derivative S_uz."""
        u, z = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(z, dtype=float))
        curve = self.curve
        offset = isinstance(curve, OffsetProfile)
        bu, k = curve.base_param(u) if offset else (u, 1.0)  # (trimmed at corners)
        p = self.base.point(bu)
        w = curve.offset(u)[..., None] * curve.normal(u) if offset else 0.0
        s = self.sweep.scale(z)[..., None]
        c, sn = _rot(self.theta(z))
        centre = np.asarray(self.centre)
        q = s * p + w
        rq = _apply(c, sn, q)
        pt = np.concatenate([rq + s * centre, z[..., None]], -1)
        if not jacobian:
            return pt
        dp = self.base.derivative(bu) * np.asarray(k)[..., None]
        qu = s * dp + ((curve.derivative(u) - dp) if offset else 0.0)
        su = _apply(c, sn, qu)
        ds = self.sweep.dscale(z)[..., None]
        jrq = np.stack([-rq[..., 1], rq[..., 0]], -1)
        sz = self.dtheta(z)[..., None] * jrq + ds * (_apply(c, sn, p) + centre)
        zeros = np.zeros(u.shape + (1,))
        out = (pt, np.concatenate([su, zeros], -1),
               np.concatenate([sz, np.ones(u.shape + (1,))], -1))
        if not twist:
            return out
        jqu = np.stack([-su[..., 1], su[..., 0]], -1)
        suz = self.dtheta(z)[..., None] * jqu + ds * _apply(c, sn, dp)
        return (*out, np.concatenate([suz, zeros], -1))

    def point(self, u, z):
        return self.evaluate(u, z)

    def jacobian(self, u, z):
        _, su, sz = self.evaluate(u, z, jacobian=True)
        return su, sz

    def normal(self, u, z):
        """Unit normal pointing out of the region the profile encloses."""
        su, sz = self.jacobian(u, z)
        n = np.cross(su, sz)
        return n / np.linalg.norm(n, axis=-1)[..., None]

    @cached_property
    def radius_max(self) -> float:
        return self.curve.radius_max

    # ------------------------------------------------------------ design of the grid
    def z_levels(self, tol_z: float) -> np.ndarray:
        """Levels with helix sag |S_zz| h^2 / 8 <= tol_z (exact planes at 0 and L)."""
        L = self.length
        z = np.linspace(0.0, L, Z_GRID)
        r = self.radius_max
        s, ds = self.sweep.scale(z), np.abs(self.sweep.dscale(z))
        t1, t2 = np.abs(self.dtheta(z)), np.abs(self.d2theta(z))
        g = (t2 + t1 * t1) * (s * r + abs(self._clearance_max)) + 2.0 * t1 * ds * r
        if not g.any():
            return np.array([0.0, L])
        dens = np.sqrt(g / (8.0 * tol_z))
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(z))])
        m = max(int(math.ceil(cum[-1] * 1.02)), 1)
        levels = np.interp(np.linspace(0.0, cum[-1], m + 1), cum, z)
        levels[0], levels[-1] = 0.0, L
        return levels

    @property
    def _clearance_max(self) -> float:
        if isinstance(self.curve, OffsetProfile):
            return self.curve.clearance.largest
        return 0.0

    def u_step_limit(self, levels: np.ndarray, tol_m: float) -> float:
        """Largest profile step (arc length) keeping the diagonal twist term in tol_m."""
        zm = 0.5 * (levels[1:] + levels[:-1])
        twist = np.abs(self.dtheta(zm)) * self.sweep.scale(zm) * np.diff(levels)
        worst = float(twist.max()) if len(twist) else 0.0
        return math.inf if worst == 0.0 else 4.0 * tol_m / worst


def foot_points(surface: SweptSurface, x, u0, z0, iterations: int = FOOT_ITERATIONS,
                focus: float = 0.0):
    """Distance from points x (m, 3) to the flank, by Gauss-Newton from (u0, z0).

    The starts are within a fraction of a mesh cell of the foot points; a step is kept
    only where it brings the point closer (halved up to 4 times), and a point stops
    when its distance improves by less than 1e-4 of itself, or (``focus`` > 0) when it
    is below ``focus`` times the largest distance found: it cannot be the largest.
    Every iterate is a point of the bounded flank, so the distance is always an upper
    bound of the true one.
    """
    L = surface.length
    u = np.array(u0, dtype=float)
    z = np.clip(np.array(z0, dtype=float), 0.0, L)
    dist = np.full(len(u), np.inf)
    done = np.zeros(len(u), dtype=bool)
    for it in range(iterations):
        todo = ~done
        if focus > 0.0 and it > 0:
            todo &= dist >= focus * dist.max()
        active = np.nonzero(todo)[0]
        if not len(active):
            break
        pa, su, sz = surface.evaluate(u[active], z[active], jacobian=True)
        r = pa - x[active]
        dist[active] = np.minimum(dist[active], np.linalg.norm(r, axis=-1))
        a11 = np.sum(su * su, -1)
        a12 = np.sum(su * sz, -1)
        a22 = np.sum(sz * sz, -1)
        det = np.maximum(a11 * a22 - a12 * a12, 1e-300)
        b1 = np.sum(su * r, -1)
        b2 = np.sum(sz * r, -1)
        du = np.clip((a22 * b1 - a12 * b2) / det, -0.05, 0.05)
        dz = (a11 * b2 - a12 * b1) / det
        keep = np.zeros(len(active), dtype=bool)
        for _ in range(4):
            un = u[active] - du
            zn = np.clip(z[active] - dz, 0.0, L)
            dn = np.linalg.norm(surface.evaluate(un, zn) - x[active], axis=-1)
            ok = (dn < dist[active]) & ((du != 0.0) | (dz != 0.0))
            gain = dist[active] - dn
            sel = active[ok]
            keep[ok] |= gain[ok] > 1e-4 * dn[ok] + 1e-13
            u[sel], z[sel], dist[sel] = un[ok], zn[ok], dn[ok]
            du, dz = np.where(ok, 0.0, 0.5 * du), np.where(ok, 0.0, 0.5 * dz)
            if not (du.any() or dz.any()):
                break
        done[active[~keep]] = True
        log.debug("foot points: %d still improving", int((~done).sum()))
    return dist


def min_horizontal_normal(surface: SweptSurface, samples: int = 64) -> float:
    """Smallest |n_xy| of the flank's unit normal (1 straight; the cosine of the largest
    tilt of a helical flank), on a grid of the profile and z."""
    curve = surface.curve
    u = (np.arange(curve.n)[:, None] + np.linspace(0.0, 1.0, samples)[None, :-1]).ravel()
    z = np.linspace(0.0, surface.length, samples)
    U, Z = np.meshgrid(u, z)
    n = surface.normal(U, Z)
    return float(np.linalg.norm(n[..., :2], axis=-1).min())
