"""The clearance gap at a sealing line, cut from the real profile pair, and its wall speeds."""

import math

import numpy as np
import pytest

from rotorflow.cases.gap_walls import GapWalls
from rotorflow.errors import CaseError
from rotorflow.geometry.internal_gear.pair import PinGerotor, sigma_limit
from rotorflow.geometry.internal_gear.sealing_gap import sealing_gap_walls, sealing_wall_speeds
from rotorflow.geometry.internal_gear.space import PinSpace
from rotorflow.geometry.planar import rotate

PAIR = PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 0.1)


@pytest.mark.parametrize("phi_deg, gap", [(120.0, 5e-6), (200.0, 5e-6), (200.0, 50e-6),
                                          (240.0, 10e-6), (300.0, 10e-6), (300.0, 50e-6)])
def test_minimum_gap_is_the_clearance_and_walls_fit_the_mesher(phi_deg, gap):
    lower, upper = sealing_gap_walls(PAIR, math.radians(phi_deg), gap)
    walls = GapWalls(lower, upper)
    x = walls.sample_x(4001)
    local = walls.gap(x)
    # The offset is along the profile's own normal, so the throat is the clearance; the
    # mesher's spline through the 201 points keeps it to 1e-3.
    assert walls.min_gap == pytest.approx(gap, rel=1e-3)
    assert local.min() >= gap * (1 - 1e-3)
    # Cut where the gap has opened 20x (inlet) and 3x (outlet).
    assert local[0] == pytest.approx(20 * gap, rel=1e-2)
    assert local[-1] == pytest.approx(3 * gap, rel=1e-2)


def test_pin_wall_is_the_relieved_pin_circle_and_the_inner_wall_the_true_profile():
    phi1, gap = math.radians(200.0), 20e-6
    lower, upper = sealing_gap_walls(PAIR, phi1, gap)
    # Clearance on the outer rotor: the pin circle shrinks by the gap about its centre,
    # which sits at (0, rho) in the gap frame (the pin arc spans the whole section here).
    r = PAIR.rho - gap
    np.testing.assert_allclose(upper[:, 1], PAIR.rho - np.sqrt(r**2 - upper[:, 0] ** 2),
                               rtol=0, atol=1e-12)  # bisection to ~1e-15 m, exact circle
    # Every lower-wall point lies on the inner rotor: its distance to the sampled inner
    # profile (fixed frame) is nil to the sampling's chord error.
    space = PinSpace(PAIR)
    x0 = space.contacts(phi1)[-1].point
    centre = rotate(PAIR.pin_centre(0), phi1)
    n = (centre - x0) / PAIR.rho
    t = np.array([n[1], -n[0]])
    if t @ np.array([-x0[1], x0[0]]) > 0:
        t = -t
    fixed = x0 + lower[:, :1] * t + lower[:, 1:] * n
    from scipy.spatial import cKDTree

    g = phi1 + np.linspace(-1.0, 1.0, 400001)
    prof = rotate(PAIR.inner_point(g), PAIR.m21 * phi1) + PAIR.O2
    d, _ = cKDTree(prof).query(fixed)
    # Samples ~0.03 um apart along the profile: a point on it is within that of one.
    assert d.max() < 5e-8
    assert upper[0, 0] < 0.0 < upper[-1, 0]


def test_clearance_on_the_inner_rotor_at_sigma_bar_1_folds_and_says_where():
    # At sigma_bar = 1 the inner profile has a point of zero speed and infinite
    # curvature (g = 70 and 290 deg): offset into the inner rotor it folds into a
    # swallowtail, so no relieved inner rotor exists.  That was why phi1 = 300 deg failed.
    with pytest.raises(CaseError, match=r"phi1 = 300 deg.*folds its profile.*outer rotor"):
        sealing_gap_walls(PAIR, math.radians(300.0), 5e-6, clearance_on="inner")
    # Away from sigma_bar = 1 the inner rotor can carry the clearance.
    pair = PinGerotor(6, 1.39934, 0.8 * sigma_limit(6, 1.39934), 0.1)
    lower, upper = sealing_gap_walls(pair, math.radians(200.0), 20e-6, clearance_on="inner")
    assert GapWalls(lower, upper).min_gap == pytest.approx(20e-6, rel=1e-3)
    # ...and then the pin wall is the exact pin circle through the contact.
    np.testing.assert_allclose(upper[:, 1], pair.rho - np.sqrt(pair.rho**2 - upper[:, 0] ** 2),
                               rtol=0, atol=1e-12)


def test_angle_without_a_section_is_named_with_its_reason():
    # At 330 deg the fillet -1 touches the inner rotor next to pin 0: a second contact
    # closes the gap again before it has opened 20-fold.
    with pytest.raises(CaseError, match=r"phi1 = 330 deg.*another contact"):
        sealing_gap_walls(PAIR, math.radians(330.0), 10e-6)
    # Near the pitch point the pin rolls on a nearly conforming flank; a wide gap reaches
    # the edge of the fillet, where the outer wall turns back, before opening 20-fold.
    with pytest.raises(CaseError, match=r"phi1 = 340 deg.*opens only .*outer wall turns back"):
        sealing_gap_walls(PAIR, math.radians(340.0), 50e-6)


def test_bad_gap_and_bad_options_are_refused():
    with pytest.raises(CaseError, match="positive"):
        sealing_gap_walls(PAIR, 1.0, 0.0)
    with pytest.raises(CaseError, match="clearance_on"):
        sealing_gap_walls(PAIR, 1.0, 1e-5, clearance_on="both")


# --- wall speeds ----------------------------------------------------------------------------


def contact(phi1):
    return PinSpace(PAIR).contacts(phi1)[-1].point


@pytest.mark.parametrize("phi_deg", [0.0, 20.0, 90.0, 180.0, 240.0, 300.0, 345.0])
def test_sliding_speed_is_the_relative_rotation_about_the_pitch_point(phi_deg):
    # Relative to the outer rotor the inner one turns about the pitch point P at
    # (m21 - 1) omega1: the sliding speed at the contact X is (m21 - 1) omega1 |X - P|,
    # along the common tangent (the contact normal passes through P).
    omega = 300.0
    phi1 = math.radians(phi_deg)
    lower, upper = sealing_wall_speeds(PAIR, phi1, omega)
    x = contact(phi1)
    slide = (PAIR.m21 - 1.0) * omega * np.linalg.norm(x - PAIR.P)
    assert abs(upper - lower) == pytest.approx(slide, rel=1e-8, abs=1e-9)  # FD of the path


def test_wall_speeds_are_equal_at_the_pitch_point_and_scale_with_the_speed():
    # Find the angle where the contact passes the pitch point (near 20 deg).
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda p: float(np.linalg.norm(contact(p) - PAIR.P)),
                          bounds=(math.radians(10), math.radians(30)), method="bounded",
                          options={"xatol": 1e-12})
    assert np.linalg.norm(contact(res.x) - PAIR.P) < 1e-9 * PAIR.diameter
    lower, upper = sealing_wall_speeds(PAIR, res.x, 500.0)
    assert upper == pytest.approx(lower, abs=1e-6)  # no sliding: rolling at P
    assert abs(upper) > 1.0  # ...but both surfaces do move relative to the contact
    # Kinematics are linear in the speed; turning backwards reverses them.
    phi1 = math.radians(240.0)
    a = np.array(sealing_wall_speeds(PAIR, phi1, 100.0))
    np.testing.assert_allclose(np.array(sealing_wall_speeds(PAIR, phi1, 250.0)), 2.5 * a,
                               rtol=1e-9)
    np.testing.assert_allclose(np.array(sealing_wall_speeds(PAIR, phi1, -100.0)), -a,
                               rtol=1e-12)


def test_pin_surface_speed_relative_to_the_contact_is_its_rolling_along_the_pin():
    # The contact runs along pin 0 at rho dtheta/dt: relative to the contact the pin
    # surface slides by minus that, whatever the rotation of the pin as a whole.
    space = PinSpace(PAIR)
    omega = 200.0
    for phi_deg in (60.0, 180.0, 250.0):
        phi1 = math.radians(phi_deg)
        h = 1e-5
        dtheta = (space.pin_theta(0, phi1 + h) - space.pin_theta(0, phi1 - h)) / (2 * h)
        _, upper = sealing_wall_speeds(PAIR, phi1, omega)
        assert abs(upper) == pytest.approx(PAIR.rho * abs(dtheta) * omega, rel=1e-6)
