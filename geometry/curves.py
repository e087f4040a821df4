"""Rotor profiles as closed analytic curves: evaluation, sampling to a
chordal tolerance and closest points (clearance offsets: :mod:`.offsets`).

A profile is a chain of analytic pieces traversed counter-clockwise; a global parameter
``u`` in ``[0, n_pieces)`` runs along it, piece ``floor(u)`` at local ``t = u - floor(u)``.

Every family's profiles are such chains (:class:`PieceCurve`, e.g. the pin-generated
pair's in :mod:`.internal_gear.profiles`); what follows works on any of them, and on
any object with the same methods.

"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from rotorflow.errors import CaseError

from .planar import cross

#: Pre-grid per piece on which curvature is tabulated to place samples.
PREGRID = 513
#: Gauss-Legendre nodes per sub-interval and sub-intervals per piece for arc-length
#: integrals (analytic integrands: 1e-12 relative).
GAUSS_NODES = 16
GAUSS_PANELS = 32
#: Bisection rounds after equidistribution before sampling gives up (2^-40 of a piece).
MAX_REFINE = 40



def gauss_rule(n: int):
    """(u, weights) of Gauss-Legendre panels on every piece of a chain of ``n`` pieces."""
    x, w = np.polynomial.legendre.leggauss(GAUSS_NODES)
    edges = np.linspace(0.0, 1.0, GAUSS_PANELS + 1)
    h = np.diff(edges)
    t = (edges[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
    wt = (0.5 * h[:, None] * w[None, :]).ravel()
    return (np.arange(n)[:, None] + t[None, :]).ravel(), np.tile(wt, n)


def piece_difference(curve, f, u, h: float):
    """df/du of a function of the curve's parameter by a central difference of step h
    kept inside u's piece (f may jump between pieces)."""
    j, t = curve._split(u)
    lo = j + np.clip(t - h, 0.0, 1.0 - 1e-12)
    hi = j + np.clip(t + h, 0.0, 1.0 - 1e-12)
    return (f(hi) - f(lo)) / (hi - lo)[..., None]


class PieceCurve:
    """A closed counter-clockwise chain of analytic pieces (lengths in metres).

    Families subclass it with ``_eval(u, order)`` (the point, order 0, or d/du, order 1,
    at global parameters u) and the attributes ``name``, ``n`` (pieces), ``lobes`` and
    ``material_inside``; everything else here (normals, curvature, arc length, the
    enclosed area, lobe fractions) follows from ``_eval``.
    """

    name: str
    lobes: int
    material_inside: bool

    @property
    def n(self) -> int:
        raise NotImplementedError

    def _eval(self, u, order: int):
        raise NotImplementedError

    def _split(self, u):
        u = np.mod(np.asarray(u, dtype=float), self.n)
        j = np.minimum(np.floor(u).astype(int), self.n - 1)
        return j, u - j

    def _lobe_start(self, ut, st) -> float:
        """Arc length from u = 0 to lobe 0's reference point (see lobe_fraction)."""
        return 0.0

    def point(self, u):
        return self._eval(u, 0)

    def derivative(self, u):
        return self._eval(u, 1)

    def second_derivative(self, u):
        """d2/du2 by a central difference of the (analytic) first derivative, in-piece."""
        return piece_difference(self, self.derivative, u, 1e-5)

    def normal(self, u):
        """Outward unit normal (right of the counter-clockwise tangent)."""
        d = self.derivative(u)
        n = np.stack([d[..., 1], -d[..., 0]], -1)
        return n / np.linalg.norm(n, axis=-1)[..., None]

    def curvature(self, u):
        """Signed curvature, positive where the region inside is convex."""
        d1, d2 = self.derivative(u), self.second_derivative(u)
        return cross(d1, d2) / np.linalg.norm(d1, axis=-1) ** 3

    def turning_rate(self, u):
        """kappa |dp/du| (finite even where the speed vanishes at sigma_bar = 1)."""
        d1, d2 = self.derivative(u), self.second_derivative(u)
        return cross(d1, d2) / np.sum(d1 * d1, -1)

    # -------------------------------------------------------------- integrals
    @cached_property
    def _gauss(self):
        return gauss_rule(self.n)

    def integrate(self, f) -> float:
        """\\oint f(u) du by Gauss-Legendre panels on every piece."""
        u, w = self._gauss
        return float(np.sum(f(u) * w))

    @cached_property
    def length(self) -> float:
        return self.integrate(lambda u: np.linalg.norm(self.derivative(u), axis=-1))

    @cached_property
    def _arc_table(self):
        u = (np.arange(self.n)[:, None] + np.linspace(0.0, 1.0, PREGRID)[None, :-1]).ravel()
        u = np.append(u, self.n)
        p = self.point(u)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=-1))])
        return u, s

    def lobe_fraction(self, u):
        """Fraction of the lobe (by arc length) from the lobe's reference point, [0, 1).

        The reference point is the family's (:meth:`_lobe_start`); u = 0 by default.
        """
        ut, st = self._arc_table
        s = np.interp(np.mod(np.asarray(u, dtype=float), self.n), ut, st)
        lobe_len = st[-1] / self.lobes
        return np.mod((s - self._lobe_start(ut, st)) / lobe_len, 1.0)

    # -------------------------------------------------------------- area
    @cached_property
    def area(self) -> float:
        """Enclosed area, 1/2 of the integral of p x p' (Green's theorem, Gauss panels).

        Families with closed forms override it."""
        return 0.5 * self.integrate(lambda u: cross(self.point(u), self.derivative(u)))

    @cached_property
    def radius_max(self) -> float:
        ut, _ = self._arc_table
        return float(np.linalg.norm(self.point(ut), axis=-1).max())


# ------------------------------------------------------------------ sampling
def _chord_error(curve, ua, ub):
    """Largest distance of the curve between ua and ub from the chord (3 interior points)."""
    a, b = curve.point(ua), curve.point(ub)
    ab = b - a
    lab = np.maximum(np.linalg.norm(ab, axis=-1), 1e-300)
    worst = np.zeros(len(ua))
    for q in (0.25, 0.5, 0.75):
        p = curve.point(ua + q * (ub - ua))
        worst = np.maximum(worst, np.abs(cross(ab, p - a)) / lab)
    return worst, lab


def sample(curve, tol: float, max_step: float = math.inf) -> np.ndarray:
    """Parameters u of a closed polyline through the curve with chord error <= tol.

    Samples are first spread so that each chord carries about the same sagitta
    (density sqrt(|kappa| / (8 tol)) per unit length, and at least 1 / max_step), then
    every chord is checked against the curve at three interior points and bisected
    until it passes; piece ends are always samples.  Returns sorted u in [0, n).
    """
    if not tol > 0.0:
        raise CaseError(f"the sampling tolerance must be positive, got {tol}")
    # Every piece's curve evaluations in one call (a call costs the same whatever its
    # length: 0.1 s of the twin screw's 1.5 s went to sampling its profiles piece by
    # piece); each piece's grid and bisections are its own, as before.
    t = np.linspace(0.0, 1.0, PREGRID)
    n = curve.n
    u = np.arange(n)[:, None] + t[None, :]
    u[:, -1] = np.arange(n) + 1.0 - 1e-13
    d1 = curve.derivative(u.ravel()).reshape(n, PREGRID, 2)
    kappa = curve.curvature(u.ravel()).reshape(n, PREGRID)
    pieces = []
    for j in range(n):
        speed = np.linalg.norm(d1[j], axis=-1)
        kap = np.abs(kappa[j])
        kap = np.where(np.isfinite(kap), kap, 0.0)
        dens = np.maximum(np.sqrt(kap / (8.0 * tol)), 1.0 / max_step) * speed
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(u[j]))])
        if not cum[-1] > 0.0:  # a straight piece and no max_step: spread by parameter
            cum = t.copy()
        m = max(int(math.ceil(cum[-1] * 1.05)), 1)
        us = np.interp(np.linspace(0.0, cum[-1], m + 1), cum, j + t)
        us[-1] = j + 1.0
        pieces.append(us)
    todo = list(range(n))
    for _ in range(MAX_REFINE):
        err, lab = _chord_error(curve, np.concatenate([pieces[j][:-1] for j in todo]),
                                np.concatenate([pieces[j][1:] for j in todo]))
        bad = np.split((err > tol) | (lab > max_step),
                       np.cumsum([len(pieces[j]) - 1 for j in todo])[:-1])
        for j, b in zip(todo, bad, strict=True):
            if b.any():
                us = pieces[j]
                pieces[j] = np.sort(np.concatenate([us, 0.5 * (us[:-1] + us[1:])[b]]))
        todo = [j for j, b in zip(todo, bad, strict=True) if b.any()]
        if not todo:
            break
    else:
        raise CaseError(f"the {curve.name} profile cannot be sampled to {tol * 1e6:.3g} um")
    return np.concatenate([us[:-1] for us in pieces])


def sample_polygon(curve, tol: float) -> np.ndarray:
    """A closed polyline (vertices on the curve, first not repeated) to chord error tol."""
    return curve.point(sample(curve, tol))


# ------------------------------------------------------------------ closest points
def closest(curve, x, u0, iterations: int = 8):
    """Foot points on the curve of points x (m, 2), starting from parameters u0.

    Newton on (p(u) - x) . p'(u) = 0 with the Gauss-Newton slope |p'|^2; every iterate
    is a point of the curve, so the distance returned is an upper bound of the true
    one and tight once converged.  Returns (u, distance, signed distance) with the sign
    positive outside the enclosed region.
    """
    u = np.array(u0, dtype=float)
    p = curve.point(u)
    dist = np.linalg.norm(p - x, axis=-1)
    for _ in range(iterations):
        d = curve.derivative(u)
        step = np.sum((p - x) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300)
        step = np.clip(step, -0.05, 0.05)  # never more than 1/20 of a piece at once
        # Backtrack: keep a step only where it brings the point closer (the slope
        # vanishes at the sigma_bar = 1 point, where a full step overshoots).
        for _ in range(6):
            un = u - step
            pn = curve.point(un)
            dn = np.linalg.norm(pn - x, axis=-1)
            better = dn <= dist
            u = np.where(better, un, u)
            p = np.where(better[..., None], pn, p)
            dist = np.where(better, dn, dist)
            step = np.where(better, 0.0, 0.5 * step)
            if not step.any():
                break
    r = x - p
    dist = np.linalg.norm(r, axis=-1)
    sign = np.sign(np.sum(r * curve.normal(u), -1))
    return np.mod(u, curve.n), dist, np.where(sign == 0, 1.0, sign) * dist
