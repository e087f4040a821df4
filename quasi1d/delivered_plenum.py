"""A discharge plenum holding the delivered gas (``[ports] discharge_plenum =
"delivered"``).

The chambers push gas into the discharge plenum and take some back (the backflow when
the port opens onto a chamber below the discharge pressure, the leakage from the
discharge side).  By default the plenum holds a fixed state, the isentropic end of the
pressure ratio (:mod:`.plenums`), and the delivered enthalpy is what the chambers push
out less what flows back at that state.  Where the backflow is large against the
delivery (a vacuum pump: 38 times at 0.01 bar) the difference amplifies any mismatch
between the fixed state and the gas the chambers deliver, and the delivered temperature
comes out beyond every chamber's (-687 K on the trochoidal pump example;
:data:`.result.DISCHARGE_T_SLACK`).

A well-mixed plenum holds what it is given: here its temperature T is found so that
the delivered gas's enthalpy is the plenum's own, h_delivered(T) = h(p_d, T), by Brent's
method, one cycle solve per iterate (as PDSim iterates its outlet state).  Between the
suction's temperature (a colder plenum: the backflow cools the chambers, the delivered
enthalpy exceeds the plenum's) and the chambers' hottest (a hotter one: the opposite)
the difference changes sign.  A dry gas only: an oil-flooded plenum is set by the oil
(:func:`.oil.flooded_discharge_T`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rotorflow.errors import CaseError

from .network import ACC_H_DIS, ACC_M_DIS
from .plenums import discharge_dew

#: Tolerance of the plenum's temperature [K].
T_TOL = 0.01
#: Cycle solves at most, the bracket's included.
MAX_SOLVES = 30
#: Factor by which the upper bracket grows while the difference keeps its sign.
WIDEN = 1.5
#: A condensable gas's plenum is kept this far above its dew point [K].
DEW_MARGIN_K = 0.5


def settle(build, solve, model, sol):
    """(model, solution) with the discharge plenum at the delivered state, starting from
    ``model`` and its solution ``sol`` (isentropic plenum); ``build(T)`` makes the model
    with the plenum at T, ``solve(model)`` solves its cycle.  Unchanged where nothing is
    delivered (no delivered state to hold)."""
    from scipy.optimize import brentq

    if not _delivered(model, sol):
        return model, sol
    fluid, p_d = model.fluid, model.op.p_discharge_Pa
    runs = {}

    def gap(T):
        if T not in runs:  # (Brent evaluates its bracket's ends again)
            if len(runs) >= MAX_SOLVES:
                raise CaseError(f"the discharge plenum's delivered state not found in "
                                f"{MAX_SOLVES} cycle solves")
            m = build(T)
            s = solve(m)
            if not (s.converged and _delivered(m, s)):
                why = "did not converge" if not s.converged else "delivers nothing"
                raise CaseError(f"with the discharge plenum at {T:.1f} K the cycle {why}: "
                                f"no delivered state found ([ports] discharge_plenum)")
            a = m.acc(s.run.y[0])
            runs[T] = (m, s, a[ACC_H_DIS] / a[ACC_M_DIS] - fluid.state_pT(p_d, T)[2])
        return runs[T][2]

    coldest, hottest = _range(model, sol)
    lo, hi = min(model.suc.T, coldest), max(hottest, model.dis.T)
    dew = discharge_dew(fluid, model.op)
    if dew is not None:  # (below it the plenum would hold liquid, not the delivered gas)
        lo, hi = max(lo, dew + DEW_MARGIN_K), max(hi, dew + 2.0 * DEW_MARGIN_K)
    if gap(lo) < 0.0:
        raise CaseError("the delivered gas is colder than a discharge plenum at "
                        f"{lo:.1f} K (the coldest chamber's, or the dew point's): no "
                        "delivered state found ([ports] discharge_plenum)")
    # (a real fluid's table ends at its hottest state: a bracket widened past it filled the
    # chambers with gas off the table, ammonia 3 -> 12 bar from 454 K to 681 K, where the
    # plenum's state is near 553 K)
    cap = fluid.T_hottest(p_d) if hasattr(fluid, "T_hottest") else math.inf
    while gap(hi) > 0.0:
        if hi >= cap:
            raise CaseError(f"the delivered gas is hotter than the hottest discharge plenum "
                            f"the fluid's table holds ({cap:.1f} K): no delivered state "
                            "found ([ports] discharge_plenum)")
        hi = min(hi * WIDEN, cap)
    T = brentq(gap, lo, hi, xtol=T_TOL, maxiter=MAX_SOLVES)
    m, s, _ = runs[min(runs, key=lambda t: abs(t - T))]
    return m, s


def check(op, ports) -> None:
    """A plenum at the delivered state needs a dry gas (no oil injected, no liquid
    drawn in)."""
    if ports.discharge_plenum == "delivered" and (op.gas_volume_fraction < 1.0
                                                  or op.oil_mass_ratio > 0.0):
        raise CaseError('[ports] discharge_plenum = "delivered" takes a dry gas: with oil '
                        "or a liquid drawn in, the plenum's state is the mixture's")


def _delivered(model, sol) -> bool:
    return bool(model.acc(sol.run.y[0])[ACC_M_DIS] > 0.0)


def _range(model, sol) -> tuple[float, float]:
    """The coldest and the hottest chamber's temperature over the solved cycle."""
    from .result import traces

    T = traces(sol)[1]["T_K"]
    return (float(np.min(T)), float(np.max(T))) if len(T) else (model.suc.T, model.dis.T)


def plenum_ports(ports, T):
    """``ports`` with the plenum held at T (what :func:`settle`'s ``build`` passes)."""
    return replace(ports, discharge_plenum_K=float(T))
