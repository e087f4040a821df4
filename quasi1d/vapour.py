"""A volatile liquid in another gas: the liquid's vapour in the chamber's gas, evaporating
from the liquid and condensing on it (water in the air of a flooded pump or compressor).

The gas phase is a mixture of ideal gases: the carrier, a perfect gas (R_a, cv_a), and
the liquid's vapour (R_v, cp_v constant, its ideal-gas heat capacity at the liquid's
datum temperature T0), of vapour mass fraction w = m_v / m.  Energies are counted from
the liquid at T0 (:mod:`.oil`'s datum, Ho = mo c_l (T_l - T0)), so the vapour's enthalpy
is h_v(T) = h_fg(T0) + cp_v (T - T0) and

    u = (1 - w) cv_a T + w (cv_v T + e0),   e0 = h_fg(T0) - cp_v T0,
    p = rho [(1 - w) R_a + w R_v] T,        kappa = cp / cv of the mixture (frozen),

closed form in (rho, u, w): no inner iteration.  The latent heat follows Kirchhoff's law,
h_fg(T) = h_fg(T0) + (cp_v - c_l)(T - T0) (water from 20 C: 2268 against CoolProp's
2257 kJ/kg at 100 C, 0.5 %).  The vapour pressure is CoolProp's p_sat(T) of the liquid's
fluid, tabulated in ln p against 1 / T (Clausius-Clapeyron's near-linear form).

Evaporation: the liquid exchanges heat with the gas through h A = mo c_l / tau (the
time-constant law of :mod:`.oil`); mass goes with it by the Chilton-Colburn analogy
(Chilton & Colburn, Ind. Eng. Chem. 26 (1934) 1183; Incropera & DeWitt, Fundamentals of
Heat and Mass Transfer, sec. 6.7), h_m = h / (rho cp Le^(2/3)):

    J = h A / (rho cp Le^(2/3)) (rho_sat(T_l) - rho_v)        (kg/s, liquid to vapour),

the vapour leaving the liquid at the liquid's temperature with h_v(T_l): the liquid pays
the latent heat, the gas receives the vapour's enthalpy, their sum is unchanged.  J falls
with the liquid's mass, so a chamber never evaporates more liquid than it holds; vapour
supersaturated without liquid stays vapour (no fog is formed).  Lewis number 1 by default:
Lewis's relation for water in air (h / (h_m rho cp) ~ 1, Le = 0.85 gives Le^(2/3) = 0.90).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import CaseError

from .perfect_gas import R_UNIVERSAL, PerfectGas

#: Nodes of the vapour-pressure table, from 1.001 x the triple point to SAT_T_MAX x the
#: critical temperature (linear interpolation of ln p in 1 / T errs below 1e-6 there).
SAT_NODES = 2000
SAT_T_MAX = 0.97


@dataclass(frozen=True)
class Vapour:
    """The vapour of a volatile liquid, an ideal gas (see the module docstring)."""

    name: str
    R: float  # J/(kg K)
    cp: float  # ideal-gas cp at T0
    h_fg0: float  # latent heat at T0
    T0: float  # the liquid's energy datum
    inv_T: np.ndarray = field(repr=False)  # 1 / T of the table, increasing
    ln_p: np.ndarray = field(repr=False)
    lewis: float = 1.0

    @property
    def cv(self) -> float:
        return self.cp - self.R

    @property
    def e0(self) -> float:
        """The vapour's internal energy less cv_v T."""
        return self.h_fg0 - self.cp * self.T0

    def p_sat(self, T):
        T = np.asarray(T, dtype=float)
        return np.exp(np.interp(1.0 / T, self.inv_T, self.ln_p))

    def rho_sat(self, T):
        """Density of the saturated vapour at T (ideal gas)."""
        return self.p_sat(T) / (self.R * np.asarray(T, dtype=float))

    def h(self, T):
        """Enthalpy of the vapour at T, from the liquid at T0."""
        return self.h_fg0 + self.cp * (np.asarray(T, dtype=float) - self.T0)

    @classmethod
    def of(cls, name: str, T0: float, lewis: float = 1.0) -> Vapour:
        """The vapour of CoolProp fluid ``name`` with its energy datum at T0."""
        import CoolProp.CoolProp as CP

        try:
            st = CP.AbstractState("HEOS", name)
        except ValueError as exc:
            raise CaseError(f"CoolProp does not know the volatile liquid {name!r}: {exc}") \
                from None
        t_lo, t_hi = 1.001 * st.Ttriple(), SAT_T_MAX * st.T_critical()
        if not t_lo < T0 < t_hi:
            raise CaseError(f"the liquid's temperature {T0:.1f} K lies outside {name}'s "
                            f"liquid range ({t_lo:.1f} to {t_hi:.1f} K)")
        inv_T = np.linspace(1.0 / t_hi, 1.0 / t_lo, SAT_NODES)  # increasing, for interp
        T = 1.0 / inv_T
        ln_p = np.empty_like(T)
        for i, t in enumerate(T):
            st.update(CP.QT_INPUTS, 1.0, t)
            ln_p[i] = math.log(st.p())
        st.update(CP.QT_INPUTS, 1.0, T0)
        h_v = st.hmass()
        st.update(CP.QT_INPUTS, 0.0, T0)
        h_fg0 = h_v - st.hmass()
        cp0 = CP.PropsSI("CP0MASS", "T", T0, "Q", 1.0, name)
        R = R_UNIVERSAL / st.molar_mass()  # (kg/mol)
        return cls(name, R, cp0, h_fg0, T0, inv_T, ln_p, lewis)


@dataclass(frozen=True)
class HumidGas:
    """A perfect carrier gas with the vapour of a volatile liquid (the module docstring).
    Every state function takes the vapour's mass fraction w."""

    gas: PerfectGas
    vapour: Vapour
    #: the suction gas's vapour fraction: the composition of the few-point functions
    #: (plenum states, reference works) where none is given
    w_ref: float = 0.0

    def _cv_R(self, w):
        g, v = self.gas, self.vapour
        return g.cv + w * (v.cv - g.cv), g.R + w * (v.R - g.R)

    def props(self, rho, u, w):
        """p, T, kappa at density rho, internal energy u, vapour fraction w."""
        cv, R = self._cv_R(w)
        T = (u - w * self.vapour.e0) / cv
        return rho * R * T, T, 1.0 + R / cv

    def dp(self, rho, u, w):
        """(dp/drho, dp/du, dp/dw) at fixed other two."""
        g, v = self.gas, self.vapour
        cv, R = self._cv_R(w)
        T = (u - w * v.e0) / cv
        dT_dw = (-v.e0 - T * (v.cv - g.cv)) / cv
        return R * T, rho * R / cv, rho * ((v.R - g.R) * T + R * dT_dw)

    def state_pT(self, p, T, w=None):
        """rho, u, h at (p, T, w)."""
        w = self.w_ref if w is None else w
        cv, R = self._cv_R(w)
        u = cv * T + w * self.vapour.e0
        return p / (R * T), u, u + R * T

    def u_from_rho_p(self, rho, p, w):
        cv, R = self._cv_R(w)
        return cv * p / (rho * R) + w * self.vapour.e0

    def T_ph(self, p, h, w=None):
        w = self.w_ref if w is None else w
        cv, R = self._cv_R(w)
        return (h - w * self.vapour.e0) / (cv + R)

    def isentropic(self, rho, u, p2, w):
        """(rho2, u2): expanded or compressed at frozen composition to p2."""
        p1, _, kappa = self.props(rho, u, w)
        rho2 = rho * (p2 / p1) ** (1.0 / kappa)
        return rho2, self.u_from_rho_p(rho2, p2, w)

    def fill(self, m, U, mv, V, h_in, w_in, p2):
        """(m2, U2, mv2): gas of enthalpy h_in and vapour fraction w_in mixed into (m, U,
        mv) at constant V until the pressure is p2.  With x kg added, p2 V = Rm T_m
        (U - e0 mv) / Cm with Rm, Cm the mixture's sum of m_i R_i and m_i cv_i: a
        quadratic in x, whose root that starts from the present state is taken."""
        g, v = self.gas, self.vapour
        ma = m - mv
        dR, dC = (1 - w_in) * g.R + w_in * v.R, (1 - w_in) * g.cv + w_in * v.cv
        R0, C0 = ma * g.R + mv * v.R, ma * g.cv + mv * v.cv
        E0, dE = U - v.e0 * mv, h_in - v.e0 * w_in  # thermal energy and its rate per kg
        # (R0 + dR x)(E0 + dE x) = p2 V (C0 + dC x)
        a = dR * dE
        b = R0 * dE + dR * E0 - p2 * V * dC
        c = R0 * E0 - p2 * V * C0
        x = np.where(np.abs(a) > 0, (-b + np.sqrt(np.maximum(b * b - 4 * a * c, 0.0)))
                     / (2 * np.where(np.abs(a) > 0, a, 1.0)), -c / b)
        return m + x, U + h_in * x, mv + w_in * x

    def fraction(self, p, pv):
        """w of gas at total pressure p holding the vapour at partial pressure pv:
        rho_v / rho = (pv / R_v) / sum(p_i / R_i)."""
        dv, da = pv / self.vapour.R, (p - pv) / self.gas.R
        return dv / (dv + da)

    def saturated_fraction(self, p, T):
        """w of gas saturated with the vapour at total pressure p and temperature T (the
        vapour at its saturation pressure, or the whole gas where p_sat >= p)."""
        return self.fraction(p, np.minimum(self.vapour.p_sat(T), p))

    def evaporation(self, mo, Ho, c_l, tau, rho, w, cp_mix):
        """J (kg/s, liquid to vapour) and the liquid's temperature (module docstring)."""
        v = self.vapour
        safe = np.maximum(mo, 1e-300)
        T_l = v.T0 + Ho / (safe * c_l)
        hA = mo * c_l / tau
        J = hA / (rho * cp_mix * v.lewis ** (2.0 / 3.0)) * (v.rho_sat(T_l) - w * rho)
        return np.where(mo > 0.0, J, 0.0), T_l

    def cp(self, w):
        cv, R = self._cv_R(w)
        return cv + R

    def work_isentropic(self, p1, T1, p2, w=None):
        """Isentropic work per kg from (p1, T1) to p2 at frozen composition."""
        w = self.w_ref if w is None else w
        cv, R = self._cv_R(w)
        return (cv + R) * T1 * ((p2 / p1) ** (R / (cv + R)) - 1.0)

    def work_isothermal(self, p1, T1, p2, w=None):
        w = self.w_ref if w is None else w
        return self._cv_R(w)[1] * T1 * math.log(p2 / p1)

    def in_range(self, rho, u) -> bool:
        """Positive density and energy (u > w e0 at any T > 0: a rough screen; the
        states' T is checked by the cycle through props)."""
        return bool(np.all(rho > 0) and np.all(u > 0))


def humid_gas(gas, op) -> HumidGas:
    """The carrier ``gas`` (a PerfectGas) with the vapour of the operating point's
    volatile liquid, its energy datum the liquid's inlet temperature, and the suction
    gas's vapour fraction at its relative humidity."""
    if not isinstance(gas, PerfectGas):
        raise CaseError("a volatile liquid (liquid_volatile) needs a perfect carrier gas: "
                        "give heat_capacity = \"constant\" in [operating]")
    hg = HumidGas(gas, Vapour.of(op.liquid_volatile, op.oil_temperature_K, op.lewis_number))
    ps, Ts = op.p_suction_Pa, op.T_suction_K
    pv = op.suction_relative_humidity * float(hg.vapour.p_sat(Ts))
    if pv >= ps:
        raise CaseError(f"the suction gas cannot hold {op.liquid_volatile}'s vapour at "
                        f"{pv / 1e5:.4g} bar under {ps / 1e5:.4g} bar: lower "
                        "suction_relative_humidity or T_suction_K")
    return dataclasses.replace(hg, w_ref=float(hg.fraction(ps, pv)))
