"""The pin-generated pair's two transverse profiles as chains of analytic pieces.

* outer rotor (frame S1, origin O1): per lobe k, pin k as a circle arc (pin angle from
  ``+pin_edge`` to ``-pin_edge``), then fillet k (conjugate: generation angle from
  ``g_hi`` to ``g_lo``; arc: the circle of :attr:`PinGerotor.arc_fillet`), both turned
  by ``2 pi k / N1``.  The region inside is fluid; outer-rotor material is outside.
* inner rotor (frame S2, origin O2): per lobe k, ``psi2(g)`` for g from ``-2 pi k`` to
  ``-2 pi (k + 1)`` (``psi2`` runs clockwise as g grows).  The region inside is material.

Every point is computed from the closed forms of :mod:`.pair`, so samples can be
placed to any chordal tolerance and distances measured to the true curve.  Pieces join
with continuous tangents (the conjugate fillet meets its pins tangentially; the inner
profile is analytic, with a G1 point of infinite curvature at sigma_bar = 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..curves import PieceCurve
from ..planar import TWO_PI, rotate
from .pair import PinGerotor

#: Relative step of the central differences used for fillet tangents and curvatures;
#: the fillet is analytic, so 1e-6 of the parameter span leaves ~1e-10 relative error.
FD_STEP = 1e-6
#: Nodes of the cubic Hermite table of the conjugate fillet (exact values and slopes at
#: the nodes): the fillet is analytic in g, so the table's error is ~1e-15 m (tested),
#: and it evaluates ~20x faster than the closed form, which matters for foot points.
FILLET_NODES = 4097

CODE_CIRCLE, CODE_INNER, CODE_FILLET = 0, 1, 2


@dataclass(frozen=True)
class Profile(PieceCurve):
    """A closed counter-clockwise chain of analytic pieces (lengths in metres)."""

    name: str
    pair: PinGerotor = field(repr=False)
    kind: np.ndarray = field(repr=False)  # (n,) CODE_*
    p0: np.ndarray = field(repr=False)  # native parameter at the piece start
    p1: np.ndarray = field(repr=False)  # ... and end
    rot: np.ndarray = field(repr=False)  # turn applied to the piece (fillets of lobe k)
    centre: np.ndarray = field(repr=False)  # (n, 2) circle centres (circle pieces)
    radius: np.ndarray = field(repr=False)  # circle radii (circle pieces)
    lobes: int = 1
    material_inside: bool = False

    @property
    def n(self) -> int:
        return len(self.kind)

    # -------------------------------------------------------------- evaluation
    def _split(self, u):
        u = np.mod(np.asarray(u, dtype=float), self.n)
        j = np.minimum(np.floor(u).astype(int), self.n - 1)
        return j, u - j

    def _eval(self, u, order: int):
        """Point (order 0) or d/du (order 1) at global parameter(s) u."""
        j, t = self._split(u)
        out = np.empty(t.shape + (2,))
        span = self.p1[j] - self.p0[j]
        par = self.p0[j] + t * span
        k = self.kind[j]
        m = k == CODE_CIRCLE
        if m.any():
            a, r, c = par[m], self.radius[j[m]], self.centre[j[m]]
            if order == 0:
                out[m] = c + r[:, None] * np.stack([np.cos(a), np.sin(a)], -1)
            else:
                out[m] = (r * span[m])[:, None] * np.stack([-np.sin(a), np.cos(a)], -1)
        m = k == CODE_INNER
        if m.any():
            g = par[m]
            if order == 0:
                out[m] = self.pair.inner_point(g)
            else:
                out[m] = self.pair.inner_derivative(g) * span[m][:, None]
        m = k == CODE_FILLET
        if m.any():
            g, rr = par[m], self.rot[j[m]]
            if order == 0:
                out[m] = rotate(self._fillet_hermite(g, 0), rr)
            else:
                out[m] = rotate(self._fillet_hermite(g, 1), rr) * span[m][:, None]
        return out

    @cached_property
    def _fillet_table(self):
        g_lo, g_hi = self.pair.fillet_range
        g = np.linspace(g_lo, g_hi, FILLET_NODES)
        h = FD_STEP * (g_hi - g_lo)
        f = self.pair.fillet(g)[1]
        df = (self.pair.fillet(g + h)[1] - self.pair.fillet(g - h)[1]) / (2.0 * h)
        return g_lo, (g_hi - g_lo) / (FILLET_NODES - 1), f, df

    def _fillet_hermite(self, g, order: int):
        """Fillet 0 point (order 0) or d/dg (order 1) from the cubic Hermite table."""
        return self._hermite(self._fillet_table, g, order)

    @staticmethod
    def _hermite(table, g, order: int):
        g0, dg, f, df = table
        x = (np.asarray(g, dtype=float) - g0) / dg
        i = np.clip(np.floor(x).astype(int), 0, len(f) - 2)
        t = (x - i)[:, None]
        p0, p1 = f[i], f[i + 1]
        m0, m1 = df[i] * dg, df[i + 1] * dg
        if order == 0:
            t2, t3 = t * t, t * t * t
            return ((2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * m0
                    + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * m1)
        t2 = t * t
        return ((6 * t2 - 6 * t) * p0 + (3 * t2 - 4 * t + 1) * m0
                + (-6 * t2 + 6 * t) * p1 + (3 * t2 - 2 * t) * m1) / dg

    def _lobe_start(self, ut, st) -> float:
        """Lobe k starts at the centre of pin k (outer) or the root g = -2 pi k (inner)."""
        per = self.n // self.lobes
        return 0.5 * np.interp(1.0, ut, st) if self.kind[0] == CODE_CIRCLE and per == 2 else 0.0

    @cached_property
    def area(self) -> float:
        """Enclosed area from the PinSpace closed forms (not from any sampling)."""
        space = self.pair.space
        if self.material_inside:
            return -space.inner_lobe_integral * self.pair.lobes_inner
        e = self.pair.pin_edge
        lobe = space.pin_arc_integral(0, e, -e) + space.fillet_full_integral
        return self.pair.lobes_outer * lobe


def outer_profile(pair: PinGerotor) -> Profile:
    n1 = pair.lobes_outer
    e = pair.pin_edge
    kind, p0, p1, rot, cen, rad = [], [], [], [], [], []
    for k in range(n1):
        turn = TWO_PI * k / n1
        c = pair.pin_centre(k)
        base = math.atan2(-c[1], -c[0])  # the pin's inward direction
        kind.append(CODE_CIRCLE)
        p0.append(base + e)
        p1.append(base - e)
        rot.append(0.0)
        cen.append(c)
        rad.append(pair.rho)
        if pair.fillet_kind == "arc":
            fc, fr, a0, a1 = pair.arc_fillet
            kind.append(CODE_CIRCLE)
            p0.append(a0 + turn)
            p1.append(a1 + turn)
            rot.append(0.0)
            cen.append(rotate(np.asarray(fc), turn))
            rad.append(fr)
        else:
            g_lo, g_hi = pair.fillet_range
            kind.append(CODE_FILLET)
            p0.append(g_hi)
            p1.append(g_lo)
            rot.append(turn)
            cen.append(np.zeros(2))
            rad.append(0.0)
    return Profile("outer", pair, np.array(kind), np.array(p0), np.array(p1), np.array(rot),
                   np.array(cen), np.array(rad), lobes=n1, material_inside=False)


def inner_profile(pair: PinGerotor) -> Profile:
    n2 = pair.lobes_inner
    k = np.arange(n2)
    return Profile("inner", pair, np.full(n2, CODE_INNER), -TWO_PI * k, -TWO_PI * (k + 1),
                   np.zeros(n2), np.zeros((n2, 2)), np.zeros(n2), lobes=n2,
                   material_inside=True)
