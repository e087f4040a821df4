"""The CRC.60-shaped conical case (seed 001): process angles and suction volume."""

import pytest

from rotorflow.geometry.summary import geometry_figures
from rotorflow.workflow.case import load_case

from .conftest import CASES


@pytest.fixture(scope="module")
def fig():
    return geometry_figures(load_case(CASES / "crc60.toml"))


def test_centre_distance_of_the_paper(fig):
    assert fig["E_over_D"] * 86.0 == pytest.approx(7.8, abs=1e-6)


def test_process_angles_follow_from_the_sweep(fig):
    step = 120.0 / 96  # one grid step of the default resolution, in degrees
    # Suction ends when the chamber leaves the suction end face: its planar life.
    assert fig["angle_suction_close_deg"] == pytest.approx(
        fig["phi_f_deg"] - fig["phi_i_deg"], abs=step)
    # Discharge starts when the chamber first reaches the discharge face: the wrap.
    assert fig["angle_discharge_open_deg"] == pytest.approx(fig["wrap_outer_deg"], abs=step)
    assert fig["angle_volume_max_deg"] < fig["angle_suction_close_deg"]
    # Seed 001: suction closes at 360 deg, discharge opens at 547 deg.
    assert fig["angle_suction_close_deg"] == pytest.approx(360.0, abs=15.0)
    assert fig["angle_discharge_open_deg"] == pytest.approx(547.0, abs=2.0)


def test_suction_volume_against_the_paper(fig):
    # The paper's 30 cc; the assumed taper and lead law (see the case file) give 29.3 cc.
    assert fig["volume_suction_close_m3"] * 1e6 == pytest.approx(30.0, rel=0.05)
