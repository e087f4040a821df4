"""Plane rotations and cross products shared by every family's profile geometry."""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def rotate(points, angle):
    """Rotate points (..., 2) counter-clockwise by ``angle`` (scalar or broadcastable)."""
    c, s = np.cos(angle), np.sin(angle)
    x, y = points[..., 0], points[..., 1]
    # (filled in place: np.stack's own cost is most of a small rotation's)
    out = np.empty(np.broadcast_shapes(np.shape(c), x.shape) + (2,))
    np.subtract(c * x, s * y, out=out[..., 0])
    np.add(s * x, c * y, out=out[..., 1])
    return out


def cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
