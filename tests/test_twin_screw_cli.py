"""The twin-screw family through the command line: its figures, and bad input.

Bad input gives exit status 2, one line naming the problem, and nothing written.
"""

import json
import subprocess
import sys

import pytest

from .conftest import CASES

GOOD = (CASES / "twin_screw_4_6.toml").read_text()
#: The same machine on the symmetric circular rack (C = 78 mm), for the rack's errors.
CIRCULAR = GOOD.replace('profile = "pin-cycloid"', 'profile = "circular"').replace(
    "centre_distance_mm = 80", "centre_distance_mm = 78")


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd)


def test_geometry_of_the_4_6_machine():
    out = run("geometry", CASES / "twin_screw_4_6.toml", "--json")
    assert out.returncode == 0, out.stderr
    fig = json.loads(out.stdout)
    assert fig["machine"] == "twin-screw"
    # The wraps are related by the lobe ratio: 325 deg on the male is 325 x 4/6 on the
    # female (seed 004 Table 1a: 217 deg).
    assert fig["wrap_female_deg"] == pytest.approx(325.0 * 4 / 6, rel=1e-12)
    # Displacement per male turn: every chamber is one male and one female groove, and
    # no chamber holds more than both whole grooves over the rotor length.
    whole = (fig["groove_area_male_mm2"] + fig["groove_area_female_mm2"]) * 1e-6 * 0.130
    assert 0.5 * whole < fig["chamber_volume_max_m3"] < whole
    assert fig["swept_volume_m3"] == pytest.approx(4 * fig["chamber_volume_max_m3"])
    # Seed 004: the suction port closes at the largest volume; the discharge port opens
    # where the volume has fallen by the built-in ratio, 7 deg early (the case's keys).
    assert fig["angle_suction_close_deg"] == pytest.approx(fig["angle_volume_max_deg"])
    assert fig["volume_suction_close_m3"] == pytest.approx(fig["chamber_volume_max_m3"],
                                                           rel=1e-3)
    assert fig["angle_discharge_open_deg"] > fig["angle_suction_close_deg"]


BAD = {
    "no female lobes": (CIRCULAR.replace("lobes_female = 6", "lobes_female = 0"), "lobe"),
    # a 5-lobe male on the 4/6 diameters: the rack's tip circle cuts back into the flank
    "undercut rack": (CIRCULAR.replace("lobes_male = 4", "lobes_male = 5"), "undercut"),
    "negative wrap": (CIRCULAR.replace("wrap_male_deg = 325", "wrap_male_deg = -10"),
                      "must not be negative"),
    "two wraps": (CIRCULAR.replace("wrap_male_deg = 325",
                                   "wrap_male_deg = 325\nwrap_female_deg = 217"), "exactly one"),
    "bores apart": (CIRCULAR.replace("centre_distance_mm = 78", "centre_distance_mm = 99"),
                    "bores do not meet"),
    "conical sweep": (CIRCULAR.replace('kind = "helical"',
                                       'kind = "conical"\ndiameter_end_mm = 80'),
                      "cannot be swept conically"),
    # (it was an undercut "at male rolling angle -39224862.771 deg")
    "rotors past each other's axis": (CIRCULAR.replace("centre_distance_mm = 78",
                                                       "centre_distance_mm = 1"),
                                      "too small for these diameters"),
    "male inside its pitch circle": (CIRCULAR.replace("male_diameter_mm = 100",
                                                  "male_diameter_mm = 62"), "addendum"),
    "unknown profile": (CIRCULAR.replace('profile = "circular"', 'profile = "sigma"'),
                        "unknown twin-screw profile"),
    "internal-gear key": (CIRCULAR.replace("[machine]", "[machine]\nlambda = 1.4"), "lambda"),
    "driven rotor unknown": (CIRCULAR.replace('driven = "male"', 'driven = "inner"'), "driven"),
    "unknown blow-hole": (CIRCULAR.replace("[machine]", '[machine]\nblow_hole = "sphere"'),
                          "blow_hole"),
    "pin-cycloid female off its pitch circle": (
        GOOD.replace("centre_distance_mm = 80", "centre_distance_mm = 78"), "pitch diameter"),
    "pin-cycloid with a tip radius": (
        GOOD.replace("[machine]", "[machine]\ntip_radius_mm = 5"), "does not apply"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, name):
    text, word = BAD[name]
    assert text not in (GOOD, CIRCULAR)  # the edit took
    case = tmp_path / "case.toml"
    case.write_text(text)
    before = sorted(tmp_path.iterdir())
    out = run("geometry", case, "--json", cwd=tmp_path)
    assert out.returncode == 2, out.stderr
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0], out.stderr
    assert sorted(tmp_path.iterdir()) == before


@pytest.mark.parametrize("lobes", [(4, 5), (5, 7), (6, 8)])
def test_the_pin_cycloid_remedies_build_as_printed(lobes):
    """The refusal of a pin-cycloid female off its pitch circle names two remedies; each,
    copied as printed, must build (at 6 digits the 5/7 pair's centre distance was
    refused again as "96 mm, not 96 mm")."""
    import re

    from rotorflow.errors import CaseError
    from rotorflow.geometry.twin_screw.family import build

    m, f = lobes
    with pytest.raises(CaseError) as err:
        build("pin-cycloid", m, f, 0.080, 0.100, 0.096)
    given = dict(re.findall(r"(female_diameter_mm|centre_distance_mm) = ([0-9.e+-]+)",
                            str(err.value)))
    assert set(given) == {"female_diameter_mm", "centre_distance_mm"}, str(err.value)
    build("pin-cycloid", m, f, 0.080, 0.100, float(given["female_diameter_mm"]) * 1e-3)
    build("pin-cycloid", m, f, float(given["centre_distance_mm"]) * 1e-3, 0.100, 0.096)
