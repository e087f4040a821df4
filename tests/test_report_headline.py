"""The report's headline and figure labels, on hand-made summaries (no pipeline run).

The demo report's own headline, as Chromium renders it, is checked in
test_workflow_report.py; these cover the cases the demo does not reach: figures the
summary leaves None, families whose angles mean the port timing, rounding edges.
"""

from __future__ import annotations

import json
import re
from types import SimpleNamespace

import pytest

from rotorflow.postprocess import report
from rotorflow.postprocess.report_headline import headline_html, headline_rows, sig
from rotorflow.postprocess.report_labels import geometry_label, quasi1d_label

#: A delivered air point (numbers of the shape of quasi1d.performance's output).
AIR = {"mass_flow_kg_s": 0.0101892, "suction_volume_flow_L_min": 514.4457,
       "indicated_power_W": 1670.264, "specific_power_J_kg": 163924.1,
       "volumetric_efficiency": 0.6177, "adiabatic_efficiency": 0.56386,
       "isothermal_efficiency": 0.4905, "discharge_temperature_K": 442.976,
       "discharge_mixture_temperature_K": None, "converged": True, "fluid": "air",
       "speed_outer_rpm": 2500.0, "shaft_power_W": 1693.53, "mechanical_loss_W": 23.27,
       "adiabatic_efficiency_shaft": 0.55612}


def rows(summary):
    return {r.quantity: r for r in headline_rows(summary)}


@pytest.mark.parametrize("value, text", [
    (1693.53, "1694"), (0.0101892, "0.01019"), (442.976, "443.0"), (1.67, "1.670"),
    (9.99961, "10.00"), (123456.0, "123500"), (-0.0004567, "-0.0004567"), (0.0, "0")])
def test_four_significant_figures(value, text):
    assert sig(value) == text


def test_specific_power_is_shaft_power_per_volume_flow():
    r = rows(AIR)["Specific power"]
    kw_per_m3_min = (AIR["shaft_power_W"] / 1e3) / (AIR["suction_volume_flow_L_min"] / 1e3)
    assert r.unit == "kW/(m³/min)" and r.value == pytest.approx(kw_per_m3_min, rel=1e-12)
    assert "shaft" in r.note


def test_without_shaft_figures_specific_power_falls_back_to_indicated():
    s = {**AIR, "shaft_power_W": None, "adiabatic_efficiency_shaft": None,
         "mechanical_loss_W": None}
    r = rows(s)
    assert r["Specific power"].value == pytest.approx(
        s["indicated_power_W"] / s["suction_volume_flow_L_min"])
    assert "indicated" in r["Specific power"].note
    assert r["Shaft power"].value is None and "gas loads" in r["Shaft power"].note
    assert r["Isentropic efficiency, shaft"].value is None


def test_condensing_isotherm_is_na_with_its_reason():
    s = {**AIR, "fluid": "R134a", "isothermal_efficiency": None}
    html = headline_html(s, None, report.esc)
    row = re.search(r"<th>Isothermal efficiency, indicated</th>(.*?)</tr>", html).group(1)
    assert ">n/a<" in row and "condense" in row


def test_no_delivery_leaves_ratios_na():
    s = {**AIR, "mass_flow_kg_s": -1e-4, "suction_volume_flow_L_min": -5.0,
         "specific_power_J_kg": None, "adiabatic_efficiency": None,
         "isothermal_efficiency": None, "adiabatic_efficiency_shaft": None,
         "discharge_temperature_K": None, "converged": False}
    r = rows(s)
    for q in ("Specific power", "Isentropic efficiency, indicated",
              "Isothermal efficiency, indicated", "Discharge temperature"):
        assert r[q].value is None and r[q].note, q
    assert "did not converge" in headline_html(s, None, report.esc)


def test_units_and_percentages():
    r = rows(AIR)
    assert r["Volumetric efficiency"].unit == "%"
    assert r["Volumetric efficiency"].value == pytest.approx(61.77)
    assert r["Volume flow at suction"].unit == "m³/min"
    assert r["Volume flow at suction"].value == pytest.approx(0.5144457)
    assert r["Discharge temperature"].unit == "K" and "169.8 °C" in r[
        "Discharge temperature"].note
    # An oil-flooded point adds the mixed temperature the discharge line shows.
    oil = rows({**AIR, "discharge_mixture_temperature_K": 350.0})
    assert oil["Discharge temperature, gas and oil mixed"].value == 350.0


def test_operating_point_names_the_driven_rotor():
    case = SimpleNamespace(raw={"operating": {"p_suction_bar": 1.0, "T_suction_K": 293.15,
                                              "p_discharge_bar": 2.6, "speed_rpm": 3000}},
                           driven="inner",
                           pair=SimpleNamespace(rotors=[SimpleNamespace(name="outer")]))
    html = headline_html(AIR, case, report.esc)
    assert ("air; suction 1 bar, 293.15 K; discharge 2.6 bar; outer rotor 2500 rpm; "
            "inner (driven) rotor 3000 rpm") in html


def test_angle_names_follow_what_the_family_measures():
    ported = geometry_label("angle_discharge_open_deg", True, "male")
    plane = geometry_label("angle_discharge_open_deg", False, "outer")
    assert ported == ("Discharge port opens at", "deg of male-rotor turn since chamber birth")
    assert "first contact with the high-pressure end plane" in plane[0]
    assert "not the discharge port opening" in plane[0]
    assert "last contact with the low-pressure end plane" in geometry_label(
        "angle_suction_close_deg", False)[0]
    assert geometry_label("V_sw_bar", False)[0] == "Normalised swept volume V_sw / (π D² L / 4)"
    assert geometry_label("wrap_female_deg", True) == ("Wrap angle of the female rotor", "deg")
    assert geometry_label("radial_window_area_male_mm2", True)[1] == "mm²"
    assert geometry_label("no_such_figure", True) == ("no_such_figure", "")
    assert quasi1d_label("leakage_kg_s.hp_face")[1] == "kg/s"
    assert quasi1d_label("loads.rotors.male.torque_Nm_mean") == (
        "Male rotor: mean gas torque", "N m")
    assert quasi1d_label("something.new") == ("something.new", "")


def test_geometry_section_labels_by_family(tmp_path):
    (tmp_path / "geometry.json").write_text(json.dumps(
        {"angle_discharge_open_deg": 136.25, "swept_volume_m3": 3.3e-4, "cusp_mm": [1, 2],
         "mystery": None}))

    def case(ported, ref):
        return SimpleNamespace(pair=SimpleNamespace(
            port_areas=ported, rotors=[SimpleNamespace(name=ref)]))

    screw = report.geometry_section(tmp_path, tmp_path, case(True, "male")).html
    gear = report.geometry_section(tmp_path, tmp_path, case(False, "outer")).html
    assert "Discharge port opens at" in screw and "end plane" not in screw
    assert "first contact with the high-pressure end plane" in gear
    assert "136.25" in gear and "0.00033" in gear and "1, 2" in screw
    assert "<code>mystery</code>" in gear and ">n/a<" in gear


def test_case_page_leads_with_the_headline():
    sec = [("geometry", report.Section("Geometry", "<p>g</p>")),
           ("quasi1d", report.Section("Quasi-1D performance", "<p>q</p>",
                                      headline=headline_html(AIR, None, report.esc)))]
    page = report.case_page("c", "c.toml", "", [["geometry", "", "", "", 0.1]], sec)
    assert page.index("id='headline'") < page.index("id='geometry'") < page.index("Stages")
    bare = report.case_page("c", "c.toml", "", [], sec[:1])
    assert "id='headline'" not in bare and "no quasi-1D stage" in bare
