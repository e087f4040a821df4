"""Mass flux through a restriction between two gas states (per unit flow area).

Both models give the flux from the high-pressure side "1" to the low-pressure side "2"
as sqrt(p1 rho1) * f(x) with x = p2/p1 <= 1, so that one vectorised call serves any
pair of states (the caller puts the sign on it).

Isentropic nozzle, seed 001 Eqs. 7-8 (the paper prints a "+" inside the root of Eq. 7
and drops T1 from Eq. 8; the standard forms are used here):

    f = sqrt(2k/(k-1) * (x^(2/k) - x^((k+1)/k)))          x >= x_cr = (2/(k+1))^(k/(k-1))
    f = sqrt(k * (2/(k+1))^((k+1)/(k-1)))                  x <  x_cr   (choked)

Isothermal flow with friction, seed 003 Eq. 9 (a^2 = R T1 = p1/rho1):

    f = sqrt((1 - x^2) / (zeta - 2 ln x))                  x >= x*
    f = f(x*)                                              x <  x*      (choked)

where x* is the pressure ratio of maximum flow, 1 - x*^2 = x*^2 (zeta - 2 ln x*); below
it Eq. 9 would predict *less* flow for a lower back pressure, which is the isothermal
choking limit.

Both f have an infinite slope at x -> 1 (f ~ sqrt(1 - x)), which would make two
chambers at nearly equal pressure an infinitely stiff pair.  The pressure drop
y = 1 - x is therefore replaced by y_eff = y^2 / sqrt(y^2 + DELTA_X^2): smooth, equal to
y to within DELTA_X^2 / (2 y^2) for y >> DELTA_X, and y^2 / DELTA_X near zero, where the
flux becomes linear in the pressure difference (slope sqrt(2 / DELTA_X)).  A kinked
linear band would serve the physics as well but not the integrators: the port flows of
a filling chamber sit right at such small pressure drops, and a kink there makes every
error estimator take tiny steps.

Real fluids, two-phase states included: k is the upstream state's isentropic exponent
k = rho a^2 / p with the sound speed of the homogeneous equilibrium mixture inside the
dome (HEM; Wallis 1969, *One-dimensional two-phase flow*, ch. 2; tabulated by
:mod:`.coolprop_table`).  The formula then stands for the HEM nozzle with the isentrope
p v^k = const fitted at the upstream state: for R134a from superheat to quality 0.5
(3 and 9 bar) it is within 1.2 % of the exact equilibrium isentrope integrated with
CoolProp (tests/test_quasi1d_real_fluid.py).  The HEM k falls through 1 near the
saturation line (0.98 for saturated R134a vapour at 9 bar): at k = 1 the formula is the
isothermal limit, and k within K_ONE_GAP of 1 is moved to that distance, where the
formula still cancels only to ~1e-10 and the flux moves by < 1e-6.

The nozzle formula itself, unsmoothed, is :func:`nozzle_psi`; the CFD cases and the
leakage analysis use it through :func:`isentropic_mass_flux` (the ideal flow of a gap).
"""

from __future__ import annotations

import functools
import math

import numpy as np

# Smoothing of the pressure drop near zero (see module docstring).  1e-4: the flow it
# changes is below 1.5 % of the choked flux, and a relative pressure difference of 1e-4
# is below the tolerance of any figure this model reports.
DELTA_X = 1.0e-4
_D2 = DELTA_X * DELTA_X
# Distance from k = 1 below which k is moved to it (see the module docstring).
K_ONE_GAP = 1.0e-6


# The functions below that the compiled right-hand side calls (:mod:`.compiled`) take
# arrays or scalars alike: numpy runs them on whole arrays, numba inside loops over the
# batch and the flows, one element at a time (no temporaries).  So they are written
# without np.where: a choice between two values is :func:`select`.


def select(cond, a, b):
    """np.where(cond, a, b); compiled, on scalars, the plain conditional (numba's np.where
    returns an array even for scalars; see :mod:`.compiled`)."""
    return np.where(cond, a, b)


def _x_eff(x):
    y = 1.0 - x
    return 1.0 - y * y / np.sqrt(y * y + _D2)


def nozzle_critical_ratio(k):
    return (2.0 / (k + 1.0)) ** (k / (k - 1.0))


def nozzle_psi(x, k):
    """The isentropic nozzle's flux over sqrt(p1 rho1) for x = p2/p1 in [0, 1] (arrays or
    scalars): Eqs. 7-8, choked below the critical ratio; not smoothed at x -> 1."""
    if np.ndim(k):
        return _psi_k(x, k)
    return _psi(x, *_nozzle_constants(float(k)))


def _psi_k(x, k):
    """nozzle_psi for an array of exponents k (plain numpy, compiled by :mod:`.compiled`)."""
    xc, c, ik = nozzle_constants(k)
    return _psi(x, xc, c, ik)


def nozzle_constants(k):
    """(critical ratio, 2k / (k - 1), 1 / k) of :func:`_psi` for exponents k (an array or
    a scalar; per node: the flows gather them, one power per node instead of per flow)."""
    # HEM two-phase exponents pass through 1 (module docstring)
    k = select(np.abs(k - 1.0) < K_ONE_GAP, 1.0 + np.copysign(K_ONE_GAP, k - 1.0), k)
    return nozzle_critical_ratio(k), 2.0 * k / (k - 1.0), 1.0 / k


def _psi(x, xc, c, ik):
    xe = np.maximum(x, xc)
    r = xe**ik  # x^(2/k) - x^((k+1)/k) = r (r - x): one power instead of two
    return np.sqrt(c * r * (r - xe))


def nozzle_f(x, k):
    """Dimensionless nozzle flux f(x, k) of the chamber model: :func:`nozzle_psi` with the
    pressure drop smoothed near x = 1 (see the module docstring)."""
    return nozzle_psi(_x_eff(x), k)


def nozzle_f_c(x, xc, c, ik):
    """:func:`nozzle_f` from the exponent's :func:`nozzle_constants` (arrays like x, or
    scalars)."""
    return _psi(_x_eff(x), xc, c, ik)


def isentropic_mass_flux(p0: float, T0: float, p: float, gamma: float, R: float) -> float:
    """Mass flux (kg/s/m^2) of an isentropic nozzle from rest at p0, T0 of a perfect gas
    (gamma, R) to the pressure p; choked below the critical pressure."""
    return float(nozzle_psi(p / p0, gamma)) * math.sqrt(p0 * p0 / (R * T0))


@functools.lru_cache(maxsize=64)
def _nozzle_constants(k: float):
    return nozzle_critical_ratio(k), 2.0 * k / (k - 1.0), 1.0 / k


def fanno_choke_ratio(zeta: float) -> float:
    """x* solving 1 - x^2 = x^2 (zeta - 2 ln x): the back-pressure ratio of maximum flow."""
    from scipy.optimize import brentq

    def g(x):
        return 1.0 - x * x - x * x * (zeta - 2.0 * math.log(x))

    return brentq(g, 1e-12, 1.0 - 1e-15)


def fanno_f(x, zeta: float, x_choke: float):
    """Dimensionless isothermal-friction flux for x = p2/p1 in [0, 1]."""
    xe = np.maximum(_x_eff(x), x_choke)
    return np.sqrt((1.0 - xe * xe) / (zeta - 2.0 * np.log(xe)))


def signed_flux(pa, ra, ka, pb, rb, kb, model: str, zeta: float = 2.0, x_choke: float = 0.0):
    """Mass flux per unit area from state a to state b (negative: from b to a)."""
    fwd = pa >= pb
    p1 = np.where(fwd, pa, pb)
    p2 = np.where(fwd, pb, pa)
    r1 = np.where(fwd, ra, rb)
    x = p2 / p1
    if model == "fanno":
        f = fanno_f(x, zeta, x_choke)
    else:
        k1 = np.where(fwd, ka, kb) if np.ndim(ka) or np.ndim(kb) else ka
        f = nozzle_f(x, k1)
    g = np.sqrt(p1 * r1) * f
    return np.where(fwd, g, -g)
