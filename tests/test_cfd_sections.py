"""Leakage-matrix points on the real gap at a sealing line of the case's rotors (plain tier:
no OpenFOAM; the sections are cut and checked, not run)."""

from __future__ import annotations

import math

import pytest

from rotorflow.cases.gap_study import MatrixPoint, RotorMachine, SectionPoint
from rotorflow.cases.leakage_stage import matrix_from_section, rotor_machine
from rotorflow.errors import CaseError
from rotorflow.geometry.internal_gear.pair import PinGerotor, sigma_limit
from rotorflow.geometry.internal_gear.sealing_gap import sealing_wall_speeds
from rotorflow.workflow.case import load_case

from .conftest import CASES

PAIR = PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 0.1)
MACHINE = RotorMachine(PAIR, 5000 * math.pi / 30)


def test_rotor_angles_make_section_points_only_unless_tips_are_asked():
    section = {"gap_um": [10, 20], "pressure_ratio": [1.5], "rotor_angle_deg": [240, 300],
               "moving_walls": [False, True]}
    points = matrix_from_section(section, "case.toml", MACHINE)
    assert all(isinstance(p, SectionPoint) for p in points)
    assert len(points) == 2 * 2 * 1 * 2  # angles x gaps x ratios x wall motions
    assert {(p.rotor_angle_deg, p.gap_um, p.moving_walls) for p in points} == {
        (a, g, m) for a in (240, 300) for g in (10, 20) for m in (False, True)}
    # With radius_mm the tip gaps come too, from the same gap and ratio lists unless the
    # section points have their own.
    mixed = matrix_from_section({**section, "radius_mm": [20], "rotor_gap_um": [10],
                                 "rotor_pressure_ratio": [1.2, 2.0]}, "case.toml", MACHINE)
    tips = [p for p in mixed if isinstance(p, MatrixPoint)]
    secs = [p for p in mixed if isinstance(p, SectionPoint)]
    assert len(tips) == 2 and len(secs) == 2 * 1 * 2 * 2
    assert {p.pressure_ratio for p in secs} == {1.2, 2.0} and {p.gap_um for p in secs} == {10}
    # Every point has its own folder name: reuse through runs_dir never mixes two points.
    names = [p.name for p in mixed]
    assert len(set(names)) == len(names)
    assert all(n.startswith("seal-") for n in names[len(tips):])


def test_section_names_tell_machines_and_wall_motion_apart():
    p = SectionPoint(10, 1.5, 240, MACHINE, moving_walls=True)
    assert p.name == f"seal-{MACHINE.tag}-a240deg-g10um-pr1.5-n5000rpm"
    assert SectionPoint(10, 1.5, 240, MACHINE).name.endswith("-static")
    other = RotorMachine(PinGerotor(6, 1.39934, 0.9 * sigma_limit(6, 1.39934), 0.1),
                         MACHINE.omega_outer_rad_s)
    assert other.tag != MACHINE.tag
    assert SectionPoint(10, 1.5, 240, other).name != SectionPoint(10, 1.5, 240, MACHINE).name


def test_section_case_has_the_clearance_and_the_rotor_wall_speeds():
    point = SectionPoint(20, 2.0, 240, MACHINE, moving_walls=True)
    case = point.case()
    assert case.walls.min_gap == pytest.approx(20e-6, rel=1e-3)
    lower, upper = sealing_wall_speeds(PAIR, math.radians(240), MACHINE.omega_outer_rad_s)
    assert (case.flow.wall_speed_lower_m_s, case.flow.wall_speed_upper_m_s) == (lower, upper)
    # At 240 deg the pin slides forward relative to the sealing line and the inner rotor
    # back, the pin faster: the mean drags gas along the leak.
    assert upper > 0 > lower and upper + lower > 0
    static = SectionPoint(20, 2.0, 240, MACHINE).case()
    assert static.flow.wall_speed_lower_m_s == static.flow.wall_speed_upper_m_s == 0.0
    assert static.key() != case.key()
    assert static.walls.lower.tobytes() == case.walls.lower.tobytes()


def test_matrix_gaps_end_where_the_jet_leaves_the_walls():
    # Every matrix gap, tip or section, is cut downstream at OUTLET_GAP_RATIO times its
    # minimum (beyond it the diverging walls stall the jet on one side or the other and
    # the steady solution has no mesh limit); upstream it starts wide (20 h).
    from rotorflow.cases.gap_study import OUTLET_GAP_RATIO

    for point in (MatrixPoint(200, 1.1, 20.0), SectionPoint(10, 1.2, 300, MACHINE),
                  SectionPoint(20, 1.2, 240, MACHINE, moving_walls=True)):
        walls = point.case().walls
        h = walls.min_gap
        assert walls.gap(walls.x_outlet) / h == pytest.approx(OUTLET_GAP_RATIO, rel=1e-3)
        assert walls.gap(walls.x_inlet) / h == pytest.approx(20.0, rel=1e-3)


@pytest.mark.parametrize("section, machine, word", [
    ({"rotor_angle_deg": [240], "rotor_gap": [10]}, MACHINE, "unknown key.*rotor_gap"),
    ({"rotor_angle_deg": [400]}, MACHINE, r"\[0, 360\)"),
    ({"rotor_angle_deg": 240}, MACHINE, "rotor_angle_deg.*list of numbers"),
    ({"rotor_angle_deg": [True]}, MACHINE, "rotor_angle_deg.*list of numbers"),
    ({"rotor_angle_deg": [330], "rotor_gap_um": [10]}, MACHINE,
     r"rotor_angle_deg = 330.*gap 10 um.*phi1 = 330 deg.*another contact"),
    ({"rotor_angle_deg": [240], "moving_walls": "yes"}, MACHINE, "moving_walls.*true, false"),
    ({"moving_walls": True}, MACHINE, "moving_walls.*needs rotor_angle_deg"),
    ({"rotor_angle_deg": [240]}, None, r"needs the case's \[machine\]"),
    ({"rotor_angle_deg": [240], "moving_walls": True}, RotorMachine(PAIR), "speed_rpm"),
    ({"rotor_angle_deg": [240], "rotor_gap_um": [0]}, MACHINE, "gaps .* > 0"),
])
def test_bad_section_keys_are_named(section, machine, word):
    with pytest.raises(CaseError, match=word):
        matrix_from_section(section, "case.toml", machine)


def test_rotor_speed_comes_from_the_driven_rotor_of_the_operating_point(tmp_path):
    case = load_case(CASES / "cfd_leakage.toml")
    m = rotor_machine(case)
    # speed_rpm is the driven (inner) rotor's: the outer one turns N2/N1 times as fast.
    assert case.driven == "inner"
    assert m.omega_outer_rad_s == pytest.approx(6000 * 5 / 6 * math.pi / 30, rel=1e-15)
    assert m.pair == case.pair
    outer = tmp_path / "outer.toml"
    outer.write_text((CASES / "cfd_leakage.toml").read_text().replace(
        'driven = "inner"', 'driven = "outer"'))
    assert rotor_machine(load_case(outer)).omega_outer_rad_s == pytest.approx(
        6000 * math.pi / 30, rel=1e-15)
    # driven = "auto": the rotor the power split picks, as in the chamber table.
    from rotorflow.geometry.summary import chamber_table

    auto = tmp_path / "auto.toml"
    auto.write_text((CASES / "cfd_leakage.toml").read_text().replace(
        'driven = "inner"', 'driven = "auto"'))
    auto_case = load_case(auto)
    ratio = chamber_table(auto_case).speed_ratio_outer_per_driven
    assert rotor_machine(auto_case).omega_outer_rad_s == pytest.approx(
        6000 * ratio * math.pi / 30, rel=1e-15)
    # Without a speed the pair still serves static sections.
    assert rotor_machine(case, with_speed=False).omega_outer_rad_s is None


# --- a recorded OpenFOAM study of a sealing-line section (tests/data/cfd/rotor_section) ---

RECORDED = CASES.parent / "tests" / "data" / "cfd" / "rotor_section"


def recorded_study(moving: bool):
    from rotorflow.cases.gap_case import GapResult
    from rotorflow.cases.gap_study import LEVELS, REFINEMENT_RATIO, MeshStudy

    point = SectionPoint(10, 1.2, 300, MACHINE, moving)
    folder = RECORDED / point.name
    results = tuple(GapResult.from_json((folder / lvl / "result.json").read_text())
                    for lvl in LEVELS)
    return point, folder, MeshStudy(point.name, point.case(), results, REFINEMENT_RATIO)


@pytest.mark.parametrize("moving", [False, True])
def test_recorded_section_is_this_geometry_and_meets_the_targets(moving):
    from rotorflow.cases.gap_study import DEFAULT_MESH_TOL, LEVELS

    point, folder, study = recorded_study(moving)
    # The recording is of exactly the section and wall speeds the code cuts now: every
    # mesh's case key (walls, flow, mesh, controls) matches.  A change of the sealing
    # geometry or kinematics fails here: re-record (tests/data/cfd/rotor_section/record.py).
    for k, lvl in zip((-1, 0, 1), LEVELS, strict=True):
        key = (folder / lvl / "case.key").read_text().strip()
        assert study.case.refined(2.0**k).key() == key, lvl
    assert study.ok
    assert all(r.imbalance < 5e-3 for r in study.results)  # the 0.5 %
    assert abs(study.default_error) < DEFAULT_MESH_TOL
    assert study.richardson.kind == "monotone" and 1.0 < study.richardson.order < 2.5
    p = study.leakage_point()
    assert p.wall_speed_m_s == pytest.approx(0.5 * sum(point.wall_speeds_m_s), rel=1e-15)
    assert 0.0 < p.flow_coefficient < 1.0


def test_recorded_flow_tables_rejudge_to_the_stored_result():
    from rotorflow.cases.gap_case import SolverControls, assess_history, read_mass_flow_history

    _, folder, study = recorded_study(True)
    history = read_mass_flow_history(folder / "default")
    status, _, m_in, m_out, imbalance = assess_history(history, SolverControls())
    stored = study.results[1]
    assert status == stored.status == "converged"
    assert imbalance == pytest.approx(stored.imbalance, rel=1e-9)
    assert m_out / m_in == pytest.approx(
        stored.mass_flow_outlet_kg_s_m / stored.mass_flow_inlet_kg_s_m, rel=1e-12)
    assert int(history.iteration[-1]) == stored.iterations


def test_recorded_wall_drag_is_that_of_lubrication_theory():
    # The walls add the drag flow rho_c U I2/I3 of lubrication theory on the section's own
    # gap h(x) (I_n = integral of h^-n) in the viscous limit; the nozzle-like entry
    # loss of a finite Reynolds number (~40 here) can only take some of it away.
    import numpy as np

    from rotorflow.quasi1d.calibrated import drag_density_ratio

    point, _, moving = recorded_study(True)
    _, _, static = recorded_study(False)
    walls = moving.case.walls
    x = walls.sample_x(200001)
    h = walls.gap(x)
    effective_gap = np.trapezoid(h**-2, x) / np.trapezoid(h**-3, x)
    flow = moving.case.flow
    rho_c = flow.gas.density(flow.p_total_Pa, flow.T_total_K) * drag_density_ratio(1.2)
    drag = rho_c * 0.5 * sum(point.wall_speeds_m_s) * effective_gap
    added = moving.mass_flow_kg_s_m - static.mass_flow_kg_s_m
    # Recorded: 82 % of the lubrication value (91 % when the section ran on to 3 h); the
    # two flows share mesh and scheme, so their discretisation errors (~0.2 % of
    # 7.7e-4 kg/s/m each) cancel in the difference: 1.628 / 1.639 / 1.642e-5 kg/s/m on
    # the coarse, default and fine meshes.
    assert 0.8 < added / drag < 1.02
