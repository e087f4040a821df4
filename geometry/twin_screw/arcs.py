"""Primary arcs: the curves a twin-screw profile is built from (seed 004: "first or
second order curved lines such as straight line, circle or ellipse").

Each arc is a small frozen dataclass that evaluates its point and its first and second
derivatives against a local parameter ``t`` in [0, 1] (``order`` 0, 1, 2).  The second
derivative is needed because the generated (secondary) arc's tangent follows from the
derivative of the meshing condition, which already holds the primary arc's tangent.

Arcs are given in the frame they live in: the rack frame (``a`` across the pitch line,
positive towards the female rotor; ``b`` along it) or a rotor's own frame.  Every arc
has a ``name`` so that an error in what it generates can say which arc it was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..planar import rotate


def _stack(x, y):
    return np.stack([np.asarray(x, dtype=float), np.asarray(y, dtype=float)], -1)


@dataclass(frozen=True)
class Line:
    """The straight segment from ``start`` to ``end``."""

    name: str
    start: tuple[float, float]
    end: tuple[float, float]

    def inclination(self) -> float:
        """Its angle from the a axis (the line of centres), in [0, pi/2]: a rack
        flank's pressure angle (it generates involutes of r cos of it)."""
        (a0, b0), (a1, b1) = self.start, self.end
        return math.atan2(abs(b1 - b0), abs(a1 - a0))

    def eval(self, t, order: int = 0):
        t = np.asarray(t, dtype=float)
        p0, p1 = np.asarray(self.start), np.asarray(self.end)
        if order == 0:
            return p0 + t[..., None] * (p1 - p0)
        if order == 1:
            return np.broadcast_to(p1 - p0, t.shape + (2,)).copy()
        return np.zeros(t.shape + (2,))


@dataclass(frozen=True)
class CircleArc:
    """``centre + radius (cos g, sin g)`` for g from ``angle0`` to ``angle1`` (radians;
    ``angle1 < angle0`` runs clockwise)."""

    name: str
    centre: tuple[float, float]
    radius: float
    angle0: float
    angle1: float

    def eval(self, t, order: int = 0):
        return self.jets(t, (order,))[0]

    def jets(self, t, orders=(0, 1, 2)):
        """:meth:`eval` at each of ``orders``, from one cosine and sine of the angles (a
        generated arc asks for three orders at every point)."""
        t = np.asarray(t, dtype=float)
        span = self.angle1 - self.angle0
        g = self.angle0 + t * span
        c, s = np.cos(g), np.sin(g)
        out = []
        for order in orders:
            if order == 0:
                out.append(np.asarray(self.centre) + self.radius * _stack(c, s))
            elif order == 1:
                out.append(self.radius * span * _stack(-s, c))
            else:
                out.append(-self.radius * span * span * _stack(c, s))
        return out


@dataclass(frozen=True)
class EllipseArc:
    """``centre + R(tilt) (semi_major cos g, semi_minor sin g)`` for g from ``angle0``
    to ``angle1`` (the eccentric angle, radians)."""

    name: str
    centre: tuple[float, float]
    semi_major: float
    semi_minor: float
    tilt: float
    angle0: float
    angle1: float

    def eval(self, t, order: int = 0):
        t = np.asarray(t, dtype=float)
        span = self.angle1 - self.angle0
        g = self.angle0 + t * span
        c, s = np.cos(g), np.sin(g)
        if order == 0:
            local = _stack(self.semi_major * c, self.semi_minor * s)
        elif order == 1:
            local = span * _stack(-self.semi_major * s, self.semi_minor * c)
        else:
            local = -span * span * _stack(self.semi_major * c, self.semi_minor * s)
        out = rotate(local, self.tilt)
        return out + np.asarray(self.centre) if order == 0 else out


@dataclass(frozen=True)
class ParabolaArc:
    """``vertex + R(tilt) (w, w^2 / (4 focal))`` for w from ``w0`` to ``w1`` (the
    parabola opens along the tilted +y axis; ``focal`` is the vertex-focus distance)."""

    name: str
    vertex: tuple[float, float]
    focal: float
    tilt: float
    w0: float
    w1: float

    def eval(self, t, order: int = 0):
        t = np.asarray(t, dtype=float)
        span = self.w1 - self.w0
        w = self.w0 + t * span
        k = 1.0 / (4.0 * self.focal)
        if order == 0:
            local = _stack(w, k * w * w)
        elif order == 1:
            local = _stack(np.full_like(w, span), 2.0 * k * w * span)
        else:
            local = _stack(np.zeros_like(w), np.full_like(w, 2.0 * k * span * span))
        out = rotate(local, self.tilt)
        return out + np.asarray(self.vertex) if order == 0 else out


def jets(arc, t, orders=(0, 1, 2)):
    """``arc.eval(t, order)`` for each of ``orders``: at once where the arc can."""
    if hasattr(arc, "jets"):
        return arc.jets(t, orders)
    return [arc.eval(t, order) for order in orders]


#: Any of the primary arcs above.
Arc = Line | CircleArc | EllipseArc | ParabolaArc
