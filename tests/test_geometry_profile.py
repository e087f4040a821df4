"""Pin-generated profiles: conjugacy, undercut limit, pitch-point pressure angle."""

import math

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.internal_gear.pair import PinGerotor, pressure_angle_at_pitch, sigma_limit
from rotorflow.geometry.internal_gear.space import PinSpace


@pytest.fixture(scope="module")
def pair():
    return PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 1.0)


def test_eq1_dimensions_reproduce_max_diameter(pair):
    # The inner tip (radius a - rho + E about O2) reaches D/2 at the fillet bottom.
    tip = np.linalg.norm(pair.inner_point(np.array([math.pi])), axis=-1)[0]
    assert tip + pair.E == pytest.approx(pair.diameter / 2, rel=1e-12)
    g = np.linspace(0, 2 * math.pi * pair.lobes_inner, 20001)
    r = np.linalg.norm(pair.inner_point(g), axis=-1)
    assert r.max() == pytest.approx(pair.a - pair.rho + pair.E, rel=1e-9)
    assert r.min() == pytest.approx(pair.a - pair.rho - pair.E, rel=1e-9)


def test_sigma_limit_is_where_inner_profile_speed_vanishes(pair):
    # At sigma_lim the offset curve's arc-length speed touches zero (onset of undercut);
    # below it the speed stays positive.
    g = np.linspace(0, 2 * math.pi, 200001)
    speed = np.linalg.norm(pair.inner_derivative(g), axis=-1)
    assert speed.min() < 1e-4 * speed.max()
    below = PinGerotor(6, 1.39934, 0.9 * pair.sigma_lim, 1.0)
    s2 = np.linalg.norm(below.inner_derivative(g), axis=-1)
    assert s2.min() > 0.02 * s2.max()


def test_fillet_meets_pin_arc_at_cone_edge(pair):
    g_lo, g_hi = pair.fillet_range
    _, ends = pair.fillet(np.array([g_hi, g_lo]))
    np.testing.assert_allclose(ends[0], pair.pin_point(0, -pair.pin_edge), atol=1e-10)
    np.testing.assert_allclose(ends[1], pair.pin_point(1, pair.pin_edge), atol=1e-10)


def test_inner_rotor_never_enters_a_pin(pair):
    # Conjugacy: at any angle, the inner profile stays outside every pin disc.
    g = np.linspace(0, 2 * math.pi * pair.lobes_inner, 4001)
    y = pair.inner_point(g)
    for phi in np.linspace(0, 2 * math.pi, 37):
        x = (y @ np.array([[math.cos(pair.m21 * phi), math.sin(pair.m21 * phi)],
                           [-math.sin(pair.m21 * phi), math.cos(pair.m21 * phi)]])) + pair.O2
        for k in range(pair.lobes_outer):
            ang = math.pi / 2 + 2 * math.pi * k / pair.lobes_outer + phi
            c = pair.a * np.array([math.cos(ang), math.sin(ang)])
            assert np.linalg.norm(x - c, axis=-1).min() > pair.rho - 1e-9


def test_pressure_angle_eq5_and_no_contact_statement(pair):
    # Table 1 of seed 000 lists 28.2 deg for this profile (rounded to 0.1 deg).
    assert math.degrees(pair.pressure_angle) == pytest.approx(28.2, abs=0.1)
    # Eq. 5 is the law of cosines of the triangle O1, pin centre, pitch point.
    lam, sig = pair.lam, pair.sigma
    c = (1 + sig**2 - lam**2) / (2 * sig)
    assert math.cos(pair.pressure_angle + math.pi / 2) == pytest.approx(c, rel=1e-12)
    assert pressure_angle_at_pitch(1.5, 0.3) is None  # lambda - 1 > sigma


def test_region_areas_sum_to_annulus(pair):
    # Conservation: the tooth spaces tile the area between the rotors at every angle.
    sp = PinSpace(pair)
    outer = pair.lobes_outer * (
        sp.pin_arc_integral(0, pair.pin_edge, -pair.pin_edge) + sp.fillet_full_integral
    )
    annulus = outer + sp.inner_lobe_integral * pair.lobes_inner
    for phi in (0.0, 0.3, 0.52, 1.1):
        total = sum(
            sp.region_areas(phi + 2 * math.pi * j / pair.lobes_outer)[1].sum()
            for j in range(pair.lobes_outer)
        )
        assert total == pytest.approx(annulus, rel=1e-12)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(lobes_outer=6, lam=1.0, sigma=0.1, diameter=1.0), "lambda"),
        (dict(lobes_outer=1, lam=1.4, sigma=0.1, diameter=1.0), "lobes_outer"),
        (dict(lobes_outer=6, lam=1.4, sigma=0.9, diameter=1.0), "undercut"),
        (dict(lobes_outer=6, lam=1.4, sigma=0.5, diameter=0.0), "diameter"),
    ],
)
def test_bad_profiles_raise_case_error(kwargs, message):
    with pytest.raises(CaseError, match=message):
        PinGerotor(**kwargs)


def test_arc_fillet_must_not_infringe_the_conjugate_one(pair):
    with pytest.raises(CaseError, match="infringes"):
        PinGerotor(6, pair.lam, pair.sigma, 1.0, "arc", 1.02)
    with pytest.raises(CaseError, match="apex"):
        PinGerotor(6, pair.lam, pair.sigma, 1.0, "arc", 0.9)


def test_arc_fillet_leaves_a_clearance_area_and_still_tiles(pair):
    arc = PinGerotor(6, pair.lam, pair.sigma, 1.0, "arc", 1.1)
    sp, sc = PinSpace(arc), PinSpace(pair)
    # The arc lies outside the conjugate fillet, so every space grows by the same area:
    # the lens between the two fillets.
    lens = sp.fillet_full_integral - sc.fillet_full_integral
    assert lens > 0
    for phi in (0.2, 0.9):
        a_arc = sp.whole_space(np.array([phi]))[0][0]
        a_con = sc.whole_space(np.array([phi]))[0][0]
        assert a_arc - a_con == pytest.approx(lens, rel=1e-12)
    # At the deep mesh the conjugate space is (nearly) closed; the arc one keeps the lens.
    deep = sp.whole_space(np.array([math.pi / 6]))[0][0]
    assert deep > 0.9 * lens
