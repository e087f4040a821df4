"""The injected liquid's acceleration to the rotors' speed (quasi1d.mechanical, the
rotors' groove scalars of geometry.summary), against independent constructions.

* The grooves' area and radius of gyration of the 4/6 pair's rotors, from a grid of
  points inside each rotor's tip circle and outside its sampled section (no Green's
  theorem): the fraction of boundary cells, ~perimeter x cell / area, bounds the grid's
  error at ~1e-3.
* Euler's turbomachinery equation for liquid taken up without swirl and carried in
  rigid rotation: torque = mass flow x omega x mean r^2 over the liquid, the liquid
  shared by the rotors' swept groove volumes; evaluated on the same grid.
* A rotor without grooves in the table (the internal gear's outer rotor) leaves it
  unmodelled, and says so.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pytest

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.quasi1d.mechanical import liquid_acceleration_W
from rotorflow.workflow.case import load_case

from .conftest import CASES

#: Grid points across a rotor's tip diameter.
GRID = 1400


@functools.cache
def twin_screw():
    case = load_case(CASES / "twin_screw_4_6.toml")
    return case, chamber_table(case, build_machine(case))


def _groove_on_grid(rotor) -> tuple[float, float]:
    """Area and mean r^2 of the rotor's grooves counted on a grid of cells: a cell is in
    the rotor's section where a row through its centre has crossed the sampled section
    an odd number of times (scan lines)."""
    u = np.linspace(0.0, rotor.profile.n, 20_000, endpoint=False)
    p = rotor.profile.point(u)
    q = np.roll(p, -1, axis=0)
    tip = float(np.max(np.linalg.norm(p, axis=-1)))
    x = np.linspace(-tip, tip, GRID)
    h = x[1] - x[0]
    area = total = 0.0
    for y in x:
        crosses = (p[:, 1] > y) != (q[:, 1] > y)
        a, b = p[crosses], q[crosses]
        xc = np.sort(a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1]))
        inside = (np.searchsorted(xc, x) % 2) == 1
        r2 = x**2 + y**2
        groove = (r2 <= tip**2) & ~inside
        area += groove.sum() * h * h
        total += r2[groove].sum() * h * h
    return area, total / area


def test_groove_scalars_match_a_grid_count():
    case, table = twin_screw()
    for rotor in case.pair.rotors:
        area, mean_r2 = _groove_on_grid(rotor)
        s = table.rotor_scalars
        assert s[f"groove_area_{rotor.name}_m2"] == pytest.approx(area, rel=2e-3)
        assert s[f"groove_gyration_{rotor.name}_m"] ** 2 == pytest.approx(mean_r2, rel=2e-3)


@dataclass
class _Rotor:
    name: str
    speed_ratio: float


@dataclass
class _Loads:
    rotors: tuple
    omega_ref: float


def test_power_is_eulers_torque_times_speed():
    """Liquid flow m shared by swept groove volume, each share leaving at omega r^2 of
    angular momentum per kg (grid mean), the shaft power sum omega T."""
    case, table = twin_screw()
    omega, flow = 628.0, 0.24
    rotors = tuple(_Rotor(r.name, r.speed_ratio) for r in case.pair.rotors)
    grid = {r.name: _groove_on_grid(r) for r in case.pair.rotors}
    swept = {r.name: grid[r.name][0] * abs(r.speed_ratio) * omega for r in rotors}
    power = 0.0
    for r in rotors:
        w = abs(r.speed_ratio) * omega
        torque = flow * swept[r.name] / sum(swept.values()) * w * grid[r.name][1]
        power += torque * w
    got = liquid_acceleration_W(flow, _Loads(rotors, omega), table.rotor_scalars)
    assert got == pytest.approx(power, rel=4e-3)
    # the same liquid turned twice as fast takes four times the power
    assert liquid_acceleration_W(flow, _Loads(rotors, 2 * omega), table.rotor_scalars) \
        == pytest.approx(4 * got, rel=1e-12)


def test_a_rotor_without_grooves_leaves_it_unmodelled():
    case = load_case(CASES / "default.toml")
    table = chamber_table(case, build_machine(case))
    names = [r.name for r in case.pair.rotors]
    assert f"groove_area_{names[1]}_m2" in table.rotor_scalars  # the inner rotor's
    assert f"groove_area_{names[0]}_m2" not in table.rotor_scalars  # not the outer's
    rotors = tuple(_Rotor(r.name, r.speed_ratio) for r in case.pair.rotors)
    assert liquid_acceleration_W(1.0, _Loads(rotors, 300.0), table.rotor_scalars) is None
    assert math.isfinite(table.rotor_scalars[f"groove_gyration_{names[1]}_m"])
