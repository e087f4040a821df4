"""Named leakage paths: declared with the chamber table, each with its own gap and model.

The frozen checks evaluate the chamber model's path flows at chosen chamber states (no
integration), where the flow through a restriction is known: the nozzle and Fanno
fluxes are per unit flow area, so a path's flow is proportional to its gap at fixed
pressures, and a choked orifice passes the textbook critical mass flow.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry import table as chamber_table
from rotorflow.geometry.table import LeakagePath
from rotorflow.quasi1d import Leakage, Operating, Ports, simulate
from rotorflow.quasi1d.chamber import prepare
from rotorflow.quasi1d.model import build
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.quasi1d.synthetic import sin2_table

GAS = PerfectGas(molar_mass_kg_kmol=28.97, cp_J_kgK=1006.43)  # seed 001's perfect-gas air
OP = Operating(p_suction_Pa=1e5, p_discharge_Pa=4e5, T_suction_K=300.0, speed_rpm=3000.0,
               volume_ratio=2.5)
OP_CASE = {"p_suction_bar": 1.0, "p_discharge_bar": 4.0, "T_suction_K": 300.0,
           "speed_rpm": 3000.0, "volume_ratio": 2.5}
# Chamber pressures (bar) far from each other and from the plenums, so that every path
# carries flow outside the nozzle's smoothing band (relative difference 1e-4).
P_BAR = (1.4, 1.9, 3.3, 2.6, 5.0, 6.2, 7.4, 8.5, 9.5)


def frozen(table, leak):
    """Chamber model with perfect-gas air, the segment with the most chambers, its mid
    angle, and a state with the chambers at the pressures P_BAR (temperature ~ p^0.25)."""
    geo = prepare(table, OP.volume_ratio, None, None, OP.speed_rpm, 1e-3)
    model = build(geo, GAS, OP, leak, Ports("ideal"))
    seg = max(model.segments, key=lambda s: s.n_act)
    theta = 0.5 * (seg.start + seg.end)
    y = np.zeros(model.n_state)
    V = geo.evaluate(theta + seg.kP)[0]
    for k, pk in enumerate(P_BAR[:seg.n_act]):
        rho, u, _ = GAS.state_pT(1e5 * pk, 300.0 * pk**0.25)
        y[k] = rho * V[k]
        y[model.n + k] = rho * V[k] * u
    return model, seg, model.path_flows(theta, y, seg)


def by_name(seg, F):
    out = {}
    for name, f in zip(seg.names, F, strict=True):
        out.setdefault(name, []).append(f)
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("model", ["nozzle", "fanno"])
@pytest.mark.parametrize("override, doubled", [
    ({"end-face": {"gap_um": 20}}, {"lp-face", "hp-face"}),
    ({"paths": {"hp-face": {"gap_um": 20}}}, {"hp-face"}),
])
def test_a_path_with_its_own_gap_changes_only_its_own_flow(model, override, doubled):
    # Both fluxes are per unit flow area (gap x line length): at the same chamber states
    # twice the gap passes twice the flow, on that path alone.
    table = sin2_table(rows=721)
    base = {"gap_um": 10, "model": model, "coefficient": 0.8}
    _, seg, F0 = frozen(table, Leakage.from_section(base, "case.toml"))
    _, seg1, F1 = frozen(table, Leakage.from_section({**base, **override}, "case.toml"))
    assert seg1.names == seg.names
    f0, f1 = by_name(seg, F0), by_name(seg1, F1)
    assert doubled <= set(f0) and "interlobe+1" in f0 and "suction port" not in f0
    for name in f0:
        if name in doubled:
            assert np.max(np.abs(f0[name])) > 1e-6, name  # kg/s: the path does carry flow
            # 1e-14: the two areas are products of the same numbers with gap 10 or 20 um
            np.testing.assert_allclose(f1[name], 2.0 * f0[name], rtol=1e-14, err_msg=name)
        else:
            np.testing.assert_array_equal(f1[name], f0[name], err_msg=name)


def test_a_sealed_kind_carries_nothing_and_leaves_the_others():
    table = sin2_table(rows=721)
    base = {"gap_um": 10, "model": "nozzle"}
    _, seg, F0 = frozen(table, Leakage.from_section(base, "case.toml"))
    _, seg1, F1 = frozen(table, Leakage.from_section(
        {**base, "interlobe": {"model": "none"}}, "case.toml"))
    f0, f1 = by_name(seg, F0), by_name(seg1, F1)
    assert "interlobe+1" in f0 and "interlobe+1" not in f1
    for name in ("lp-face", "hp-face"):
        np.testing.assert_array_equal(f1[name], f0[name])


def blow_hole_table(area_m2):
    """The synthetic table with a constant blow-hole orifice to the next older chamber,
    declared the way a twin-screw family would declare its own path."""
    tab = sin2_table(rows=721)
    hole = LeakagePath("blow-hole", "blow-hole", 1, "blow_hole_m2", measure="area")
    return dataclasses.replace(tab, leakage_paths=(*tab.paths, hole),
                               columns={"blow_hole_m2": np.full_like(tab.angle_rad, area_m2)})


@pytest.mark.parametrize("gap_um", [10, 40])
def test_a_choked_blow_hole_passes_the_critical_mass_flow(gap_um):
    # Textbook critical flow of an orifice: Cd A p0 sqrt(gamma / (R T0))
    # (2 / (gamma + 1))^((gamma + 1) / (2 (gamma - 1))), whatever the clearance gaps.
    area, cd = 2e-6, 0.6
    leak = Leakage.from_section({"gap_um": gap_um, "model": "nozzle",
                                 "blow-hole": {"coefficient": cd}}, "case.toml")
    model, seg, F = frozen(blow_hole_table(area), leak)
    g = GAS.gamma
    checked = 0
    for f, name in enumerate(seg.names):
        a, b = int(seg.ia[f]), int(seg.ib[f])
        if name != "blow-hole" or not (1 <= a <= seg.n_act and 1 <= b <= seg.n_act):
            continue
        (p_a, p_b) = (1e5 * P_BAR[a - 1], 1e5 * P_BAR[b - 1])
        up = max(p_a, p_b)
        if min(p_a, p_b) / up > (2.0 / (g + 1.0)) ** (g / (g - 1.0)):
            continue  # not choked
        T0 = 300.0 * (up / 1e5) ** 0.25
        crit = cd * area * up * math.sqrt(g / (GAS.R * T0)) * (
            (2.0 / (g + 1.0)) ** ((g + 1.0) / (2.0 * (g - 1.0))))
        assert abs(F[f]) == pytest.approx(crit, rel=1e-12)  # round-off of two formulas
        assert np.sign(F[f]) == (1 if p_a > p_b else -1)
        checked += 1
    assert checked >= 1


@pytest.mark.parametrize("model, refused", [("nozzle", True), ("fanno", True),
                                             ("rarefied", False)])
def test_a_gap_given_to_an_orifice_is_refused_where_its_law_reads_none(model, refused):
    # The blow-hole's flow area is the table's column: a gap there was ignored without a
    # word, except by the rarefied law (the hole's size sets its Knudsen number).
    from rotorflow.quasi1d.paths import resolve

    leak = Leakage.from_section({"gap_um": 20, "model": model,
                                 "blow-hole": {"gap_um": 100}}, "case.toml")
    paths = blow_hole_table(2e-6).paths
    if not refused:
        assert {law.path.name: law.gap_m for law in resolve(paths, leak)}["blow-hole"] \
            == pytest.approx(100e-6)
        return
    with pytest.raises(CaseError, match=r"\[leakage.blow-hole\] of case.toml gives gap_um"):
        resolve(paths, leak)


def twin_screw_like_table():
    """Paths of another family's kinds: a tip line to the older chamber with the
    family's own gap (seen from this chamber only), a blow-hole orifice, the
    discharge end face with its own model."""
    tab = sin2_table(rows=721)
    cols = {"tip_m": tab.seal_next_m * 0.5, "blow_hole_m2": np.full_like(tab.angle_rad, 1e-6)}
    paths = (
        LeakagePath("tip", "tip", 1, "tip_m", gap_m=30e-6),
        LeakagePath("interlobe", "interlobe", -1, "seal_prev_m", mirror="seal_next_m",
                    moving_wall=True),
        LeakagePath("blow-hole", "blow-hole", 1, "blow_hole_m2", measure="area"),
        LeakagePath("hp-face", "end-face", "discharge", "seal_hp_face_m", model="fanno"),
    )
    return dataclasses.replace(tab, leakage_paths=paths, columns=cols, seal_far={})


def test_another_familys_paths_conserve_mass_and_energy():
    leak = Leakage.from_section({"gap_um": 10, "model": "nozzle", "wall_motion": True},
                                "case.toml")
    res = simulate(twin_screw_like_table(), Operating.from_section(OP_CASE, "case.toml"),
                   leak)
    f = res.figures
    assert f["converged"]
    # the cycle's mass and energy balances close (the solver's own bar is 1e-7)
    assert f["mass_balance_error"] < 1e-6 and f["energy_balance_error"] < 1e-6
    assert list(f["leakage_kg_s"]) == ["tip", "interlobe", "blow-hole", "hp-face"]
    assert all(v > 0 for v in f["leakage_kg_s"].values())


def test_model_none_seals_what_the_case_does_not_open():
    # A sealed machine with the end faces opened: nothing crosses the interlobe lines.
    leak = Leakage.from_section({"model": "none", "end-face": {"model": "nozzle",
                                                               "gap_um": 10}}, "case.toml")
    f = simulate(twin_screw_like_table(), Operating.from_section(OP_CASE, "case.toml"),
                 leak).figures
    assert f["leakage_kg_s"]["hp-face"] > 0
    for key in ("tip", "interlobe", "blow-hole"):
        assert f["leakage_kg_s"][key] == 0.0


def test_declarations_round_trip_through_the_side_car(tmp_path):
    tab = twin_screw_like_table()
    chamber_table.write(tab, tmp_path / "t.csv")
    side = json.loads((tmp_path / "t.json").read_text())
    assert [p["name"] for p in side["leakage_paths"]] == [p.name for p in tab.paths]
    back = chamber_table.read(tmp_path / "t.csv")
    assert back.paths == tab.paths
    for name, col in tab.columns.items():
        # the CSV keeps 13 significant digits (%.12e)
        np.testing.assert_allclose(back.column(name), col, rtol=1e-12, atol=0.0)


def test_an_internal_gear_table_keeps_its_csv_columns(tmp_path):
    tab = sin2_table(rows=61)
    far = {2: tab.seal_next_m * 0.1, -2: tab.seal_prev_m * 0.1}
    chamber_table.write(dataclasses.replace(tab, seal_far=far), tmp_path / "t.csv")
    header = (tmp_path / "t.csv").read_text().splitlines()[0]
    assert header == ("angle_rad,volume_m3,dVdangle_m3_rad,area_lp_m2,area_hp_m2,seal_next_m,"
                      "seal_prev_m,seal_lp_face_m,seal_hp_face_m,seal_next2_m,seal_prev2_m")


def test_a_side_car_without_declarations_gets_the_internal_gear_paths(tmp_path):
    tab = sin2_table(rows=61)
    far = {3: tab.seal_next_m * 0.1, -3: tab.seal_prev_m * 0.1, -2: tab.seal_prev_m * 0.2}
    chamber_table.write(dataclasses.replace(tab, seal_far=far), tmp_path / "t.csv")
    side = tmp_path / "t.json"
    meta = json.loads(side.read_text())
    del meta["leakage_paths"]  # as written before the declarations existed
    side.write_text(json.dumps(meta))
    back = chamber_table.read(tmp_path / "t.csv")
    assert back.leakage_paths is None
    # the paths the model had before they were named: the lines to the chambers one
    # period away, seen from both; the end faces; every far line (from both sides where
    # both columns exist); all reported as the three figures of old
    want = [("interlobe+1", "interlobe", 1, "seal_next_m", "seal_prev_m", "interlobe"),
            ("lp-face", "end-face", "suction", "seal_lp_face_m", None, "lp_face"),
            ("hp-face", "end-face", "discharge", "seal_hp_face_m", None, "hp_face"),
            ("interlobe-2", "interlobe", -2, "seal_prev2_m", None, "interlobe"),
            ("interlobe+3", "interlobe", 3, "seal_next3_m", "seal_prev3_m", "interlobe")]
    got = [(p.name, p.kind, p.target, p.column, p.mirror, p.report_key) for p in back.paths]
    assert got == want
    assert [p.moving_wall for p in back.paths] == [True, False, False, False, False]
    prepare(back, 2.5, None, None, 3000.0, 1e-3)  # and the model reads it


def test_case_file_syntax_reaches_the_paths():
    text = """
    [leakage]
    gap_um = 20
    model = "nozzle"
    [leakage.end-face]
    gap_um = 40
    [leakage.paths."interlobe+2"]
    model = "none"
    """
    leak = Leakage.from_section(tomllib.loads(text)["leakage"], "case.toml")
    assert dict(leak.by_kind)["end-face"].gap_m == pytest.approx(40e-6)
    assert dict(leak.by_path)["interlobe+2"].model == "none"
    assert leak.gap_m == pytest.approx(20e-6)


@pytest.mark.parametrize("d, words", [
    ({"end-face": {"gap": 40}}, ["unknown key 'gap'", "[leakage.end-face]", "case.toml"]),
    ({"tips": {"gap_um": 40}}, ["unknown key 'tips'", "[leakage]", "case.toml"]),
    ({"end-face": 40}, ["[leakage.end-face]", "must be a table"]),
    ({"paths": {"hp-face": {"gap_um": -1}}}, ["gap_um", "[leakage.paths.hp-face]", "positive"]),
    ({"paths": {"hp-face": 3}}, ["[leakage.paths.hp-face]", "must be a table"]),
    ({"tip": {"model": "labyrinth"}}, ["model", "[leakage.tip]", "nozzle"]),
    ({"tip": {"model": "cfd-calibrated"}}, ["[leakage.tip]", "correlation"]),
    ({"tip": {"correlation": "fit.json"}}, ["correlation", "[leakage.tip]", "cfd-calibrated"]),
])
def test_bad_overrides_are_one_clear_line(d, words):
    with pytest.raises(CaseError) as e:
        Leakage.from_section({"gap_um": 10, **d}, "case.toml")
    msg = str(e.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg


@pytest.mark.parametrize("d, words", [
    ({"paths": {"tip-male": {"gap_um": 40}}},
     ["[leakage.paths.tip-male]", "case.toml", "no leakage path", "hp-face"]),
    ({"tip": {"gap_um": 40}}, ["[leakage.tip]", "case.toml", "no leakage kind", "end-face"]),
])
def test_overrides_must_name_what_the_table_declares(d, words):
    leak = Leakage.from_section({"gap_um": 10, **d}, "case.toml")
    with pytest.raises(CaseError) as e:
        simulate(sin2_table(rows=301), Operating.from_section(OP_CASE, "case.toml"), leak)
    msg = str(e.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg


@pytest.mark.parametrize("fields, words", [
    ({"kind": "vane"}, ["kind 'vane'"]),
    ({"target": 0}, ["target 0"]),
    ({"target": "inlet"}, ["target 'inlet'"]),
    ({"target": "suction", "mirror": "seal_prev_m"}, ["mirror"]),
    ({"measure": "volume"}, ["measure"]),
    ({"gap_m": 0.0}, ["gap_m", "positive"]),
])
def test_malformed_declarations_are_refused(fields, words):
    d = {"name": "p", "kind": "tip", "target": 1, "column": "seal_next_m", **fields}
    with pytest.raises(ValueError) as e:
        LeakagePath.from_dict(d)
    for w in words:
        assert w in str(e.value)


def test_a_kind_with_its_own_model_flows_by_it_alone(tmp_path):
    # A fit whose flow coefficient is the constant 0.7 is the nozzle times 0.7: the end
    # faces calibrated by it (their own coefficient 1, the factor every model's flow is
    # multiplied by) flow as nozzles with coefficient 0.7, the interlobe lines keep the
    # section's nozzle with 0.9.
    from rotorflow.postprocess.leakage import FlowCoefficientFit

    fit = tmp_path / "fit.json"
    fit.write_text(FlowCoefficientFit(("1",), (1.0 / 0.7**2,), 0.0).to_json())
    where = str(tmp_path / "case.toml")
    table = sin2_table(rows=721)
    base = {"gap_um": 10, "model": "nozzle", "coefficient": 0.9}
    cal = Leakage.from_section({**base, "end-face": {"model": "cfd-calibrated",
                                                     "correlation": "fit.json",
                                                     "coefficient": 1.0}}, where)
    noz = Leakage.from_section({**base, "end-face": {"coefficient": 0.7}}, where)
    (_, seg, Fc), (_, _, Fn) = frozen(table, cal), frozen(table, noz)
    fc, fn = by_name(seg, Fc), by_name(seg, Fn)
    assert np.max(np.abs(fc["hp-face"])) > 1e-6
    for name in fc:
        # 1e-12: the fit's closed form of Cd psi against the nozzle's psi times 0.7
        np.testing.assert_allclose(fc[name], fn[name], rtol=1e-12, atol=0.0, err_msg=name)
    base_flows = by_name(seg, frozen(table, Leakage.from_section(base, where))[2])
    np.testing.assert_array_equal(fc["interlobe+1"], base_flows["interlobe+1"])
