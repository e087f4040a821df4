"""CSV files for the machine shop: a transverse profile (``x_<unit>,y_<unit>``, the first
point repeated at the end) and a point cloud with normals (``x,y,z,nx,ny,nz``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def write_profile_csv(path: Path, poly: np.ndarray, unit: str, scale: float) -> None:
    pts = np.vstack([poly, poly[:1]]) * scale
    np.savetxt(path, pts, delimiter=",", header=f"x_{unit},y_{unit}", comments="",
               fmt="%.9f")


def read_profile_csv(path: Path) -> np.ndarray:
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def write_cloud_csv(path: Path, pts, nrm, unit: str, scale: float) -> None:
    data = np.hstack([pts * scale, nrm])
    np.savetxt(path, data, delimiter=",", comments="",
               header=f"x_{unit},y_{unit},z_{unit},nx,ny,nz", fmt="%.9f")
