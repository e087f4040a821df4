"""Working-fluid properties in the form the chamber equations need them.

The chamber state is (mass m, internal energy U); with the volume V this gives density
rho = m/V and specific internal energy u = U/m.  Every fluid therefore answers, for
arrays of (rho, u) and without inner iteration:

    props(rho, u)  -> p, T, kappa      (kappa = rho a^2 / p, the isentropic exponent
                                        used by the nozzle formulas)
    dp(rho, u)     -> (dp/drho)_u, (dp/du)_rho   (for the ideal-port constraint)

and, at a few points per run (plenum states, port events, performance figures):

    state_pT(p, T) -> rho, u, h
    u_from_rho_p(rho, p) -> u                   (starting states of the chambers)
    isentropic(rho, u, p2) -> rho2, u2          (blow-down of the gas left in a chamber)
    fill(m, U, V, h_in, p2) -> m2, U2           (back-flow into a chamber at constant V)
    T_ph(p, h), work_isentropic(p1, T1, p2), work_isothermal(p1, T1, p2)

:class:`IdealGas` is closed form (u = cv T).  :class:`ThermallyPerfectGas` (dry air) has
p = rho R T with cp(T): T, kappa and 1/cv come from a one-dimensional table in u.
:class:`TabulatedFluid` wraps a CoolProp
fluid: ln p, T, kappa and the two pressure derivatives are tabulated once on a regular
grid of (ln rho, u) covering the states a run can reach and interpolated bilinearly (ln p
is nearly linear in ln rho, so the interpolation error is small: below 1e-4 on the
default grid); the few event and performance evaluations call CoolProp directly.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import CaseError

from .settings import Operating


@dataclass(frozen=True)
class IdealGas:
    """Calorically perfect gas: p = rho R T, u = cv T, h = cp T."""

    R: float
    cp: float
    name: str = "air"

    @functools.cached_property
    def cv(self) -> float:
        return self.cp - self.R

    @functools.cached_property
    def gamma(self) -> float:
        return self.cp / self.cv

    @functools.cached_property
    def _g1(self) -> float:
        return self.gamma - 1.0

    @functools.cached_property
    def _icv(self) -> float:
        return 1.0 / self.cv

    def props(self, rho, u):
        return self._g1 * rho * u, u * self._icv, self.gamma

    def dp(self, rho, u):
        g1 = self.gamma - 1.0
        return g1 * u, g1 * rho

    def state_pT(self, p: float, T: float):
        return p / (self.R * T), self.cv * T, self.cp * T

    def u_from_rho_p(self, rho, p):
        return p / ((self.gamma - 1.0) * rho)

    def T_ph(self, p, h):
        return h / self.cp

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
        return self.cp * T1 * ((p2 / p1) ** ((g - 1.0) / g) - 1.0)

    def work_isothermal(self, p1, T1, p2):
        return self.R * T1 * math.log(p2 / p1)

    def in_range(self, rho, u) -> bool:
        return bool(np.all(rho > 0) and np.all(u > 0))


# Ideal-gas heat capacity of dry air, cp/R = a + sum n_k E(theta_k / T) with the
# Planck-Einstein function E(x) = x^2 e^x / (e^x - 1)^2: the rigid-molecule 7/2 plus one
# vibrational mode per term (the two largest sit near N2's 3354 K and O2's 2239 K).
# Fitted to the ideal-gas part of CoolProp's air (Lemmon et al. 2000) over 100-2500 K:
# within 7.2e-5 of it (checked by the tests).  R from CoolProp's molar mass 28.96546.
DRY_AIR_R = 287.0491267875601
DRY_AIR_CP_TERMS = (3.49156461, ((0.228800013, 11225.6465), (0.816824551, 3381.18178),
                                 (0.209866139, 2198.01519)))
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
        return self._solve_T(self.u_T, u, self.cv, np.asarray(u) / (2.5 * self.R))

    # -- the table of T(u) ----------------------------------------------------------------
    @functools.cached_property
    def _table(self):
        T_lo, T_hi = THERMALLY_PERFECT_T_RANGE
        u_lo, u_hi = float(self.u_T(T_lo)), float(self.u_T(T_hi))
        ug = np.linspace(u_lo, u_hi, THERMALLY_PERFECT_NODES)
        Tg = self.T_u(ug)
        cv = self.cv(Tg)
        return (u_lo, (u_hi - u_lo) / (ug.size - 1), ug.size,
                np.stack([Tg, (cv + self.R) / cv, 1.0 / cv]))

    def _interp(self, u):
        """T, kappa and 1/cv at u.  dp/du uses the interpolated 1/cv, continuous in u: the
        interpolant's own slope (piecewise constant) agrees with p to round-off but its
        jumps stall the cycle convergence of 8 % of the stress points."""
        u0, du, nu, rows = self._table
        f = (np.asarray(u, dtype=float) - u0) / du
        j = np.clip(f.astype(np.intp), 0, nu - 2)
        t = f - j
        c0 = rows[:, j]
        dc = rows[:, j + 1] - c0
        v = c0 + t * dc
        return v[0], v[1], v[2]

    def props(self, rho, u):
        T, kappa, _ = self._interp(u)
        return self.R * rho * T, T, kappa

    def dp(self, rho, u):
        T, _, icv = self._interp(u)
        return self.R * T, self.R * rho * icv

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


# Grid of the property table: 200 x 200 nodes in (ln rho, u).  The interpolation error of
# p, which is nearly linear in ln rho, stays below 1e-4 over a 1e4 span of density.
TABLE_NODES = 200


@dataclass(frozen=True)
class TabulatedFluid:
    """A CoolProp fluid tabulated in (ln rho, u) over [rho_lo, rho_hi] x [T_lo, T_hi]."""

    name: str  # CoolProp name, e.g. "Air"
    x0: float
    dx: float
    u0: float
    du: float
    nx: int
    nu: int
    table: np.ndarray = field(repr=False)  # (5, nx*nu): ln p, T, kappa, dp/drho|u, dp/du|rho

    @classmethod
    def build(cls, name: str, rho_lo: float, rho_hi: float, T_lo: float, T_hi: float,
              nodes: int = TABLE_NODES) -> TabulatedFluid:
        import CoolProp.CoolProp as CP

        x = np.linspace(math.log(rho_lo), math.log(rho_hi), nodes)
        Tf = np.geomspace(T_lo, T_hi, 2 * nodes)
        rho = np.exp(x)
        uf = _props_grid(CP, name, "Umass", rho[:, None], Tf[None, :])
        u_lo = np.nanmax(uf[:, 0])
        u_hi = np.nanmin(uf[:, -1])
        if not (np.isfinite(u_lo) and np.isfinite(u_hi) and u_hi > u_lo):
            raise CaseError(f"CoolProp cannot tabulate {name} between {T_lo:.0f} and {T_hi:.0f} K")
        ug = np.linspace(u_lo, u_hi, nodes)
        Tg = np.empty((nodes, nodes))
        for i in range(nodes):
            ok = np.isfinite(uf[i])
            Tg[i] = np.interp(ug, uf[i, ok], Tf[ok])
        R = np.broadcast_to(rho[:, None], Tg.shape)
        p = _props_grid(CP, name, "P", R, Tg)
        a = _props_grid(CP, name, "A", R, Tg)
        dpdr = _props_grid(CP, name, "d(P)/d(Dmass)|Umass", R, Tg)
        dpdu = _props_grid(CP, name, "d(P)/d(Umass)|Dmass", R, Tg)
        kappa = R * a**2 / p
        tab = np.stack([np.log(p), Tg, kappa, dpdr, dpdu]).reshape(5, -1)
        if not np.all(np.isfinite(tab)):
            raise CaseError(f"CoolProp {name}: the operating range reaches states it cannot "
                            "evaluate (two-phase or outside the equation of state)")
        return cls(name, float(x[0]), float(x[1] - x[0]), float(ug[0]), float(ug[1] - ug[0]),
                   nodes, nodes, tab)

    def _interp(self, rho, u, rows):
        fx = (np.log(rho) - self.x0) / self.dx
        fu = (u - self.u0) / self.du
        i = np.clip(fx.astype(np.intp), 0, self.nx - 2)
        j = np.clip(fu.astype(np.intp), 0, self.nu - 2)
        tx = fx - i
        tu = fu - j
        k = i * self.nu + j
        t = self.table[rows]
        c00 = t[:, k]
        c01 = t[:, k + 1]
        c10 = t[:, k + self.nu]
        c11 = t[:, k + self.nu + 1]
        a = c00 + tu * (c01 - c00)
        b = c10 + tu * (c11 - c10)
        return a + tx * (b - a)

    def props(self, rho, u):
        v = self._interp(rho, u, slice(0, 3))
        return np.exp(v[0]), v[1], v[2]

    def dp(self, rho, u):
        v = self._interp(rho, u, slice(3, 5))
        return v[0], v[1]

    def in_range(self, rho, u) -> bool:
        fx = (np.log(rho) - self.x0) / self.dx
        fu = (u - self.u0) / self.du
        return bool(np.all((fx >= 0) & (fx <= self.nx - 1) & (fu >= 0) & (fu <= self.nu - 1)))

    def u_from_rho_p(self, rho, p):
        """u at (rho, p) on the table (the inverse of props in u, for starting states)."""
        from scipy.optimize import brentq

        def dp(uu):
            return float(self.props(np.array([rho]), np.array([uu]))[0][0]) - p

        return brentq(dp, self.u0, self.u0 + self.du * (self.nu - 1))

    # -- direct CoolProp evaluations (a few per run) -------------------------------------
    @functools.cached_property
    def _state(self):
        import CoolProp.CoolProp as CP

        return CP.AbstractState("HEOS", self.name)

    def _upd(self, pair, a, b):
        import CoolProp.CoolProp as CP

        st = self._state
        st.update(getattr(CP, pair), float(a), float(b))
        return st

    def state_pT(self, p: float, T: float):
        st = self._upd("PT_INPUTS", p, T)
        return st.rhomass(), st.umass(), st.hmass()

    def T_ph(self, p, h):
        return self._upd("HmassP_INPUTS", h, p).T()

    def isentropic(self, rho, u, p2):
        rho = np.atleast_1d(rho)
        u = np.atleast_1d(u)
        out_r = np.empty_like(rho)
        out_u = np.empty_like(u)
        for i in range(rho.size):
            s = self._upd("DmassUmass_INPUTS", rho.flat[i], u.flat[i]).smass()
            st = self._upd("PSmass_INPUTS", p2, s)
            out_r.flat[i], out_u.flat[i] = st.rhomass(), st.umass()
        return out_r, out_u

    def fill(self, m, U, V, h_in, p2):
        from scipy.optimize import brentq

        m = np.atleast_1d(m)
        U = np.atleast_1d(U)
        m2 = np.empty_like(m)
        for i in range(m.size):
            mi, Ui = m.flat[i], U.flat[i]

            def f(mm, mi=mi, Ui=Ui):
                uu = (Ui + (mm - mi) * h_in) / mm
                return self._upd("DmassUmass_INPUTS", mm / V, uu).p() - p2

            hi = mi * 2.0
            while f(hi) < 0:
                hi *= 2.0
            m2.flat[i] = brentq(f, mi, hi, xtol=1e-15 * mi, rtol=1e-14)
        return m2, U + (m2 - m) * h_in

    def work_isentropic(self, p1, T1, p2):
        st = self._upd("PT_INPUTS", p1, T1)
        h1, s1 = st.hmass(), st.smass()
        return self._upd("PSmass_INPUTS", p2, s1).hmass() - h1

    def work_isothermal(self, p1, T1, p2):
        st = self._upd("PT_INPUTS", p1, T1)
        h1, s1 = st.hmass(), st.smass()
        st = self._upd("PT_INPUTS", p2, T1)
        return (st.hmass() - h1) - T1 * (st.smass() - s1)


def _props_grid(CP, name, out, rho, T):
    """PropsSI on a grid; rows that CoolProp rejects are filled point by point (NaN where
    it cannot evaluate)."""
    rho, T = np.broadcast_arrays(rho, T)
    res = np.full(rho.shape, np.nan)
    for i in range(rho.shape[0]):
        try:
            res[i] = CP.PropsSI(out, "Dmass", rho[i], "T", T[i], name)
        except ValueError:
            for j in range(rho.shape[1]):
                try:
                    res[i, j] = CP.PropsSI(out, "Dmass", rho[i, j], "T", T[i, j], name)
                except ValueError:
                    pass
    res[~np.isfinite(res)] = np.nan
    return res


@functools.lru_cache(maxsize=1)
def dry_air() -> ThermallyPerfectGas:
    """Dry air with cp(T); one instance, so that its T(u) table is built once a process."""
    return ThermallyPerfectGas()


def make_fluid(op: Operating, volume_ratio: float):
    """The fluid of an operating point: a perfect gas, dry air with cp(T), or a CoolProp
    fluid tabulated over the reachable range.

    Range: pressures from 1 % of suction (deep under-pressure in a leaking vacuum chamber)
    to 3 x the larger of the discharge pressure and the built-in compression end pressure;
    temperatures from 0.6 x the coldest to 2.5 x the hottest boundary or isentropic end
    temperature.  A state outside it is reported, not extrapolated silently.
    """
    if op.perfect_gas:
        return IdealGas(R=op.R_J_kgK, cp=op.cp_J_kgK)
    if op.fluid == "air":
        return dry_air()
    name = op.fluid.split("::", 1)[1]
    return _tabulated(name, op.p_suction_Pa, op.p_discharge_Pa, op.T_suction_K,
                      op.wall_temperature_K, op.oil_temperature_K, volume_ratio)


@functools.lru_cache(maxsize=16)
def _tabulated(name, ps, pd, Ts, Tw, To, vr):
    import CoolProp.CoolProp as CP

    cp = CP.PropsSI("CPMASS", "P", ps, "T", Ts, name)
    gamma = cp / CP.PropsSI("CVMASS", "P", ps, "T", Ts, name)
    p_hi = 3.0 * max(pd, ps * vr**gamma)
    p_lo = 0.01 * ps
    T_end = Ts * max(pd / ps, vr ** gamma) ** ((gamma - 1.0) / gamma)
    T_lo = 0.6 * min(Ts, Tw, To)
    T_hi = 2.5 * max(Ts, Tw, To, T_end)
    rho_lo = CP.PropsSI("Dmass", "P", p_lo, "T", T_hi, name)
    rho_hi = CP.PropsSI("Dmass", "P", p_hi, "T", max(T_lo, 0.9 * Ts), name)
    return TabulatedFluid.build(name, rho_lo, rho_hi, T_lo, T_hi)
