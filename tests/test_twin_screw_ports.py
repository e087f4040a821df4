"""The end-plate ports of a twin screw (geometry/ports.py) on the section table's grid.

Independent references: the chamber's section cut afresh (a pair with no memo of cut
sections) intersected with the port shapes by Clipper; the port model's own
construction (a footprint taken out of a port meets it nowhere).  The table's open
areas themselves: tests/test_twin_screw_port_areas.py.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rotorflow.geometry import footprint as FP
from rotorflow.geometry import ports as P
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.summary import case_port_timing
from rotorflow.workflow.case import load_case

from .conftest import CASES

#: The 4/6 pin-cycloid machine at the coarsest resolution the bench runs.
PPP = 24


@pytest.fixture(scope="module")
def built():
    case = load_case(CASES / "twin_screw_4_6.toml")
    machine = SweptMachine(case.pair, case.sweep(None), PPP)
    assert machine.section.area.max() > 0.0  # the table cut first
    table_cuts = set(case.pair.cut_memo)
    timing = case_port_timing(case, machine)
    ages = machine.curves.phi - machine.curves.phi[0]
    suction, discharge = P.ports(machine, timing)
    sweepers = []  # the open areas' sweepers, for the samples they cut at turns
    init = FP.Sweeper.__init__

    def recording(self, *args, **kwargs):
        init(self, *args, **kwargs)
        sweepers.append(self)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(FP.Sweeper, "__init__", recording)
        areas = P.open_areas(machine, timing, ages)
    turns = np.array([p for s in sweepers for p in s.turns])
    return case, machine, timing, (suction, discharge), table_cuts, areas, turns


def _fresh_area(case, machine, port, psi, scale=1.0):
    """The chamber's section at psi cut by a pair that has cut nothing yet, inside port."""
    from manifold3d import CrossSection, FillRule

    pair = dataclasses.replace(case.pair)
    polys = [q for q in pair.chamber_polygons(psi) if len(q) >= 3]
    if not polys:
        return 0.0
    chamber = CrossSection([np.ascontiguousarray(q * scale) for q in polys], FillRule.Positive)
    return (chamber ^ port).area()


def test_ports_reuse_the_table_cuts(built):
    # Only the port timing's own angles (suction closing and the discharge opening, both
    # between the table's nodes), the discharge face's nodes where its area has a
    # kink (shifted by the wrap off the grid: port_areas.KINK_TOL) and the samples the
    # sweeps cut at a corner's turn (footprint_events.Events._turns, a few per sweep)
    # cost a section of their own, and the bisections of the chamber's birth and death
    # (ports.planar_life, the origin of the angles a case gives and reads): the open
    # areas' sweeps and the shapes' samples lie on the section table's grid.
    from rotorflow.geometry.twin_screw.section import RESIDUE_TOL, _beta0

    case, m, *_ , table_cuts, _, turns = built
    period = m.period

    def residues(psi):
        q = np.floor((psi + _beta0(m.pair)) / period + RESIDUE_TOL)
        return {round(float(r) / RESIDUE_TOL) for r in psi - q * period}

    shifted = residues(m.curves.phi - m.sweep.wrap)  # the discharge face's planar angles
    extra = set(case.pair.cut_memo) - table_cuts
    assert len(extra - shifted - residues(turns)) == 2 + 2 * P.LIFE_BISECTIONS
    assert 0 < len(turns) <= 2 * PPP
    assert 0 < len(extra & shifted) <= PPP  # one lobe period of residues at most


def test_port_shapes_offer_the_open_areas(built):
    """The port shapes (for solids and CFD cases) are unions of sampled sections, the
    table's areas the sections less the exact sealed region: a section cut afresh
    inside the shapes has the table's open area up to the shapes' sampling strips
    (measured 7e-4 suction, 5.3e-2 discharge of the largest area), at angles on the
    shapes' samples."""
    case, m, timing, (suction, discharge), _, _, _ = built
    sec, sw = m.section, m.sweep
    step = m.period / P.STEP_PER_PERIOD
    lp_ages = step * np.arange(2, int(timing.suction_close / step), 9)
    hp_ages = sw.wrap + step * np.arange(int((timing.discharge_open - sw.wrap) / step) + 1,
                                         int((timing.death - sw.wrap) / step), 5)
    assert len(lp_ages) >= 3 and len(hp_ages) >= 3
    lp, hp = P.open_areas(m, timing, np.concatenate([lp_ages, hp_ages]))
    direct_lp = [_fresh_area(case, m, suction, sec.phi_i + a) for a in lp_ages]
    direct_hp = [_fresh_area(case, m, discharge, sec.phi_i + a - sw.wrap) for a in hp_ages]
    assert np.abs(lp[:len(lp_ages)] - direct_lp).max() < 5e-3 * lp.max()
    assert np.abs(hp[len(lp_ages):] - direct_hp).max() < 1e-1 * hp.max()
    assert min(direct_lp) > 0.0 and max(direct_hp) > 0.0  # the samples are open


def test_ports_open_and_close_at_their_timing(built):
    case, m, timing, (suction, discharge), _, (lp, hp), _ = built
    ages = m.curves.phi - m.curves.phi[0]
    # The footprint at the discharge opening is taken out of the discharge port (the
    # sealed union ends there): it meets the port in slivers of Clipper's rounding only
    # (measured 1.4e-9 of the largest open area).
    at_opening = _fresh_area(case, m, discharge, m.section.phi_i + timing.discharge_open
                             - m.sweep.wrap)
    assert at_opening < 1e-8 * hp.max()
    # So the table's areas are zero up to the port's own angle, not a ramp across a step,
    # and open right after it.
    assert not hp[ages <= timing.discharge_open].any()
    assert hp[np.searchsorted(ages, timing.discharge_open)] > 0.0
    assert not lp[ages >= timing.suction_close].any()
    assert lp[np.searchsorted(ages, timing.suction_close) - 1] > 0.0
