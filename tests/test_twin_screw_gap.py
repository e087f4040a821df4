"""The twin-screw interlobe clearance gap as a CFD section, and its wall speeds.

The pairs: the family's circular 4/6 example (seed 004's sizes at C = 78 mm), one smooth
contact at every angle but 45 deg, where the female-tip arc's centre passes the pitch
point and the rotors touch along it (the contact passes the pitch point at 42.75 deg);
and the pin-cycloid 4/6 of examples/twin_screw_4_6.toml (C = 80 mm), whose contacts sit
at sharp corners at most angles and whose male root rolls on the female land at the
pitch point from about 40 to 70 deg.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from rotorflow.cases.gap_walls import GapWalls
from rotorflow.errors import CaseError
from rotorflow.geometry.curves import closest, sample
from rotorflow.geometry.planar import rotate
from rotorflow.geometry.twin_screw.family import build
from rotorflow.geometry.twin_screw.pair import TwinScrewPair
from rotorflow.geometry.twin_screw.pin_cycloid import pin_cycloid_from_diameters
from rotorflow.geometry.twin_screw.sealing_gap import contacts, gap_frame
from rotorflow.workflow.case import load_case

from .conftest import CASES

CIRCULAR = build("circular", 4, 6, 0.078, 0.100, 0.096)
PIN = TwinScrewPair(*pin_cycloid_from_diameters(4, 6, 0.100, 0.096), "pin-cycloid")
RATIO = 4 / 6  # N1 / N2


def female_fixed(pair, u, psi):
    """Female profile points at male angle psi, fixed frame."""
    return rotate(pair.female.point(u), -psi * RATIO) + pair.gearing.female_axis


def to_fixed(walls, frame):
    x0, n, t = frame
    return x0 + walls[:, :1] * t + walls[:, 1:] * n


def signed_distance(curve, points):
    """Signed distance of points from a closed profile (positive outside), to rounding."""
    u = sample(curve, 1e-7)
    from scipy.spatial import cKDTree

    _, k = cKDTree(curve.point(u)).query(points)
    return closest(curve, points, u[k], iterations=30)[2]


# --- the section --------------------------------------------------------------------------


@pytest.mark.parametrize("pair, deg, gap, on", [
    (CIRCULAR, 10.0, 10e-6, "male"), (CIRCULAR, 30.0, 40e-6, "male"),
    (CIRCULAR, 43.0, 5e-6, "male"), (CIRCULAR, 70.0, 20e-6, "female"),
    (CIRCULAR, 0.0, 10e-6, "female"), (PIN, 50.0, 10e-6, "male")])
def test_narrowest_gap_is_the_clearance_and_walls_fit_the_mesher(pair, deg, gap, on):
    lower, upper = pair.gap_walls(math.radians(deg), gap, clearance_on=on)
    walls = GapWalls(lower, upper)  # the mesher's own checks: x increasing, no crossing
    local = walls.gap(walls.sample_x(4001))
    # A normal offset leaves exactly the clearance at the contact (x = 0); the mesher's
    # spline through the 201 points keeps the narrowest gap to 1e-3 of it.
    assert walls.min_gap == pytest.approx(gap, rel=1e-3)
    assert local.min() >= gap * (1 - 1e-3)
    assert abs(walls.throat_x) < 0.05 * walls.length
    assert local[0] == pytest.approx(20 * gap, rel=1e-2)  # cut at 20 h upstream
    assert local[-1] == pytest.approx(3 * gap, rel=1e-2)  # and 3 h downstream


@pytest.mark.parametrize("deg, on", [(20.0, "male"), (60.0, "female")])
def test_walls_are_the_true_profiles_one_of_them_offset_by_the_clearance(deg, on):
    psi, gap = math.radians(deg), 30e-6
    pair = CIRCULAR
    lower, upper = pair.gap_walls(psi, gap, clearance_on=on)
    frame = gap_frame(pair, psi)
    # In the male's frame the lower wall lies on the male (relieved: gap inside it), in
    # the female's the upper wall on the female; foot points by Newton on the curves.
    male_pts = rotate(to_fixed(lower, frame), -psi)
    female_pts = rotate(to_fixed(upper, frame) - pair.gearing.female_axis, psi * RATIO)
    d_male = signed_distance(pair.male, male_pts)
    d_female = signed_distance(pair.female, female_pts)
    want_m, want_f = (-gap, 0.0) if on == "male" else (0.0, -gap)
    np.testing.assert_allclose(d_male, want_m, rtol=0, atol=1e-10)  # bisection: ~1e-15 m
    np.testing.assert_allclose(d_female, want_f, rtol=0, atol=1e-10)


def test_at_zero_clearance_the_walls_touch_at_the_origin_with_a_common_tangent():
    psi = math.radians(25.0)
    x0, n, t = gap_frame(CIRCULAR, psi)
    pick = min(contacts(CIRCULAR, psi), key=lambda c: np.linalg.norm(c.point - x0))
    # The unrelieved profiles pass through the origin, both tangent to the x axis.
    dm = rotate(CIRCULAR.male.derivative(np.array([pick.u_male])), psi)[0]
    df = rotate(CIRCULAR.female.derivative(np.array([pick.u_female])), -psi * RATIO)[0]
    pm = rotate(CIRCULAR.male.point(np.array([pick.u_male])), psi)[0]
    pf = female_fixed(CIRCULAR, np.array([pick.u_female]), psi)[0]
    assert np.linalg.norm(pm - x0) < 1e-12 and np.linalg.norm(pf - x0) < 1e-10
    assert abs(dm @ n) / np.linalg.norm(dm) < 1e-9 and abs(df @ n) / np.linalg.norm(df) < 1e-9
    # And the section as the clearance vanishes: 1 nm leaves both walls at the origin,
    # level there (the slopes of the neighbouring points' chords, ~1e-4 rad at 1 um).
    lower, upper = CIRCULAR.gap_walls(psi, 1e-9, clearance_on="female")
    i = int(np.argmin(np.abs(lower[:, 0])))
    assert lower[i, 0] == 0.0 and abs(lower[i, 1]) < 1e-15 and upper[i, 1] == pytest.approx(
        1e-9, rel=1e-6)
    for wall in (lower, upper):
        slope = (wall[i + 1, 1] - wall[i - 1, 1]) / (wall[i + 1, 0] - wall[i - 1, 0])
        assert abs(slope) < 1e-3


def test_contacts_are_the_ones_the_chamber_table_is_cut_at():
    # The sections' contacts (law of gearing and on both rotors) against the contact
    # points of the Boolean cut the chamber table is built from.
    for deg in (5.0, 33.0, 61.0):
        psi = math.radians(deg)
        mine = np.array([c.point for c in contacts(CIRCULAR, psi)])
        cut = [c for p in CIRCULAR.cutter.cut(psi) for c in p.contacts]
        assert len(mine) == 1
        assert min(np.linalg.norm(c - mine[0]) for c in cut) < 1e-10


def test_x_runs_from_the_older_chamber_into_the_younger():
    # The chamber table's interlobe tracks: beyond an "interlobe-lead" contact lies the
    # chamber one period older (offset +1), beyond a "-trail" one the younger.  So the
    # table's chamber 0 must hold the outlet end of the gap at a lead contact and the
    # inlet end at a trail contact.
    pair = CIRCULAR
    table = pair.section(48)
    checked = 0
    for track in table.tracks:
        if track.kind != "interlobe":
            continue
        nodes = np.nonzero(track.present)[0]
        for i in nodes[[len(nodes) // 4, len(nodes) // 2, 3 * len(nodes) // 4]]:
            psi = float(table.psi[i])
            x0, n, t = gap_frame(pair, psi)
            if np.linalg.norm(x0 - track.points[i]) > 1e-9:
                continue  # another contact than the default one
            lower, upper = pair.gap_walls(psi, 20e-6)
            mid = 0.5 * (lower + upper)
            inlet, outlet = to_fixed(mid[[0, -1]], (x0, n, t))
            rings = pair.chamber_polygons(psi)
            younger_here = int(track.offset[i]) > 0
            assert inside(rings, outlet) == younger_here, (track.name, psi)
            assert inside(rings, inlet) == (not younger_here), (track.name, psi)
            checked += 1
    assert checked >= 4


def inside(rings, point) -> bool:
    """Even-odd rule over every ring (outer boundaries and holes alike)."""
    count = 0
    for ring in rings:
        x, y = ring[:, 0], ring[:, 1]
        x2, y2 = np.roll(x, -1), np.roll(y, -1)
        cross = (y > point[1]) != (y2 > point[1])
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x + (point[1] - y) * (x2 - x) / (y2 - y)
        count += int(np.sum(cross & (point[0] < xi)))
    return bool(count % 2)


# --- wall speeds ----------------------------------------------------------------------------


@pytest.mark.parametrize("deg", [3.0, 20.0, 44.0, 58.0, 85.0])
def test_wall_speeds_are_the_rotors_rigid_motions_relative_to_the_contact(deg):
    omega, psi, pair = 628.3, math.radians(deg), CIRCULAR
    lower, upper = pair.wall_speeds(psi, omega)
    x0, _, t = gap_frame(pair, psi)
    # Independently: each rotor's rigid motion v = omega x r at the contact, less the
    # contact's own velocity, a central difference of its path (the pair's law-of-gearing
    # root near it at psi -+ h): O(h^2) = 1e-12 relative.
    h = 1e-6
    ahead = pair.contact_near(x0, psi + h)[0]
    behind = pair.contact_near(x0, psi - h)[0]
    v_contact = omega * (ahead - behind) / (2 * h)
    v_male = omega * np.array([-x0[1], x0[0]])
    r2 = x0 - pair.gearing.female_axis
    v_female = -omega * RATIO * np.array([-r2[1], r2[0]])
    scale = omega * pair.male_radius
    assert lower == pytest.approx(float((v_male - v_contact) @ t), abs=1e-8 * scale)
    assert upper == pytest.approx(float((v_female - v_contact) @ t), abs=1e-8 * scale)
    # Their difference is the sliding speed: relative rotation (1 + N1/N2) omega about P.
    slide = omega * (1 + RATIO) * np.linalg.norm(x0 - pair.gearing.pitch_point)
    assert abs(upper - lower) == pytest.approx(slide, rel=1e-8, abs=1e-9 * scale)


def test_circular_rack_rolls_without_sliding_at_the_pitch_point():
    pair, omega = CIRCULAR, 500.0
    p = pair.gearing.pitch_point

    def distance(psi):
        return float(np.linalg.norm(contacts(pair, psi)[0].point - p))

    res = minimize_scalar(distance, bounds=(math.radians(40), math.radians(44)),
                          method="bounded", options={"xatol": 1e-10})
    assert distance(res.x) < 1e-8 * pair.gearing.centre_distance
    lower, upper = pair.wall_speeds(res.x, omega)
    assert abs(upper - lower) < 1e-6 * abs(upper)  # no sliding: pure rolling at P
    assert abs(upper) > 1.0  # ...while both surfaces move relative to the contact
    # Approaching P the sliding falls linearly with the distance (the law of gearing).
    for d_deg in (4.0, 1.0, 0.25):
        psi = res.x + math.radians(d_deg)
        lo, up = pair.wall_speeds(psi, omega)
        assert abs(up - lo) / distance(psi) == pytest.approx(omega * (1 + RATIO), rel=1e-6)
    # Kinematics are linear in the speed.
    a = np.array(pair.wall_speeds(math.radians(20), 100.0))
    np.testing.assert_allclose(pair.wall_speeds(math.radians(20), -250.0), -2.5 * a, rtol=1e-9)


def test_pin_cycloid_rolls_its_root_on_the_female_land_at_the_pitch_point():
    lower, upper = PIN.wall_speeds(math.radians(55), 628.3)
    assert upper == pytest.approx(lower, rel=1e-8)  # the pitch circles roll


# --- where no section exists ----------------------------------------------------------------


def test_angles_and_clearances_without_a_section_are_named_with_the_reason():
    with pytest.raises(CaseError, match=r"male angle 20 deg: .*sharp corner of the female"):
        PIN.gap_walls(math.radians(20), 10e-6)
    # At 0 deg the pin arcs coincide (the pin's centre on the pitch point): a band.
    band = [i for i, c in enumerate(contacts(PIN, 0.0)) if c.defect and "band" in c.defect]
    assert len(band) == 1
    with pytest.raises(CaseError, match=r"male angle 0 deg: .*band of contact"):
        PIN.gap_walls(0.0, 10e-6, contact=band[0])
    with pytest.raises(CaseError, match=r"male angle 50 deg: contact 3 is not one of the 1"):
        CIRCULAR.gap_walls(math.radians(50), 10e-6, contact=3)
    # The female's smallest convex radius is 1.2 mm: 1.5 mm folds its offset.
    with pytest.raises(CaseError, match=r"male angle 50 deg: .*folds its profile.*"
                                        r"clearance_on = 'male'"):
        CIRCULAR.gap_walls(math.radians(50), 1.5e-3, clearance_on="female")
    with pytest.raises(CaseError, match="opens only"):
        CIRCULAR.gap_walls(math.radians(50), 500e-6)
    # The pin-cycloid male's point-generated flanks curve at 36 um near their cusps: 50 um
    # folds it; on the female the offset land ends at its sharp corners, which the section
    # reaches at 60 deg before the gap has opened 20-fold.
    with pytest.raises(CaseError, match=r"male angle 50 deg: .*male rotor folds its profile"):
        PIN.gap_walls(math.radians(50), 50e-6)
    PIN.gap_walls(math.radians(50), 50e-6, clearance_on="female")
    with pytest.raises(CaseError, match=r"male angle 60 deg: .*opens only .*female wall "
                                        r"reaches a sharp corner of its relieved profile"):
        PIN.gap_walls(math.radians(60), 50e-6, clearance_on="female")
    with pytest.raises(CaseError, match="positive"):
        CIRCULAR.gap_walls(1.0, 0.0)
    with pytest.raises(CaseError, match="clearance_on"):
        CIRCULAR.gap_walls(1.0, 1e-5, clearance_on="outer")


def test_example_case_cuts_its_sections_at_the_male_speed():
    from rotorflow.cases.gap_study import SectionPoint
    from rotorflow.cases.leakage_stage import matrix_from_section, rotor_machine

    case = load_case(CASES / "twin_screw_cfd_leakage.toml")
    machine = rotor_machine(case)
    assert machine.omega_outer_rad_s == pytest.approx(6000 * math.pi / 30)  # male driven
    points = matrix_from_section(case.raw["cfd"], "example", machine)
    assert len(points) == 4 and all(isinstance(p, SectionPoint) for p in points)
    moving = [p for p in points if p.moving_walls]
    assert {p.rotor_angle_deg for p in moving} == {60, 70}
    for p in moving:
        lower, upper = p.wall_speeds_m_s
        assert lower > upper > 0  # both drag toward the younger chamber, the male faster


@pytest.mark.parametrize("edits, word", [
    ({"rotor_gap_um = [20]": "rotor_gap_um = [1500]"}, "gap 1500 um"),
    ({"rotor_angle_deg = [60, 70]": "rotor_angle_deg = [60, 45]"}, "band of contact"),
    ({'profile = "circular"': 'profile = "pin-cycloid"',
      "centre_distance_mm = 78": "centre_distance_mm = 80",
      "rotor_angle_deg = [60, 70]": "rotor_angle_deg = [50, 20]"}, "rotor_angle_deg = 20"),
])
def test_bad_section_exits_2_with_one_line(tmp_path, edits, word):
    text = (CASES / "twin_screw_cfd_leakage.toml").read_text()
    for old, new in edits.items():
        assert old in text
        text = text.replace(old, new)
    case = tmp_path / "case.toml"
    case.write_text(text)
    with pytest.raises(CaseError, match=word):  # refused when the case loads: nothing runs
        load_case(case)
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "run", str(case),
                          "--build", str(tmp_path / "build")], capture_output=True, text=True)
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and word in out.stderr
    assert not (tmp_path / "build").exists()


# --- one real OpenFOAM run of a twin-screw section ---------------------------------------


@pytest.mark.openfoam
@pytest.mark.gmsh
def test_a_twin_screw_section_runs_in_openfoam(tmp_path):
    from rotorflow.cases import foam
    from rotorflow.cases.gap_case import run_gap_case
    from rotorflow.cases.gap_study import RotorMachine, SectionPoint

    if not foam.is_available():
        pytest.skip("OpenFOAM not installed: run `make openfoam`")
    # The example's 60 deg section (20 um on the male, moving walls at 6000 rpm) on the
    # coarse mesh of its study: the gap case machinery takes the twin screw's walls as
    # they come, and the solver converges with inlet and outlet in balance.
    machine = RotorMachine(CIRCULAR, 6000 * math.pi / 30)
    point = SectionPoint(20, 1.2, 60, machine, moving_walls=True)
    case = point.case().refined(0.5)
    assert (case.flow.wall_speed_lower_m_s, case.flow.wall_speed_upper_m_s) == pytest.approx(
        (12.2367, 5.1954), rel=1e-4)
    result = run_gap_case(case, tmp_path / point.name)
    assert result.ok, result.message + result.log_tail
    assert result.imbalance < 5e-3  # the 0.5 %
    assert result.min_gap_m == pytest.approx(20e-6, rel=1e-3)
    log = (tmp_path / point.name / "log.rhoSimpleFoam").read_text().splitlines()
    assert not any("FOAM FATAL" in line for line in log)
    assert log[-1].strip() == "End" or any(line.strip() == "End" for line in log[-5:])
