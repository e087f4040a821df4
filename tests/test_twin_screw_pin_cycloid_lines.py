"""Sealing lines of the pin-cycloid pair (examples/twin_screw_4_6.toml), whose contact
rests on corners and passes cusps.

Its male has a sharp tip (the contact rests there while the female flank it generates
meshes) and epicycloids with cusps on the pitch circle; its pin arcs coincide once a
period (a band).  The law of gearing has spurious zeros next to a cusp (the evolute is
near) and jumps at the corners, so the contact is found by the pieces' rolling angles
(:meth:`.TwinScrewPair._root`), and the track's joints are both ends of every piece.
Before issue 13 the lines converged at first order (1.6e-2, 7.5e-3, 3.3e-3 at 24, 48,
96 points per period against 192: bench/results/twin_screw.csv).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.planar import rotate
from rotorflow.workflow.case import load_case

CASE = Path(__file__).resolve().parents[1] / "examples" / "twin_screw_4_6.toml"


@functools.cache
def _case():
    return load_case(CASE)


@functools.cache
def machine(ppp: int) -> SweptMachine:
    case = _case()
    pair = dataclasses.replace(case.pair)  # a pair of its own: no shared caches
    return SweptMachine(pair, case.sweep(None), ppp)


def _total(lines: dict, kind: str):
    return sum(v for (name, d), v in lines.items() if name.startswith(kind) and d > 0)


@pytest.mark.parametrize("kind", ["tip", "interlobe"])
def test_pin_cycloid_lines_converge(kind):
    """Every end of a stretch is found exactly (joints, the band, the cusps, a tip that
    sealed before the chamber's first node), so what is left is the cubic's O(h^4):
    measured 1.4e-8 (interlobe) and 3e-10 (tip) at 24 points per period against 96."""
    ref = machine(96)
    for ppp in (24, 48):
        m = machine(ppp)
        here = _total(m.track_lines, kind)
        there = _total(ref.track_lines_at(m.curves.phi), kind)
        # 1e-6: two decades above what is measured, three below the first-order error
        # of a stretch end off by half a step.
        assert np.abs(here - there).max() / there.max() < 1e-6, ppp


def test_lines_hold_as_the_table_grows_finer():
    """The same at 384 points per period, where a track's last nodes before the joint at
    the top cusp are lost in more steps than at 96 (the sliver there is below the
    polygons' resolution over 0.0082 rad: four nodes, not two) and a node's contact lies
    between two far-apart points of the profile's foot grid.  The interlobe lines to
    the chamber 4 periods on fell short by 0.3 mm there (4e-3; 1.3e-4 once the lost
    nodes were reached by angle); measured now 3.5e-7 against 768."""
    ref = machine(96)
    m = machine(384)
    for kind in ("tip", "interlobe"):
        here = _total(m.track_lines, kind)
        there = _total(ref.track_lines_at(m.curves.phi), kind)
        assert np.abs(here - there).max() / there.max() < 1e-6, kind


def test_a_contact_between_far_apart_foot_grid_points_is_found():
    """The contact search starts at the nearest point of a grid sampled by chord error,
    whose points lie 0.35 mm apart on the male's gentle flank: a corner 14 um from the
    contact at 384 points per period (male angle -1.5524 rad) had its nearest grid
    point 0.17 mm away, 0.022 of a piece off, beyond the search window, and was kept
    as a contact with no rate.  The point found must be on the male and satisfy the law
    of gearing (its normal through the pitch point), moving at the male's speed."""
    pair = _case().pair
    psi = -1.5523885154299637
    x = np.array([35.17538976, -17.1293251]) * 1e-3
    found, rate = pair.contact_near(x, psi)
    assert np.linalg.norm(found - x) < 3e-5  # it is the nearby contact
    local = rotate(found[None, :], -psi)[0]
    u = np.linspace(0.0, pair.male.n, 400_001)[:-1]
    on_male = np.linalg.norm(pair.male.point(u) - local, axis=-1)
    k = int(np.argmin(on_male))
    foot = minimize_scalar(lambda v: float(np.linalg.norm(pair.male.point(np.array([v]))[0]
                                                          - local)),
                           bounds=(u[k - 1], u[k + 1]), method="bounded",
                           options={"xatol": 1e-13})
    assert foot.fun < 1e-9  # a point of the male profile
    pitch = rotate(pair.gearing.pitch_point[None, :], -psi)[0]
    normal = pair.male.normal(np.array([foot.x]))[0]
    miss = abs(normal[0] * (pitch - local)[1] - normal[1] * (pitch - local)[0])
    # (the angle between the normal and the way to the pitch point; a contact 0.022 of
    # a piece off along this flank misses by ~1e-2)
    assert miss < 1e-7 * np.linalg.norm(pitch - local)
    assert np.linalg.norm(rate) > 1e-3  # it moves (m/rad)


def test_contact_next_to_a_cusp_is_the_meshing_point():
    """Just past the instant the female corner D2 passes the pitch point, the contact
    is that corner, i.e. the point of the male's epicycloid traced by D2 at male angle
    psi itself; the law of gearing has a second zero a few microns away on the same
    arc (the evolute of a cusp is near), which was once taken (7e-5 m off)."""
    pair = _case().pair
    trace = pair.male.pieces[3]  # the epicycloid traced by D2, its cusp at the end
    span = trace.angle1 - trace.angle0
    for dpsi in (0.01, 0.03, 0.066, 0.1):
        psi = trace.angle1 + dpsi
        t = 1.0 - ((trace.angle1 - psi) / span) ** 2
        true = rotate(trace.eval(np.array([t])), psi)[0]
        found, _ = pair.contact_near(true, psi)
        # 1e-9 C: the contact's parameter is found to 1e-13 of a piece.
        assert np.linalg.norm(found - true) < 1e-9 * pair.gearing.centre_distance, dpsi


def test_every_line_is_one_path_seen_from_both_chambers():
    """A chamber's two interlobe points of one kind are named by continuity
    (``interlobe-trail`` and ``interlobe-trail#2``), not by which line they are; each
    line must still be one leakage path carrying both chambers' columns (an unpaired
    view leaked the same line twice: +17 % interlobe leakage at 96 points per period)."""
    m = machine(96)
    paths = m.pair.leakage_paths({}, m.track_lines, {})
    lines = [p for p in paths if p.kind in ("tip", "interlobe")]
    assert lines and all(p.mirror is not None for p in lines), [p.name for p in lines]
    assert len(lines) == len(m.track_lines) // 2
    assert math.isfinite(sum(float(np.sum(v)) for v in m.track_lines.values()))
