"""The fluid domain: casing bore between the end plates less both rotors, with the ports
cut into the end plates (geometry/export.py, ports.py)."""

import math

import numpy as np
import pytest
import trimesh
from manifold3d import CrossSection, FillRule

from rotorflow.errors import CaseError
from rotorflow.geometry.export import stl
from rotorflow.geometry.export.assembly import chamber_sum
from rotorflow.geometry.export.driver import export
from rotorflow.geometry.export.settings import Export
from rotorflow.geometry.internal_gear.space import PinSpace
from rotorflow.geometry.ports import chamber_section, port_timing, ports
from rotorflow.geometry.summary import build_machine
from rotorflow.workflow.case import load_case

from .conftest import CASES


def _between_profiles(machine):
    """Fluid volume between the conjugate profiles (zero clearance), PinSpace forms."""
    p = machine.pair
    sp = PinSpace(p)
    e = p.pin_edge
    outer = p.lobes_outer * (sp.pin_arc_integral(0, e, -e) + sp.fillet_full_integral)
    inner = -sp.inner_lobe_integral * p.lobes_inner
    return (outer - inner) * machine.sweep.scale_squared_integral


@pytest.mark.parametrize("name", ["default", "table1_outer_ev2", "crc60"])
def test_chambers_fill_the_space_between_the_rotors(name):
    # The chambers present at any angle partition the space between the profiles: the
    # chamber table's volumes sum to it (chamber-table accuracy: splines in angle, 1e-6).
    m = build_machine(load_case(CASES / f"{name}.toml"))
    total = _between_profiles(m)
    for phi in np.linspace(0.0, 2.0 * math.pi / m.pair.lobes_outer, 7):
        assert chamber_sum(m, phi) == pytest.approx(total, rel=1e-6)
    # ... and a chamber table missing one chamber would not
    assert chamber_sum(m, 0.3) - float(m.volume_at(m.curves.phi[len(m.curves.phi) // 2])[0]) \
        < (1 - 1e-3) * total


def test_ports_open_and_seal_the_chamber():
    case = load_case(CASES / "default.toml")
    m = build_machine(case)
    t = port_timing(m, case.volume_ratio)
    suction, discharge = ports(m, t)
    sec, sw = m.section, m.sweep
    scale_hp = float(sw.scale(sw.length))

    def share(region, polys, scale):
        if not polys:
            return None
        cs = CrossSection([np.ascontiguousarray(q * scale) for q in polys], FillRule.Positive)
        return (cs ^ region).area() / cs.area()

    eps = math.radians(2.0)
    for age in np.linspace(0.0, t.death, 61):
        lp = share(suction, chamber_section(m, sec.phi_i + age), 1.0)
        hp = share(discharge, chamber_section(m, sec.phi_i + age - sw.wrap), scale_hp)
        if t.suction_close + eps < age < t.discharge_open - eps:  # compression: sealed
            assert lp is None or lp < 1e-3, (math.degrees(age), lp)
            assert hp is None or hp < 1e-3, (math.degrees(age), hp)
        if age < t.suction_close - eps and hp is not None:  # filling: not open to discharge
            assert hp < 1e-3, (math.degrees(age), hp)
        if age > t.discharge_open + eps and lp is not None:  # discharging: not to suction
            assert lp < 1e-3, (math.degrees(age), lp)
    # mid-way through each window the chamber's face lies in its port
    assert share(suction, chamber_section(m, sec.phi_i + 0.5 * t.suction_close), 1.0) > 0.99
    mid = 0.5 * (t.discharge_open + t.death)
    assert share(discharge, chamber_section(m, sec.phi_i + mid - sw.wrap), scale_hp) > 0.99


def test_fluid_domain_volumes(tmp_path):
    case = load_case(CASES / "default.toml")
    settings = Export(formats=("fluid",), tolerance_m=5e-6, clearance_m=(20e-6,),
                      fluid_angle_rad=math.radians(10.0))
    man = export(case, settings, tmp_path)
    entry = man["files"]["fluid.stl"]
    assert not (tmp_path / "outer.stl").exists()  # only what was asked
    verts, faces = stl.read(tmp_path / "fluid.stl")
    tm = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    # the file: core (bore less both rotors) plus the port pockets, 1e-4
    a = man["analytic_volumes_m3"]
    ports_volume = (entry["suction_port_area_m2"] + entry["discharge_port_area_m2"]) \
        * entry["port_depth_m"]
    assert abs(tm.volume * 1e-9 / (a["fluid_core_m3"] + ports_volume) - 1) < 1e-4
    # the core: casing less both rotors (analytic), 1e-4
    assert a["fluid_core_m3"] == pytest.approx(a["casing_m3"] - a["outer_m3"] - a["inner_m3"],
                                               rel=1e-12)
    assert entry["core_volume_rel_error"] < 1e-4
    # ... and the chambers of the table plus what the clearance opens, 1e-4 (mesh) and
    # the table alone against the profiles, 1e-6 (table accuracy)
    assert entry["chamber_sum_rel_error"] < 1e-4
    assert entry["chamber_sum_vs_analytic_rel"] < 1e-6
    m = build_machine(case)
    p = m.pair
    sp = PinSpace(p)
    e = p.pin_edge
    perimeter = p.lobes_outer * (2 * e * p.rho + sp.fillet_length)
    # the clearance opens c P + pi c^2 per unit length (uniform offset of the outer profile)
    want = (20e-6 * perimeter + math.pi * 20e-6 ** 2) * m.sweep.length
    assert entry["clearance_volume_m3"] == pytest.approx(want, rel=1e-5)
    # the two flanks stay apart: together they deviate less than the narrowest gap
    assert 2 * entry["max_deviation_m"] < man["fluid_gap_min_m"]


def test_fluid_without_ports_is_the_chambers(tmp_path):
    case = load_case(CASES / "table1_outer_ev5.toml")
    settings = Export(formats=("fluid",), tolerance_m=10e-6, clearance_m=(30e-6,),
                      port_depth_m=0.0, clearance_on="outer")
    man = export(case, settings, tmp_path)
    entry = man["files"]["fluid.stl"]
    verts, faces = stl.read(tmp_path / "fluid.stl")
    tm = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    want = entry["chamber_sum_m3"] + entry["clearance_volume_m3"]
    assert abs(tm.volume * 1e-9 / want - 1) < 1e-4
    assert "suction_port_area_m2" not in entry


def test_fluid_needs_a_clearance(tmp_path):
    case = load_case(CASES / "default.toml")
    with pytest.raises(CaseError, match="clearance"):
        export(case, Export(formats=("fluid",)), tmp_path)
    assert not any(tmp_path.iterdir())
