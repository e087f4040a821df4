"""One pass of the chamber model without cycle convergence (quasi1d.simulate_transient).

On the analytic sin^2 table of CRC.60 size (rotorflow.quasi1d.synthetic).  The CFD
chamber comparison's single chamber is tested in test_cfd_chamber.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate, simulate_transient
from rotorflow.quasi1d.synthetic import sin2_table

#: Tight tolerances for both runs, so that their different step sequences agree far
#: below the cycle's own convergence (1e-6).
TIGHT = Numerics(rtol=1e-8, atol=1e-10, cycle_rtol=1e-8, balance_tol=1e-9)


@pytest.fixture(scope="module")
def table():
    return sin2_table(rows=721)


def _op() -> Operating:
    return Operating.from_section({"p_suction_bar": 1.0, "p_discharge_bar": 4.0,
                                   "T_suction_K": 300.0, "speed_rpm": 3000.0,
                                   "volume_ratio": 3.0, "heat_capacity": "constant"}, "test")


def test_one_pass_from_the_periodic_state_returns_to_it(table):
    leakage, ports = Leakage(gap_m=30e-6, model="nozzle", coefficient=0.8), Ports("ideal")
    cycle = simulate(table, _op(), leakage, ports, TIGHT)
    assert cycle.converged
    model = cycle.solution.model
    geo = model.geo
    angles = geo.birth + geo.period * np.array([0.0, 0.25, 0.5, 1.0])
    res = simulate_transient(table, _op(), angles, leakage, ports, TIGHT,
                             y0=cycle.solution.y_start)
    assert res.p_Pa.shape == (4, model.n)
    # The period's end state (before the slots shift) is the cycle's, whose shift is the
    # start again: the same equations and integrator, only the cycle iteration left out.
    # Masses and energies to 1e-6 of a full chamber's (a dying chamber's few micrograms
    # differ by 4e-6 of their own: the converged cycle replays a frozen step sequence).
    n = model.n
    for block in (slice(0, n), slice(n, 2 * n)):
        mine, cycles = res.y[-1, block], cycle.solution.run.y[0, block]
        np.testing.assert_allclose(mine, cycles, rtol=1e-6, atol=1e-6 * np.max(cycles))
    # Shifted, the end is the start again (slot 0 is born at the start, so not compared).
    p_next = model.observe(geo.birth, model.shift(res.y[-1]))[2]
    np.testing.assert_allclose(p_next[1:], res.p_Pa[0, 1:], rtol=1e-6)
    # At the start the newborn chamber holds the suction state.
    assert res.p_Pa[0, 0] == pytest.approx(1e5, rel=1e-12)


def test_more_output_angles_change_no_state(table):
    # The period is cut at the output angles, which are not events: asking for more of
    # them changes the step sequence, not the equations, so the states agree to the
    # integrator's tolerance.
    leakage, ports = Leakage(gap_m=30e-6, model="fanno"), Ports("ideal")
    few = np.array([0.3, 1.1, 2.0])
    many = np.union1d(few, np.linspace(0.1, 2.1, 41))
    a = simulate_transient(table, _op(), few, leakage, ports, TIGHT)
    b = simulate_transient(table, _op(), many, leakage, ports, TIGHT)
    rows = np.searchsorted(many, few)
    np.testing.assert_array_equal(b.angle_rad[rows], few)
    np.testing.assert_allclose(b.p_Pa[rows], a.p_Pa, rtol=1e-6)
    slots = slice(0, b.model.nv * b.model.n)  # the accumulators: see the cycle's tests
    np.testing.assert_allclose(b.y[rows, slots], a.y[:, slots], rtol=1e-6)


def test_bad_angles_and_states_are_refused(table):
    with pytest.raises(CaseError, match="within the lobe period"):
        simulate_transient(table, _op(), [7.0], Leakage(model="none"))
    with pytest.raises(CaseError, match="non-empty"):
        simulate_transient(table, _op(), [], Leakage(model="none"))
    with pytest.raises(CaseError, match="state values"):
        simulate_transient(table, _op(), [0.5], Leakage(model="none"), y0=np.zeros(3))
