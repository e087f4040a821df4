"""Sweep laws: how a planar rotor pair becomes a 3D rotor pair.

Every section of the pair at height z is the planar pair at outer-rotor angle
``phi - twist(z)``, scaled about the outer axis by ``scale(z)`` (design.md):

    P(u, z) = scale(z) R(phi(z)) p(u) + z e_z

* straight: scale 1, twist 0;
* helical: scale 1, twist linear, ``twist(L) = wrap`` (constant lead);
* conical: scale linear from 1 at the low-pressure end (z = 0) to ``scale_end`` at the
  high-pressure end, centre distance scaled with it, and a lead that changes linearly
  along z from ``lead_0`` to ``lead_ratio * lead_0`` with ``twist(L) = wrap``.

The inner rotor follows from the gearing ratio: its twist is ``m21 * twist(z)``.
Integrals along z use Gauss-Legendre panels; chambers are smooth inside their life and
C^3 at its ends (their area grows like the fourth power of the angle since birth), so
a few hundred nodes give 1e-8 relative accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

#: Gauss-Legendre nodes per panel and panels along the rotor for z integrals.
GAUSS_NODES = 8
PANELS = 48
#: Gauss-Legendre nodes per half hat in :meth:`Sweep.hat_kernel` (the weight is smooth
#: and the half hats are short: 4 nodes integrate it to rounding).
KERNEL_GAUSS_NODES = 4


@dataclass(frozen=True)
class Sweep:
    kind: str
    length: float
    wrap: float = 0.0  # outer-rotor twist over the length [rad]
    scale_end: float = 1.0  # scale at z = L (conical), 1 at z = 0
    lead_ratio: float = 1.0  # lead at z = L over lead at z = 0 (conical, variable lead)

    def __post_init__(self):
        if self.kind not in ("straight", "helical", "conical"):
            raise CaseError(f"unknown sweep kind '{self.kind}' (straight, helical or conical)")
        if not self.length > 0.0:
            raise CaseError(f"length must be positive, got {self.length}")
        if self.kind == "straight" and self.wrap != 0.0:
            raise CaseError("a straight sweep has no wrap angle")
        if self.wrap < 0.0:
            raise CaseError(f"wrap angle must not be negative, got {self.wrap}")
        if not 0.0 < self.scale_end <= 1.0:
            raise CaseError(f"scale_end must lie in (0, 1], got {self.scale_end}")
        if not self.lead_ratio > 0.0:
            raise CaseError(f"lead_ratio must be positive, got {self.lead_ratio}")

    def scale(self, z):
        z = np.asarray(z, dtype=float)
        return 1.0 + (self.scale_end - 1.0) * z / self.length

    def dscale(self, z):
        return np.full_like(np.asarray(z, dtype=float), (self.scale_end - 1.0) / self.length)

    def twist(self, z):
        """Outer-rotor twist at z, 0 at the low-pressure end and ``wrap`` at z = L."""
        zeta = np.asarray(z, dtype=float) / self.length
        r = self.lead_ratio
        if abs(r - 1.0) < 1e-12:
            return self.wrap * zeta
        # twist' ~ 1/lead, lead linear in z: twist ~ log(1 + (r - 1) zeta).
        return self.wrap * np.log1p((r - 1.0) * zeta) / math.log(r)

    def dtwist(self, z):
        zeta = np.asarray(z, dtype=float) / self.length
        r = self.lead_ratio
        if abs(r - 1.0) < 1e-12:
            return np.full_like(zeta, self.wrap / self.length)
        return self.wrap * (r - 1.0) / (math.log(r) * (1.0 + (r - 1.0) * zeta)) / self.length

    def z_of_twist(self, theta):
        """Height at which the outer rotor has twisted by ``theta`` (inverse of twist)."""
        frac = np.asarray(theta, dtype=float) / self.wrap
        r = self.lead_ratio
        if abs(r - 1.0) < 1e-12:
            return self.length * frac
        return self.length * np.expm1(frac * math.log(r)) / (r - 1.0)

    def nodes(self, panels: int | None = None, order: int = GAUSS_NODES):
        """Gauss-Legendre nodes and weights over [0, L]."""
        panels = panels or PANELS
        x, w = np.polynomial.legendre.leggauss(order)
        edges = np.linspace(0.0, self.length, panels + 1)
        h = np.diff(edges)
        z = (edges[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
        wz = (0.5 * h[:, None] * w[None, :]).ravel()
        return z, wz

    def hat_kernel(self, h: float, power: int) -> np.ndarray:
        """Weights K[m] of the sweep integral of a function linear between angle nodes.

        For f tabulated every ``h`` of section angle and interpolated linearly,
        ``\\int_0^L f(phi - twist(z)) scale(z)^power dz`` at ``phi = psi_j`` equals
        ``sum_m K[m] f[j - m]``: substituting theta = twist(z) turns the integral into
        ``\\int_0^wrap f(phi - theta) W(theta) dtheta`` with the smooth weight
        ``W = scale^power / twist'``, and K[m] is W integrated against the hat function
        of node j - m.  Gauss-Legendre on each half of a hat, split at the ends of the
        wrap, integrates the smooth W to rounding; so the sweep adds no error to the
        table's own, however sharp the table's kinks.  No wrap: K = [\\int scale^power].
        """
        if self.wrap == 0.0:
            z, wz = self.nodes()
            return np.array([float(np.sum(wz * self.scale(z) ** power))])
        x, w = np.polynomial.legendre.leggauss(KERNEL_GAUSS_NODES)
        m = np.arange(int(math.ceil(self.wrap / h)) + 2)
        kernel = np.zeros(len(m))
        for lo, hi in ((-1, 0), (0, 1)):
            a = np.clip((m + lo) * h, 0.0, self.wrap)
            b = np.clip((m + hi) * h, 0.0, self.wrap)
            theta = 0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * x[None, :]
            hat = 1.0 - np.abs(theta - (m * h)[:, None]) / h
            z = self.z_of_twist(theta)
            weight = self.scale(z) ** power / self.dtwist(z)
            kernel += (hat * weight * 0.5 * (b - a)[:, None] * w[None, :]).sum(1)
        return kernel

    @property
    def scale_squared_integral(self) -> float:
        """\\int_0^L scale(z)^2 dz: the volume of a prism of unit section."""
        s1 = self.scale_end
        return self.length * (1.0 + s1 + s1 * s1) / 3.0
