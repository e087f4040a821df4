"""The perfect gas: the one definition the quasi-1D model, the CFD case writer and the
leakage post-processing share.

A calorically perfect gas, p = rho R T, u = cv T, h = cp T, with R from the molar mass and
the one universal gas constant :data:`R_UNIVERSAL`, and a viscosity law (Sutherland's or a
constant).  :class:`PerfectGas` answers the chamber equations' fluid interface (see
:mod:`rotorflow.quasi1d.fluids`) in closed form, and gives the CFD cases their
thermophysical properties and the leakage analysis its R, gamma and mu(T).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

#: Molar gas constant, J/(mol K) (CODATA 2018, exact since the SI of 2019).
R_UNIVERSAL = 8.314462618

VISCOSITY_LAWS = ("sutherland", "const")


@dataclass(frozen=True)
class PerfectGas:
    """Calorically perfect gas with constant cp; viscosity constant or Sutherland's law.

    The defaults are the air of the CFD gap cases (dry air's molar mass, cp 1005 J/(kg K),
    Sutherland's law for air); those cases hash these fields into their keys, so the
    field names and defaults are part of every recorded CFD run.
    """

    molar_mass_kg_kmol: float = 28.9647
    """kg/kmol, numerically g/mol: OpenFOAM's ``molWeight``."""
    cp_J_kgK: float = 1005.0
    prandtl: float = 0.71
    transport: str = "sutherland"
    """'sutherland' (mu from T) or 'const' (mu_Pa_s everywhere; for analytic checks)."""
    mu_Pa_s: float = 1.81e-5
    sutherland_As: float = 1.458e-6
    sutherland_Ts_K: float = 110.4

    def __post_init__(self) -> None:
        if self.transport not in VISCOSITY_LAWS:
            raise CaseError(f"gas transport must be 'sutherland' or 'const', not {self.transport}")

    @classmethod
    def from_gas_constant(cls, R_J_kgK: float, cp_J_kgK: float, **kw) -> PerfectGas:
        """The gas of specific gas constant R (its molar mass R_UNIVERSAL / R)."""
        return cls(1e3 * R_UNIVERSAL / R_J_kgK, cp_J_kgK, **kw)

    # -- constants (cached: the chamber equations read them at every step) ---------------
    @functools.cached_property
    def R(self) -> float:
        # 1e3 * R_UNIVERSAL is exactly 8314.462618 in binary: R is the same double the CFD
        # cases have always written, whatever the molar mass.
        return 1e3 * R_UNIVERSAL / self.molar_mass_kg_kmol

    @functools.cached_property
    def cv(self) -> float:
        return self.cp_J_kgK - self.R

    @functools.cached_property
    def gamma(self) -> float:
        return self.cp_J_kgK / self.cv

    @functools.cached_property
    def _g1(self) -> float:
        return self.gamma - 1.0

    @functools.cached_property
    def _icv(self) -> float:
        return 1.0 / self.cv

    # -- transport and state ---------------------------------------------------------------
    def mu(self, T: float) -> float:
        if self.transport == "const":
            return self.mu_Pa_s
        return self.sutherland_As * T**1.5 / (T + self.sutherland_Ts_K)

    def density(self, p, T):
        return p / (self.R * T)

    # -- the chamber equations' interface (rotorflow.quasi1d.fluids) ----------------------
    def props(self, rho, u):
        return self._g1 * rho * u, u * self._icv, self.gamma

    def kernel_params(self):
        """(kind, parameters, table) of the compiled right-hand side (:mod:`.kernel`)."""
        return 0, np.array([self._g1, self._icv, self.gamma]), np.zeros((1, 1))

    def dp(self, rho, u):
        g1 = self.gamma - 1.0
        return g1 * u, g1 * rho

    def state_pT(self, p: float, T: float):
        return p / (self.R * T), self.cv * T, self.cp_J_kgK * T

    def u_from_rho_p(self, rho, p):
        return p / ((self.gamma - 1.0) * rho)

    def T_ph(self, p, h):
        return h / self.cp_J_kgK

    def isentropic(self, rho, u, p2):
        p1 = (self.gamma - 1.0) * rho * u
        rho2 = rho * (p2 / p1) ** (1.0 / self.gamma)
        return rho2, p2 / ((self.gamma - 1.0) * rho2)

    def fill(self, m, U, V, h_in, p2):
        """Mix gas of enthalpy h_in into (m, U) at constant V until the pressure is p2."""
        U2 = p2 * V / (self.gamma - 1.0)
        return m + (U2 - U) / h_in, U2

    def work_isentropic(self, p1, T1, p2):
        g = self.gamma
        return self.cp_J_kgK * T1 * ((p2 / p1) ** ((g - 1.0) / g) - 1.0)

    def work_isothermal(self, p1, T1, p2):
        return self.R * T1 * math.log(p2 / p1)

    def in_range(self, rho, u) -> bool:
        return bool(np.all(rho > 0) and np.all(u > 0))
