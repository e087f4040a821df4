"""Screw-pump profiles (seed 003): identical N-N rotors, the trochoidal pair's lands.

A trochoidal lobe is a tip arc on the bore over half the lobe (a land), a root arc and
flanks traced by the mate's sharp corners.  A land covers a cusp at most angles, so no
groove reaches a cusp there: the grooves end at the land's corners, the land's arc on
its own bore is a clearance gap whose two sides load it up to its middle, and the male
and female grooves of one chamber meet in the mesh, through the space between the
flanks that straddles the cusp line.  The invariants are the family's
(tests/test_twin_screw_few_lobes.py), on C = 78 mm, both rotors 110 mm.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from rotorflow.geometry.forces import power_split
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.ports import port_timing
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.family import build

PPP = 48
#: (profile, lobes): the trochoidal 1-1 and 2-2 pairs, the circular and the involute
#: identical 1-1.
PAIRS = [("trochoidal", 1), ("trochoidal", 2), ("circular", 1), ("involute", 1)]


@functools.cache
def pair(profile: str, lobes: int):
    return build(profile, lobes, lobes, 0.078, 0.110, 0.110)


@functools.cache
def machine(profile: str, lobes: int, wrap_deg: float = 1080.0, ppp: int = PPP):
    return SweptMachine(pair(profile, lobes), Sweep("helical", 0.2, math.radians(wrap_deg)),
                        ppp)


def _fold(x: np.ndarray, ppp: int) -> np.ndarray:
    n = len(x)
    pad = -(-n // ppp) * ppp - n
    return np.concatenate([x, np.zeros((pad,) + x.shape[1:])]).reshape(
        (-1, ppp) + x.shape[1:]).sum(0)


def test_a_trochoidal_lobe_has_a_land_of_half_the_lobe():
    """The land is found from the profile alone (no knowledge of its construction):
    half the lobe's polar span (pi / N), on the outer radius, its middle the lobe's tip
    (the tip arc's centre line, on +x for both rotors' lobe 0 by construction).  A
    rounded tip (the circular rack) has none."""
    for lobes in (1, 2):
        p = pair("trochoidal", lobes)
        for rotor in (0, 1):
            assert p.land_half_width(rotor) == pytest.approx(0.5 * math.pi / lobes, abs=1e-9)
        assert math.remainder(p.tip_angle(0), 2 * math.pi / lobes) == pytest.approx(0, abs=1e-9)
        corners = p.corner_points(p.male)
        assert np.linalg.norm(corners, axis=-1) == pytest.approx(0.055, abs=1e-12)
    assert not pair("circular", 1).has_lands


@pytest.mark.parametrize("profile, lobes", PAIRS)
def test_sections_close_around_both_rotors(profile, lobes):
    """At uniform pressure the chambers of a section load no rotor, and with both
    rotors they fill the two bores.  Loads: round-off (2e-16 D measured; before the
    lands' gaps were loaded to their middles the trochoidal male was pushed by 1 D x 1 Pa
    per metre, the land's missing chord).  Areas: 1e-7, the cuts' (8e-9 measured)."""
    p = pair(profile, lobes)
    sec = p.section(PPP)
    d = p.diameter
    assert np.abs(_fold(sec.force, PPP)).max() < 1e-12 * d
    assert np.abs(_fold(sec.torque, PPP)).max() < 1e-12 * d * d
    fill = (_fold(sec.area, PPP) + p.male.area + p.female.area) / p.working_area - 1.0
    assert np.abs(fill).max() < 1e-7


@pytest.mark.parametrize("profile, lobes", PAIRS)
def test_a_chamber_changes_only_as_the_rotors_sweep_it(profile, lobes):
    """dA between sections is the integral of the torques' power (tests/test_twin_
    screw_few_lobes.py): a part booked to the wrong chamber breaks it by its whole area
    (a trochoidal part between the flanks is 3 % of A_max).  The sharp corners crossing
    the cusps are kinks in the rate: 2.1e-3 of A_max measured at 48 points per period."""
    sec = pair(profile, lobes).section(PPP)
    power = sec.torque @ np.array(sec.speed_ratio)
    h = sec.psi[1] - sec.psi[0]
    slope = np.gradient(power, h)
    step = 0.5 * h * (power[1:] + power[:-1]) + h * h / 12.0 * (slope[:-1] - slope[1:])
    assert (np.abs(np.diff(sec.area) - step) / sec.area.max()).max() < 5e-3


def test_the_trochoidal_chamber_is_one_male_and_one_female_groove():
    """The chamber's male and female grooves are half a revolution apart in age (they
    meet through the space between the flanks, a quarter turn either side of the
    flanks standing on the line of centres); and with the male land facing the female
    (psi = 0) the male groove is whole: the cut's area is pi R^2 less the rotor's own
    area (Green's theorem on the profile, an independent construction; 1e-7)."""
    p = pair("trochoidal", 1)
    assert p.female_shift == pytest.approx(math.pi, abs=1e-9) or \
        p.female_shift == pytest.approx(-math.pi, abs=1e-9)
    whole = math.pi * 0.055 ** 2 - p.male.area
    parts = p.cutter.cut(0.0)  # male land facing the female: the male groove is whole
    male = [q for q in parts if q.rotor == 0]
    assert len(male) == 1 and male[0].area == pytest.approx(whole, rel=1e-7)


@pytest.mark.parametrize("profile, lobes", [("trochoidal", 1), ("circular", 1),
                                            ("involute", 1)])
def test_a_three_turn_wrap_transports_at_constant_volume(profile, lobes):
    """The plateau's volume is L / wrap times the area table's integral (an independent
    quadrature: 1e-6; 4e-10 measured), and it lasts the wrap less the chamber's planar
    life; the ports' plateau rule closes suction at its start, opens discharge at its
    end."""
    m = machine(profile, lobes)
    sec, cur = m.section, m.curves
    plateau = (cur.phi >= sec.phi_f) & (cur.phi <= sec.phi_i + m.sweep.wrap)
    assert plateau.sum() > 0.6 * (m.sweep.wrap - m.life_2d) / cur.step
    held = np.trapezoid(sec.area, sec.psi) * m.sweep.length / m.sweep.wrap
    assert cur.volume[plateau] == pytest.approx(held, rel=1e-6)
    # The plateau's ends, where the section leaves the suction plate and reaches the
    # discharge plate, lie between the nodes (ports.planar_life): as absolute angles
    # they agree at 48 and 96 points per period within 1e-4 rad (2e-5 measured), where
    # the zero nodes either side of the life moved by a step (the suction closed at the
    # later node until 2026-11-30: a 1-1 pump's eta_v moved by 3.3e-3 with resolution).
    fine = machine(profile, lobes, 1080.0, 2 * PPP)
    ends = []
    for mm in (m, fine):
        t = port_timing(mm, 1.0)
        phi0 = float(mm.curves.phi[0])
        ends.append((t.suction_close + phi0, t.discharge_open - mm.sweep.wrap + phi0))
    assert ends[0] == pytest.approx(ends[1], abs=1e-4)
    # and within a node's step of the nodes' life (the cut's own edges, not a step off)
    assert sec.phi_i - 1e-9 < ends[0][1] < sec.phi_i + cur.step
    assert sec.phi_f - cur.step < ends[0][0] < sec.phi_f + 1e-9


def test_the_power_balance_closes():
    """Seed 000 Eqs. 17-18 at volume_ratio 1 into 2 bar.  Trochoidal 1-1: 1.3e-3 at 48,
    4.2e-4 at 96 and 1.0e-4 at 192 points per period (the corners reaching the cusps
    put kinks in the areas' rates, which the loads' linear interpolant takes at low
    order; a land carries no torque, so the gap's load split does not enter)."""
    m = machine("trochoidal", 1, 1080.0, 96)
    assert power_split(m, 1.0, p_discharge=2.0e5).power_balance_error < 1e-3


CASE = """[machine]
type = "twin-screw"
profile = "{profile}"
lobes_male = 1
lobes_female = 1
centre_distance_mm = 78
male_diameter_mm = 110
female_diameter_mm = 110
length_mm = 200
[sweep]
kind = "helical"
wrap_male_deg = 1080
[operating]
volume_ratio = 1
p_suction_bar = 0.5
p_discharge_bar = 1.0
T_suction_K = 293.15
speed_rpm = 3000
[leakage]
model = "nozzle"
gap_um = 100
"""


@functools.cache
def pump_case(profile: str, tmp: Path):
    """(case, chamber table) of CASE on ``profile``."""
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.workflow.case import load_case

    path = tmp / f"pump_{profile}.toml"
    path.write_text(CASE.format(profile=profile))
    case = load_case(path)
    return case, chamber_table(case)


@pytest.fixture(scope="module")
def tmp(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("pumps")


PROFILES = ["trochoidal", "circular", "involute"]


@pytest.mark.parametrize("profile", PROFILES)
def test_a_pump_without_internal_compression_simulates(tmp, profile):
    """volume_ratio = 1: the quasi-1D model reads the table's port timing (suction closes
    at the plateau's start, the discharge opens at its end) and its cycle conserves mass
    and energy (balances below 1e-6)."""
    from rotorflow.quasi1d import Leakage, Numerics, Operating
    from rotorflow.quasi1d import simulate as run

    case, table = pump_case(profile, tmp)
    m = machine(profile, 1, 1080.0, 96)
    # the plateau's ends (the test above), as ages of the curves: the table counts its
    # angles from the birth, birth_age after the curves' first node
    timing = port_timing(m, 1.0)
    sc, do = timing.suction_close - m.birth_age, timing.discharge_open - m.birth_age
    assert table.port_timing["suction_close_rad"] == pytest.approx(sc, abs=1e-9)
    assert table.port_timing["discharge_open_rad"] == pytest.approx(do, abs=1e-9)
    raw = case.raw
    res = run(table, Operating.from_section(raw["operating"], "test"),
              Leakage.from_section(raw["leakage"], "test"), numerics=Numerics())
    f = res.figures
    assert res.converged
    assert f["suction_close_deg"] == pytest.approx(math.degrees(sc), abs=1e-6)
    assert f["discharge_open_deg"] == pytest.approx(math.degrees(do), abs=1e-6)
    assert abs(f["mass_balance_error"]) < 1e-6
    assert abs(f["energy_balance_error"]) < 1e-6


def _carry_over(profile: str, tmp: Path) -> float:
    """The volume a chamber still holds at the last node its discharge port is open,
    per V_max: what it carries past its discharge (its rotors' pocket handed on to the
    chamber behind; a conjugate pair squeezes it to nothing)."""
    _, table = pump_case(profile, tmp)
    last = np.nonzero(table.area_hp_m2 > 0.0)[0][-1]
    return float(table.volume_m3[last] / table.volume_m3.max())


@pytest.mark.parametrize("profile", PROFILES)
def test_a_conjugate_pump_pair_carries_nothing_over(tmp, profile):
    """Every shipped pump profile is conjugate (rack-generated, or traced by the mate's
    corners): at the discharge face the mate fills the groove, so the chamber's volume
    at the port's last open node is a node's step of its vanishing (<= 1e-6 of V_max;
    1.4e-8 circular, 1.5e-8 involute, 7.4e-8 trochoidal measured), and the section
    table hands no area from a dying chamber to a newborn one (a pair that left a
    pocket would start its chamber with it: geometry/machine.py's non-conjugate
    branch)."""
    assert _carry_over(profile, tmp) < 1e-6
    assert pair(profile, 1).section(PPP).area[0] == 0.0


@pytest.mark.xfail(strict=True, reason=(
    "seed 003: the circular profile 'retains a high carryover, as is the case for the "
    "involute profile ...  The trochoidal profile ... has a small carry over'; the "
    "shipped circular, involute and trochoidal 1-1 pairs are all conjugate and carry "
    "nothing over (<= 1e-7 of V_max each): the seed's profiles, of which it gives no "
    "dimensions, must leave pockets these do not; this measure can pass only on a pair "
    "that is not conjugate"))
def test_seed_003_the_circular_carries_more_over_than_the_trochoidal(tmp):
    assert _carry_over("circular", tmp) > 10.0 * max(_carry_over("trochoidal", tmp), 1e-6)


def test_the_involute_interlobe_line_does_not_depend_on_the_resolution():
    """The 1-1 involute's chamber takes its leading contact where the contact crosses
    the cusp line, which for identical rotors is at the pitch point, met by a node of
    the table exactly: there the contact (found to ~1e-11 m) fell on either side of the
    line, the crossing went unlocated, the line's end kept half a step and the interlobe
    line converged at first order (1.7e-3 off at 96 points per period,
    bench/bench_pump_profiles.py).  Now 24 and 96 points per period give one line at
    every common angle (1e-9; 3e-15 measured)."""
    def interlobe(m, at=None):
        lines = m.track_lines if at is None else m.track_lines_at(at)
        return sum(x for (name, d), x in lines.items() if name.startswith("interlobe") and d > 0)

    coarse, fine = machine("involute", 1, 1080.0, 24), machine("involute", 1, 1080.0, 96)
    here, there = interlobe(coarse), interlobe(fine, coarse.curves.phi)
    assert np.abs(here - there).max() < 1e-9 * there.max()


@pytest.mark.parametrize("profile", ["circular", "involute"])
def test_a_one_lobe_pairs_blow_holes_are_booked_where_its_sections_book_them(profile):
    """Off the grid, a cut's own booking (blowhole.openings_of: the male and female
    parts meeting at a cusp belong to different chambers) says where chamber 0 has
    each blow-hole; the section table's Opening intervals must say the same, at 48 and
    at 49 points per period alike.  A one-lobe rotor's one groove reaches both cusps,
    so its tip crossing either cusp changes which chambers meet at both: before the
    other cusp's crossings were slot ends, the intervals spanned whole slots of which
    the chamber held the latter half (the vacuum pump's blow-hole integrals 53 % too
    large), and at 49 (4 k + 1) the halves fell short of a majority and none was
    booked."""
    from rotorflow.geometry.twin_screw import section as S
    from rotorflow.geometry.twin_screw.blowhole import openings_of

    p = pair(profile, 1)
    period, base = 2.0 * math.pi, -S._beta0(p)
    for ppp in (PPP, PPP + 1):
        sec = p.section(2 * ppp)
        booked = {(o.name, o.offset): o.intervals for o in sec.openings}
        assert len(booked) == 4, booked
        ends = np.concatenate([iv.ravel() for iv in booked.values()])
        for psi in np.linspace(sec.phi_i, sec.phi_f, 97)[1:-1]:
            if np.min(np.abs(ends - psi)) < 1e-3:
                continue  # (at a crossing itself)
            q = int(np.floor((psi - base) / period + 1e-9))
            parts = S._cut(p, float(psi - q * period))
            qs = [S.chamber_index(p, x, float(psi - q * period), p.female_shift)
                  for x in parts]
            own = {(n, d) for c, n, d, w in openings_of(parts, qs) if c == q and w > 0.0}
            table = {key for key, iv in booked.items()
                     if np.any((iv[:, 0] < psi) & (psi < iv[:, 1]))}
            assert own <= table, (ppp, psi, own, table)
            assert {k for k in table if _width(sec, k, psi) > 1e-9} <= own, (ppp, psi)


def _width(sec, key, psi):
    (o,) = [o for o in sec.openings if (o.name, o.offset) == key]
    return float(o.width(np.array([psi]))[0])
