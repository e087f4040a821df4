"""Where the twin-screw rotors touch: the contact on the male at any male angle.

A mixin of :class:`.pair.TwinScrewPair` (it needs the pair's gearing, male profile and
period).  Where the male's pieces give their rolling angles (the male angle at which
each point is in contact: rack-generated arcs, the pin-cycloid's arcs and epicycloids)
the contact at angle psi is where that angle is psi, or a corner the contact rests on;
elsewhere a root of the law of gearing (the male's normal through the pitch point).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
from scipy.optimize import brentq

from ..planar import cross, rotate

#: Half-width (in profile parameter) of the window in which a contact is sought around
#: its polygon estimate: a few polygon edges.
CONTACT_WINDOW = 0.02
#: Points of that window on which the law of gearing is bracketed.
CONTACT_GRID = 17
#: Step in the profile parameter for the law of gearing's slope (central difference of
#: analytic curves: 1e-6 of a piece leaves ~1e-10 relative error).
LAW_STEP = 1e-6
#: Parameter tolerance of a contact: 1e-13 of a piece is far below a nanometre.
CONTACT_XTOL = 1e-13
#: A root of the law of gearing leaves at most this residual (per C): the law's slope
#: is ~C per unit parameter, so CONTACT_XTOL leaves ~1e-13; a bracket closed on a jump
#: of the law (a cusp's normal flip) leaves the jump, ~1e-4 and more.
ROOT_RESIDUAL = 1e-9
#: Rolling angles within this (rad) are one: a band's points (closed forms agree to
#: ~1e-15), psi and a band's instant, psi and the ends of a corner's rest.  Far below
#: a table step (1e-2) and far above rounding.
ROLLING_TOL = 1e-6
#: Points per piece on which its rolling angle is bracketed (monotone on the pieces
#: seen; a few more guard a turning one).
ROLLING_SCAN = 9
#: Either side of a jump of the law, this far (in profile parameter) ...
CORNER_STEP = 1e-9
#: ... the normals of a cusp are opposite (cos -1); a corner's turn by less than
#: ~170 deg is a corner.
CUSP_COS = -0.985
#: A contact within CORNER_STEP of a joint whose normals either side turn by more than
#: this (rad) rests on a corner (closed forms join smooth pieces to ~1e-12).
CORNER_TURN = 1e-6


def _illinois(f, a, b, fa, fb, iterations: int = 60) -> float:
    """A root of f in [a, b] (f(a), f(b) of opposite signs): regula falsi with the
    Illinois modification (superlinear, never leaves the bracket)."""
    side = 0
    c = a
    for _ in range(iterations):
        c = (a * fb - b * fa) / (fb - fa)
        fc = float(f(c)[0])
        if fc == 0.0 or abs(b - a) < CONTACT_XTOL:
            break
        if np.sign(fc) == np.sign(fb):
            b, fb = c, fc
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb *= 0.5
            side = 1
        if abs(b - a) < CONTACT_XTOL:
            break
    return float(c)


def _offset_rolling(t: float, piece, target: float) -> float:
    return float(np.asarray(piece.rolling_angle(np.array([t])))[0]) - target


class ContactSearch:
    """The contact-finding methods of :class:`.pair.TwinScrewPair`."""

    def _law(self, u, psi: float):
        """The law of gearing on the male at parameters u, male angle psi: the cross
        product of the normal with the way to the pitch point (zero at a contact)."""
        male = self.male
        u = np.mod(np.atleast_1d(u), male.n)
        pitch = rotate(self.gearing.pitch_point[None, :], -psi)[0]
        return cross(male.normal(u), pitch - male.point(u))

    def _root(self, lo: float, hi: float, near: float, psi: float) -> float | None:
        """The contact on the male in [lo, hi] (profile parameter) nearest ``near`` at
        male angle psi (None if it has none there).

        Where the pieces give their rolling angles the contact is where that angle is
        psi (:meth:`_rolling_roots`), or a corner the contact rests on.  Elsewhere it is
        a root of the law of gearing, which is weaker near a cusp: there the normals of
        nearby points also pass through the pitch point (the evolute is near) and
        zeros come in close pairs that a coarse bracket misses."""
        found, known = self._rolling_roots(lo, hi, psi)
        if not known:
            found += self._law_roots(lo, hi, psi)
        if not found:
            return None
        return float(np.mod(min(found, key=lambda u: abs(u - near)), self.male.n))

    def _rolling_roots(self, lo: float, hi: float, psi: float) -> tuple[list, bool]:
        """(contacts in [lo, hi] by the pieces' rolling angles, whether every piece
        there gives one)."""
        male, per = self.male, len(self.male.pieces)
        found, known = [], True
        for j in range(math.floor(lo), math.ceil(hi)):
            a, b = max(lo, j), min(hi, j + 1)
            if b <= a:
                continue
            piece = male.pieces[j % per]
            t = np.linspace(a - j, b - j, ROLLING_SCAN)
            r = np.asarray(piece.rolling_angle(t), dtype=float)
            if not np.all(np.isfinite(r)):
                known = False
                continue
            if np.ptp(r) <= ROLLING_TOL:
                # A band: at its instant every point of it touches (the one nearest
                # the middle of [lo, hi] stands for it), else none does.
                if abs(math.remainder(r[0] - psi, self.period)) <= ROLLING_TOL:
                    found.append(float(np.clip(0.5 * (lo + hi), a, b)))
                continue
            # psi's images within a period of the piece's angles (its span < a period).
            base = r[0] + math.remainder(psi - r[0], self.period)
            for target in (base - self.period, base, base + self.period):
                g = r - target
                for i in np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]:
                    found.append(j + brentq(_offset_rolling, t[i], t[i + 1],
                                            args=(piece, target), xtol=CONTACT_XTOL))
                found.extend(j + t[np.nonzero(g == 0.0)[0]])
        for k in range(math.ceil(lo), math.floor(hi) + 1):
            if self._rests(float(k), psi, strict=True):
                found.append(float(k))
        return found, known

    def _law_roots(self, lo: float, hi: float, psi: float) -> list:
        """Roots of the law of gearing in [lo, hi], where the pieces give no rolling
        angle."""
        grid = np.linspace(lo, hi, CONTACT_GRID)
        # The law jumps at the joints between pieces (the normal turns there): each joint
        # gets its own bracket, so that a zero just beside it is not cancelled by it.
        joints = np.arange(math.ceil(lo), math.floor(hi) + 1, dtype=float)
        grid = np.unique(np.concatenate([grid, joints - CORNER_STEP, joints + CORNER_STEP]))
        grid = grid[(grid >= lo) & (grid <= hi)]
        vals = self._law(grid, psi)
        sign = np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0]
        law = lambda u: self._law(u, psi)  # noqa: E731
        out = []
        # The law also changes sign where the male's normal jumps.  At a corner that is
        # a contact: the corner seals while the normal's turn there sweeps through the
        # pitch point.  At a cusp the normal flips and the sign change is none.
        for j in sign:
            u = _illinois(law, grid[j], grid[j + 1], vals[j], vals[j + 1])
            if abs(float(law(u)[0])) <= ROOT_RESIDUAL * self.gearing.centre_distance:
                out.append(u)
                continue
            side = self.male.normal(np.mod(np.array([u - CORNER_STEP, u + CORNER_STEP]),
                                           self.male.n))
            if float(side[0] @ side[1]) > CUSP_COS:
                out.append(u)
        return out

    def _rolling(self, u: float) -> float:
        """The rolling angle of male point u (its piece's; NaN where it gives none)."""
        male = self.male
        v = float(np.mod(u, male.n))
        j = min(int(np.floor(v)), male.n - 1)
        k = j % len(male.pieces)
        return float(np.asarray(male.pieces[k].rolling_angle(np.array([v - j])))[0])

    def _rests(self, u: float, psi: float, strict: bool = False) -> bool:
        """Whether the contact rests on the male corner u at angle psi: strictly between
        the instants the pieces either side mesh their ends there (where those differ;
        the ends themselves are the pieces' contacts)."""
        a, b = self._rolling(u - CORNER_STEP), self._rolling(u + CORNER_STEP)
        if not (math.isfinite(a) and math.isfinite(b)):
            return not strict
        span = math.remainder(b - a, self.period)
        if strict and abs(span) <= ROLLING_TOL:
            return False
        x = math.remainder(psi - a, self.period)
        lo, hi = min(0.0, span), max(0.0, span)
        return lo - ROLLING_TOL <= x <= hi + ROLLING_TOL

    def contact_near(self, x, psi: float) -> tuple[np.ndarray, np.ndarray]:
        """(point, d point / d psi) of the contact of the rotors near ``x`` at male
        angle ``psi`` (fixed frame).

        At a contact the male's normal passes through the pitch point (the law of
        gearing), which holds for every conjugate arc whatever generated it; the root
        is sought on the male profile around the sampled point nearest ``x``.
        """
        local = rotate(np.asarray(x, dtype=float)[None, :], -psi)[0]
        u_grid, p_grid = self._foot_grid
        i = int(np.argmin(np.linalg.norm(p_grid - local, axis=-1)))
        u0 = float(u_grid[i])
        # The grid is sampled by chord error: on a gentle arc its points lie far apart
        # (0.042 of a piece on the pin-cycloid's flank), and the foot of x may be half
        # that from the nearest, beyond the window; the window spans the grid's
        # neighbours (the search missed a contact 14 um from x there at 384 points per
        # period, which shortened an interlobe line).
        n = len(u_grid)
        below = u_grid[i - 1] - (self.male.n if i == 0 else 0.0)
        above = u_grid[(i + 1) % n] + (self.male.n if i == n - 1 else 0.0)
        u = self._root(min(u0 - CONTACT_WINDOW, below), max(u0 + CONTACT_WINDOW, above),
                       u0, psi)
        if u is None:
            # No contact here: keep the polygon's corner, moving with neither rotor.
            return np.asarray(x, dtype=float), np.zeros(2)
        return self._contact_at(u, psi)

    def contact_between(self, u_poly, lo: int, hi: int, psi: float
                        ) -> tuple[np.ndarray, np.ndarray]:
        """(point, d point / d psi) of the contact on the male between polygon vertices
        ``lo`` and ``hi`` (indices into ``u_poly``, running up from lo to hi, around the
        closed profile): the root of the law of gearing nearest the middle."""
        male = self.male
        ulo = float(u_poly[lo])
        uhi = float(u_poly[hi]) + (male.n if hi < lo else 0.0)
        mid = 0.5 * (ulo + uhi)
        u = self._root(ulo, uhi, mid, psi)
        if u is None:
            # Just off a band's instant the lens can lie along the band's arc while the
            # contact has passed onto the next piece, beyond the lens's end (the
            # pin-cycloid's pin arc and the female corner D1): look a window further.
            u = self._root(ulo - CONTACT_WINDOW, uhi + CONTACT_WINDOW, mid, psi)
        if u is None:
            # No root in the lens (a conformal band at its tangency): its middle, with
            # no rate of its own (the band is not a sealing point that moves).
            return rotate(male.point(np.array([np.mod(mid, male.n)])), psi)[0], np.zeros(2)
        return self._contact_at(u, psi)

    def _contact_at(self, u: float, psi: float):
        """(point, d point / d psi) of the contact at male parameter u, fixed frame.

        The contact moves along the male as the rotors turn: law(u, psi) = 0 gives
        du/dpsi = -law_psi / law_u (implicit function), and the point R(psi) p(u)
        moves by J R p + R p' du/dpsi.  The sealing lines need this rate (a contact runs
        fast near the cusps, where differences between table nodes would blur it).
        """
        male = self.male
        h = LAW_STEP
        # (u and the law's two points in one evaluation of each: a profile's call costs
        # ~0.2 ms, whatever its length)
        uu = np.mod(np.array([u, u + h, u - h]), male.n)
        pts, ds = male.point(uu), male.derivative(uu)
        p, d = pts[0], ds[0]
        ns = np.stack([ds[:, 1], -ds[:, 0]], -1)  # as PieceCurve.normal
        ns = ns / np.linalg.norm(ns, axis=-1)[:, None]
        n = ns[0]
        pitch = rotate(self.gearing.pitch_point[None, :], -psi)[0]
        dpitch = np.array([pitch[1], -pitch[0]])  # d/dpsi of R(-psi) P
        law = cross(ns[1:], pitch - pts[1:])  # as _law
        law_u = float(law[0] - law[1]) / (2.0 * h)
        law_psi = float(cross(n, dpitch))
        du = -law_psi / law_u if law_u != 0.0 else 0.0
        if self._on_corner(u) and self._rests(float(round(u)), psi):
            # Resting on a corner the contact turns with the male; the difference
            # across the corner is the law's jump there, not its slope, and left a
            # rate 2e-5 off on the trochoidal's land corners (their interlobe lines
            # then converged at first order: 8e-7 of the line at 192 points per
            # period, halving with the step).
            du = 0.0
        point = rotate(p[None, :], psi)[0]
        rate = np.array([-point[1], point[0]]) + rotate((d * du)[None, :], psi)[0]
        return point, rate

    def _on_corner(self, u: float) -> bool:
        """Whether male parameter u lies at a joint where the profile turns (a corner),
        within CORNER_STEP.  (Whether the contact rests there at an angle is
        :meth:`_rests`'s: a corner a contact passes at one instant has the rate of the
        piece it moves on.)"""
        k = round(u)
        if abs(u - k) > CORNER_STEP:
            return False
        side = self.male.normal(np.mod(np.array([k - CORNER_STEP, k + CORNER_STEP]),
                                       self.male.n))
        return abs(math.atan2(cross(side[0], side[1]), float(side[0] @ side[1]))) > CORNER_TURN

    @cached_property
    def _foot_grid(self):
        from ..curves import sample

        u = sample(self.male, 1e-5 * self.gearing.centre_distance)
        return u, self.male.point(u)
