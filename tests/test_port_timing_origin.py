"""The angles a case gives and the figures and table report are counted from the
chamber's birth itself, not from the first node of the resolution's grid.

A twin screw's section table starts at the grid node before the birth, which moves by
up to a step with the resolution (0.94 deg between 24 and 48 points per period on the
4/6 pin-cycloid): a port angle counted from it named a different rotor position at each
resolution, and the reported timing moved with the grid.
"""

import dataclasses
import math

import numpy as np
import pytest

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.ports import chamber_section
from rotorflow.geometry.summary import chamber_table, geometry_figures
from rotorflow.workflow.case import load_case

from .conftest import CASES

#: Explicit port angles in the filling and the compression (the volume changes fast
#: there, so a shifted origin shows in the volume at the angle).
TIMED = (CASES / "twin_screw_4_6.toml").read_text().replace(
    "volume_ratio = 7.6", "suction_close_deg = 300").replace(
    "discharge_early_opening_deg = 7", "discharge_open_deg = 700")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    path = tmp_path_factory.mktemp("origin") / "timed.toml"
    path.write_text(TIMED)
    case = load_case(path)
    out = {}
    for ppp in (24, 48):
        fresh = dataclasses.replace(case, pair=dataclasses.replace(case.pair))
        m = SweptMachine(fresh.pair, fresh.sweep(None), ppp)
        out[ppp] = (m, geometry_figures(fresh, m), chamber_table(fresh, m))
    return out


def test_the_grids_first_nodes_differ(runs):
    # (what makes the rest a test: the two grids start at different angles)
    (m24, *_), (m48, *_) = runs[24], runs[48]
    assert abs(m24.curves.phi[0] - m48.curves.phi[0]) > math.radians(0.5)


def test_the_birth_is_where_the_section_first_holds_fluid_at_every_resolution(runs):
    births = []
    for m, fig, _ in runs.values():
        birth = math.radians(fig["phi_i_deg"])
        # cut independently either side of it (the bisection's last bracket is 2^-12 of
        # a section step, 8e-6 rad at 24 points per period)
        assert not any(len(q) >= 3 for q in chamber_section(m, birth - 1e-4))
        assert any(len(q) >= 3 for q in chamber_section(m, birth + 1e-4))
        births.append(birth)
    assert births[0] == pytest.approx(births[1], abs=2e-5)


def test_a_given_port_angle_is_the_same_rotor_position_at_every_resolution(runs):
    figs = [fig for _, fig, _ in runs.values()]
    for fig in figs:
        assert fig["angle_suction_close_deg"] == pytest.approx(300.0, abs=1e-9)
        assert fig["angle_discharge_open_deg"] == pytest.approx(700.0, abs=1e-9)
    # The volume at the closing angle: 0.94 deg apart (the grids' offset), it differed
    # by 5.3e-3 of itself; the curves at 24 points per period are within 1e-4.
    v = [fig["volume_suction_close_m3"] for fig in figs]
    assert v[0] == pytest.approx(v[1], rel=1e-4)


def test_the_tables_angles_start_at_the_birth(runs):
    for m, fig, table in runs.values():
        a = table.angle_rad
        # the first row is the node before the birth (volume 0), the second after it
        assert -m.curves.step < a[0] <= 0.0 < a[1]
        assert table.volume_m3[0] == 0.0
        # the table's port timing is the case's, in its own angles
        assert table.port_timing["suction_close_rad"] == pytest.approx(math.radians(300.0))
        vol = np.interp(math.radians(300.0), a, table.volume_m3)
        assert vol == pytest.approx(fig["volume_suction_close_m3"], rel=1e-3)
