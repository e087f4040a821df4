"""Plane rotations and cross products shared by every family's profile geometry."""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def rotate(points, angle):
    """Rotate points (..., 2) counter-clockwise by ``angle`` (scalar or broadcastable)."""
    x, y = points[..., 0], points[..., 1]
    # (filled in place, and one angle by math: numpy's calls cost most of a small
    # rotation's time, and sections turn thousands)
    if isinstance(angle, float | int):
        c, s = math.cos(angle), math.sin(angle)
        out = np.empty(x.shape + (2,))
    else:
        c, s = np.cos(angle), np.sin(angle)
        out = np.empty(np.broadcast_shapes(np.shape(c), x.shape) + (2,))
    np.subtract(c * x, s * y, out=out[..., 0])
    np.add(s * x, c * y, out=out[..., 1])
    return out


def cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
