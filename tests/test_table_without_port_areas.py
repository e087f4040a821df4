"""A chamber table made without its port areas (for ideal ports, which follow the port
timing alone): the same figures as the full table's, refused where areas are read."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry import table as table_io
from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.quasi1d import case_settings, simulate
from rotorflow.workflow.case import load_case

from .conftest import CASES


@pytest.fixture(scope="module")
def tables():
    case = load_case(CASES / "twin_screw_4_6.toml")
    m = build_machine(case)
    return case, chamber_table(case, m), chamber_table(case, m, port_areas=False)


def test_ideal_ports_give_the_same_figures_without_the_areas(tables):
    case, full, bare = tables
    assert full.port_areas and not bare.port_areas
    assert full.area_hp_m2.max() > 0 and not bare.area_hp_m2.any()
    assert bare.port_timing == full.port_timing
    settings = case_settings(case.raw, "twin_screw_4_6.toml")
    assert settings[2].model == "ideal"
    a, b = (simulate(t, *settings).summary() for t in (full, bare))
    for key in ("mass_flow_kg_s", "indicated_power_W", "shaft_power_W",
                "discharge_temperature_K"):
        assert b[key] == pytest.approx(a[key], rel=1e-9), key


def test_nozzle_ports_refuse_a_table_without_areas(tables, tmp_path):
    case, _, bare = tables
    op, leak, ports, num, mech = case_settings(case.raw, "twin_screw_4_6.toml")
    with pytest.raises(CaseError, match="nozzle ports need the chamber table's port areas"):
        simulate(bare, op, leak, dataclasses.replace(ports, model="nozzle"), num, mech)
    with pytest.raises(ValueError, match="without its port areas"):
        table_io.write(bare, tmp_path / "table.csv")
    assert not list(tmp_path.iterdir())


def test_the_internal_gear_keeps_its_areas_either_way():
    # (its port areas are the section's own, computed with the curves: nothing to save)
    case = load_case(CASES / "default.toml")
    bare = chamber_table(case, port_areas=False)
    assert bare.port_areas and np.asarray(bare.area_lp_m2).max() > 0
