"""The chamber model over a converged cycle: ideal limits, analytic checks, conservation.

All on analytic sin^2 chamber tables (rotorflow.quasi1d.synthetic) of CRC.60 size:
V_max 30 cc, 3 lobes, volume maximum at 220 deg, death at 907 deg.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
from rotorflow.quasi1d.fluids import DRY_AIR_R
from rotorflow.quasi1d.synthetic import scaled_table, sin2_table

GAMMA = 1006.43 / (1006.43 - 8.314462618 / 0.02897)  # perfect-gas "air" of seed 001
EPS_V = 4.6


@pytest.fixture(scope="module")
def table():
    return sin2_table(rows=721)


def _op(**kw):
    d = {"p_suction_bar": 1.0, "p_discharge_bar": 8.0, "T_suction_K": 300.0,
         "speed_rpm": 3000.0, "volume_ratio": EPS_V}
    d.update(kw)
    return Operating.from_section(d, "test")


def _perfect_op(**kw):
    """Seed 001's air with constant cp, for the closed forms of a perfect gas."""
    d = {"p_suction_bar": 1.0, "p_discharge_bar": 8.0, "T_suction_K": 300.0,
         "speed_rpm": 3000.0, "volume_ratio": EPS_V, "heat_capacity": "constant"}
    d.update(kw)
    return Operating.from_section(d, "test")


def _work_per_chamber(res):
    geo = res.solution.model.geo
    return res.figures["indicated_power_W"] * geo.period / geo.omega_outer


def _eq17(p_suc, p_dis, v_max):
    """seed 000 Eq. 17: work per cycle with matched, loss-free compression."""
    return GAMMA / (GAMMA - 1.0) * (p_dis * v_max / EPS_V - p_suc * v_max)


def test_ideal_cycle_work_equals_eq17(table):
    p_dis = EPS_V**GAMMA  # bar: matched, the chamber reaches p_dis as the port opens
    res = simulate(table, _perfect_op(p_discharge_bar=p_dis), Leakage(model="none"),
                   Ports("ideal"))
    assert res.converged
    w = _work_per_chamber(res)
    v_max = res.solution.model.geo.v_trapped
    exact = _eq17(1e5, p_dis * 1e5, v_max)
    # the issue asks for 0.1 % at the default tolerance (rtol 1e-4 gives ~2e-5) ...
    assert abs(w / exact - 1.0) < 1e-3
    # ... and the difference is integration error only: it shrinks with the tolerance
    tight = simulate(table, _perfect_op(p_discharge_bar=p_dis), Leakage(model="none"),
                     Ports("ideal"), Numerics(rtol=1e-8, atol=1e-10))
    assert abs(_work_per_chamber(tight) / exact - 1.0) < 1e-6
    # a 1 % mismatch of the discharge pressure moves the work by more than the test
    # resolves, so the comparison is not one that passes everything
    off = _eq17(1e5, 1.01 * p_dis * 1e5, v_max)
    assert abs(w / off - 1.0) > 1e-3
    # no leakage, lossless ports: every trapped volume is delivered (to the tolerance)
    assert abs(tight.figures["volumetric_efficiency"] - 1.0) < 1e-6
    assert abs(tight.figures["adiabatic_efficiency"] - 1.0) < 1e-6


def test_closed_chamber_compresses_adiabatically(table):
    res = simulate(table, _perfect_op(), Leakage(model="none"), Ports("ideal"),
                   Numerics(rtol=1e-8, atol=1e-10))
    geo = res.solution.model.geo
    c = res.chamber
    a = c["angle_rad"]
    closed = (a > geo.suction_close + 1e-9) & (a < geo.discharge_open - 1e-9)
    assert closed.sum() > 5
    pv = c["p_Pa"][closed] * c["volume_m3"][closed] ** GAMMA
    ref = 1e5 * geo.v_trapped**GAMMA
    # isentropic p V^gamma = const to the integration error: a global error, some ten
    # times the step tolerance (1.1e-6 at rtol 1e-7 with the max norm), hence rtol 1e-8
    assert np.max(np.abs(pv / ref - 1.0)) < 1e-6
    # mass is trapped: m constant between closing and opening
    m = c["m_kg"][closed]
    assert np.ptp(m) / m.mean() < 1e-12
    # suction phase at the plenum pressure (ideal port), discharge phase at p_dis
    suction = c["angle_rad"] < geo.suction_close - 1e-9
    assert np.max(np.abs(c["p_Pa"][suction] / 1e5 - 1.0)) < 1e-6
    dis = c["angle_rad"] > geo.discharge_open + 1e-9
    assert np.max(np.abs(c["p_Pa"][dis] / 8e5 - 1.0)) < 1e-6


@pytest.mark.parametrize(
    "leak, ports, extra",
    [
        (Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5), Ports("ideal"), {}),
        # nozzle ports make the equations stiff (ros23); a port coefficient of 0.3 keeps
        # the port pressure drop resolvable at the default tolerance and the test short
        (Leakage(gap_m=20e-6, model="fanno", coefficient=1.0, wall_motion=True),
         Ports("nozzle", 0.3), {}),
        (Leakage(gap_m=10e-6, model="nozzle"), Ports("ideal"),
         {"heat_transfer_W_m2K": 200.0, "T_wall_K": 330.0, "oil_mass_ratio": 2.0,
          "T_oil_K": 320.0}),
    ],
    ids=["nozzle-ideal", "fanno-nozzle-wall", "oil-heat"],
)
def test_cycle_balances_close(table, leak, ports, extra):
    num = Numerics()
    res = simulate(table, _op(**extra), leak, ports, num)
    f = res.summary()
    assert res.converged, f.get("message")
    # issue 3: a converged cycle closes mass to 1e-6 of throughput, energy to 1e-6 of work
    assert f["mass_balance_error"] < 1e-6
    assert f["energy_balance_error"] < 1e-6
    # (m, U) states make mass and energy linear invariants of the Runge-Kutta steps and
    # every event books what it moves: conservation holds to round-off
    assert res.solution.conservation_mass < 1e-11
    assert res.solution.conservation_energy < 1e-11
    assert 0 < f["volumetric_efficiency"] < 1
    assert all(v >= 0 for v in f["leakage_kg_s"].values())
    json.dumps(f, allow_nan=False)


def test_oil_cools_the_discharge(table):
    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    dry = simulate(table, _op(), leak).figures
    wet = simulate(table, _op(oil_mass_ratio=3.0, T_oil_K=310.0), leak).figures
    # 3 kg of oil at cp 1900 per kg of air at cp 1006: the gas ends far cooler
    assert wet["discharge_temperature_K"] < dry["discharge_temperature_K"] - 100.0
    # With leakage the oil (3 kg per kg of gas trapped at suction closing, less the oil
    # leaking into the suction plenum) is not 3 kg per kg delivered: gas leaks into the
    # chamber before it closes and oil leaks out with it (measured 3.015 here); 10 % only
    # says the oil is injected at the stated ratio at all.
    assert wet["oil_flow_kg_s"] == pytest.approx(3.0 * wet["mass_flow_kg_s"], rel=0.1)
    # Without leakage the gas trapped is the gas drawn in and delivered, and the oil
    # supplied is exactly 3 times it (mass conservation; the cycle closes to 1e-6, its
    # Runge-Kutta steps to round-off: 4e-16 measured).
    sealed = simulate(table, _op(oil_mass_ratio=3.0, T_oil_K=310.0), Leakage(model="none"))
    assert sealed.figures["oil_flow_kg_s"] == pytest.approx(
        3.0 * sealed.figures["mass_flow_kg_s"], rel=1e-9)


def test_leakage_grows_with_the_gap(table):
    etas = []
    for gap in (1e-6, 5e-6, 20e-6):
        f = simulate(table, _op(), Leakage(gap_m=gap, model="nozzle")).figures
        etas.append(f["volumetric_efficiency"])
    assert etas[0] > etas[1] > etas[2]
    # a 1 um gap leaks little: within 2 % of the leak-free delivery
    assert etas[0] > 0.98


def test_tiny_gap_tends_to_the_leak_free_cycle(table):
    free = simulate(table, _op(), Leakage(model="none")).figures
    tiny = simulate(table, _op(), Leakage(gap_m=1e-9, model="nozzle")).figures
    for key in ("mass_flow_kg_s", "indicated_power_W"):
        assert tiny[key] == pytest.approx(free[key], rel=1e-4)


def test_newton_and_plain_iteration_find_the_same_cycle(table):
    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    # rtol 1e-7: the two integrate their last period by other step sequences, so their
    # figures differ by the integration error of the power accumulator (2e-5 at rtol
    # 5e-4 and 1e-5, 1e-6 at 1e-7), which must sit below the 1e-5 compared here
    a = simulate(table, _op(), leak, numerics=Numerics(newton=True, rtol=1e-7))
    b = simulate(table, _op(), leak, numerics=Numerics(newton=False, max_cycles=200, rtol=1e-7))
    assert a.converged and b.converged
    assert a.figures["cycles"] < b.figures["cycles"]
    for key in ("mass_flow_kg_s", "indicated_power_W", "discharge_temperature_K"):
        assert a.figures[key] == pytest.approx(b.figures[key], rel=1e-5)


def test_chord_periods_find_the_newton_cycle(table, monkeypatch):
    """Chord periods (the state alone, the last batch's Jacobian) converge to the fixed
    point that Newton's method with a fresh Jacobian every period finds, in fewer
    batched periods; the figures agree to the cycle tolerance's effect (1e-6 on p, T
    and the balances; 1e-5 compared, as above, for the last period's step sequences)."""
    from rotorflow.quasi1d import cycle

    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    batches = []
    integrate = cycle.integrate_period

    def counting(model, y0, *args, **kw):
        batches.append(y0.shape[0] > 1)
        return integrate(model, y0, *args, **kw)

    monkeypatch.setattr(cycle, "integrate_period", counting)
    a = simulate(table, _op(), leak, numerics=Numerics(rtol=1e-7))
    chord_batches = sum(batches)
    batches.clear()
    monkeypatch.setattr(cycle, "CHORD_BELOW", 0.0)
    b = simulate(table, _op(), leak, numerics=Numerics(rtol=1e-7))
    assert a.converged and b.converged
    assert chord_batches < sum(batches)
    for key in ("mass_flow_kg_s", "indicated_power_W", "discharge_temperature_K"):
        assert a.figures[key] == pytest.approx(b.figures[key], rel=1e-5)


def test_explicit_and_implicit_integrators_agree(table):
    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    ref = simulate(table, _op(), leak, numerics=Numerics(integrator="radau", rtol=1e-6,
                                                          atol=1e-8)).figures
    for integ in ("dopri5", "bs3"):
        f = simulate(table, _op(), leak, numerics=Numerics(integrator=integ, rtol=1e-6,
                                                           atol=1e-8)).figures
        for key in ("mass_flow_kg_s", "indicated_power_W"):
            # both solve the same equations to rtol 1e-6 per step
            assert f[key] == pytest.approx(ref[key], rel=2e-5)


def test_ideal_gas_and_coolprop_air_agree():
    # CRC.60 conditions (seed 001 Table 3) with moderate leakage: dry air's cp(T) and
    # CoolProp's real-gas air differ only by compressibility (Z - 1 < 0.3 % at 8 bar)
    table = sin2_table(rows=601)
    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.3)
    ideal = simulate(table, _op(speed_rpm=3000.0), leak).figures
    real = simulate(table, _op(speed_rpm=3000.0, fluid="CoolProp::Air"), leak).figures
    for key in ("mass_flow_kg_s", "suction_volume_flow_L_min", "indicated_power_W",
                "volumetric_efficiency"):
        assert real[key] == pytest.approx(ideal[key], rel=5e-3), key


@pytest.mark.parametrize("lobes", [3, 5, 7])
def test_other_lobe_counts_and_sizes(lobes):
    table = scaled_table(v_max=1e-4, lobes=lobes)
    res = simulate(table, _op(p_discharge_bar=4.0, volume_ratio=3.0),
                   Leakage(gap_m=20e-6, model="nozzle"), Ports("ideal"))
    assert res.converged, res.figures.get("message")
    assert res.figures["mass_balance_error"] < 1e-6
    assert res.figures["chambers"] == res.solution.model.geo.slots
    assert 0.5 < res.figures["volumetric_efficiency"] < 1.0


def test_traces_and_plots(table, tmp_path):
    res = simulate(table, _op(), Leakage(gap_m=5e-6, model="nozzle"))
    paths = res.write_traces(tmp_path)
    one = np.genfromtxt(paths[0], delimiter=",", names=True)
    assert set(one.dtype.names) == {"angle_rad", "volume_m3", "p_Pa", "T_K", "m_kg"}
    assert np.all(np.diff(one["angle_rad"]) >= 0)
    geo = res.solution.model.geo
    assert one["angle_rad"][0] == pytest.approx(geo.birth)
    assert one["angle_rad"][-1] == pytest.approx(geo.death, rel=1e-9)
    assert np.all(one["p_Pa"] > 0) and np.all(one["T_K"] > 0) and np.all(one["m_kg"] > 0)
    allc = np.genfromtxt(paths[1], delimiter=",", names=True)
    assert "p_Pa_0" in allc.dtype.names and f"p_Pa_{res.solution.model.n - 1}" in allc.dtype.names
    pngs = res.plot(tmp_path)
    assert all(p.stat().st_size > 1000 for p in pngs)


def test_summary_has_the_issue_keys(table):
    f = simulate(table, _op(), Leakage(gap_m=5e-6, model="nozzle")).summary()
    for key in ("mass_flow_kg_s", "suction_volume_flow_L_min", "indicated_power_W",
                "specific_power_J_kg", "volumetric_efficiency", "adiabatic_efficiency",
                "discharge_temperature_K", "cycles", "mass_balance_error",
                "energy_balance_error"):
        assert key in f
    # suction volume flow is mass flow over suction density, in L/min
    rho = 1e5 / (DRY_AIR_R * 300.0)
    assert f["suction_volume_flow_L_min"] == pytest.approx(f["mass_flow_kg_s"] / rho * 6e4)
    assert f["specific_power_J_kg"] == pytest.approx(f["indicated_power_W"] / f["mass_flow_kg_s"])
    assert math.isfinite(f["isothermal_efficiency"])
    assert f["isothermal_efficiency"] < f["adiabatic_efficiency"]


def test_heat_flows_from_the_hotter_side(table):
    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    cold = simulate(table, _op(heat_transfer_W_m2K=500.0, T_wall_K=300.0), leak).figures
    hot = simulate(table, _op(heat_transfer_W_m2K=500.0, T_wall_K=700.0), leak).figures
    # a wall at suction temperature cools the compressed gas; a 700 K wall heats it
    assert cold["heat_to_gas_W"] < 0 < hot["heat_to_gas_W"]
    assert hot["discharge_temperature_K"] > cold["discharge_temperature_K"]
    assert hot["energy_balance_error"] < 1e-6 and cold["energy_balance_error"] < 1e-6


def test_a_cycle_that_runs_out_of_periods_says_so(table):
    res = simulate(table, _op(), Leakage(gap_m=20e-6, model="nozzle"),
                   numerics=Numerics(max_cycles=1))
    f = res.summary()
    assert not res.converged and f["converged"] is False
    assert "not converged after 1 periods" in f["message"]
    assert "\n" not in f["message"]


def test_time_budget_holds_inside_the_first_period(table):
    # The budget was read only between periods: a stiff first period (a wet pentane pump,
    # 200,000 steps of ros23) ran 8.7 min against a 60-s budget.  Now the clock is read
    # between segments and every CLOCK_STEPS steps, and a first period that runs out has
    # no state to return: it is an error naming the budget.
    from rotorflow.quasi1d.integrate import OverTime

    with pytest.raises(OverTime, match=r"max_seconds\) in the first period"):
        simulate(table, _op(), numerics=Numerics(max_seconds=1e-6))


def test_an_event_that_leaves_no_finite_state_is_an_error_naming_it(table, monkeypatch):
    # A dying chamber whose state the fluid cannot evaluate (a wet pentane pump under
    # scipy's Radau: the chamber died full of liquid at negative mass, its pressure NaN)
    # went into the next segment as NaN and ended in scipy's traceback ("y0 must be
    # finite"); now the event that made it is named.
    from rotorflow.quasi1d import events
    from rotorflow.quasi1d.integrate import IntegrationError

    def poisoned(model, kind, k, theta, y):
        real(model, kind, k, theta, y)
        if kind == "death":
            y[:, model.nv * model.n:] = np.nan

    real = events.apply_event
    monkeypatch.setattr(events, "apply_event", poisoned)
    with pytest.raises(IntegrationError, match=r"the death of slot \d+ at [\d.]+ rad left a "
                                               r"state that is not finite"):
        simulate(table, _op())


def test_a_newton_iterate_whose_period_leaves_the_fluid_is_rejected_not_fatal(table,
                                                                            monkeypatch):
    # cycle_states.rejected: a damped Newton iterate whose period ends outside the fluid's
    # table (a wet pentane chamber filled past the table's densest liquid) is an iterate
    # whose residual grew: Newton halves its step from the best iterate and goes on to
    # the same fixed point (figures to the 1e-5 of the tests above); a failure in the
    # first period, which has no iterate to retreat to, stays fatal.
    from rotorflow.quasi1d import cycle_states
    from rotorflow.quasi1d.integrate import IntegrationError

    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    num = Numerics(rtol=1e-7)
    clean = simulate(table, _op(), leak, numerics=num)
    assert clean.converged and clean.figures["cycles"] >= 3
    real, checks = cycle_states.check_states, []

    def failing_at(period):
        def check(model, y):
            checks.append(1)
            if len(checks) == period:
                raise IntegrationError("chamber state left the range of the fluid's table")
            real(model, y)
        return check

    monkeypatch.setattr(cycle_states, "check_states", failing_at(2))
    hit = simulate(table, _op(), leak, numerics=num)
    assert hit.converged and hit.figures["cycles"] > clean.figures["cycles"]
    for key in ("mass_flow_kg_s", "indicated_power_W", "discharge_temperature_K"):
        assert hit.figures[key] == pytest.approx(clean.figures[key], rel=1e-5)
    checks.clear()
    monkeypatch.setattr(cycle_states, "check_states", failing_at(1))
    with pytest.raises(IntegrationError, match="left the range"):
        simulate(table, _op(), leak, numerics=num)


def test_an_implicit_solver_that_ends_at_negative_mass_is_an_error(table, monkeypatch):
    # scipy's Radau accepted a wet pentane pump's chamber at -3 kg (its trial states are
    # kept finite, not physical); a segment that ends so is a failed integration, named
    # at once (not only by the cycle's check of the period's end state).
    import scipy.integrate

    from rotorflow.quasi1d.integrate import IntegrationError

    real = scipy.integrate.solve_ivp

    def negative(*args, **kw):
        sol = real(*args, **kw)
        sol.y[0, -1] = -1e-3  # slot 0's mass, kg (the chamber holds ~3e-5 kg)
        return sol

    monkeypatch.setattr(scipy.integrate, "solve_ivp", negative)
    with pytest.raises(IntegrationError, match=r"radau left a chamber with negative mass "
                                               r"between [\d.]+ and [\d.]+ rad"):
        simulate(table, _op(), numerics=Numerics(integrator="radau", max_cycles=1))


def test_chord_periods_go_on_while_they_reach_the_gain_sooner_than_a_batch():
    """cycle._chord_pays: a chord period that cut the residual 2x is worth repeating when
    a batch costs more than the log(0.1) / log(0.5) = 3.3 chord periods that reach
    CHORD_GAIN (the humid stress point: batch 15 s, chord 0.7 s), not when it costs
    less; one that reached CHORD_GAIN always is, one that did not gain never."""
    from rotorflow.quasi1d import cycle

    assert cycle._chord_pays(0.05, [1.0, 10.0])
    assert cycle._chord_pays(0.5, [15.0, 0.7])
    assert not cycle._chord_pays(0.5, [2.0, 0.7])  # 3.3 x 0.7 = 2.3 s > 2 s
    assert cycle._chord_pays(0.5, [2.4, 0.7])
    assert not cycle._chord_pays(1.0, [1e9, 1e-9])
    assert not cycle._chord_pays(float("nan"), [1e9, 1e-9])


def test_the_damping_newton_keeps_is_the_step_it_took(monkeypatch):
    # cycle._damped shrinks a Newton step until the iterate is physical; the damping it
    # returns is the one taken, so that a failure halves from the step that ran (from the
    # one asked, three halvings of a wet n-pentane pump ran the same fallback iterate).
    from rotorflow.quasi1d import cycle

    monkeypatch.setattr(cycle, "plausible", lambda model, z: z[1] < 0.3)
    z, step, successor = np.zeros(2), np.array([1.0]), np.array([0.0, 0.1])
    best = (1.0, z, None, step, successor, None)
    idx = np.array([1])
    for lam in (1.0, 0.5, 0.25):
        cand, taken = cycle._damped(None, best, idx, lam)
        assert cand[1] < 0.3 and cand[1] == pytest.approx(taken * step[0])
        assert taken <= lam
    cand, taken = cycle._damped(None, best, idx, 4.0)  # nothing physical: the successor
    assert cand is successor and taken == 1.0
