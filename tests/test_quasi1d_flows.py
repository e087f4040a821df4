"""Flow models and the explicit integrator against closed-form solutions.

Blow-down of an adiabatic tank through an isentropic nozzle (seed 001 Eqs. 7-8): choked,
the pressure follows p/p0 = (1 + (g-1)/2 * t/tau)^(-2g/(g-1)) exactly; unchoked, the
time to reach a pressure is the quadrature of the same ODE, t(p) = int V drho / mdot,
evaluated with scipy.quad to 1e-12.  The tank is integrated with the model's own
Runge-Kutta integrators, so these tests check the flux formulas and the integrators.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.integrate import quad

from rotorflow.quasi1d import flows
from rotorflow.quasi1d.integrate import integrate_period
from rotorflow.quasi1d.perfect_gas import PerfectGas

AIR = PerfectGas.from_gas_constant(287.0, 1004.5)  # gamma = 1.4 exactly (R = 287.0 exactly)


@dataclass(frozen=True)
class _Seg:
    start: float
    end: float
    events: tuple = ()


@dataclass
class Tank:
    """An adiabatic tank of volume V blowing down through area A into back pressure pb.

    The state is (m, U) as in the chamber model; "angle" is time here."""

    V: float
    A: float
    pb: float
    t_end: float

    @property
    def segments(self):
        return (_Seg(0.0, self.t_end),)

    def apply_event(self, *args):
        pass

    def rhs(self, t, y, seg):
        m, U = y[:, 0], y[:, 1]
        rho, u = m / self.V, U / m
        p, _, k = AIR.props(rho, u)
        mdot = np.sqrt(p * rho) * flows.nozzle_f(self.pb / p, k) * self.A
        return np.column_stack([-mdot, -mdot * AIR.gamma * u])


def _blowdown(p0, T0, pb, t_end, method, rtol):
    V, A = 1e-3, 1e-6
    rho0, u0, _ = AIR.state_pT(p0, T0)
    tank = Tank(V, A, pb, t_end)
    y0 = np.array([[rho0 * V, rho0 * V * u0]])
    run = integrate_period(tank, y0, method, rtol, np.array([1e-14, 1e-9]), record=True)
    t = np.array(run.trace_theta)
    y = np.array(run.trace_y)
    p = AIR.props(y[:, 0] / V, y[:, 1] / y[:, 0])[0]
    return t, p, V, A, rho0


@pytest.mark.parametrize("method", ["dopri5", "bs3"])
def test_choked_blowdown_matches_closed_form(method):
    g = AIR.gamma
    p0, T0, pb = 10e5, 300.0, 1e5
    # stays choked: p/pb above 1/0.528 = 1.89 until the end time chosen below
    V, A = 1e-3, 1e-6
    a0 = math.sqrt(g * AIR.R * T0)
    tau = V / (A * a0) * (2.0 / (g + 1.0)) ** (-(g + 1.0) / (2.0 * (g - 1.0)))
    t_end = 0.9 * tau
    t, p, *_ = _blowdown(p0, T0, pb, t_end, method, 1e-8)
    exact = p0 * (1.0 + 0.5 * (g - 1.0) * t / tau) ** (-2.0 * g / (g - 1.0))
    assert p[-1] / pb > 1.0 / flows.nozzle_critical_ratio(g)  # still choked at the end
    assert p[-1] < 0.35 * p0  # and the tank lost two thirds of its pressure
    # rtol 1e-8 per step over a few hundred steps: 1e-6 leaves room for accumulation
    assert np.max(np.abs(p / exact - 1.0)) < 1e-6
    # the check resolves a 0.1 % error in the nozzle area (it would fail on it)
    off = p0 * (1.0 + 0.5 * (g - 1.0) * t / (tau / 1.001)) ** (-2.0 * g / (g - 1.0))
    assert np.max(np.abs(p / off - 1.0)) > 1e-4


@pytest.mark.parametrize("method", ["dopri5", "bs3"])
def test_unchoked_blowdown_matches_quadrature(method):
    g = AIR.gamma
    p0, T0, pb = 1.6e5, 300.0, 1.0e5  # p_b/p0 = 0.625 > 0.528: never choked
    rho0 = p0 / (AIR.R * T0)
    V, A = 1e-3, 1e-6

    def time_to(p):
        # adiabatic tank: rho = rho0 (p/p0)^(1/g); V drho/dt = -A sqrt(p rho) f(pb/p)
        def integrand(q):
            rho = rho0 * (q / p0) ** (1.0 / g)
            drho_dp = rho / (g * q)
            return V * drho_dp / (A * math.sqrt(q * rho) * float(flows.nozzle_f(pb / q, g)))

        return quad(integrand, p, p0, epsabs=0, epsrel=1e-12)[0]

    t_end = time_to(1.1 * pb)  # stop well clear of the linear band 1 - pb/p < 1e-4
    t, p, *_ = _blowdown(p0, T0, pb, t_end, method, 1e-9)
    assert abs(p[-1] / (1.1 * pb) - 1.0) < 1e-6
    for ti, pi in zip(t[5::7], p[5::7], strict=False):
        assert abs(time_to(pi) - ti) < 1e-6 * t_end


def test_nozzle_flux_is_continuous_at_choking_and_zero_at_equal_pressure():
    k = 1.4
    xc = flows.nozzle_critical_ratio(k)
    f = flows.nozzle_f(np.array([xc * (1 - 1e-9), xc * (1 + 1e-9), 1.0, 0.0]), k)
    assert abs(f[0] - f[1]) < 1e-8
    assert f[2] == 0.0
    # choked flux: sqrt(k (2/(k+1))^((k+1)/(k-1))) = 0.6847 for k = 1.4
    assert abs(f[3] - 0.684731) < 1e-6
    # monotone: less back pressure never gives less flow
    x = np.linspace(0.0, 1.0, 2001)
    assert np.all(np.diff(flows.nozzle_f(x, k)) <= 1e-15)


def test_fanno_flux_choking_and_limits():
    zeta = 2.0
    xs = flows.fanno_choke_ratio(zeta)
    # x* satisfies 1 - x^2 = x^2 (zeta - 2 ln x)
    assert abs(1 - xs**2 - xs**2 * (zeta - 2 * math.log(xs))) < 1e-12
    x = np.linspace(0.0, 1.0, 4001)
    f = flows.fanno_f(x, zeta, xs)
    assert np.all(np.diff(f) <= 1e-15)  # monotone, flat below x*
    assert f[-1] == 0.0
    assert np.allclose(f[x < xs], f[0])
    # more friction, less flow; at small pressure difference Eq. 9 tends to
    # sqrt(2 (1 - x) / zeta), a laminar-like square-root law
    f_hi = flows.fanno_f(x, 20.0, flows.fanno_choke_ratio(20.0))
    assert np.all(f_hi[:-1] < f[:-1])
    x1 = 0.99
    approx = math.sqrt(2 * (1 - x1) / zeta)
    assert abs(float(flows.fanno_f(np.array([x1]), zeta, xs)[0]) / approx - 1) < 0.02


def test_signed_flux_is_antisymmetric():
    pa, pb = np.array([3e5, 1e5]), np.array([1e5, 3e5])
    ra, rb = np.array([3.5, 1.2]), np.array([1.2, 3.5])
    F = flows.signed_flux(pa, ra, 1.4, pb, rb, 1.4, "nozzle")
    assert F[0] > 0 and abs(F[0] + F[1]) < 1e-12 * F[0]


def test_rosenbrock_blowdown_converges_at_second_order():
    # ros23 is order 2: ten times tighter a tolerance cuts the error by ~10^(2/3) = 4.6
    g = AIR.gamma
    p0, T0, pb = 10e5, 300.0, 1e5
    V, A = 1e-3, 1e-6
    a0 = math.sqrt(g * AIR.R * T0)
    tau = V / (A * a0) * (2.0 / (g + 1.0)) ** (-(g + 1.0) / (2.0 * (g - 1.0)))
    errs = []
    for rtol in (1e-4, 1e-5, 1e-6):
        t, p, *_ = _blowdown(p0, T0, pb, 0.9 * tau, "ros23", rtol)
        exact = p0 * (1.0 + 0.5 * (g - 1.0) * t / tau) ** (-2.0 * g / (g - 1.0))
        errs.append(np.max(np.abs(p / exact - 1.0)))
    assert errs[2] < 1e-4
    assert errs[0] / errs[1] > 3.0 and errs[1] / errs[2] > 3.0


# --- the unsmoothed nozzle, as the CFD cases and the leakage analysis use it ---------------

R_AIR, GAMMA = 287.05, 1.4


def test_choked_nozzle_flux_is_the_textbook_value():
    # Air, gamma 1.4: m'' = 0.6847 p0 / sqrt(R T0) at and below the critical ratio 0.5283.
    p0, T0 = 3e5, 300.0
    expected = 0.68473 * p0 / math.sqrt(R_AIR * T0)
    for p in (0.5283 * p0, 0.3 * p0, 0.0):
        assert flows.isentropic_mass_flux(p0, T0, p, GAMMA, R_AIR) == pytest.approx(
            expected, rel=1e-4)  # 5 significant digits of the textbook constant
    assert flows.isentropic_mass_flux(p0, T0, p0, GAMMA, R_AIR) == 0.0


def test_nozzle_flux_at_low_pressure_drop_is_bernoulli():
    p0, T0, dp = 1e5, 300.0, 10.0
    rho = p0 / (R_AIR * T0)
    bernoulli = rho * math.sqrt(2 * dp / rho)
    # Compressibility corrections are O(dp/p0) = 1e-4.
    assert flows.isentropic_mass_flux(p0, T0, p0 - dp, GAMMA, R_AIR) == pytest.approx(
        bernoulli, rel=3e-4)
