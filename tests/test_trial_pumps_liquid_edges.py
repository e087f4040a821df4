"""The multiphase pump at the edge of its gas volume fraction: a fraction of 1 with the
liquid's keys left in the case (a designer's all-gas point of a multiphase map) is the
dry pump, not a chamber whose gas volume is read from the accumulators."""

from __future__ import annotations

import copy
import functools

import pytest

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_multiphase as pm
from rotorflow.workflow.case import case_from_raw, load_toml


@functools.cache
def pump():
    raw = load_toml(pm.EXAMPLE)
    case = case_from_raw(raw, pm.EXAMPLE)
    return raw, chamber_table(case, build_machine(case))


def test_a_gas_volume_fraction_of_one_with_liquid_keys_is_the_dry_pump():
    """Measured before the fix: 'step size underflow near angle 1.057410 rad' (the model
    took 1 / rho_l with no liquid block, so the liquid's mass was read from the
    accumulators' columns)."""
    raw, table = pump()
    dry = copy.deepcopy(raw)
    for key in ("gas_volume_fraction", "liquid_density_kg_m3", "liquid_cp_J_kgK"):
        dry["operating"].pop(key)
    wet = copy.deepcopy(raw)
    wet["operating"]["gas_volume_fraction"] = 1.0
    a = pm.point(dry, table, str(pm.EXAMPLE))
    b = pm.point(wet, table, str(pm.EXAMPLE))
    assert b["converged"]
    for key in ("eta_v", "indicated_kW", "power_kW", "mass_flow_kg_s"):
        assert b[key] == pytest.approx(a[key], rel=1e-9), key
