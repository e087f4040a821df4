"""The `rotorflow geometry` and `rotorflow table` commands: output, and bad input."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from rotorflow.geometry import table

from .conftest import CASES

GOOD = (CASES / "default.toml").read_text()


def run(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "rotorflow.workflow.cli", *map(str, args)],
        capture_output=True, text=True, cwd=cwd,
    )


def test_geometry_json_has_the_contract_keys():
    out = run("geometry", CASES / "default.toml", "--json")
    assert out.returncode == 0, out.stderr
    fig = json.loads(out.stdout)
    for key in ("E_over_D", "a_over_D", "rho_over_D", "lambda", "sigma", "sigma_lim",
                "pressure_angle_deg", "phi_i_deg", "phi_f_deg", "wrap_bar",
                "pitch_over_length", "V_sw_bar", "V_dr_bar", "Pi_max", "driven",
                "power_balance_error", "chamber_volume_max_m3", "swept_volume_m3"):
        assert key in fig, key
    # Swept volume per outer revolution = N1 V_max (seed 000, section 3.1.1).
    assert fig["swept_volume_m3"] == pytest.approx(6 * fig["chamber_volume_max_m3"])


def test_table_round_trip(tmp_path):
    target = tmp_path / "t" / "chamber.csv"
    out = run("table", CASES / "crc60.toml", "--out", target)
    assert out.returncode == 0, out.stderr
    tab = table.read(target)
    assert tab.lobes_outer == 3
    assert tab.speed_ratio_outer_per_driven == pytest.approx(2 / 3)
    assert tab.volume_m3[0] == 0.0 and tab.volume_m3.max() > 1e-5
    assert sorted(p.name for p in target.parent.iterdir()) == ["chamber.csv", "chamber.json"]


def test_points_per_period_sets_the_tables_angle_step(tmp_path):
    """[machine] points_per_period: the table's rows are a lobe period over that many
    apart, and the largest volume moves by less than the 1e-4 the benches hold at 24."""
    case = tmp_path / "coarse.toml"
    case.write_text(GOOD.replace("[machine]", "[machine]\npoints_per_period = 24"))
    out = run("table", case, "--out", tmp_path / "coarse.csv")
    assert out.returncode == 0, out.stderr
    coarse = table.read(tmp_path / "coarse.csv")
    out = run("table", CASES / "default.toml", "--out", tmp_path / "fine.csv")
    assert out.returncode == 0, out.stderr
    fine = table.read(tmp_path / "fine.csv")
    period = 2 * math.pi / coarse.lobes_outer
    assert np.diff(coarse.angle_rad) == pytest.approx(period / 24, rel=1e-9)
    assert np.diff(fine.angle_rad) == pytest.approx(period / 96, rel=1e-9)
    assert coarse.volume_m3.max() == pytest.approx(fine.volume_m3.max(), rel=1e-4)


BAD = {
    "lambda <= 1": (GOOD.replace("lambda = 1.39934", "lambda = 0.9"), "lambda"),
    "sigma above limit": (GOOD.replace("sigma_bar = 1.0", "sigma = 0.9"), "undercut"),
    "one lobe": (GOOD.replace("lobes_outer = 6", "lobes_outer = 1"), "lobes_outer"),
    "zero length": (GOOD.replace("length_mm = 100", "length_mm = 0"), "length_mm"),
    "negative diameter": (GOOD.replace("diameter_mm = 100", "diameter_mm = -5"), "diameter"),
    "unknown key": (GOOD.replace("[sweep]", "[sweep]\ncolour = 'red'"), "colour"),
    "too few points per period": (GOOD.replace("[machine]", "[machine]\npoints_per_period = 8"),
                                  "points_per_period"),
    "fractional points per period": (GOOD.replace("[machine]",
                                                  "[machine]\npoints_per_period = 24.5"),
                                     "points_per_period"),
    "unknown section": (GOOD + "\n[turbo]\nx = 1\n", "turbo"),
    "malformed": (GOOD.replace("lambda = 1.39934", "lambda = = 1"), "malformed"),
    # the registry names the families it knows
    "unknown machine type": (GOOD.replace('type = "internal-gear"', 'type = "scroll"'),
                             "known: internal-gear"),
    # keys belong to their family: a twin-screw key on an internal gear is unknown
    "another family's key": (GOOD.replace("[machine]", "[machine]\nlobes_male = 4"),
                             "lobes_male"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, name):
    text, word = BAD[name]
    case = tmp_path / "case.toml"
    case.write_text(text)
    before = sorted(tmp_path.iterdir())
    for args in (("geometry", case, "--json"), ("table", case, "--out", tmp_path / "o.csv")):
        out = run(*args, cwd=tmp_path)
        assert out.returncode == 2
        assert out.stdout == ""
        lines = out.stderr.strip().splitlines()
        assert len(lines) == 1 and word in lines[0], out.stderr
    assert sorted(tmp_path.iterdir()) == before


def test_missing_case_file(tmp_path):
    out = run("geometry", tmp_path / "nope.toml")
    assert out.returncode == 2 and "not found" in out.stderr


def test_contacts_csv_and_a_bad_step(tmp_path):
    import csv

    target = tmp_path / "contacts.csv"
    out = run("contacts", CASES / "default.toml", "--out", target, "--step-deg", 5)
    assert out.returncode == 0, out.stderr
    rows = list(csv.DictReader(target.open()))
    # 12 angles over one 60-degree period, six pins each, plus the fillet contacts.
    assert sum(r["kind"] == "pin" for r in rows) == 12 * 6
    bad = tmp_path / "bad.csv"
    out = run("contacts", CASES / "default.toml", "--out", bad, "--step-deg", 0)
    assert out.returncode == 2 and "step" in out.stderr and len(out.stderr.splitlines()) == 1
    assert not bad.exists()
