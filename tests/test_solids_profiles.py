"""Transverse profiles as analytic curves: sampling to a chordal tolerance, clearance
offsets, self-intersection checks (geometry/curves.py, geometry/internal_gear/profiles.py)."""

import math

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.curves import closest, sample, sample_polygon
from rotorflow.geometry.internal_gear.pair import PinGerotor
from rotorflow.geometry.internal_gear.profiles import inner_profile, outer_profile
from rotorflow.geometry.internal_gear.space import PinSpace
from rotorflow.geometry.offsets import Clearance, offset_profile
from rotorflow.geometry.planar import cross
from rotorflow.geometry.polygons import (
    check_simple,
    rings_intersections,
    self_intersections,
    signed_area,
)
from rotorflow.workflow.case import load_case

from .conftest import CASES

EXAMPLES = ("default", "table1_outer_ev2", "table1_outer_ev5", "table1_inner_ev5", "crc60")


@pytest.fixture(scope="module")
def pair():
    return load_case(CASES / "default.toml").pair


@pytest.mark.parametrize("name", EXAMPLES)
def test_fillet_table_is_the_closed_form(name):
    # The Hermite table stands in for the closed-form fillet in every evaluation; it must
    # be the same curve far below any tolerance (2e-11 m = 4e-6 of 5 um). The largest
    # error sits in the table's first interval, at the fillet's steep end: 1.0018e-11 m
    # on the CRC.60, which a one-ulp change of the pin radius (the undercut limit found
    # by golden section instead of Brent's method) moved across the former 1e-11.
    p = load_case(CASES / f"{name}.toml").pair
    prof = outer_profile(p)
    g_lo, g_hi = p.fillet_range
    g = np.random.default_rng(1).uniform(g_lo, g_hi, 20000)
    err = np.linalg.norm(prof._fillet_hermite(g, 0) - p.fillet(g)[1], axis=-1)
    assert err.max() < 2e-11


@pytest.mark.parametrize("name", EXAMPLES)
def test_profiles_close_and_enclose_the_pinspace_area(name):
    p = load_case(CASES / f"{name}.toml").pair
    for prof in (outer_profile(p), inner_profile(p)):
        # pieces join: end of piece j = start of piece j+1 (1e-11 m: closed forms)
        ends = prof.point(np.arange(prof.n) + 1.0 - 1e-13)
        starts = prof.point(np.arange(1, prof.n + 1) % prof.n)
        assert np.abs(ends - starts).max() < 1e-11
        # a fine polygon encloses the exact area (its error ~ tol * perimeter / area)
        poly = sample_polygon(prof, 1e-7)
        assert signed_area(poly) == pytest.approx(prof.area, rel=1e-5)


@pytest.mark.parametrize("tol", [20e-6, 5e-6])
def test_sampling_honours_the_chordal_tolerance(pair, tol):
    for prof in (outer_profile(pair), inner_profile(pair)):
        u = sample(prof, tol)
        poly = prof.point(u)
        _, dv, _ = closest(prof, poly, u)
        assert dv.max() < 1e-12  # vertices on the curve
        un = np.append(u[1:], prof.n)
        mid = 0.5 * (poly + np.roll(poly, -1, axis=0))
        _, dm, _ = closest(prof, mid, 0.5 * (u + un), iterations=12)
        assert dm.max() <= tol
        assert dm.max() > 0.5 * tol  # and not needlessly fine


def test_polygon_area_error_is_first_order(pair):
    # Chords cut the curve on one side: the enclosed area's error scales with the
    # tolerance (order 1), which is why the STL vertices are shifted (solids.py).
    prof = inner_profile(pair)
    tols = np.array([40e-6, 20e-6, 10e-6, 5e-6])
    err = [abs(signed_area(sample_polygon(prof, t)) / prof.area - 1) for t in tols]
    slope = np.polyfit(np.log(tols), np.log(err), 1)[0]
    assert 0.8 < slope < 1.2


def test_uniform_offset_is_a_true_normal_offset(pair):
    base = outer_profile(pair)
    c = 50e-6
    off = offset_profile(base, Clearance((c,)), +1)
    u = sample(off, 1e-6)
    q = off.point(u)
    _, d, sd = closest(base, q, u, iterations=12)
    # every offset point is c from the base curve, on the outside (material side)
    assert np.abs(d - c).max() < 1e-10
    assert (sd > 0).all()
    # area: A + c P + pi c^2, and the moments agree with the polygon
    assert off.area == pytest.approx(base.area + c * base.length + math.pi * c * c, rel=1e-12)
    # (the polygon at a 0.1 um chord tolerance is itself ~2e-6 off: chords)
    assert signed_area(sample_polygon(off, 1e-7)) == pytest.approx(off.area, rel=1e-5)


def test_distributed_offset_follows_the_distribution(pair):
    base = outer_profile(pair)
    cl = Clearance((10e-6, 40e-6, 20e-6, 5e-6))
    off = offset_profile(base, cl, +1)
    u = np.linspace(0.0, base.n, 3001)[:-1]
    q = off.point(u)
    _, d, _ = closest(base, q, u, iterations=12)
    want = cl(base.lobe_fraction(u))
    assert np.abs(d - want).max() < 1e-10
    assert want.min() >= 0.0
    # (the polygon at a 0.1 um chord tolerance is itself ~2e-6 off: chords)
    assert signed_area(sample_polygon(off, 1e-7)) == pytest.approx(off.area, rel=1e-5)


def test_clearance_that_folds_the_profile_is_refused(pair):
    # sigma_bar = 1: the inner profile has a point of zero convex radius; any clearance
    # taken off the inner rotor folds it there.
    with pytest.raises(CaseError, match="folds"):
        offset_profile(inner_profile(pair), Clearance((1e-6,)), -1)
    # on the outer rotor the pins (radius rho) limit it
    with pytest.raises(CaseError, match="folds"):
        offset_profile(outer_profile(pair), Clearance((1.01 * pair.rho,)), +1)
    offset_profile(outer_profile(pair), Clearance((0.5 * pair.rho,)), +1)  # fine
    # below the undercut limit the inner rotor takes a small clearance
    p = PinGerotor(5, 1.4, 0.9 * PinGerotor(5, 1.4, 0.5, 0.1).sigma_lim, 0.1)
    offset_profile(inner_profile(p), Clearance((5e-6,)), -1)


def test_self_intersection_is_found_and_only_then():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    bow = square[[0, 2, 1, 3]]
    assert len(self_intersections(square)) == 0
    assert len(self_intersections(bow)) == 1
    assert len(rings_intersections([square, 0.5 * square[::-1] + 0.25])) == 0
    assert len(rings_intersections([square, 0.5 * square[::-1] + 0.75])) > 0
    with pytest.raises(CaseError, match="self-intersects"):
        check_simple(bow, "test polygon")


def test_example_profiles_are_simple_and_a_perturbed_one_is_not(pair):
    for prof in (outer_profile(pair), inner_profile(pair)):
        poly = sample_polygon(prof, 5e-6)
        check_simple(poly, prof.name)
        bad = poly.copy()
        bad[[10, 12]] = bad[[12, 10]]  # swap two vertices: the polygon crosses itself
        assert len(self_intersections(bad)) > 0


def test_pinspace_area_is_what_the_profile_encloses(pair):
    # The analytic volumes of the solids use these areas: cross-check them against an
    # independent integral of the curve (Gauss-Legendre on the pieces).
    for prof in (outer_profile(pair), inner_profile(pair)):
        green = 0.5 * prof.integrate(lambda u, c=prof: cross(c.point(u), c.derivative(u)))
        assert green == pytest.approx(prof.area, rel=1e-9)
    sp = PinSpace(pair)
    assert inner_profile(pair).area == pytest.approx(-sp.inner_lobe_integral * 5)
