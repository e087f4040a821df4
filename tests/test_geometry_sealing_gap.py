"""The clearance gap at a sealing line, cut from the real profile pair."""

import math

import numpy as np
import pytest

from rotorflow.cases.gap_mesh import GapWalls
from rotorflow.errors import CaseError
from rotorflow.geometry.pin_gerotor import PinGerotor, sigma_limit
from rotorflow.geometry.sealing_gap import sealing_gap_walls

PAIR = PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 0.1)


@pytest.mark.parametrize("phi_deg, gap", [(120.0, 5e-6), (200.0, 5e-6), (200.0, 50e-6)])
def test_minimum_gap_is_the_clearance_and_walls_fit_the_mesher(phi_deg, gap):
    lower, upper = sealing_gap_walls(PAIR, math.radians(phi_deg), gap)
    walls = GapWalls(lower, upper)
    x = walls.sample_x(4001)
    local = walls.gap(x)
    # The offset is along the inner profile's own normal, so the throat is the clearance.
    assert local.min() == pytest.approx(gap, rel=2e-3)
    # Cut where the gap has opened 20x (inlet) and 3x (outlet).
    assert local[0] == pytest.approx(20 * gap, rel=1e-2)
    assert local[-1] == pytest.approx(3 * gap, rel=1e-2)
    # The pin wall is the exact circle of the pin radius.
    np.testing.assert_allclose(upper[:, 1], PAIR.rho - np.sqrt(PAIR.rho**2 - upper[:, 0] ** 2))


def test_contact_near_the_undercut_point_is_refused_clearly():
    # At sigma_bar = 1 the inner profile has a point of zero speed whose curvature matches
    # the pin's: near it the walls osculate and the gap never opens 20-fold on a wall that
    # is a graph over x, so no gap section can be cut there.
    with pytest.raises(CaseError, match="does not open"):
        sealing_gap_walls(PAIR, math.radians(300.0), 5e-6)


def test_bad_gap_is_refused():
    with pytest.raises(CaseError, match="positive"):
        sealing_gap_walls(PAIR, 1.0, 0.0)
