"""Clearance offsets of rotor profiles.

A clearance is a true normal offset ``q(u) = p(u) + d c(u) n(u)`` (``n`` the outward
unit normal, ``d = +1`` grows the region, ``-1`` shrinks it) with ``c`` uniform or a
smooth periodic distribution along each lobe: the set of points at the clearance from
the profile on one side.  It is valid when ``1 + d c kappa > 0`` everywhere (no fold)
and the offset polygon is simple.

At a sharp corner of the profile (pieces meeting at an angle) the offset needs more
than each piece moved along its normal (:mod:`.offset_corners`): where the pieces'
offsets cross (the corner on the offset's inside) each is cut at the crossing
(``trims``); where they part (the corner on its outside) the offset goes round the
corner on the clearance's circular arc (``arcs``, a piece more in the offset's chain).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rotorflow.errors import CaseError

from .curves import PREGRID, PieceCurve, gauss_rule, piece_difference
from .offset_corners import END, corner_cuts
from .planar import cross, rotate
from .spline import CubicSpline


@dataclass(frozen=True)
class Clearance:
    """A clearance distribution along each lobe of a profile (metres).

    ``values`` at equally spaced lobe fractions (by arc length, from the lobe's
    reference point), joined by a periodic cubic spline; one value is uniform.
    """

    values: tuple[float, ...]

    @property
    def uniform(self) -> bool:
        return len(self.values) == 1 or len(set(self.values)) == 1

    @property
    def largest(self) -> float:
        return max(self.values)

    @cached_property
    def _spline(self):
        v = np.asarray(self.values, dtype=float)
        x = np.linspace(0.0, 1.0, len(v) + 1)
        return CubicSpline(x, np.append(v, v[0]), bc_type="periodic")

    def __call__(self, fraction):
        if self.uniform:
            return np.full(np.shape(fraction), float(self.values[0]))
        return self._spline(np.mod(fraction, 1.0))


@dataclass(frozen=True)
class OffsetProfile:
    """``base`` moved along its outward normal by ``direction * c(u)``.

    With ``trims`` (per base piece, its local range (lo, hi) kept: cut at corners) piece
    j's own t maps to the base's lo + (hi - lo) t.  With ``arcs`` (per base piece, the
    tangent's turn at its start where the offset goes round that corner, else 0) the
    chain holds an arc piece before each such piece: the corner's point, its normal
    turned from the previous piece's end normal by the turn times t."""

    base: PieceCurve
    clearance: Clearance
    direction: int  # +1 grows the enclosed region, -1 shrinks it
    trims: tuple[tuple[float, float], ...] | None = None
    arcs: tuple[float, ...] | None = None

    @cached_property
    def _chain(self):
        """Per own piece: its base piece, whether it is an arc, and the turn (rad)."""
        if self.arcs is None:
            j = np.arange(self.base.n)
            return j, np.zeros(len(j), dtype=bool), np.zeros(len(j))
        ref, arc = [], []
        for j, turn in enumerate(self.arcs):
            if turn:
                ref.append(j)
                arc.append(True)
            ref.append(j)
            arc.append(False)
        ref = np.array(ref)
        return ref, np.array(arc), np.where(arc, np.asarray(self.arcs)[ref], 0.0)

    @cached_property
    def _ranges(self):
        lo, hi = (np.zeros(self.base.n), np.ones(self.base.n)) if self.trims is None \
            else np.asarray(self.trims).T
        return lo, hi

    @cached_property
    def _arc_normals(self):
        """Per base piece: the normal at the end of the piece before it (an arc's start)."""
        j = np.arange(self.base.n)
        return self.base.normal((j - 1) % self.base.n + END)

    def _split(self, u):
        return PieceCurve._split(self, u)

    def _pieces(self, u):
        """(own piece, local t, base piece, arc?, turn) at own parameters u."""
        i, t = self._split(u)
        ref, arc, turn = self._chain
        return i, t, ref[i], arc[i], turn[i]

    def base_param(self, u):
        """(the base's parameter at the offset's u, d(base u) / du): the trimmed range;
        on an arc its corner, which stays put (0)."""
        if self.trims is None and self.arcs is None:
            return np.asarray(u, dtype=float), 1.0
        _, t, j, arc, _ = self._pieces(u)
        lo, hi = self._ranges
        k = np.where(arc, 0.0, hi[j] - lo[j])
        return j + np.where(arc, 0.0, lo[j] + k * t), k

    def own_param(self, bu):
        """The offset's own u at base parameters ``bu``: the point offset from base point
        bu, on its piece's offset (clipped to the range kept: beyond a cut corner the
        cut's end)."""
        if self.trims is None and self.arcs is None:
            return np.asarray(bu, dtype=float)
        j, t = self.base._split(bu)
        lo, hi = self._ranges
        ref, arc, _ = self._chain
        own = np.nonzero(~arc)[0]  # own piece of each base piece, in order
        return own[j] + np.clip((t - lo[j]) / (hi[j] - lo[j]), 0.0, END)

    @property
    def name(self):
        return self.base.name

    @property
    def n(self):
        return len(self._chain[0])

    @property
    def lobes(self):
        return self.base.lobes

    @property
    def material_inside(self):
        return self.base.material_inside

    def offset(self, u):
        return self.direction * self.clearance(self.lobe_fraction(u))

    def point(self, u):
        bu, _ = self.base_param(u)
        return self.base.point(bu) + self.offset(u)[..., None] * self.normal(u)

    def derivative(self, u):
        if self.clearance.uniform:
            # d/du (c n) = c kappa p' = c (kappa |p'|) t: finite where |p'| vanishes.
            bu, k = self.base_param(u)
            d = self.base.derivative(bu)
            t = d / np.maximum(np.linalg.norm(d, axis=-1), 1e-300)[..., None]
            out = d + (self.offset(u) * self.base.turning_rate(bu))[..., None] * t
            out = out * np.asarray(k)[..., None]
            if self.arcs is None:
                return out
            # on an arc the normal turns at d(angle)/du = turn: q' = c turn J n
            _, _, _, arc, turn = self._pieces(u)
            nrm = self.normal(u)
            jn = np.stack([-nrm[..., 1], nrm[..., 0]], -1)
            return np.where(arc[..., None], (self.offset(u) * turn)[..., None] * jn, out)
        return piece_difference(self, self.point, u, 1e-6)

    def normal(self, u):
        """The offset's direction: the base's normal, turning round a corner on an arc."""
        nb = self.base.normal(self.base_param(u)[0])
        if self.arcs is None:
            return nb
        _, t, j, arc, turn = self._pieces(u)
        return np.where(arc[..., None], rotate(self._arc_normals[j], turn * t), nb)

    # (in-piece differences and curvature as a chain of pieces has them)
    second_derivative = PieceCurve.second_derivative
    curvature = PieceCurve.curvature

    def integrate(self, f) -> float:
        """\\oint f(u) du over the offset's own pieces (Gauss-Legendre panels)."""
        if self.arcs is None:
            return self.base.integrate(f)
        u, w = self._gauss
        return float(np.sum(f(u) * w))

    @cached_property
    def _gauss(self):
        return gauss_rule(self.n)

    @cached_property
    def moments(self) -> tuple[float, float]:
        """(\\oint c ds, 1/2 \\oint c^2 kappa ds) along the base profile.

        The offset of ``s p`` (the base scaled by s, the offset not) encloses
        ``s^2 A + d s M1 + M2``: exact for a regular offset (uniform c: c P, pi c^2).
        With corners, M2 is what makes the sum the offset's own area (Green's theorem
        along it): a cut corner's c^2 tan(turn / 2) replaces the regular formula's share,
        an arc's sector c^2 turn / 2 is that share; exact at s = 1, and to O(c^3 kappa)
        on a scaled section where corners are cut.
        """
        b = self.base
        if self.trims is not None or self.arcs is not None:
            m1 = self._first_moment()
            own = 0.5 * self.integrate(lambda u: cross(self.point(u), self.derivative(u)))
            return m1, own - b.area - self.direction * m1
        if self.clearance.uniform:
            c = self.clearance.values[0]
            return c * b.length, math.pi * c * c

        def second(u):
            return self.clearance(b.lobe_fraction(u)) ** 2 * b.turning_rate(u)

        return self._first_moment(), 0.5 * b.integrate(second)

    def _first_moment(self) -> float:
        """\\oint c ds along the whole base profile."""
        b = self.base
        if self.clearance.uniform:
            return self.clearance.values[0] * b.length
        return b.integrate(lambda u: self.clearance(b.lobe_fraction(u))
                           * np.linalg.norm(b.derivative(u), axis=-1))

    @cached_property
    def area(self) -> float:
        """A + d \\oint c ds + 1/2 \\oint c^2 kappa ds (exact for a regular offset)."""
        m1, m2 = self.moments
        return self.base.area + self.direction * m1 + m2

    @cached_property
    def length(self) -> float:
        return self.integrate(lambda u: np.linalg.norm(self.derivative(u), axis=-1))

    def lobe_fraction(self, u):
        return self.base.lobe_fraction(self.base_param(u)[0])

    @cached_property
    def radius_max(self) -> float:
        return self.base.radius_max + max(0.0, self.direction * self.clearance.largest)


def region_volume(curve, sweep) -> float:
    """Volume enclosed by the swept ``curve`` between z = 0 and L (analytic)."""
    i2 = sweep.scale_squared_integral
    if not isinstance(curve, OffsetProfile):
        return curve.area * i2
    i1 = 0.5 * sweep.length * (1.0 + sweep.scale_end)
    m1, m2 = curve.moments
    return curve.base.area * i2 + curve.direction * m1 * i1 + m2 * sweep.length


def offset_profile(base: PieceCurve, clearance: Clearance, direction: int):
    """The clearance offset of ``base``, checked for folds; ``base`` if c = 0."""
    if clearance.largest == 0.0 and min(clearance.values) == 0.0:
        return base
    if min(clearance.values) < 0.0:
        raise CaseError(f"clearance on the {base.name} rotor must not be negative")
    off = OffsetProfile(base, clearance, direction)
    # A fold appears where 1 + d c kappa <= 0: check on every piece's dense pre-grid and
    # around the sharpest point found (the inner profile at sigma_bar = 1 has a point of
    # infinite curvature that no grid lands on exactly).
    u = (np.arange(base.n)[:, None] + np.linspace(0.0, 1.0, 4 * PREGRID)[None, :]).ravel()
    u = np.minimum(u, base.n - 1e-12)
    kappa = base.curvature(u)
    worst = int(np.argmin(1.0 + off.offset(u) * kappa))
    h = 1.0 / (4 * PREGRID)
    fine = np.clip(u[worst] + np.linspace(-h, h, 2001), 0.0, base.n - 1e-12)
    kf = base.curvature(fine)
    fold = 1.0 + off.offset(fine) * kf
    i = int(np.argmin(fold))
    if not fold[i] > 0.0:
        radius = 1.0 / abs(kf[i]) if kf[i] != 0 else math.inf
        p = base.point(fine[i])
        raise CaseError(
            f"a clearance of {abs(off.offset(fine[i])) * 1e6:.3g} um on the {base.name} rotor "
            f"folds its profile: its radius of curvature there is {radius * 1e6:.3g} um, at "
            f"({p[0] * 1e3:.3f}, {p[1] * 1e3:.3f}) mm"
            + ("; apply the clearance to the outer rotor" if base.material_inside else "")
        )
    trims, arcs = corner_cuts(off)
    return dataclasses.replace(off, trims=trims, arcs=arcs)
