"""Plane rotations and cross products shared by every family's profile geometry."""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def rotate(points, angle):
    """Rotate points (..., 2) counter-clockwise by ``angle`` (scalar or broadcastable)."""
    c, s = np.cos(angle), np.sin(angle)
    x, y = points[..., 0], points[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], -1)


def cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
