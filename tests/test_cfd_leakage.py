"""Leakage models, the CFD comparison table and the fitted flow coefficient (plain tier)."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from rotorflow.postprocess import leakage, leakage_report
from rotorflow.postprocess.leakage import LeakagePoint
from rotorflow.quasi1d import calibrated

R_AIR, GAMMA = 287.05, 1.4


def point(name="p", gap=50e-6, length=1e-3, pr=2.0, mass_flow=math.nan, mu=1.85e-5,
          wall=0.0):
    return LeakagePoint(name=name, gap_m=gap, length_m=length, p_up_Pa=1e5 * pr, T_up_K=300.0,
                        p_down_Pa=1e5, mu_Pa_s=mu, R_J_kgK=R_AIR, gamma=GAMMA,
                        wall_speed_m_s=wall, mass_flow_kg_s_m=mass_flow)


# --- reference formulas -------------------------------------------------------------------


def test_compressible_poiseuille_reduces_to_the_incompressible_law():
    p = point(gap=10e-6, length=1e-3, pr=1.0001)
    dp = p.p_up_Pa - p.p_down_Pa
    rho_mean = 0.5 * (p.p_up_Pa + p.p_down_Pa) / (R_AIR * p.T_up_K)
    incompressible = rho_mean * p.gap_m**3 * dp / (12 * p.mu_Pa_s * p.length_m)
    # (p1^2 - p2^2)/(2 R T) = rho_mean dp exactly: the two agree to round-off.
    assert leakage.plane_poiseuille_mass_flow(p) == pytest.approx(incompressible, rel=1e-12)


def test_flow_coefficient_and_reynolds_definitions():
    p = point(mass_flow=0.01)
    assert p.flow_coefficient == pytest.approx(0.01 / p.ideal_mass_flow)
    assert p.reynolds == pytest.approx(p.ideal_mass_flow / p.mu_Pa_s)
    assert p.length_over_gap == pytest.approx(20.0)


# --- comparison ---------------------------------------------------------------------------


def test_comparison_table_errors_and_outputs(tmp_path):
    pts = [point(f"p{i}", pr=pr, mass_flow=0.8 * point(pr=pr).ideal_mass_flow)
           for i, pr in enumerate((1.2, 1.5, 3.0))]
    table = leakage.compare(pts, {"nozzle": leakage.nozzle_model(),
                                  "nozzle Cd 0.8": leakage.nozzle_model(0.8)})
    np.testing.assert_allclose(table.errors["nozzle"], 0.25, rtol=1e-12)  # 1 / 0.8 - 1
    np.testing.assert_allclose(table.errors["nozzle Cd 0.8"], 0.0, atol=1e-12)
    summary = {s.model: s for s in table.summary()}
    assert summary["nozzle"].max_abs_error == pytest.approx(0.25)
    assert "| nozzle | 25.0% |" in table.markdown()
    rows = list(csv.DictReader(table.write_csv(tmp_path / "t.csv").open()))
    assert [r["point"] for r in rows] == ["p0", "p1", "p2"]
    assert float(rows[0]["nozzle_error"]) == pytest.approx(0.25)


def test_comparison_refuses_points_without_cfd():
    with pytest.raises(ValueError, match="without a valid CFD"):
        leakage.compare([point("bad")], {"nozzle": leakage.nozzle_model()})


def test_mismatches_flags_perturbed_and_missing_values():
    ref = {"a": 1.0, "b": 2.0}
    assert leakage.mismatches({"a": 1.0005, "b": 2.0}, ref, 1e-3) == []
    assert len(leakage.mismatches({"a": 1.01, "b": 2.0}, ref, 1e-3)) == 1
    assert len(leakage.mismatches({"a": 1.0}, ref, 1e-3)) == 1


# --- fitted flow coefficient --------------------------------------------------------------

TRUE = (1.3, 0.4, 0.6)  # A = 1.3 + 0.4 ln PR, b = 0.6


def synthetic_points(noise=None):
    """Points whose Cd follows A Cd^2 + b X Cd = 1 exactly (times optional scatter)."""
    truth = calibrated.FlowCoefficientFit(("1", "ln(PR)"), TRUE[:2], TRUE[2])
    pts = []
    rng = np.random.default_rng(7)
    for gap in (5e-6, 20e-6, 50e-6, 200e-6):
        for pr in (1.1, 1.5, 2.5):
            for length in (0.3e-3, 2e-3):
                p = point(f"g{gap}-pr{pr}-L{length}", gap=gap, length=length, pr=pr)
                m = truth.model()(p)
                if noise:
                    m *= 1 + noise * rng.standard_normal()
                pts.append(point(p.name, gap=gap, length=length, pr=pr, mass_flow=m))
    return pts


def test_viscous_limit_of_the_fit_form_is_lubrication_flow():
    # A = 0, b = 1: Cd = 1 / X, which must be the isothermal plane Poiseuille flow exactly
    # (X is built from it), at any pressure ratio.
    viscous_only = calibrated.FlowCoefficientFit(("1",), (0.0,), 1.0)
    for pr in (1.001, 1.5, 3.0):
        p = point(gap=10e-6, length=1e-3, pr=pr)
        assert viscous_only.model()(p) == pytest.approx(leakage.plane_poiseuille_mass_flow(p),
                                                         rel=1e-12)


def test_fit_recovers_a_known_correlation_and_predicts_left_out_points():
    fit = leakage.fit_flow_coefficient(synthetic_points())
    np.testing.assert_allclose([*fit.inertial, fit.viscous], TRUE, rtol=1e-9)
    assert max(abs(e) for e in fit.leave_out_errors) < 1e-9
    lo, hi = fit.ranges["pressure_ratio"]
    assert (lo, hi) == pytest.approx((1.1, 2.5))


WALL = 1.3  # w: the drag flow over rho_c U h_min (4/3 for a parabolic throat)


def moving_points(speeds=(-5.0, 15.0, 40.0)):
    """Points whose Cd follows A Cd|Cd| + b X (Cd - w W) = 1 with walls moving."""
    truth = calibrated.FlowCoefficientFit(("1", "ln(PR)"), TRUE[:2], TRUE[2], wall=WALL)
    pts = []
    for gap in (20e-6, 50e-6, 200e-6):  # at 5 um walls running back reverse the flow
        for pr in (1.1, 2.5):
            for u in speeds:
                p = point(f"g{gap}-pr{pr}-u{u}", gap=gap, length=1e-3, pr=pr, wall=u)
                pts.append(point(p.name, gap=gap, length=1e-3, pr=pr, wall=u,
                                 mass_flow=truth.model()(p)))
    return pts


def test_wall_term_limits_are_couette_and_nothing():
    # Viscous limit (A = 0, b = 1, w = 1): Cd = 1/X + W, i.e. lubrication pressure flow
    # plus the drag flow rho_c U h.  At PR -> 1, rho_c -> rho_up.
    fit = calibrated.FlowCoefficientFit(("1",), (0.0,), 1.0, wall=1.0)
    p = point(gap=10e-6, length=1e-3, pr=1.0001, wall=5.0)
    rho = p.p_up_Pa / (R_AIR * p.T_up_K)
    expected = leakage.plane_poiseuille_mass_flow(p) + rho * 5.0 * p.gap_m
    assert fit.model()(p) == pytest.approx(expected, rel=1e-4)  # rho_c/rho_up - 1 ~ 1e-4
    assert calibrated.drag_density_ratio(np.array([1.0, 1.0 + 1e-9, 1e9])) == pytest.approx(
        [1.0, 1.0, 2.0 / 3.0], rel=1e-6)
    # Inviscid limit (b = 0): the walls change nothing.
    nozzle = calibrated.FlowCoefficientFit(("1",), (1 / 0.64,), 0.0, wall=1.0)
    assert nozzle.flow_coefficient(10.0, 2.0, 50.0, 0.3) == pytest.approx(0.8)
    # Walls running backwards faster than the pressure pushes: the flow reverses, and
    # the coefficient stays a root of A Cd|Cd| + b X (Cd - w W) = 1.
    fit = calibrated.FlowCoefficientFit(("1",), (1.5,), 0.8, wall=1.0)
    re, pr, lh, v = 20.0, 1.1, 200.0, -0.5
    cd = fit.flow_coefficient(re, pr, lh, v)
    x = calibrated.viscous_parameter(re, pr, lh)
    w = calibrated.couette_parameter(v, pr)
    assert cd < 0
    assert 1.5 * cd * abs(cd) + 0.8 * x * (cd - w) == pytest.approx(1.0, rel=1e-12)


def test_fit_with_wall_term_recovers_it_and_predicts_what_the_static_form_cannot():
    static, moving = synthetic_points(), moving_points()
    fit = leakage.fit_flow_coefficient(static + moving)
    np.testing.assert_allclose([*fit.inertial, fit.viscous, fit.wall], [*TRUE, WALL],
                               rtol=1e-9)
    loo = fit.leave_out_summary()
    assert loo["moving"]["points"] == len(moving) and loo["moving"]["max"] < 1e-9
    assert fit.ranges["wall_speed_ratio"][0] < 0 < fit.ranges["wall_speed_ratio"][1]
    # The correlation without the wall term, fitted to the same points, cannot follow
    # the walls: its left-out errors on the moving points are large (the check can fail).
    old = leakage.fit_flow_coefficient(static + moving, wall=False)
    assert old.wall == 0.0
    assert old.leave_out_summary()["moving"]["max"] > 0.05
    # ...and fitted to the static points alone it predicts the moving ones no better.
    only_static = leakage.fit_flow_coefficient(static)
    errors = [only_static.model()(p) / p.mass_flow_kg_s_m - 1 for p in moving]
    assert max(abs(e) for e in errors) > 0.05


def test_fit_without_moving_points_has_no_wall_term():
    fit = leakage.fit_flow_coefficient(synthetic_points())
    assert fit.wall == 0.0 and not any(fit.leave_out_moving)
    # With a wall speed it then predicts what static walls would pass.
    assert fit.flow_coefficient(50.0, 1.5, 20.0, 0.1) == fit.flow_coefficient(50.0, 1.5, 20.0)


def test_fit_saved_before_the_wall_term_loads_with_it_zero(tmp_path):
    import json

    fit = leakage.fit_flow_coefficient(synthetic_points())
    old = json.loads(fit.to_json())
    for key in ("wall", "leave_out_moving"):
        del old[key]
    old["ranges"].pop("wall_speed_ratio")
    back = calibrated.FlowCoefficientFit.from_json(json.dumps(old))
    assert back.wall == 0.0 and back.leave_out_moving == ()
    assert back.flow_coefficient(50.0, 1.3, 10.0) == fit.flow_coefficient(50.0, 1.3, 10.0)
    assert back.leave_out_summary()["static"]["points"] == len(fit.leave_out_errors)
    # The recorded fit of the chamber case, written by the first version, still loads.
    from pathlib import Path

    recorded = Path(__file__).parent / "data" / "cfd" / "chamber" / "flow_coefficient.json"
    assert "wall" not in json.loads(recorded.read_text())
    assert calibrated.FlowCoefficientFit.load(recorded).wall == 0.0


def test_fit_leave_out_error_reveals_noisy_data():
    # 2 % scatter in the "CFD" must show up as leave-out errors of that size: the check
    # on the correlation is not one that passes everything.
    fit = leakage.fit_flow_coefficient(synthetic_points(noise=0.02))
    rms = math.sqrt(np.mean(np.square(fit.leave_out_errors)))
    assert 0.01 < rms < 0.04


def test_fit_round_trips_through_json(tmp_path):
    fit = leakage.fit_flow_coefficient(synthetic_points())
    back = calibrated.FlowCoefficientFit.load(fit.save(tmp_path / "fit.json"))
    assert back == fit
    re, pr, lh = np.array([50.0, 500.0]), np.array([1.3, 2.0]), np.array([10.0, 40.0])
    np.testing.assert_array_equal(back.flow_coefficient(re, pr, lh),
                                  fit.flow_coefficient(re, pr, lh))
    assert isinstance(back.flow_coefficient(50.0, 1.3, 10.0), float)
    assert "Cd = m / m_id" in back.definitions


def test_fit_json_with_unknown_feature_is_refused(tmp_path):
    text = leakage.fit_flow_coefficient(synthetic_points()).to_json().replace('"ln(PR)"',
                                                                             '"PR^2"')
    with pytest.raises(ValueError, match="PR\\^2"):
        calibrated.FlowCoefficientFit.from_json(text)


def test_fit_needs_more_points_than_coefficients():
    with pytest.raises(ValueError, match="cannot fit"):
        leakage.fit_flow_coefficient(synthetic_points()[:3])


# --- rotorflow.quasi1d through the adapter ------------------------------------------------


def test_quasi1d_nozzle_agrees_with_the_reference_nozzle():
    # rotorflow.quasi1d is part of the package: an import error here is a failure, not a
    # reason to skip.
    models = leakage.quasi1d_models(coefficient=1.0)
    nozzle = models["quasi1d-nozzle"]
    # The quasi-1D model smooths the flux near PR = 1 (relative change ~DELTA_X^2/(2y^2)
    # with y = 1 - 1/PR, DELTA_X = 1e-4: 6e-7 at PR 1.1); beyond that its flux and the
    # unsmoothed nozzle of the ideal flow (one formula, flows.nozzle_psi) must agree.
    for pr in (1.1, 1.5, 1.8929, 3.0):
        p = point(pr=pr)
        assert nozzle(p) == pytest.approx(p.ideal_mass_flow, rel=1e-6)
    fanno = next(m for name, m in models.items() if name.startswith("quasi1d-fanno"))
    # Friction can only reduce the flow below the loss-free nozzle's.
    assert all(fanno(point(pr=pr)) < point(pr=pr).ideal_mass_flow for pr in (1.1, 2.0, 4.0))


def test_report_writes_tables_fit_and_plot(tmp_path):
    pts = synthetic_points()
    moving = moving_points()
    summary = leakage_report.write_report([*pts, *moving], tmp_path,
                                   {"nozzle": leakage.nozzle_model()})
    for name in ("leakage_errors.csv", "leakage_errors.md", "flow_coefficient.json",
                 "flow_coefficient.png"):
        assert (tmp_path / name).stat().st_size > 0
    # Every point follows the correlation with its wall term exactly.
    assert summary["fit"]["leave_out_max_error"] < 1e-9
    assert summary["fit"]["wall"] == pytest.approx(WALL, rel=1e-9)
    loo = summary["fit"]["leave_out"]
    assert (loo["static"]["points"], loo["moving"]["points"]) == (len(pts), len(moving))
    fit = calibrated.FlowCoefficientFit.load(tmp_path / "flow_coefficient.json")
    assert len(fit.leave_out_errors) == len(pts) + len(moving)
    text = (tmp_path / "leakage_errors.md").read_text()
    assert "cfd-calibrated" in text and "moving walls" in text
    # The static form, fitted to the static points, is shown against the moving ones.
    static = next(m for m in summary["models"] if m["model"] == "cfd-calibrated-static")
    assert static["max_abs_error"] > 0.05


def test_report_section_names_failed_studies(tmp_path):
    import json

    artifact, report_dir = tmp_path / "a", tmp_path / "r"
    report_dir.mkdir()
    leakage_report.write_report(synthetic_points(), artifact, {"nozzle": leakage.nozzle_model()})
    studies = [{"name": "ok-point", "ok": True, "failures": [], "kind": "monotone",
                "order": 1.9, "default_error": 0.01, "extrapolated_kg_s_m": 0.02},
               {"name": "bad-point", "ok": False, "failures": ["fine: diverged (sigFpe)"],
                "kind": "failed", "order": float("nan"), "default_error": float("nan"),
                "extrapolated_kg_s_m": float("nan")}]
    (artifact / "studies.json").write_text(json.dumps(studies))
    section = leakage_report.report_section(artifact, report_dir, None)
    assert "bad-point: fine: diverged (sigFpe)" in section.html
    assert "cfd-calibrated" in section.html
    assert (report_dir / "cfd_leakage_flow_coefficient.png").stat().st_size > 0
