"""Key frames of the internal-gear section in motion (issue 17), without OpenFOAM.

The interpolation error is measured against grids built independently at the mid-frames
(:func:`interpolation_error`); the exact bound on cells between frames is checked against
a dense sampling of the interpolated motion; a degenerate frame is refused with nothing
written; a failed run is judged from its log and tables, its log tail kept.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import replace

import numpy as np
import pytest

from rotorflow.cases import moving_case
from rotorflow.cases.machine_case import slot_name
from rotorflow.cases.moving_section import (
    WALL_ERROR_RATIO,
    MovingSection,
    check_motion,
    interpolation_error,
    interval_minimum,
    key_frames,
)
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.errors import CaseError
from rotorflow.geometry.internal_gear.family import examples

PAIR = examples()["table1"]  # examples/default.toml's pair
GAP = 100e-6
SPEC = OGridSpec(columns=512, cells_across_gap=4)
OMEGA = 2500.0 * 2.0 * math.pi / 60.0  # the default case's outer rotor (inner at 3000 rpm)


def _section(frame_deg: float, frames: int = 2, start_deg: float = 13.0) -> MovingSection:
    return MovingSection(PAIR, GAP, SPEC, math.radians(start_deg),
                         math.radians(frame_deg * frames), frames, OMEGA)


def test_interval_minimum_is_the_least_value_of_the_quadratic():
    rng = np.random.default_rng(7)
    c = rng.normal(size=(3, 200))
    t = np.linspace(0.0, 1.0, 20001)
    q = c[0][:, None] + c[1][:, None] * t + c[2][:, None] * t * t
    f0, fm, f1 = q[:, 0], q[:, 10000], q[:, -1]
    # dense sampling finds the minimum to within the quadratic's change over a step
    assert interval_minimum(f0, fm, f1) == pytest.approx(q.min(1), abs=1e-8)


@pytest.fixture(scope="module")
def frames_quarter_deg():
    s = _section(0.25)
    return s, key_frames(s)


def test_wall_nodes_interpolated_between_frames_stay_on_the_walls(frames_quarter_deg):
    s, grids = frames_quarter_deg
    err = interpolation_error(s, grids)
    assert err["wall_ratio"] <= WALL_ERROR_RATIO
    # the nodes' own positions are off by the grid's jitter along the walls, which is far
    # larger than their departure from the walls: the two measures differ, as they must
    assert err["node_m"] > 3.0 * err["wall_m"]


def test_wall_error_falls_with_the_frame_spacing():
    # second order in the spacing (a chord of a smooth path); 2 against 0.5 deg is 16x
    # in theory, ~10x measured (the nodes' paths are not exactly smooth)
    coarse = interpolation_error(s := _section(2.0, 1), key_frames(s))["wall_m"]
    fine = interpolation_error(s := _section(0.5, 1), key_frames(s))["wall_m"]
    assert coarse > 4.0 * fine


def test_too_few_frames_are_refused_with_nothing_written(tmp_path):
    case = tmp_path / "case"
    with pytest.raises(CaseError, match="key frames every 2 deg") as exc:
        moving_case.write_case(_section(2.0, 1), case)
    assert "\n" not in str(exc.value)
    assert not case.exists()


def test_a_degenerate_key_frame_is_refused(frames_quarter_deg):
    s, grids = frames_quarter_deg
    points = [g.points.copy() for g in grids]
    # fold one cell of the last frame: swap two nodes across a row
    points[-1][100, 2], points[-1][100, 3] = points[-1][100, 3].copy(), points[-1][100, 2].copy()
    with pytest.raises(CaseError, match=r"key frame at 13\.5 deg degenerates"):
        check_motion(s.frame_angles, points)


def test_a_motion_that_collapses_cells_between_valid_frames_is_refused(frames_quarter_deg):
    s, grids = frames_quarter_deg
    p0 = grids[0].points
    c = p0.reshape(-1, 2).mean(0)
    # frame 1: frame 0 turned by 180 deg, every area the same and positive; the linear
    # interpolation passes every node through the centre half-way
    points = [p0, 2.0 * c - p0, 2.0 * c - p0]
    with pytest.raises(CaseError, match="between key frames at 13 and 13.25 deg inverts"):
        check_motion(s.frame_angles, points)


def test_exact_bound_agrees_with_dense_sampling(frames_quarter_deg):
    s, grids = frames_quarter_deg
    from rotorflow.cases.moving_section import _areas

    p0, p1 = grids[0].points, grids[1].points
    lo = interval_minimum(_areas(p0)[0], _areas(0.5 * (p0 + p1))[0], _areas(p1)[0])
    dense = np.min([_areas(p0 + t * (p1 - p0))[0] for t in np.linspace(0, 1, 41)], axis=0)
    assert np.all(lo <= dense * (1 + 1e-12))
    assert lo == pytest.approx(dense, rel=1e-3)


def test_a_diverged_run_is_marked_failed_with_its_log_tail(tmp_path):
    s = _section(0.25, 2)
    case = tmp_path / "run"
    case.mkdir()
    plan, built = moving_case.write_case(s, case)
    (case / f"log.{moving_case.SOLVER}").write_text(
        "trapFpe: Floating point exception trapping enabled\nTime = 1e-07\n"
        "#0  Foam::error::printStack(Foam::Ostream&) at ??:?\n"
        "#1  Foam::sigFpe::sigHandler(int) at ??:?\n")
    run = moving_case.judge(case, built, moving_case.RunControls(), 1.0,
                            "rhoPimpleFoam failed (exit status -8)")
    assert run.status == "diverged" and not run.ok
    assert "sigFpe" in run.log_tail


def test_a_run_whose_mass_drifts_is_inconsistent(tmp_path):
    s = _section(0.25, 2)
    case = tmp_path / "run"
    case.mkdir()
    _, built = moving_case.write_case(s, case)
    names = ["mass", "Co_gaps", "Co_all", *[f"p_{slot_name(c)}" for c in built.chambers]]
    for name in names:
        d = case / "postProcessing" / name / "0"
        d.mkdir(parents=True)
        mass = name == "mass"
        rows = [(t, (1.0 + 2e-4 * t / built.duration) if mass else 1.0)
                for t in np.linspace(built.duration / 10, built.duration, 10)]
        (d / "volFieldValue.dat").write_text(
            "# Time value\n" + "".join(f"{t:.12g} {v:.12g}\n" for t, v in rows))
    (case / f"log.{moving_case.SOLVER}").write_text("Time = 1\nEnd\n")
    run = moving_case.judge(case, built, moving_case.RunControls(), 1.0, "")
    assert run.status == "inconsistent" and "mass" in run.message
    assert run.log_tail  # kept, as for every failed run
    ok = moving_case.judge(case, built, replace(moving_case.RunControls(), mass_tol=1e-3),
                           1.0, "")
    assert ok.ok  # the same tables within a looser bound: the check is the drift's
    shutil.rmtree(case)



def _wall_checks(s, grids, steps, built_for=None):
    from rotorflow.cases import moving_walls
    from rotorflow.cases.polymesh import build_polymesh

    mesh = build_polymesh([grids[0], grids[0]], np.array([0.0, s.depth]), moving_case._ends)
    frames = [g.points.reshape(-1, 2) for g in grids]
    out = {}
    for patch in moving_case.ROTORS:
        omega, axis = moving_case._rotor(s, patch)
        out[patch] = moving_walls.check(
            frames, s.frame_times, moving_walls.wall_edges(mesh, patch),
            s.duration / s.frames / steps, omega, axis, steps, built_for)
    return out

def test_the_wall_velocity_carries_the_mesh_flux_and_the_rotors_omega_x_r(frames_quarter_deg):
    s, grids = frames_quarter_deg
    out = _wall_checks(s, grids, 16)
    for patch in moving_case.ROTORS:
        # the flux of the imposed velocity against the area each wall face sweeps in
        # every step, by the shoelace of its old and new edge: round-off
        assert out[patch]["normal_max"] <= 1e-10
        # tangentially the rotor's own surface velocity, to well within 1 % of the tip
        # speed (the grid's own sliding velocity is 11 % / 31 % RMS off)
        assert out[patch]["tangential_rms"] <= 0.002
        assert out[patch]["tangential_max"] <= 0.01


def test_the_wall_velocity_misses_the_mesh_flux_for_another_step(frames_quarter_deg):
    s, grids = frames_quarter_deg
    # built for a step twice the one the mesh moves in: the check must see it
    out = _wall_checks(s, grids, 16, built_for=2.0 * s.duration / s.frames / 16)
    assert min(out[p]["normal_max"] for p in moving_case.ROTORS) > 1e-7


def test_a_run_above_the_courant_limit_is_inconsistent(tmp_path):
    s = _section(0.25, 2)
    case = tmp_path / "run"
    case.mkdir()
    _, built = moving_case.write_case(s, case)
    for name in ["mass", "Co_gaps", "Co_all", *[f"p_{slot_name(c)}" for c in built.chambers]]:
        d = case / "postProcessing" / name / "0"
        d.mkdir(parents=True)
        v = 1.5 if name.startswith("Co") else 1.0  # the step is fixed: nothing held it
        (d / "volFieldValue.dat").write_text("# Time value\n" + "".join(
            f"{t:.12g} {v:.12g}\n" for t in np.linspace(built.duration / 10, built.duration, 10)))
    (case / f"log.{moving_case.SOLVER}").write_text("Time = 1\nEnd\n")
    run = moving_case.judge(case, built, moving_case.RunControls(), 1.0, "")
    assert run.status == "inconsistent" and "Courant" in run.message
    ok = moving_case.judge(case, built, replace(moving_case.RunControls(), max_courant=2.0),
                           1.0, "")
    assert ok.ok
