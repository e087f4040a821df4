"""Invariants of the sweep and load integrals, and convergence of the volume curve."""

import math

import numpy as np
import pytest

from rotorflow.geometry.forces import net_loads
from rotorflow.geometry.internal_gear.pair import PinGerotor, sigma_limit
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep

PAIR = PinGerotor(5, 1.3, sigma_limit(5, 1.3), 0.1)
L = 0.12


def machine(sweep, ppp=96, pair=PAIR):
    return SweptMachine(pair, sweep, ppp)


def test_helical_tends_to_straight_as_wrap_vanishes():
    straight = machine(Sweep("straight", L)).curves
    for wrap, tol in ((1e-3, 2e-3), (1e-4, 2e-4)):
        hel = machine(Sweep("helical", L, wrap)).curves
        n = len(straight.volume)
        # Deviation is first order in the wrap: the chamber lags by at most wrap.
        dv = np.abs(hel.volume[:n] - straight.volume).max() / straight.volume.max()
        assert dv < tol


def test_straight_volume_is_area_times_length():
    # By symmetry the largest straight chamber sits at phi = pi (1 + 1/N1) (seed 000).
    from rotorflow.geometry.internal_gear.space import PinSpace

    m = machine(Sweep("straight", L))
    a_max = PinSpace(PAIR).whole_space(np.array([math.pi * (1 + 1 / 5)]))[0][0]
    assert m.volume_max == pytest.approx(a_max * L, rel=1e-9)


def test_conical_with_unit_scale_equals_helical():
    hel = machine(Sweep("helical", L, 2.0)).curves
    con = machine(Sweep("conical", L, 2.0, scale_end=1.0, lead_ratio=1.0)).curves
    np.testing.assert_allclose(con.volume, hel.volume, rtol=0, atol=1e-15)
    np.testing.assert_allclose(con.torque, hel.torque, rtol=0, atol=1e-15)


def test_conical_volume_scales_with_integral_of_scale_squared():
    # A straight cone (no twist) is the straight chamber times \int s^2 dz.
    con = machine(Sweep("conical", L, 0.0, scale_end=0.6)).curves
    st = machine(Sweep("straight", L)).curves
    factor = (1 + 0.6 + 0.36) / 3
    assert con.volume.max() == pytest.approx(st.volume.max() * factor, rel=1e-10)


@pytest.mark.parametrize("sweep", [
    Sweep("straight", L), Sweep("helical", L, 2.4), Sweep("conical", L, 3.0, 0.7, 0.5)])
def test_net_force_and_torque_vanish_at_uniform_pressure(sweep):
    m = machine(sweep)
    p = np.full_like(m.curves.volume, 3.0e5)
    _, torque, force = net_loads(m, p)
    scale = 3.0e5 * m.pair.diameter**2 * L
    assert np.abs(torque).max() < 1e-9 * scale
    assert np.abs(force).max() < 1e-9 * 3.0e5 * m.pair.diameter * L


def test_power_identity_section_by_section():
    # Kinematics: dA/dphi1 = (torque on outer) + m21 (torque on inner) per unit pressure.
    sec = machine(Sweep("straight", L), ppp=384).section
    dA = np.gradient(sec.area, sec.psi)
    resid = dA - (sec.torque[:, 0] + PAIR.m21 * sec.torque[:, 1])
    assert np.abs(resid[1:-1]).max() < 1e-4 * np.abs(dA).max()


def test_volume_curve_converges_with_points():
    # The section table is exact at its nodes; the error is the spline between them,
    # fourth order away from birth and death. Measured against a fine reference.
    sweep = Sweep("helical", L, 2.0)
    ref = machine(sweep, ppp=768)
    errs, ns = [], [24, 48, 96]
    for n in ns:
        m = machine(sweep, ppp=n)
        # Compare on the coarse grid, which is a subset of the reference grid.
        k = 768 // n
        n_common = min(len(m.curves.volume), len(ref.curves.volume[::k]))
        diff = m.curves.volume[:n_common] - ref.curves.volume[::k][:n_common]
        errs.append(np.abs(diff).max() / ref.volume_max)
    order = -np.polyfit(np.log(ns), np.log(errs), 1)[0]
    assert errs[-1] < 1e-4
    assert order > 2.0


@pytest.mark.parametrize("sweep", [Sweep("straight", L), Sweep("helical", L, 2.4)])
def test_power_balance_with_a_clearance_volume(sweep):
    # A non-conjugate (arc) fillet hands a chamber over with a finite area; the shaft
    # power must still equal the p dV work of the chamber loop (Eq. 18).
    from rotorflow.geometry.forces import power_split

    arc = PinGerotor(5, 1.3, sigma_limit(5, 1.3), 0.1, "arc", 0.11)
    split = power_split(machine(sweep, pair=arc), 3.0)
    assert split.power_balance_error < 1e-4
