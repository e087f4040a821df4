"""Chambers (cellZones) and sealing lines (faceZones) of a stacked O-grid (issue 16),
checked against the machine's own chamber volume curve (Gauss quadrature of the
conjugate pair's chamber areas along the sweep, :mod:`rotorflow.geometry.machine`), an
independent construction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotorflow.cases.grid3d_quality import cell_centres, stack_nodes
from rotorflow.cases.grid3d_zones import contacts, find_zones
from rotorflow.cases.polymesh import build_polymesh, helical_stack
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep

LENGTH = 0.02
GAP = 20e-6
PAIR = examples()["table1"]
SWEEPS = {
    "helical": Sweep("helical", LENGTH, math.radians(136.0) * LENGTH / 0.1),
    # Tapering to 0.9 with the lead doubling along the length (variable lead).
    "conical": Sweep("conical", LENGTH, math.radians(136.0) * LENGTH / 0.1, 0.9, 2.0),
}


@pytest.mark.parametrize("kind", SWEEPS)
def test_chambers_hold_the_machines_chamber_volumes(kind):
    """One zone per tooth space, each holding the volume the machine's chamber curve
    gives at that space's angle, plus the relief: the outer rotor is relieved by the
    clearance, which adds at most the clearance times the chamber's outer wall (at most
    twice its share of the pitch circle of pins, the longest outer arc) times the
    length; a zone cut one column off its contact would be off by a column's area
    times the length (81 mm3 in the largest chamber) and fail."""
    machine = SweptMachine(PAIR, SWEEPS[kind])
    pair = machine.pair
    sections, z = helical_stack(pair, 0.0, GAP, machine.sweep, 8, end_layer=2e-4)
    X = stack_nodes(sections, z)
    zones = find_zones(X, GAP, build_polymesh(sections, z))
    assert [len(c) for c in contacts(X, GAP)][0] == pair.lobes_outer
    volume = cell_centres(X)[1].ravel()
    got = np.sort(np.bincount(zones.chamber, volume))
    ages = np.arange(-12, 13) * pair.period
    want = machine.volume_at(ages)
    relief = GAP * 2.0 * (2.0 * math.pi * pair.a / pair.lobes_outer) * LENGTH
    # A chamber just born (0.02 mm3 here, its area growing as the fourth power of its
    # age) has no contact of its own in the relieved grid yet: below the relief it is
    # part of its neighbour.
    want = np.sort(want[want > relief])
    assert len(got) == len(want) == pair.lobes_outer
    assert np.all(got - want > 0.0) and np.all(got - want < relief), (got - want) * 1e9
