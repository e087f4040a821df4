"""The twin screw's radial discharge port (geometry/twin_screw/radial_port.py).

Independent references: the chamber's sections cut by Booleans (their vertices on the
casing arcs: where the chamber meets the bores, measured, not derived from the tips),
the closed form of straight rotors (tips are axial lines: the window is a rectangle and
each leading tip uncovers R |speed ratio| (age - opening) of arc over the whole length),
seed 004's triangles for a constant lead, a dense trapezoid rule for a variable one, and
the quasi-1D model's own response to a larger port.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import subprocess
import sys

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.ports import port_timing
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw import radial_port as rp
from rotorflow.geometry.twin_screw.family import build

from .conftest import CASES

#: Seed 004's 4/6 (male 100 mm, female 96 mm, 130 mm long, 325 deg male wrap; the centre
#: distance, not given there, assumed 78 mm, as in examples/twin_screw_4_6.toml).
SIZE = (4, 6, 0.078, 0.100, 0.096)
LENGTH = 0.130
WRAP = math.radians(325.0)
#: Coarser section tables than the cases' (48 per period, twice refined): the port is
#: exact in the tips, the tables only place the opening (the volume ratio's crossing).
PPP = 48
#: A volume ratio that leaves a radial port on this machine (8.3 does not: the module
#: docstring), opened 7 deg early as in seed 004.
VOLUME_RATIO = 3.5
EARLY = math.radians(7.0)
DEG = math.pi / 180.0


@functools.cache
def pair():
    return build("circular", *SIZE)


@functools.cache
def machine(kind: str = "helical", lead_ratio: float = 1.0) -> SweptMachine:
    wrap = 0.0 if kind == "straight" else WRAP
    return SweptMachine(pair(), Sweep(kind, LENGTH, wrap, 1.0, lead_ratio), PPP)


@functools.cache
def port(kind: str = "helical", lead_ratio: float = 1.0):
    m = machine(kind, lead_ratio)
    return rp.radial_port(m, port_timing(m, VOLUME_RATIO, early_opening=EARLY))


def casing_u(polygons, r: int) -> np.ndarray:
    """u (module docstring) of the section vertices on rotor r's casing arc: within a
    few chord errors (1e-6 C) of its bore and outside the other bore."""
    (axis, radius), (other, other_radius) = (pair().casing_bores()[r],
                                             pair().casing_bores()[1 - r])
    tol = 5e-6 * SIZE[2]
    out = []
    for q in polygons:
        on = np.abs(np.linalg.norm(q - axis, axis=-1) - radius) < tol
        on &= np.linalg.norm(q - other, axis=-1) > other_radius + tol
        theta = np.arctan2(q[on, 1] - axis[1], q[on, 0] - axis[0])
        # The male turns counter-clockwise, its grooves live on angles (0, 2 pi); the
        # female clockwise, its grooves on (-pi, pi) read backwards.
        out.append(np.mod(theta, 2.0 * math.pi) if r == 0 else -theta)
    return np.concatenate(out) if out else np.zeros(0)


def measured_opening(polygons, r: int) -> float:
    """Arc length of the section's edges lying on rotor r's casing arc."""
    (axis, radius), (other, other_radius) = (pair().casing_bores()[r],
                                             pair().casing_bores()[1 - r])
    tol = 5e-6 * SIZE[2]
    total = 0.0
    for q in polygons:
        on = np.abs(np.linalg.norm(q - axis, axis=-1) - radius) < tol
        on &= np.linalg.norm(q - other, axis=-1) > other_radius - tol
        theta = np.arctan2(q[:, 1] - axis[1], q[:, 0] - axis[0])
        step = np.abs(np.remainder(np.roll(theta, -1) - theta + math.pi, 2 * math.pi) - math.pi)
        total += radius * float(step[on & np.roll(on, -1)].sum())
    return total


def section_at(m, age: float, z: float):
    """The chamber's section at height z when its age is ``age``."""
    return m.pair.chamber_polygons(float(m.section.phi_i + age - m.sweep.twist(z)))


# ---------------------------------------------------------------- the chamber's openings
def test_the_groove_openings_are_the_arcs_between_the_tips_on_the_casing():
    """Over the chamber's whole life, each bore's opening from the tips equals the
    sections' edges on that bore.  Tolerance: the sections' bore edges stop where a
    rounded tip leaves its bore by more than their chord tolerance, tens of microns
    short of the tip point (measured 1.3e-3 of a groove's opening at worst).  Tips 3 deg
    off (a wrong anchor) fail it."""
    m, p = machine(), port()
    sec = m.section
    off = [dataclasses.replace(b, lead0=b.lead0 + 3.0 * DEG) for b in p.bores]
    worst = {"exact": 0.0, "off": 0.0}
    for psi in np.linspace(sec.phi_i, sec.phi_f, 41):
        polys = m.pair.chamber_polygons(float(psi))
        for r in (0, 1):
            seen = measured_opening(polys, r)
            for name, b in (("exact", p.bores[r]), ("off", off[r])):
                arc = b.radius * float(rp._arc(b.lead(psi), b.pitch, b))
                worst[name] = max(worst[name], abs(arc - seen) / (b.radius * b.pitch))
    assert worst["exact"] < 2e-3
    assert worst["off"] > 2e-2


# ---------------------------------------------------------------- never early
def _inside_before(m, p, ages, zs):
    """The largest depth (u) by which any of the chamber's casing vertices enters the
    windows, over the given ages and heights (negative: it stays behind the edges)."""
    depth = -np.inf
    for age in ages:
        for z in zs:
            polys = section_at(m, age, z)
            for r, b in enumerate(p.bores):
                u = casing_u(polys, r)
                if len(u) and p.has_window(b):
                    depth = max(depth, float(u.max()) - max(float(p.edge(b, z)), b.top))
    return depth


@pytest.mark.parametrize("lead_ratio", [1.0, 1.6])
def test_the_window_opens_at_the_discharge_opening_never_earlier(lead_ratio):
    m, p = machine("helical", lead_ratio), port("helical", lead_ratio)
    do = p.opening
    before = do - np.linspace(60.0, 0.25, 40) * DEG
    after = do + np.array([0.5, 2.0, 8.0]) * DEG
    assert np.all(rp.open_area(p, before) == 0.0)
    a = rp.open_area(p, after)
    assert np.all(np.diff(a) > 0.0) and a[0] > 0.0
    # The sections say the same: before the opening no vertex of the chamber on a bore
    # lies in a window (1e-4 rad: the grown rotors' polygons; the leading tip is still
    # 0.25 deg x speed ratio behind the edge), after it some do.
    zs = np.linspace(0.0, LENGTH, 14)
    assert _inside_before(m, p, do - np.array([20.0, 5.0, 0.25]) * DEG, zs) < -1e-4
    assert _inside_before(m, p, [do + 5.0 * DEG], zs) > 1e-2
    # A window whose edge lies 3 deg further from the cusp opens early: the check sees it.
    wider = dataclasses.replace(p, opening=do - 3.0 * DEG)
    assert _inside_before(m, wider, [do - 0.25 * DEG], zs) > 1e-2


# ---------------------------------------------------------------- closed forms
def test_straight_rotors_uncover_the_arc_beyond_the_edge_over_the_whole_length():
    m = machine("straight")
    # An explicit timing (the straight chamber's opening by a volume ratio comes after its
    # leading tips have left the bores): opening at 360 deg of the planar life.
    timing = port_timing(m, 2.0, 300.0 * DEG, 360.0 * DEG)
    p = rp.radial_port(m, timing)
    g = pair().gearing
    ages = timing.discharge_open + np.array([1.0, 5.0, 15.0, 30.0, 40.0]) * DEG
    # Precondition from the sections: up to the last age no leading tip has reached the
    # discharge-side cusp (the chamber's casing vertices stay clear of it).
    last = section_at(m, ages[-1], 0.0)
    for r, b in enumerate(p.bores):
        assert casing_u(last, r).max() < b.bottom - 1.0 * DEG
    rate = (1.0, g.lobes_male / g.lobes_female)
    expected = LENGTH * sum(b.radius * k for b, k in zip(p.bores, rate, strict=True)) * (
        ages - timing.discharge_open)
    assert rp.open_area(p, ages) == pytest.approx(expected, rel=1e-12)


def test_constant_lead_windows_are_seed_004s_triangles():
    p = port()
    for b in p.bores:
        span = b.bottom - float(p.edge(b, LENGTH))
        assert 0.0 < span < b.bottom - b.top
        height = span / b.rate * LENGTH / WRAP
        assert rp.window_area(p, b) == pytest.approx(0.5 * b.radius * span * height, rel=1e-12)
        fig = rp.port_figures(p)
        assert fig[f"radial_window_length_{b.rotor}_mm"] == pytest.approx(height * 1e3)


def test_variable_lead_window_against_a_dense_trapezoid():
    p = port("helical", 1.6)
    z = np.linspace(0.0, LENGTH, 200_001)
    for b in p.bores:
        width = np.clip(b.bottom - np.maximum(p.edge(b, z), b.top), 0.0, None)
        # Trapezoid error: one kink where the edge meets the cusp, ~ h^2 x slope.
        assert rp.window_area(p, b) == pytest.approx(b.radius * np.trapezoid(width, z),
                                                     rel=1e-7)


@pytest.mark.parametrize("lead_ratio", [1.0, 1.6])
def test_a_chamber_wholly_past_the_edge_is_open_over_its_whole_footprint(lead_ratio):
    """A lobe pitch after the opening the chamber's trailing tips have passed the edges:
    its open area is all of its openings on the bores, here integrated along z from the
    sections.  Tolerance 1 %: the trapezoid rule on 121 heights across the kinks (0.2 %
    on the exact integrand) and the tips' rounding (measured 0.3 % together)."""
    m, p = machine("helical", lead_ratio), port("helical", lead_ratio)
    ages = p.opening + np.array([92.0, 100.0]) * DEG
    assert rp.open_area(p, ages) == pytest.approx(rp.footprint(p, ages), rel=1e-12)
    z = np.linspace(0.0, LENGTH, 121)
    arcs = [sum(measured_opening(section_at(m, ages[0], zz), r) for r in (0, 1)) for zz in z]
    assert rp.open_area(p, ages[:1])[0] == pytest.approx(np.trapezoid(arcs, z), rel=1e-2)
    # Before that, never more than either the footprint or the windows.
    ages = np.linspace(p.opening - 10 * DEG, p.opening + 140 * DEG, 301)
    windows = sum(rp.window_area(p, b) for b in p.bores)
    a = rp.open_area(p, ages)
    assert np.all(a <= rp.footprint(p, ages) * (1 + 1e-12))
    assert np.all(a <= windows * (1 + 1e-12))


def test_a_discharge_after_the_grooves_reach_the_cusp_has_no_radial_port():
    m = machine()
    # Seed 004's own timing: volume ratio 8.3 less 7 deg opens after both leading tips
    # have crossed the cusp at the discharge end.
    with pytest.raises(CaseError, match="no radial discharge port can open"):
        rp.radial_port(m, port_timing(m, 8.3, early_opening=EARLY))


# ---------------------------------------------------------------- the case key
def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd)


@pytest.mark.parametrize("text,words", [
    ('discharge_port = "side"', ("discharge_port", "'axial+radial'")),
    ("discharge_port = 2", ("discharge_port", "'radial'")),
])
def test_a_bad_discharge_port_exits_2_with_one_line(tmp_path, text, words):
    case = tmp_path / "case.toml"
    good = (CASES / "twin_screw_radial_port.toml").read_text()
    case.write_text(good.replace('discharge_port = "axial+radial"', text))
    out = run("geometry", case, "--json", cwd=tmp_path)
    assert out.returncode == 2 and out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and all(w in lines[0] for w in words), out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


def test_a_radial_port_on_an_internal_gear_is_refused(tmp_path):
    from rotorflow.workflow.case import load_case

    case = tmp_path / "case.toml"
    text = (CASES / "default.toml").read_text()
    case.write_text(text.replace("[operating]", '[operating]\ndischarge_port = "radial"'))
    with pytest.raises(CaseError, match="discharge_port"):
        load_case(case)


def test_the_table_stages_read_the_key():
    from rotorflow.workflow.stages import GEOMETRY_READS, REGISTRY

    for stage in ("geometry", "table"):
        assert "operating.discharge_port" in REGISTRY[stage].reads
    assert "operating.discharge_port" in GEOMETRY_READS


# ---------------------------------------------------------------- the quasi-1D model
@pytest.fixture(scope="module")
def tables():
    """The radial-port example's table ("axial+radial"), coarse; its "axial" and "radial"
    twins."""
    from rotorflow.geometry.summary import build_machine, chamber_table
    from rotorflow.workflow.case import load_case

    case = load_case(CASES / "twin_screw_radial_port.toml")
    m = build_machine(case, PPP)
    return m, *(chamber_table(dataclasses.replace(case, discharge_port=k), m)
                for k in ("axial+radial", "axial", "radial"))


def test_the_tables_hold_the_ports_asked_for(tables):
    m, both, axial, radial = tables
    # The default, axial, is today's table: no columns of parts.
    assert "area_hp_radial_m2" not in axial.columns
    assert np.array_equal(axial.area_hp_m2, both.columns["area_hp_axial_m2"])
    assert np.array_equal(both.area_hp_m2, both.columns["area_hp_axial_m2"]
                          + both.columns["area_hp_radial_m2"])
    assert np.array_equal(radial.area_hp_m2, both.columns["area_hp_radial_m2"])
    assert np.all(radial.columns["area_hp_axial_m2"] == 0.0)
    for t in (axial, radial):
        assert np.array_equal(t.area_lp_m2, both.area_lp_m2)
    # The radial port opens where the timing says, exactly (the axial port, sampled, shows
    # slivers of up to 3e-8 m2 long before, and its linear interpolation between samples
    # 3.75 deg apart starts a sample early; the quasi-1D model reads neither before the
    # opening), and it is no sliver: its largest open area is of the axial one's order
    # (seed 004 sums them; here 330 against 823 mm2).
    radial_area, axial_area = (both.columns[f"area_hp_{k}_m2"] for k in ("radial", "axial"))
    # (an age of the curves; the table counts from the birth, birth_age later)
    opening = port_timing(m, VOLUME_RATIO, early_opening=EARLY).discharge_open - m.birth_age
    assert np.all(radial_area[both.angle_rad < opening] == 0.0)
    assert radial_area[np.searchsorted(both.angle_rad, opening)] > 0.0
    assert radial_area.max() > 0.3 * axial_area.max()


def test_a_larger_discharge_port_throttles_less(tables):
    """Sealed chambers of a dry perfect gas, nozzle ports, the discharge pressure near
    the built-in one (3.5^1.4 = 5.8 bar; 6 bar): the gas left in the chamber after the
    opening is squeezed through the port, over-compressed above the discharge pressure.
    A larger port (axial + radial) lowers that peak and the work; the delivery is the
    trapped mass whatever the port (sealed chambers).  The radial port alone cannot
    empty the chamber: its windows close when the grooves leave the bores, and the
    pocket left at the discharge end is squeezed shut."""
    from rotorflow.quasi1d.settings import Operating, Ports
    from rotorflow.quasi1d.simulate import simulate

    both = tables[1]
    op = Operating.from_section({
        "p_suction_bar": 1.0, "p_discharge_bar": 6.0, "T_suction_K": 293.15,
        "speed_rpm": 6000, "volume_ratio": VOLUME_RATIO, "discharge_early_opening_deg": 7,
        "heat_capacity": "constant"}, "test")
    runs = {}
    for kind in ("axial", "radial", "axial+radial"):
        area = (both.area_hp_m2 if kind == "axial+radial"
                else both.columns[f"area_hp_{kind}_m2"])
        res = simulate(dataclasses.replace(both, area_hp_m2=area), op, None,
                       Ports(model="nozzle"))
        assert res.converged
        runs[kind] = (res.figures, float(res.chamber["p_Pa"].max()))
    over = {k: p - op.p_discharge_Pa for k, (_, p) in runs.items()}
    assert 0.0 < over["axial+radial"] < 0.8 * over["axial"]
    assert over["axial+radial"] < over["radial"]
    power = {k: f["indicated_power_W"] for k, (f, _) in runs.items()}
    assert power["axial+radial"] < power["axial"] and power["axial+radial"] < power["radial"]
    flows = [f["mass_flow_kg_s"] for f, _ in runs.values()]
    # Sealed chambers deliver what they trap (the solver's mass balance: 1e-6).
    assert max(flows) == pytest.approx(min(flows), rel=1e-5)
