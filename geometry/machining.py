"""Machining and inspection files: transverse profiles (CSV, DXF) and point clouds with
normals (CSV, PLY).

* Profiles: the rotor's transverse section at the low-pressure face (z = 0) in the
  rotor's own frame (origin on its axis, at rotor angle 0), clearance included, as a
  closed polyline whose vertices lie on the analytic curve and whose chords deviate
  from it by at most the tolerance (:func:`profile_curves.sample`), i.e. reduced to the
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
from pathlib import Path

import numpy as np

from .profile_curves import sample
from .solids import SweptSurface


def write_profile_csv(path: Path, poly: np.ndarray, unit: str, scale: float) -> None:
    pts = np.vstack([poly, poly[:1]]) * scale
    np.savetxt(path, pts, delimiter=",", header=f"x_{unit},y_{unit}", comments="",
               fmt="%.9f")


def read_profile_csv(path: Path) -> np.ndarray:
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def write_profile_dxf(path: Path, poly: np.ndarray, scale: float, units: str,
                      circle_radius: float | None = None) -> None:
    """ASCII DXF (R12): one closed 2D POLYLINE, optionally a CIRCLE centred at 0."""
    insunits = 4 if units == "mm" else 6  # AutoCAD unit codes: 4 mm, 6 m
    out = ["0", "SECTION", "2", "HEADER", "9", "$ACADVER", "1", "AC1009",
           "9", "$INSUNITS", "70", str(insunits), "0", "ENDSEC",
           "0", "SECTION", "2", "ENTITIES",
           "0", "POLYLINE", "8", "PROFILE", "66", "1", "70", "1",
           "10", "0.0", "20", "0.0", "30", "0.0"]
    for x, y in poly * scale:
        out += ["0", "VERTEX", "8", "PROFILE", "10", f"{x:.9f}", "20", f"{y:.9f}", "30", "0.0"]
    out += ["0", "SEQEND", "8", "PROFILE"]
    if circle_radius is not None:
        out += ["0", "CIRCLE", "8", "BORE", "10", "0.0", "20", "0.0", "30", "0.0",
                "40", f"{circle_radius * scale:.9f}"]
    out += ["0", "ENDSEC", "0", "EOF"]
    Path(path).write_text("\n".join(out) + "\n")


def read_profile_dxf(path: Path) -> tuple[np.ndarray, bool]:
    """Vertices of the first POLYLINE of an R12 DXF and whether it is flagged closed."""
    lines = [s.strip() for s in Path(path).read_text().splitlines()]
    pairs = list(zip(lines[0::2], lines[1::2], strict=False))
    pts, closed, inside, vert = [], False, False, None
    for code, value in pairs:
        if code == "0":
            if vert is not None:
                pts.append(vert)
                vert = None
            if value == "POLYLINE":
                inside = True
            elif value == "SEQEND" and inside:
                break
            elif value == "VERTEX" and inside:
                vert = [0.0, 0.0]
        elif inside and vert is None and code == "70":
            closed = bool(int(value) & 1)
        elif vert is not None and code == "10":
            vert[0] = float(value)
        elif vert is not None and code == "20":
            vert[1] = float(value)
    return np.array(pts), closed


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


def write_cloud_csv(path: Path, pts, nrm, unit: str, scale: float) -> None:
    data = np.hstack([pts * scale, nrm])
    np.savetxt(path, data, delimiter=",", comments="",
               header=f"x_{unit},y_{unit},z_{unit},nx,ny,nz", fmt="%.9f")


def write_cloud_ply(path: Path, pts, nrm, scale: float, comment: str = "rotorflow") -> None:
    n = len(pts)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment {comment}\n"
        f"element vertex {n}\n"
        "property double x\nproperty double y\nproperty double z\n"
        "property double nx\nproperty double ny\nproperty double nz\n"
        "end_header\n"
    )
    data = np.hstack([pts * scale, nrm]).astype("<f8")
    with Path(path).open("wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(data.tobytes())


def read_cloud_ply(path: Path) -> np.ndarray:
    raw = Path(path).read_bytes()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    head = raw[:end].decode("ascii").splitlines()
    n = int(next(s.split()[2] for s in head if s.startswith("element vertex")))
    return np.frombuffer(raw, dtype="<f8", count=6 * n, offset=end).reshape(n, 6)
