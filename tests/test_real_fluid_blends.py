"""CoolProp's pseudo-pure blends (R404A, R410A, ...) run dry close to their dew line.

CoolProp's (rho, u) flash fails inside a blend's dome, so the property table's nodes
there are NaN; the nodes next to the dew line are continued from the vapour
(:func:`rotorflow.quasi1d.coolprop_table.continue_vapour_side`).  Before, a suction
within a cell of the dew line (R404A at 4 bar, 0.6 K of superheat) left the table at the
first compression step and exited 1 with a step size underflow; 0.2 K was refused as
"not superheated"; a delivered discharge plenum 0.5 K above the dew point had a NaN
sound speed.
"""

from __future__ import annotations

import json

import CoolProp.CoolProp as CP
import numpy as np
import pytest

from rotorflow.quasi1d.coolprop_fluid import tabulated

from .conftest import CASES, run_cli

R134A_CASE = CASES / "refrigeration_r134a.toml"
DEW_4BAR = CP.PropsSI("T", "P", 4e5, "Q", 1.0, "R404A")  # 261.03 K


def test_r404a_table_holds_a_near_dew_suction_and_its_compression():
    # 0.6 K of superheat at 4 bar; the isentrope compressed 3 % in density runs along the
    # dew line, into the cell it cuts (it was NaN there)
    Ts = DEW_4BAR + 0.6
    fluid = tabulated("R404A", 4e5, 12e5, Ts, Ts, Ts, 2.7)
    st = CP.AbstractState("HEOS", "R404A")
    st.update(CP.PT_INPUTS, 4e5, Ts)
    rho, s = st.rhomass(), st.smass()
    for squeeze in (1.0, 1.01, 1.03, 1.1):
        st.update(CP.DmassSmass_INPUTS, rho * squeeze, s)
        r, u = np.array([st.rhomass()]), np.array([st.umass()])
        assert fluid.in_range(r, u), squeeze
        p, T, kappa = (float(v[0]) for v in fluid.props(r, u))
        assert p == pytest.approx(st.p(), rel=2e-3) and T == pytest.approx(st.T(), abs=0.3)
        assert np.isfinite(kappa) and kappa > 0.9


def test_a_pure_fluids_dome_is_coolprops_own():
    # the continuation is for blends only: R134a's nodes inside the dome are the flash's
    from rotorflow.quasi1d import coolprop_table

    tab = np.full((5, 1, 4), np.nan)
    tab[:, 0, 2:] = 1.0
    coolprop_table.continue_vapour_side("R134a", tab)
    assert np.isnan(tab[:, 0, :2]).all()
    coolprop_table.continue_vapour_side("R404A", tab)
    assert np.isfinite(tab[:, 0, 1]).all() and np.isnan(tab[:, 0, 0]).all()


@pytest.mark.parametrize("superheat, extra", [(0.6, ""), (0.2, ""),
                                              (6.0, '\n[ports]\ndischarge_plenum = "delivered"')])
def test_r404a_near_its_dew_line_runs(tmp_path, superheat, extra):
    text = R134A_CASE.read_text().replace('"CoolProp::R134a"', '"CoolProp::R404A"').replace(
        "p_suction_bar = 3.0", "p_suction_bar = 4.0").replace(
        "T_suction_K = 285", f"T_suction_K = {DEW_4BAR + superheat:.3f}")
    if extra:  # 16 bar: the plenum's lowest bracket, 0.5 K above the dew point, was NaN
        text = text.replace("p_discharge_bar = 9.0", "p_discharge_bar = 16.0") + extra
    else:
        text = text.replace("p_discharge_bar = 9.0", "p_discharge_bar = 12.0")
    case = tmp_path / "case.toml"
    case.write_text(text)
    out = run_cli("simulate", case, "--json")
    assert out.returncode == 0, out.stderr
    fig = json.loads(out.stdout)
    pd = 16e5 if extra else 12e5
    s = CP.PropsSI("S", "P", 4e5, "T", DEW_4BAR + superheat, "R404A")
    T_is = CP.PropsSI("T", "P", pd, "S", s, "R404A")
    assert fig["converged"] and fig["discharge_temperature_K"] > T_is
    assert 0.7 < fig["volumetric_efficiency"] < 0.9
