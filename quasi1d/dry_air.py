"""Dry air as a thermally perfect gas: p = rho R T with cp(T) of the ideal-gas part of
CoolProp's air (Lemmon et al. 2000), the fluid of ``[operating] fluid = "air"`` by default.
It answers the chamber equations' fluid interface (:mod:`rotorflow.quasi1d.fluids`)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

# Ideal-gas heat capacity of dry air, cp/R = a + sum n_k E(theta_k / T) with the
# Planck-Einstein function E(x) = x^2 e^x / (e^x - 1)^2: the rigid-molecule 7/2 plus one
# vibrational mode per term (the two largest sit near N2's 3354 K and O2's 2239 K).
# Fitted to the ideal-gas part of CoolProp's air (Lemmon et al. 2000) over 100-2500 K:
# within 7.2e-5 of it (checked by the tests).  R is that reference's own: its molar gas
# constant 8.31451 J/(mol K) over its molar mass 28.96546 g/mol.  The fit is relative to
# it, so it keeps it rather than R_UNIVERSAL of the perfect gas (5.7e-6 apart).
DRY_AIR_R = 8.31451 / 0.02896546
DRY_AIR_CP_TERMS = (3.49156461, ((0.228800013, 11225.6465), (0.816824551, 3381.18178),
                                 (0.209866139, 2198.01519)))
# The top of that fit: a chamber hotter than this is warned of (quasi1d.result).
DRY_AIR_T_FITTED_MAX = 2500.0
# The range of T(u) tabulated for the chamber equations; outside it is reported.
THERMALLY_PERFECT_T_RANGE = (20.0, 10000.0)
THERMALLY_PERFECT_NODES = 8192


@dataclass(frozen=True)
class ThermallyPerfectGas:
    """Ideal gas with a temperature-dependent heat capacity: p = rho R T, u = u(T).

    cp(T)/R = a + sum n_k E(theta_k/T) integrates in closed form:

        u/R   = (a - 1) T + sum n_k theta_k / (e^x_k - 1)                x_k = theta_k / T
        s0/R  = a ln T + sum n_k (x_k / (e^x_k - 1) - ln(1 - e^-x_k))    (s = s0 - R ln p)

    The chamber equations need T from u without iteration: T and kappa = cp/cv are
    tabulated once on a uniform grid of u (linear interpolation: T within 1e-6 relative),
    with 1/cv for dp/du.
    Event and performance evaluations solve u(T), h(T), s0(T) by Newton's method.
    """

    R: float = DRY_AIR_R
    a: float = DRY_AIR_CP_TERMS[0]
    modes: tuple = DRY_AIR_CP_TERMS[1]
    name: str = "air"
    T_fitted_max: float = DRY_AIR_T_FITTED_MAX

    # -- closed forms in T ---------------------------------------------------------------
    def cp(self, T):
        T = np.asarray(T, dtype=float)
        c = np.full_like(T, self.a)
        for n, th in self.modes:
            x = th / T
            em = np.exp(-x)
            c = c + n * x * x * em / (1.0 - em) ** 2
        return self.R * c

    def cv(self, T):
        return self.cp(T) - self.R

    def u_T(self, T):
        T = np.asarray(T, dtype=float)
        u = (self.a - 1.0) * T
        for n, th in self.modes:
            u = u + n * th / np.expm1(th / T)
        return self.R * u

    def h_T(self, T):
        return self.u_T(T) + self.R * np.asarray(T, dtype=float)

    def s0_T(self, T):
        T = np.asarray(T, dtype=float)
        s = self.a * np.log(T)
        for n, th in self.modes:
            x = th / T
            s = s + n * (x / np.expm1(x) - np.log(-np.expm1(-x)))
        return self.R * s

    def _solve_T(self, f, target, dfdT, T0):
        """Newton on a monotonic f(T) = target (u, h or s0: cv, cp, cp/T > 0)."""
        T = np.array(T0, dtype=float) * np.ones_like(np.asarray(target, dtype=float))
        for _ in range(50):
            dT = (f(T) - target) / dfdT(T)
            T = T - dT
            if np.all(np.abs(dT) <= 1e-12 * T):
                break
        return T

    def T_u(self, u):
        # from the table's T (within ~1e-6), so that Newton converges in one or two
        # steps: the events call this every period (issue 19: per-point overheads)
        return self._solve_T(self.u_T, u, self.cv, self._interp(u)[0])

    # -- the table of T(u) ----------------------------------------------------------------
    @functools.cached_property
    def _table(self):
        T_lo, T_hi = THERMALLY_PERFECT_T_RANGE
        u_lo, u_hi = float(self.u_T(T_lo)), float(self.u_T(T_hi))
        ug = np.linspace(u_lo, u_hi, THERMALLY_PERFECT_NODES)
        Tg = self._solve_T(self.u_T, ug, self.cv, ug / (2.5 * self.R))
        cv = self.cv(Tg)
        return (u_lo, (u_hi - u_lo) / (ug.size - 1), ug.size,
                np.stack([Tg, (cv + self.R) / cv, 1.0 / cv]))

    def _interp(self, u):
        """T, kappa and 1/cv at u.  dp/du uses the interpolated 1/cv, continuous in u: the
        interpolant's own slope (piecewise constant) agrees with p to round-off but its
        jumps stall the cycle convergence of 8 % of the stress points."""
        u0, du, _, rows = self._table
        v = table_interp(np.asarray(u, dtype=float), u0, du, rows)
        return v[0], v[1], v[2]

    def kernel_params(self):
        """(kind, parameters, table) of the compiled right-hand side (:mod:`.kernel`)."""
        u0, du, _, rows = self._table
        return 1, np.array([u0, du, self.R]), rows

    def props(self, rho, u):
        T, kappa, _ = self._interp(u)
        return self.R * rho * T, T, kappa

    def dp(self, rho, u):
        T, _, icv = self._interp(u)
        return self.R * T, self.R * rho * icv

    def state(self, rho, u):
        """p, T, kappa, (dp/drho)_u, (dp/du)_rho from one interpolation."""
        T, kappa, icv = self._interp(u)
        return self.R * rho * T, T, kappa, self.R * T, self.R * rho * icv

    def in_range(self, rho, u) -> bool:
        u0, du, nu, _ = self._table
        return bool(np.all(rho > 0) and np.all(u >= u0) and np.all(u <= u0 + du * (nu - 1)))

    def u_from_rho_p(self, rho, p):
        return float(self.u_T(p / (self.R * rho)))

    # -- event and performance evaluations -------------------------------------------------
    def state_pT(self, p: float, T: float):
        u = float(self.u_T(T))
        return p / (self.R * T), u, u + self.R * T

    def T_ph(self, p, h):
        return float(self._solve_T(self.h_T, h, self.cp, h / (3.5 * self.R)))

    def _T_isentropic(self, T1, p1, p2):
        target = self.s0_T(T1) + self.R * np.log(p2 / p1)
        return self._solve_T(self.s0_T, target, lambda T: self.cp(T) / T,
                             T1 * (p2 / p1) ** (1.0 / 3.5))

    def isentropic(self, rho, u, p2):
        rho = np.atleast_1d(np.asarray(rho, dtype=float))
        T1 = self.T_u(np.atleast_1d(np.asarray(u, dtype=float)))
        T2 = self._T_isentropic(T1, self.R * rho * T1, p2)
        return p2 / (self.R * T2), self.u_T(T2)

    def fill(self, m, U, V, h_in, p2):
        """Mix gas of enthalpy h_in into (m, U) at constant V until the pressure is p2:
        m2 = p2 V / (R T2) and m2 u(T2) = U + (m2 - m) h_in, solved for T2."""
        m = np.atleast_1d(np.asarray(m, dtype=float))
        U = np.atleast_1d(np.asarray(U, dtype=float))
        c = p2 * V / self.R
        rest = U - m * h_in

        def g(T):  # m2 (u(T2) - h_in) = U - m h_in with m2 = c / T2
            return self.u_T(T) - rest * T / c

        def dg(T):
            return self.cv(T) - rest / c

        T2 = self._solve_T(g, h_in, dg, np.full_like(m, h_in / (3.5 * self.R)))
        m2 = c / T2
        return m2, U + (m2 - m) * h_in

    def work_isentropic(self, p1, T1, p2):
        return float(self.h_T(self._T_isentropic(T1, p1, p2)) - self.h_T(T1))

    def work_isothermal(self, p1, T1, p2):
        return self.R * T1 * math.log(p2 / p1)


def table_interp(u, u0, du, rows):
    """Rows (T, kappa, 1/cv) of the table interpolated linearly at u (an array of any
    shape, or a scalar: the compiled right-hand side calls it per slot, :mod:`.compiled`)."""
    f = (u - u0) / du
    # truncate, then clip: a NaN u lands in the first cell (never out of the table)
    j = np.minimum(np.maximum(np.intp(f), 0), rows.shape[1] - 2)
    t = f - j
    return _lerp(rows, 0, j, t), _lerp(rows, 1, j, t), _lerp(rows, 2, j, t)


def _lerp(rows, r, j, t):
    c0 = rows[r, j]
    return c0 + t * (rows[r, j + 1] - c0)


@functools.lru_cache(maxsize=1)
def dry_air() -> ThermallyPerfectGas:
    """Dry air with cp(T); one instance, so that its T(u) table is built once a process."""
    return ThermallyPerfectGas()
