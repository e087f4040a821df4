"""The envelope meshing condition: secondary arcs from primary arcs (seed 003, Eqs. 1-5).

Frames (all lengths in metres, angles in radians):

* fixed frame: the male axis O1 at the origin, the female axis O2 at (C, 0); the pitch
  point P = (r1, 0), with pitch radii r1 = C N1 / (N1 + N2), r2 = C N2 / (N1 + N2).
* the male turns counter-clockwise by theta; the female clockwise by theta r1 / r2
  (external gearing, speed ratio -N1 / N2).
* the rack frame: (a, b), ``a`` across the pitch line (positive towards the female),
  ``b`` along it.  A rack shifted by s has its point (a, b) at (r1 + a, b + s) in the
  fixed frame; rolling without slip on both pitch circles means theta = s / r1.

The meshing condition says that at a contact the common normal passes through P.  For a
rack point q = (a, b) with tangent q' = (a', b') that fixes the shift directly
(seed 003 Eq. 5, "the rack meshing condition can be solved directly"):
s = -b - a a' / b'; the generated points follow from Eq. 4 (male) and its female
analogue.  For a primary arc on the male, the rotation phi with the normal through P
solves r1 |n| cos(phi - delta) = q x n (Eq. 1 in this frame); the mate follows by Eq. 2.

Every generated arc here is evaluated in closed form, point and tangent, so a profile
can be sampled to any tolerance and measured against the true curve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rotorflow.errors import CaseError

from ..planar import cross, rotate
from .arcs import jets

#: A rack tangent within this fraction of perpendicular to the pitch line has no finite
#: contact shift (its normal runs parallel to the pitch line): below 1e-9 the shift
#: would be larger than 1e9 rack heights, i.e. the arc does not mesh there.
PERPENDICULAR_TOL = 1e-9
#: A generated arc whose speed along the primary tangent falls below -1e-9 of the
#: primary arc's own speed runs backwards (undercut, a cusp): the terms are closed forms
#: exact to ~1e-14, so anything below 1e-9 is the curve, not rounding.
UNDERCUT_TOL = 1e-9
#: Points per arc on which the generated speed is checked for a sign change; an
#: undercut narrower than 1/4096 of an arc is below any manufacturing tolerance.
CHECK_POINTS = 4097


def _perp(v):
    """v turned by +90 degrees."""
    return np.stack([-v[..., 1], v[..., 0]], -1)


def _along(t, reverse: bool) -> np.ndarray:
    """The primary arc's parameter at profile parameter t (a reversed piece runs the arc
    from its end)."""
    t = np.asarray(t, dtype=float)
    return 1.0 - t if reverse else t


@dataclass(frozen=True)
class Gearing:
    """Centre distance and lobe combination of an external (twin-screw) pair."""

    centre_distance: float
    lobes_male: int
    lobes_female: int

    def __post_init__(self):
        if not (self.lobes_male >= 1 and self.lobes_female >= 1):
            raise CaseError(f"lobe counts must be positive, got "
                            f"{self.lobes_male}/{self.lobes_female}")
        if not self.centre_distance > 0.0:
            raise CaseError(f"the centre distance must be positive, got {self.centre_distance}")

    @property
    def r1(self) -> float:
        return self.centre_distance * self.lobes_male / (self.lobes_male + self.lobes_female)

    @property
    def r2(self) -> float:
        return self.centre_distance * self.lobes_female / (self.lobes_male + self.lobes_female)

    @property
    def pitch(self) -> float:
        """The rack period: one lobe of either rotor along its pitch circle."""
        return 2.0 * math.pi * self.r1 / self.lobes_male

    @property
    def pitch_point(self) -> np.ndarray:
        return np.array([self.r1, 0.0])

    @property
    def female_axis(self) -> np.ndarray:
        return np.array([self.centre_distance, 0.0])


# ------------------------------------------------------------------ rack -> rotors
def rack_shift(arc, t):
    """(s, ds/dt): the rack shift at which rack point t of ``arc`` is in contact (Eq. 5)."""
    return _rack_contact(arc, t)[:2]


def _rack_contact(arc, t):
    """(s, ds/dt, rack point, its tangent): :func:`rack_shift` with the arc's point and
    first derivative it was found from (a generated arc needs them too)."""
    q, q1, q2 = jets(arc, t)
    a, b = q[..., 0], q[..., 1]
    da, db = q1[..., 0], q1[..., 1]
    dda, ddb = q2[..., 0], q2[..., 1]
    speed = np.hypot(da, db)
    bad = np.abs(db) <= PERPENDICULAR_TOL * speed
    if np.any(bad):
        tb = np.broadcast_to(np.asarray(t, dtype=float), bad.shape)[bad].ravel()[0]
        raise CaseError(f"rack arc '{arc.name}' is perpendicular to the pitch line at "
                        f"t = {tb:.4g}: its normal never passes through the pitch point")
    s = -b - a * da / db
    ds = -db - (da * da + a * dda) / db + a * da * ddb / (db * db)
    return s, ds, q, q1


@dataclass(frozen=True)
class RackGenerated:
    """The arc that rack arc ``arc`` generates on ``rotor`` ("male" or "female"), in
    that rotor's frame; ``reverse`` runs it from the arc's end to its start."""

    arc: object
    gearing: Gearing
    rotor: str
    reverse: bool = False

    @property
    def name(self) -> str:
        return f"{self.rotor} arc generated by rack arc '{self.arc.name}'"

    def eval(self, t, order: int = 0):
        tt = _along(t, self.reverse)
        g = self.gearing
        s, ds, q, q1 = _rack_contact(self.arc, tt)
        x = np.stack([g.r1 + q[..., 0], q[..., 1] + s], -1)
        if self.rotor == "male":
            ang, rate, x0 = -s / g.r1, -ds / g.r1, x
        else:
            ang, rate, x0 = s / g.r2, ds / g.r2, x - g.female_axis
        if order == 0:
            return rotate(x0, ang)
        dx = np.stack([q1[..., 0], q1[..., 1] + ds], -1)
        d = rotate(dx, ang) + rate[..., None] * _perp(rotate(x0, ang))
        return -d if self.reverse else d

    def primary_tangent(self, t):
        """The primary arc's tangent carried into the rotor frame at the contact."""
        tt = _along(t, self.reverse)
        s, _ = rack_shift(self.arc, tt)
        ang = -s / self.gearing.r1 if self.rotor == "male" else s / self.gearing.r2
        d = rotate(self.arc.eval(tt, 1), ang)
        return -d if self.reverse else d

    def rolling_angle(self, t):
        """The male rotation angle at which the point of parameter t is in contact."""
        tt = _along(t, self.reverse)
        return rack_shift(self.arc, tt)[0] / self.gearing.r1


# ------------------------------------------------------------------ male arc -> female
@dataclass(frozen=True)
class OnRotor:
    """A primary arc given on a rotor itself (in its frame), as a profile piece."""

    arc: object
    rotor: str
    reverse: bool = False
    #: Given for a male arc, the male angle at which each of its points is in contact
    #: (:meth:`rolling_angle`) is known, and the contact's joints and bands with it.
    gearing: Gearing | None = None

    @property
    def name(self) -> str:
        return f"{self.rotor} primary arc '{self.arc.name}'"

    def eval(self, t, order: int = 0):
        d = self.arc.eval(_along(t, self.reverse), order)
        return -d if (self.reverse and order == 1) else d

    def primary_tangent(self, t):
        return self.eval(t, 1)

    def rolling_angle(self, t):
        """The male angle at which the point of parameter t is in contact: the meshing
        condition's root that brings the arc's middle nearer the pitch point (as for the
        female arc it generates, :class:`MaleGenerated`); NaN on a female arc, or a male
        one given no gearing (its contact's joints are then not located)."""
        if self.rotor != "male" or self.gearing is None:
            return np.full(np.shape(t), np.nan)
        try:
            return self._conjugate.rolling_angle(t)
        except CaseError:  # a normal that misses the pitch circle: no contact there
            return np.full(np.shape(t), np.nan)

    @cached_property
    def _conjugate(self) -> MaleGenerated:
        # (kept: its meshing branch costs three times a rolling angle, and the contact
        # search asks for thousands)
        return MaleGenerated(self.arc, self.gearing, self.reverse)


@dataclass(frozen=True)
class MaleGenerated:
    """The female arc conjugate to male primary arc ``arc`` (gear meshing condition,
    seed 003 Eqs. 1-2), in the female frame."""

    arc: object
    gearing: Gearing
    reverse: bool = False

    @property
    def name(self) -> str:
        return f"female arc generated by male arc '{self.arc.name}'"

    @cached_property
    def branch(self) -> float:
        """Which root of the meshing condition: the one that brings the arc's middle
        point nearer to the pitch point (the other is a contact the rotors never reach
        from the working side)."""
        q = self.arc.eval(np.array([0.5]), 0)
        best = None
        for sign in (1.0, -1.0):
            phi = self._phi(np.array([0.5]), sign)
            dist = float(np.linalg.norm(rotate(q, phi) - self.gearing.pitch_point))
            best = (dist, sign) if best is None or dist < best[0] else best
        return best[1]

    def _phi(self, t, sign):
        q, q1 = self.arc.eval(t, 0), self.arc.eval(t, 1)
        n = np.stack([q1[..., 1], -q1[..., 0]], -1)
        m = np.linalg.norm(n, axis=-1)
        c = cross(q, n) / (self.gearing.r1 * m)
        if np.any(np.abs(c) > 1.0):
            tb = np.broadcast_to(t, c.shape)[np.abs(c) > 1.0].ravel()[0]
            raise CaseError(f"male arc '{self.arc.name}' has no contact at t = {tb:.4g}: "
                            f"its normal misses the male pitch circle")
        delta = np.arctan2(n[..., 0], n[..., 1])
        return delta + sign * np.arccos(np.clip(c, -1.0, 1.0))

    def rolling_angle(self, t):
        tt = _along(t, self.reverse)
        return self._phi(tt, self.branch)

    def eval(self, t, order: int = 0):
        tt = _along(t, self.reverse)
        g = self.gearing
        phi = self._phi(tt, self.branch)
        psi = phi * g.r1 / g.r2
        q = self.arc.eval(tt, 0)
        w = rotate(q, phi) - g.female_axis
        if order == 0:
            return rotate(w, psi)
        q1, q2 = self.arc.eval(tt, 1), self.arc.eval(tt, 2)
        n, dn = np.stack([q1[..., 1], -q1[..., 0]], -1), np.stack([q2[..., 1], -q2[..., 0]], -1)
        pp = g.r1 * np.stack([np.cos(phi), -np.sin(phi)], -1)  # P in the turned male frame
        f_t = np.sum(q1 * q1, -1) + cross(pp - q, dn)
        f_phi = cross(g.r1 * np.stack([-np.sin(phi), -np.cos(phi)], -1), n)
        dphi = -f_t / f_phi
        dw = rotate(q1, phi) + dphi[..., None] * _perp(rotate(q, phi))
        d = rotate(dw, psi) + (dphi * g.r1 / g.r2)[..., None] * _perp(rotate(w, psi))
        return -d if self.reverse else d

    def primary_tangent(self, t):
        tt = _along(t, self.reverse)
        phi = self._phi(tt, self.branch)
        d = rotate(rotate(self.arc.eval(tt, 1), phi), phi * self.gearing.r1 / self.gearing.r2)
        return -d if self.reverse else d


def check_no_undercut(piece) -> None:
    """Raise CaseError naming the arc, its parameter and the rolling angle where the
    generated arc runs backwards along the primary tangent (an undercut: its speed
    changes sign, a cusp forms), instead of trimming it."""
    t = np.linspace(0.0, 1.0, CHECK_POINTS)
    d = piece.eval(t, 1)
    tan = piece.primary_tangent(t)
    speed = np.sum(d * tan, -1) / np.linalg.norm(tan, axis=-1)
    scale = np.linalg.norm(tan, axis=-1)
    bad = speed < -UNDERCUT_TOL * scale
    if bad.any():
        i = int(np.argmax(bad))
        # (within a turn: near a rack normal parallel to the pitch line the rolling angle
        # runs to thousands of degrees, which named nothing a user can find)
        angle = math.remainder(float(np.degrees(piece.rolling_angle(t[i:i + 1])[0])), 360.0)
        raise CaseError(f"undercut: the {piece.name} turns back (a cusp) at t = {t[i]:.4f}, "
                        f"male rolling angle {angle:.3f} deg")
