"""Design limits of a pin-generated pair: the undercut limit of the pin radius (seed 000
Eq. 4) and the pressure angle at the pitch point (Eq. 5)."""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.geometry.scalar import minimum


def sigma_limit(lobes_outer: int, lam: float, samples: int = 20001) -> float:
    """Undercut limit sigma_lim(N1, lambda) of seed 000 Eq. 4.

    ``zeta(phi)`` is the normalised curvature radius of the pin-centre trochoid in the
    inner frame; the pin radius must stay below its smallest positive value.  A coarse
    scan brackets the minimum, a bounded scalar search polishes it to machine precision.
    """
    if lobes_outer < 2:
        raise CaseError(f"lobes_outer must be at least 2, got {lobes_outer}")
    if not lam > 1.0:
        raise CaseError(f"lambda must be greater than 1 (pins outside the pitch circle), got {lam}")
    m21 = lobes_outer / (lobes_outer - 1)

    def zeta(phi):
        num = (1.0 - m21) * (1.0 + lam**2 - 2.0 * lam * np.cos(phi)) ** 1.5
        den = lam**2 * (1.0 - m21) - m21 + lam * (2.0 * m21 - 1.0) * np.cos(phi)
        return num / den

    phi = np.linspace(0.0, math.pi, samples)
    z = zeta(phi)
    z = np.where(z > 0.0, z, np.inf)
    i = int(np.argmin(z))
    if not np.isfinite(z[i]):
        raise CaseError(f"no undercut-free pin radius exists for N1={lobes_outer}, lambda={lam}")
    lo, hi = phi[max(i - 1, 0)], phi[min(i + 1, samples - 1)]
    _, least = minimum(lambda p: zeta(p) if zeta(p) > 0 else np.inf, lo, hi, xtol=1e-13)
    return float(min(least, z[i]))


def pressure_angle_at_pitch(lam: float, sigma: float) -> float | None:
    """Pressure angle when the contact passes the pitch point (seed 000 Eq. 5), radians.

    Returns None when the pin never touches at the pitch point, i.e. when
    ``lambda - 1 > sigma`` (the pitch point lies outside the pin circle's reach).
    """
    c = (1.0 + sigma**2 - lam**2) / (2.0 * sigma)
    if not -1.0 <= c <= 1.0:
        return None
    return math.acos(c) - math.pi / 2.0
