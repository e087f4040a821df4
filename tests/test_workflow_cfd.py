"""The CFD leakage stage as a workflow stage: case validation and registration."""

import subprocess
import sys

import pytest

from rotorflow.errors import CaseError
from rotorflow.workflow.case import load_case
from rotorflow.workflow.stages import REGISTRY

from .conftest import CASES


def test_cfd_case_loads_and_its_stage_is_registered():
    case = load_case(CASES / "cfd_leakage.toml")
    assert case.raw["cfd"]["gap_um"] == [5, 10, 50, 200]
    assert case.raw["cfd"]["rotor_angle_deg"] == [240, 300]
    stage = REGISTRY["cfd.leakage"]
    # Sealing-line sections are cut from the machine and move at the operating speed.
    assert {"cfd", "machine", "operating.speed_rpm", "operating.driven"} <= set(stage.reads)
    assert stage.missing({}) and stage.missing(case.raw) is None


@pytest.mark.parametrize("old, new, word", [
    ("gap_um = [5, 10, 50, 200]", "gap_um = [5, 10]\nmesh = 3", "mesh"),
    ("gap_um = [5, 10, 50, 200]", "gap_um = [-10]", "must be positive"),
    ("pressure_ratio = [1.1, 2.0, 4.0]", "pressure_ratio = 2.0", "list"),
    ("rotor_angle_deg = [240, 300]", "rotor_angle_deg = [240, 330]", "330"),
    ("speed_rpm = 6000", "", "speed_rpm"),
])
def test_bad_cfd_section_exits_2_with_one_line(tmp_path, old, new, word):
    case = tmp_path / "case.toml"
    case.write_text((CASES / "cfd_leakage.toml").read_text().replace(old, new))
    with pytest.raises(CaseError, match=word):
        load_case(case)
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "run", str(case),
                          "--build", str(tmp_path / "build")], capture_output=True, text=True)
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and word in out.stderr
    assert not (tmp_path / "build").exists()
