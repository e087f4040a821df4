"""What the machining and inspection files hold: transverse profiles (written as CSV,
DXF) and point clouds with normals (written as CSV, PLY).

* Profiles: the rotor's transverse section at the low-pressure face (z = 0) in the
  rotor's own frame (origin on its axis, at rotor angle 0), clearance included, as a
  closed polyline whose vertices lie on the analytic curve and whose chords deviate
  from it by at most the tolerance (:func:`..curves.sample`), i.e. reduced to the
  tolerance.  CSV: ``x_<unit>,y_<unit>``, the first point repeated at the end.  DXF: an
  ASCII R12 file with one closed POLYLINE (layer PROFILE); the outer rotor's file adds
  its outside circle (layer BORE).
* Point clouds: points exactly on the flank (analytic, no mesh), about ``spacing``
  apart along the profile and along z, with unit normals pointing out of the material,
  in the machine frame of the STL files.  CSV ``x,y,z,nx,ny,nz``; PLY binary
  little-endian with double-precision vertex properties x, y, z, nx, ny, nz.
"""

from __future__ import annotations

import math

import numpy as np

from ..curves import sample
from .surface import SweptSurface


def cloud(surface: SweptSurface, spacing: float, material_inside: bool):
    """Points on the flank (about ``spacing`` apart) and unit normals out of the material."""
    curve = surface.curve
    # profile samples: at most `spacing` apart, and closer where the curvature is high
    u = sample(curve, spacing * 1e-3, spacing)
    nz = max(int(math.ceil(surface.length / spacing)), 1) + 1
    z = np.linspace(0.0, surface.length, nz)
    U, Z = np.meshgrid(u, z)
    pts = surface.point(U, Z).reshape(-1, 3)
    nrm = surface.normal(U, Z).reshape(-1, 3)
    if not material_inside:
        nrm = -nrm  # the outer rotor's material lies outside its profile
    return pts, nrm
