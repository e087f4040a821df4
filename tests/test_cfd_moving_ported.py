"""The quasi-1D side of the ported section in motion (issue 17), without OpenFOAM.

The model is the product's periodic cycle of the slab (:mod:`rotorflow.cases.
moving_ported`); what is checked here is what the comparison adds to it: the map from
the CFD's slots (the chamber of machine age phi + s P) to the model's one-chamber trace,
against the model's own per-slot traces of the period (a different route: the integrator's
states observed slot by slot, not the chamber's life joined by age); the start state it
hands the CFD; and the periodicity measure on traces built to be periodic or not.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rotorflow.cases.moving_ported import (
    initial_state,
    periodicity,
    ported_models,
    slot_pressures,
)
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.workflow.case import case_from_raw, load_toml

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "examples" / "default.toml"


@pytest.fixture(scope="module")
def model():
    return ported_models(load_toml(CASE), CASE, 0.01, 100e-6, PerfectGas(), ["fanno"],
                         case_from_raw)["fanno"]


def test_slots_map_onto_the_models_own_per_slot_traces(model):
    mach = model.result.machine
    theta = np.asarray(mach["theta_rad"])
    # model slot k at table angle theta holds the chamber of table age theta + k P: the
    # CFD's slot k + 1 at machine angle theta + origin - P
    pick = np.linspace(0, len(theta) - 1, 9).astype(int)
    got = slot_pressures(model, theta[pick] + model.origin - model.period)
    want = np.asarray(mach["p_Pa"])[pick]
    n = min(got.shape[1], want.shape[1])
    ok = np.isfinite(want[:, :n])
    assert ok.sum() >= 3 * len(pick)
    assert got[:, :n][ok] == pytest.approx(want[:, :n][ok], rel=2e-3)
    # the closed phase is in there: the check sees a compression, not only plenums
    ps, pd = model.plenums["suction"][0], model.plenums["discharge"][0]
    closed = got[:, :n][ok]
    assert np.any((closed > 1.05 * ps) & (closed < 0.95 * pd))


def test_the_start_state_holds_the_plenum_pressures_where_the_ports_are_open(model):
    p, T = initial_state(model, math.radians(13.0))
    assert set(p) == set(T) and len(p) >= model.chambers - 1
    ps, pd = model.plenums["suction"][0], model.plenums["discharge"][0]
    # ideal ports: an open chamber is at its plenum's pressure
    assert sum(abs(v - ps) < 1.0 for v in p.values()) >= 1
    assert sum(abs(v - pd) < 1.0 for v in p.values()) >= 1
    assert all(t > 0.0 for t in T.values())


def test_periodicity_is_zero_on_a_periodic_machine_and_sees_a_drift():
    period = math.radians(60.0)
    angles = np.arange(0.0, 120.5, 0.5)
    a = np.radians(angles)
    # slot s holds the chamber of age phi + s P: one chamber's trace f, shifted
    f = lambda age: 1e5 + 5e4 * np.sin(age) ** 2  # noqa: E731
    p = {str(s): list(f(a + s * period)) for s in range(1, 7)}
    assert periodicity(angles, p, period)["max"] < 1e-12
    drift = {c: list(np.asarray(v) * (1.0 + 0.01 * a / a[-1])) for c, v in p.items()}
    got = periodicity(angles, drift, period)["max"]
    assert 0.003 < got < 0.05
