"""The interlobe contact line (seed 004 Fig. 2) from the rack, against the sections.

Two constructions that share nothing but the profile: the rack's path of contact with
its meshing angle (contact_line.py) and the Clipper-cut sections' contacts, each
snapped where the law of gearing holds (regions.py, boundaries.py).
"""

import math

import numpy as np
import pytest

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.contact_line import contact_line_length
from rotorflow.geometry.twin_screw.family import build

L = 0.13


@pytest.fixture(scope="module")
def pair():
    return build("circular", 4, 6, 0.078, 0.100, 0.096)


def _section_contacts(pair, theta):
    found = []
    for part in pair.cutter.cut(theta):
        for c in part.contacts:
            if not any(np.linalg.norm(c - d) < 1e-7 for d in found):
                found.append(c)
    return found


def test_straight_rotors_touch_along_lines_through_the_section_contacts(pair):
    for theta in np.radians([5.0, 20.0, 40.0, 60.0, 80.0]):
        n = len(_section_contacts(pair, theta))
        # Straight rotors: every section contact is a line along the whole rotor.
        assert contact_line_length(pair, pair.rack, Sweep("straight", L), theta) == \
            pytest.approx(n * L, rel=1e-12)


def test_helical_line_tends_to_the_straight_one(pair):
    straight = contact_line_length(pair, pair.rack, Sweep("straight", L), 0.3)
    errors = [abs(contact_line_length(pair, pair.rack, Sweep("helical", L, w), 0.3)
                  / straight - 1) for w in (0.05, 0.025)]
    # Each branch runs the whole length, tilted by the twist: its length grows like
    # sqrt(1 + (r twist')^2), second order in the wrap (half the wrap, a quarter).
    assert 3.5 < errors[0] / errors[1] < 4.5, errors


def test_chamber_lines_do_not_exceed_the_contact_line(pair):
    """The chamber table's interlobe lines (summed over all chambers present) are the
    contact line where it separates two chambers: never longer than the whole line.
    Measured: 95 % of it on the 4/6 circular pair at 325 deg of wrap (the rest separates
    parts of one chamber or faces a sliver dropped from the section)."""
    sweep = Sweep("helical", L, math.radians(325.0))
    ppp = 48
    m = SweptMachine(pair, sweep, ppp)
    phi = m.curves.phi
    n = len(phi)
    total = np.zeros(-(-n // ppp) * ppp)
    for (name, d), x in m.track_lines.items():
        if name.startswith("interlobe") and d > 0:
            total[:n] += x
    fold = total.reshape(-1, ppp).sum(0)
    for j in range(0, ppp, 6):
        whole = contact_line_length(pair, pair.rack, sweep, float(phi[j]))
        assert 0.9 * whole < fold[j] <= whole * (1.0 + 1e-3), (j, fold[j], whole)
