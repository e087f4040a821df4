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
