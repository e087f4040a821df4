"""The vectorised split phase, the exact sweep integral of the loads, and contact tables."""

import math

import numpy as np
import pytest

from rotorflow.geometry.forces import power_split
from rotorflow.geometry.internal_gear.contacts import contact_table, pitch_point_distance
from rotorflow.geometry.internal_gear.pair import PinGerotor, sigma_limit
from rotorflow.geometry.internal_gear.space import PinSpace
from rotorflow.geometry.internal_gear.split import SplitSpace
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep

# Three birth patterns of Table 1 (seed 000): N1 = 6 and 3 are born at a pin junction,
# N1 = 4 at an interior double root of the contact-time function.
PAIRS = [PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 0.1),
         PinGerotor(4, 1.05774, sigma_limit(4, 1.05774), 0.1),
         PinGerotor(3, 1.39227, sigma_limit(3, 1.39227), 0.1)]


def _split_angles(space, n):
    t_lo, t_hi = space.fillet_time_range
    period = 2 * math.pi / space.pair.lobes_outer
    phi_i = math.remainder(t_lo + period, 2 * math.pi)
    phi_j = phi_i + t_hi - t_lo
    phi_f = 2 * math.pi + period - phi_i
    # Interior points only: at the phase ends a double root splits at rounding level.
    inner = np.linspace(0, 1, n + 2)[1:-1]
    return np.concatenate([phi_i + (phi_j - phi_i) * inner,
                           phi_f - (phi_j - phi_i) * inner[::-1]])


@pytest.mark.parametrize("pair", PAIRS, ids=["N6", "N4", "N3"])
def test_vectorised_split_matches_the_scalar_regions(pair):
    space = PinSpace(pair)
    phi = _split_angles(space, 60)
    reg = SplitSpace(space).regions(phi)
    d = pair.diameter
    for i, angle in enumerate(phi):
        cs, areas, touched = space.region_areas(angle)
        assert reg.count[i] == len(cs)
        np.testing.assert_allclose(reg.area[i, : len(areas)], areas, rtol=0, atol=1e-13 * d * d)
        np.testing.assert_array_equal(reg.touched[i, : len(areas)], touched)
        pts = np.array([c.point for c in cs])
        np.testing.assert_allclose(reg.points[i, : len(cs)], pts, rtol=0, atol=1e-11 * d)


def test_split_phase_has_more_than_two_contacts_somewhere():
    # Otherwise the previous test would compare nothing but whole spaces.
    space = PinSpace(PAIRS[0])
    reg = SplitSpace(space).regions(_split_angles(space, 60))
    assert reg.count.max() >= 4


@pytest.mark.parametrize("sweep", [Sweep("helical", 0.1, 2.2),
                                   Sweep("conical", 0.1, 3.0, 0.6, 0.4)],
                         ids=["helical", "conical"])
def test_hat_kernel_integrates_the_linear_interpolant_exactly(sweep):
    # Against brute force: very many Gauss nodes along z on the linear interpolant of a
    # kinked table, at a node of the section grid.
    h = 0.01
    psi = np.arange(0, 8.0, h)
    f = np.sqrt(np.abs(np.sin(3 * psi))) + psi  # square-root kinks, like the loads
    kernel = sweep.hat_kernel(h, 2)
    j = 600
    conv = float(np.dot(kernel, f[j - np.arange(len(kernel))]))
    z, wz = sweep.nodes(panels=4000)
    brute = float(np.sum(np.interp(psi[j] - sweep.twist(z), psi, f) * sweep.scale(z) ** 2 * wz))
    assert conv == pytest.approx(brute, rel=1e-7)
    # A constant integrates to \int scale^2 dz whatever the twist law.
    assert kernel.sum() == pytest.approx(sweep.scale_squared_integral, rel=1e-12)


def test_pi_max_converges_with_the_section_refinement():
    # Pi_max needs the kinked section loads finely; the sweep adds no error, so the
    # refinement alone converges it (the default, 32, is within 1e-4 of 128).
    pair = PAIRS[0]
    sweep = Sweep("helical", 0.1, math.radians(136))
    values = {r: power_split(SweptMachine(pair, sweep, 48, r), 2.0, "inner").pi_max
              for r in (4, 64, 256)}
    assert abs(values[64] / values[256] - 1) < 1e-4
    assert abs(values[4] / values[256] - 1) > 10 * abs(values[64] / values[256] - 1)


def test_contact_table_obeys_the_law_of_gearing():
    pair = PAIRS[0]
    table = contact_table(pair, 2.0)
    # Every pin touches once at every angle; fillet contacts come and go.
    assert np.sum(table.kind == "pin") == pair.lobes_outer * 30
    assert np.sum(table.kind == "fillet") > 0
    # The common normal of every pin contact passes through the pitch point.
    assert pitch_point_distance(table, pair).max() < 1e-12 * pair.diameter
    # Contacts lie on the pin circles' radius band of the outer rotor.
    r = table.radius_outer_m[table.kind == "pin"]
    assert r.min() >= pair.a - pair.rho - 1e-12 and r.max() <= pair.a + 1e-12


def test_neighbour_labels_are_seen_alike_from_both_sides():
    # The line between a chamber and the one d periods older, at section angle psi, is
    # that chamber's line to this one at psi + d periods: labels must mirror.
    from rotorflow.geometry.internal_gear.section import section_chamber

    pair = PAIRS[0]
    sec = section_chamber(pair, 96)
    n1, step = pair.lobes_outer, 96
    alive = np.nonzero(sec.psi < sec.phi_f)[0]
    checked = 0
    for k in alive[1:-1]:
        d = int(sec.lead_offset[k])
        j = k + d * step
        if 0 < j < len(sec.psi) - 1 and sec.psi[j] < sec.phi_f:
            assert sec.trail_offset[j] == -d, (np.degrees(sec.psi[k]), d)
            checked += 1
    assert checked > 200
    assert set(np.unique(sec.lead_offset[alive])) >= {1, 1 - n1}


def test_straight_sealing_lines_are_the_rotor_length():
    # Without twist or taper every contact line is straight along z: the lines around a
    # live chamber add up to two rotor lengths (leading + trailing), whatever their
    # neighbours, and the table keeps one line per pair of chambers.
    L = 0.1
    m = SweptMachine(PAIRS[0], Sweep("straight", L), 48)
    total = sum(m.seal_lines.values())
    live = m.curves.volume > 1e-6 * m.volume_max
    exact = np.isclose(total[live], 2 * L, rtol=1e-9)
    # At the instant a line changes neighbour both views may hold it for one node of
    # the table (the larger-view rule); everywhere else the sum is exact.
    assert exact.mean() > 0.99 and total.max() <= 4 * L * (1 + 1e-9)
    for d, line in m.seal_lines.items():
        k = d * 48
        if d > 0 and k < len(line):
            np.testing.assert_allclose(line[: len(line) - k], m.seal_lines[-d][k:], atol=1e-12)


def test_chamber_table_round_trip_keeps_the_far_lines(tmp_path):
    from rotorflow.geometry import table
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.workflow.case import load_case

    from .conftest import CASES

    tab = chamber_table(load_case(CASES / "crc60.toml"))
    assert set(tab.seal_far) == {2, -2, 3, -3}
    table.write(tab, tmp_path / "t.csv")
    back = table.read(tmp_path / "t.csv")
    for d in (2, -2, 3, -3, 1, -1):
        np.testing.assert_allclose(back.seal_to(d), tab.seal_to(d), rtol=1e-11)
