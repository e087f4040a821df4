"""Form (disc) cutter of the inner rotor from the contact condition, and its round trip
(geometry/cutter.py)."""

import math

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.export.cutter import (
    CutterSetup,
    _Turned,
    default_setup,
    form_cutter,
    round_trip,
)
from rotorflow.geometry.internal_gear.profiles import inner_profile
from rotorflow.geometry.summary import build_machine
from rotorflow.workflow.case import load_case

from .conftest import CASES

TOL = 5e-6


@pytest.mark.parametrize("name", ["default", "table1_outer_ev2", "table1_inner_ev5"])
def test_helical_cutter_regenerates_the_rotor(name):
    case = load_case(CASES / f"{name}.toml")
    m = build_machine(case)
    curve = inner_profile(m.pair)
    setup = default_setup(m.pair, m.sweep, None, None)
    # default setting angle: the helix angle at the inner pitch radius
    k = m.pair.m21 * m.sweep.wrap / m.sweep.length
    assert math.tan(setup.setting_angle) == pytest.approx(k * m.pair.lobes_inner * m.pair.E)
    cut = form_cutter(curve, setup, TOL)
    # tool profile rounded as written (9 decimals of mm), then enveloped back
    axial = np.round(cut.axial * 1e3, 9) * 1e-3
    radius = np.round(cut.radius * 1e3, 9) * 1e-3
    rt = round_trip(curve, cut, axial, radius)
    assert rt["round_trip_max_m"] <= TOL
    assert rt["interference_m"] <= TOL
    # the contact points are on the rotor flank: screwed back to z = 0 they are profile
    # points (rotor frame, turned)
    prof = _Turned(curve)
    c, s = np.cos(k * cut.contact[:, 2]), np.sin(k * cut.contact[:, 2])
    q = np.stack([c * cut.contact[:, 0] - s * cut.contact[:, 1],
                  s * cut.contact[:, 0] + c * cut.contact[:, 1]], -1)
    assert np.abs(q - prof.point(cut.u)).max() < 1e-12


def test_round_trip_fails_on_a_perturbed_tool():
    case = load_case(CASES / "default.toml")
    m = build_machine(case)
    curve = inner_profile(m.pair)
    cut = form_cutter(curve, default_setup(m.pair, m.sweep, None, None), TOL)
    radius = cut.radius.copy()
    mid = slice(len(radius) // 3, 2 * len(radius) // 3)
    radius[mid] += 3 * TOL  # a tool 15 um too big over a third of its profile
    rt = round_trip(curve, cut, cut.axial, radius)
    assert rt["round_trip_max_m"] > TOL
    assert rt["interference_m"] > TOL


def test_straight_rotor_cutter_is_the_profile():
    # A straight rotor (no lead) and a tool axis normal to the rotor axis (S = 0): the
    # contact lies in the plane through the tool axis, so the tool profile is the rotor
    # profile itself: axial = y, radius = C - x (rotor frame, tooth space on +x).
    case = load_case(CASES / "default.toml")
    pair = case.pair
    curve = inner_profile(pair)
    setup = CutterSetup(0.0, 0.1, 0.0)
    cut = form_cutter(curve, setup, TOL)
    p = _Turned(curve).point(cut.u)
    np.testing.assert_allclose(cut.contact[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(cut.axial, p[:, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(cut.radius, 0.1 - p[:, 0], rtol=0, atol=1e-12)
    rt = round_trip(curve, cut)
    assert rt["round_trip_max_m"] <= TOL and rt["interference_m"] <= TOL


def test_conical_rotor_has_no_form_cutter():
    m = build_machine(load_case(CASES / "crc60.toml"))
    with pytest.raises(CaseError, match="conical"):
        default_setup(m.pair, m.sweep, None, None)
