"""Twin-screw pairs with one or two lobes (issue 14: seed 003's 1-1 screw pumps).

With few lobes a groove is most of the bore: one connected piece of fluid holds both
lives of a groove (newborn at the top of the mesh, dying at the bottom), a 1-lobe tip
bounds its groove at both ends, and a wrap of several turns gives the chamber a
transport phase at constant volume.  The invariants are the 4/6 pair's
(tests/test_family_contract.py, tests/test_twin_screw_lines.py), checked here on the
symmetric circular rack at 1/1 and 2/2 (C = 78 mm, both rotors 100 mm).  That rack is no
pump profile at one lobe (its pitch is 2 pi r1 = 245 mm against a depth of 22 mm: two
nearly eccentric discs with a shallow crescent groove, male and female unlike), but it
is a conjugate pair, and the bookkeeping must hold for any.

Before the fix a part's life was told by its groove's mid-line and by which cusp its
whole piece of fluid reached: at 1/1, parts of 20-60 % of the largest chamber changed
chambers from one section to the next, and the power balance was off by 0.09 (1/1) and
0.17 (2/2).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.forces import power_split
from rotorflow.geometry.machine import SweptMachine, _extend
from rotorflow.geometry.ports import port_timing
from rotorflow.geometry.scalar import minimum
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.contact_line import contact_line_length
from rotorflow.geometry.twin_screw.family import build, centred_tip_radius
from rotorflow.geometry.twin_screw.meshing import Gearing

#: lobes -> (rotor length, male wrap in degrees): the 1/1 pump wraps three turns (its
#: chamber's planar life is 825 deg, so it transports for 255 deg), the 2/2 less.
SWEEPS = {1: (0.2, 1080.0), 2: (0.12, 300.0)}
PPP = 48  # coarse: every invariant below holds at any resolution but the power balance


@functools.cache
def pair(lobes: int):
    """The circular rack whose female tip circle is centred on the pitch line (the
    compressor default; with equal lobes and diameters the family now defaults to the
    rack of equal circles, whose identical rotors test_pump_profiles checks)."""
    g = Gearing(0.078, lobes, lobes)
    h = 0.050 - g.r1
    return build("circular", lobes, lobes, 0.078, 0.100, 0.100,
                 tip_radius=centred_tip_radius(g, h, h))


@functools.cache
def machine(lobes: int, ppp: int = PPP) -> SweptMachine:
    length, wrap = SWEEPS[lobes]
    return SweptMachine(pair(lobes), Sweep("helical", length, math.radians(wrap)), ppp)


def _fold(x: np.ndarray, ppp: int) -> np.ndarray:
    """Sum of every chamber present at each section (chambers one period apart share
    grid nodes)."""
    n = len(x)
    pad = -(-n // ppp) * ppp - n
    return np.concatenate([x, np.zeros((pad,) + x.shape[1:])]).reshape(
        (-1, ppp) + x.shape[1:]).sum(0)


@pytest.mark.parametrize("lobes, ppp", [(1, PPP), (2, PPP), (1, 192)])
def test_sections_close_around_both_rotors(lobes, ppp):
    """At uniform pressure the chambers of a section load no rotor, and with both
    rotors they fill the two bores.  Loads: round-off (1e-16 of D measured; a wetted arc
    booked to no part, as a sliver of fluid between a flat 1-lobe tip and its bore at
    one of the 192 sections was, left 4e-3 D, and flank chords cut short where they
    run along the cusp line 1e-4 D).  Areas: 1e-7, the sections' cuts (3e-9 measured).
    (The 192-point table is the one the power balance's loads are sampled on.)"""
    p = pair(lobes)
    sec = p.section(ppp)
    d = p.diameter
    assert np.abs(_fold(sec.force, ppp)).max() < 1e-12 * d
    assert np.abs(_fold(sec.torque, ppp)).max() < 1e-12 * d * d
    inside = p.male.area + p.female.area
    fill = (_fold(sec.area, ppp) + inside) / p.working_area - 1.0
    assert np.abs(fill).max() < 1e-7


@pytest.mark.parametrize("lobes", [1, 2])
def test_a_chamber_changes_only_as_the_rotors_sweep_it(lobes):
    """Per unit pressure the fluid's torques' power on a chamber is the rate of its
    area (the rotors' arcs sweep it; bores and cusp line stand still), so between two
    sections dA is the integral of that power (trapezoid with its end correction).
    A part handed to another chamber breaks that by its whole area: 0.2-0.6 of the
    largest chamber before the fix.  What remains is the quadrature across kinks (a tip
    reaching a cusp, a flank crossing the cusp line, where the rate has a square-root
    onset), 1.5e-3 of A_max at most at 48 points per period (measured)."""
    sec = pair(lobes).section(PPP)
    power = sec.torque @ np.array(sec.speed_ratio)
    h = sec.psi[1] - sec.psi[0]
    slope = np.gradient(power, h)
    step = (0.5 * h * (power[1:] + power[:-1])
            + h * h / 12.0 * (slope[:-1] - slope[1:]))
    mismatch = np.abs(np.diff(sec.area) - step) / sec.area.max()
    assert mismatch.max() < 5e-3, np.degrees(sec.psi[np.argmax(mismatch)])


@pytest.mark.parametrize("lobes", [1, 2])
def test_interlobe_contacts_part_two_lives_of_one_groove(lobes):
    """Both sides of an interlobe contact are one groove, newborn and dying: N lobe
    periods apart (a revolution), on either side of the cusp line."""
    for track in pair(lobes).section(PPP).tracks:
        if track.kind == "interlobe":
            assert set(np.abs(track.offset[track.present])) == {lobes}, track.name


@pytest.mark.parametrize("lobes", [1, 2])
def test_interlobe_lines_add_up_to_the_rack_contact_line(lobes):
    """The chambers' interlobe lines, summed over the chambers present, are the whole
    contact line the rack gives (contact_line.py, which never cuts a section): 4e-8
    measured at 48 points per period."""
    m = machine(lobes)
    n = len(m.curves.phi)
    total = sum(np.concatenate([v, np.zeros(-(-n // PPP) * PPP - n)])
                for (name, d), v in m.track_lines.items()
                if name.startswith("interlobe") and d > 0)
    fold = total.reshape(-1, PPP).sum(0)
    p = pair(lobes)
    for j in range(0, PPP, 8):
        whole = contact_line_length(p, p.rack, m.sweep, float(m.curves.phi[j]))
        assert fold[j] == pytest.approx(whole, rel=1e-6), j


def test_a_one_lobe_tip_leads_one_life_and_trails_the_other():
    """A 1-lobe tip bounds its groove's newborn life (whose leading tip it is) and its
    dying one (trailing): both lines exist, each the tip's closed-form line, its turn
    from the cusp where it leaves the other bore to the one where it enters it (2 pi
    less twice the cusps' polar angle) within the wrap, times sqrt(1 / twist'^2 +
    R^2); 1e-8 as for the 4/6 pair (cubic rates between nodes)."""
    m = machine(1)
    p = m.pair
    xc, yc = p.cusp
    rate = m.sweep.wrap / m.sweep.length
    for rotor, radius, axis in (("male", p.male_radius, 0.0),
                                ("female", p.female_radius, p.gearing.centre_distance)):
        span = 2.0 * math.pi - 2.0 * math.atan2(yc, abs(xc - axis))
        exact = min(span, m.sweep.wrap) * math.hypot(1.0 / rate, radius)
        for side, d in (("lead", 1), ("trail", -1)):
            assert m.track_lines[(f"tip-{rotor}-{side}", d)].max() == \
                pytest.approx(exact, rel=1e-8), (rotor, side)


def test_a_long_wrap_transports_at_constant_volume():
    """Seed 003: a wrap longer than the chamber's planar life gives a transport phase.
    The chamber holds its whole planar life between the end plates from the section's
    death (it leaves the suction plate) to its birth reaching the discharge plate, and
    its volume there is L / wrap times the area's integral over the life (the table's
    trapezoid, an independent quadrature: 5e-8 measured; the volume's Gauss nodes
    along z leave the plateau flat to 2e-8).  Off the plateau it falls (like the fifth
    power of the angle: 2e-5 at 30 deg)."""
    m = machine(1)
    sec, cur = m.section, m.curves
    assert m.sweep.wrap - m.life_2d == pytest.approx(math.radians(255.0), abs=1e-9)
    plateau = (cur.phi >= sec.phi_f) & (cur.phi <= sec.phi_i + m.sweep.wrap)
    assert plateau.sum() > 0.6 * math.radians(255.0) / cur.step
    held = np.trapezoid(sec.area, sec.psi) * m.sweep.length / m.sweep.wrap
    assert cur.volume[plateau] == pytest.approx(held, rel=1e-6)
    edge = round(math.radians(30.0) / cur.step)
    first, last = np.nonzero(plateau)[0][[0, -1]]
    assert cur.volume[first - edge] < held * (1.0 - 1e-6)
    assert cur.volume[last + edge] < held * (1.0 - 1e-6)


def test_the_power_balance_closes():
    """Seed 000 Eqs. 17-18: the shaft power of the fluid's torques against the
    chambers' p dV work.  1/1 at the default 96 points per period: 3e-6 (built-in ratio
    2, measured; 1.4e-5 at ratio 1 into 2 bar).  The 2/2 pair's female flanks cross the
    cusp line, a square-root onset in two chambers' area rates that the loads' linear
    interpolant takes at low order: 1.6e-4 at 48 and at 96 points per period (7e-5 with
    the loads 4 times finer), against 0.17 before."""
    assert power_split(machine(1, 96), 2.0).power_balance_error < 2e-5
    assert power_split(machine(2), 2.0).power_balance_error < 3e-4


def test_volume_ratio_one_discharges_at_the_end_of_transport():
    """Without internal compression (a vacuum or multiphase pump) suction closes where
    the chamber leaves the suction plate and the discharge opens where it reaches the
    discharge plate: the two ends of the transport plateau, where the volume stops
    rising and starts falling.  The chamber then meets the discharge pressure at
    constant volume, and the ideal cycle's work is (p_d - p_s) V_max (the closed form,
    against the chamber's own p-V loop: the plateau's end carries no dV, 1e-6)."""
    m = machine(1)
    timing = port_timing(m, 1.0)
    # The plateau's ends lie between the section table's nodes (ports.planar_life;
    # tests/test_twin_screw_pumps.py checks them across resolutions): the planar life
    # they span is the nodes' less at most two section steps at either end (the zero
    # nodes either side, and a sealing point's node next to the fluid).
    h = float(m.section.psi[1] - m.section.psi[0])
    life = timing.suction_close - (timing.discharge_open - m.sweep.wrap)
    assert 0.0 < m.life_2d - life < 4.0 * h
    split = power_split(m, 1.0, p_discharge=2.0e5)
    closed = 1.0e5 * m.volume_max * m.pair.rotors[0].lobes / (2.0 * math.pi)
    assert split.cycle_power_per_omega1 == pytest.approx(closed, rel=1e-6)
    # 1.4e-5 at the default 96 points per period (3e-4 at 48, as at ratio 2).
    assert power_split(machine(1, 96), 1.0, p_discharge=2.0e5).power_balance_error < 5e-5
    with pytest.raises(ValueError, match="discharge pressure"):
        power_split(m, 1.0)
    # No plateau: suction closes and discharge opens together, at the volume maximum
    # (between the table's nodes, 7.5 deg apart here: by the machine's own quadrature,
    # 7e-4 deg).
    short = SweptMachine(pair(1), Sweep("helical", 0.2, math.radians(400.0)), PPP)
    timing = port_timing(short, 1.0)
    k = int(np.argmax(short.curves.volume))
    phi = short.curves.phi
    peak, _ = minimum(lambda p: -float(short.volume_at(p)[0]), phi[k - 1], phi[k + 1])
    assert timing.suction_close == timing.discharge_open == \
        pytest.approx(peak - phi[0], abs=math.radians(0.01))


CASE = """[machine]
type = "twin-screw"
profile = "circular"
lobes_male = 1
lobes_female = 1
centre_distance_mm = 78
male_diameter_mm = 100
female_diameter_mm = 100
length_mm = 200
[sweep]
kind = "helical"
wrap_male_deg = 1080
[operating]
volume_ratio = {ratio}
p_suction_bar = 1.0
p_discharge_bar = 2.0
T_suction_K = 293.15
speed_rpm = 3000
"""


def test_a_case_may_ask_for_no_internal_compression(tmp_path: Path):
    from rotorflow.workflow.case import load_case

    for ratio, ok in (("1", True), ("1.0", True), ("0.99", False)):
        path = tmp_path / "pump.toml"
        path.write_text(CASE.format(ratio=ratio))
        if ok:
            assert load_case(path).volume_ratio == 1.0
        else:
            with pytest.raises(CaseError, match="at least 1"):
                load_case(path)


def test_the_area_table_is_what_the_volume_integrates():
    """A guard on the plateau test's reference: the spline the volumes integrate and
    the table's trapezoid agree (1e-7 at 48 points per period)."""
    sec = machine(1).section
    spline = _extend(sec, sec.area).integrate(sec.psi[0], sec.psi[-1])
    assert np.trapezoid(sec.area, sec.psi) == pytest.approx(spline, rel=1e-6)
