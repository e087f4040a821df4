"""Offline tests on small recorded OpenFOAM outputs (tests/data/cfd, see record.py there).

No OpenFOAM needed: these read what rhoSimpleFoam and checkMesh wrote in a real run of
the plane Poiseuille channel on three meshes, a run made to diverge, and checkMesh's
verdicts on a good and a rejected mesh.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from rotorflow.cases import foam, foam_case, foam_mesh, gap_case, gap_walls
from rotorflow.errors import CaseError, ExternalRunError
from rotorflow.postprocess import foam_output, leakage
from rotorflow.postprocess.richardson import richardson

DATA = Path(__file__).resolve().parent / "data" / "cfd"
STUDY = DATA / "channel_study"
LEVELS = ("coarse", "default", "fine")
PARAMS = json.loads((DATA / "channel_study.json").read_text())


def channel_point(mass_flow: float = float("nan")) -> leakage.LeakagePoint:
    p = PARAMS
    return leakage.LeakagePoint(
        name="channel", gap_m=p["gap_m"], length_m=p["length_m"], p_up_Pa=p["p_total_Pa"],
        T_up_K=p["T_total_K"], p_down_Pa=p["p_exit_Pa"], mu_Pa_s=p["mu_Pa_s"],
        R_J_kgK=p["R_J_kgK"], gamma=p["gamma"], mass_flow_kg_s_m=mass_flow,
    )


def recorded_mass_flows(root: Path = STUDY) -> list[float]:
    """Mass flow per metre of depth of each mesh level, judged from the tables alone."""
    flows = []
    for level in LEVELS:
        history = gap_case.read_mass_flow_history(root / level)
        status, message, m_in, m_out, _ = gap_case.assess_history(
            history, gap_case.SolverControls())
        assert status == "converged", f"{level}: {message}"
        flows.append(0.5 * (m_in + m_out) / PARAMS["depth_m"])
    return flows


def perturbed_copy(tmp_path: Path, level: str, patches: tuple[str, ...], factor: float) -> Path:
    """A copy of the study with the mass-flow tables of one level scaled by ``factor``."""
    root = tmp_path / "study"
    shutil.copytree(STUDY, root)
    for patch in patches:
        table = root / level / "postProcessing" / patch / "0" / "surfaceFieldValue.dat"
        out = []
        for line in table.read_text().splitlines(keepends=True):
            if line.startswith("#"):
                out.append(line)
            else:
                t, v = line.split()
                out.append(f"{t}\t{float(v) * factor:.10e}\n")
        table.write_text("".join(out))
    return root


# --- tables -------------------------------------------------------------------------------


def test_recorded_flows_balance_within_half_a_percent():
    for level in LEVELS:
        history = gap_case.read_mass_flow_history(STUDY / level)
        assert np.all(history.inlet > 0) and np.all(history.outlet[-10:] > 0)
        # The acceptance: inlet and outlet mass flow within 0.5 % (steady state).
        assert history.imbalance[-1] < 5e-3


def test_recorded_flows_match_the_stored_results():
    for level, flow in zip(LEVELS, recorded_mass_flows(), strict=True):
        stored = gap_case.GapResult.from_json((STUDY / level / "result.json").read_text())
        assert stored.ok
        # Same numbers through the same arithmetic: only float formatting differs.
        assert flow == pytest.approx(stored.mass_flow_kg_s_m, rel=1e-12)


def test_outlet_flow_perturbed_by_one_percent_fails_the_balance(tmp_path):
    root = perturbed_copy(tmp_path, "default", ("massFlowOutlet",), 1.01)
    history = gap_case.read_mass_flow_history(root / "default")
    status, message, *_ = gap_case.assess_history(history, gap_case.SolverControls())
    assert status == "not-converged"
    assert "differ by 1.00%" in message


def test_table_reader_skips_a_half_written_line(tmp_path):
    src = STUDY / "default" / "postProcessing" / "massFlowInlet" / "0" / "surfaceFieldValue.dat"
    table = tmp_path / "t.dat"
    table.write_text(src.read_text() + "999\t-2.70")  # the solver is mid-line
    header, data = foam_output.read_table(table)
    assert header == ["Time", "sum(phi)"]
    assert data[-1, 0] < 999


def test_restart_folders_are_joined_with_the_later_copy_winning(tmp_path):
    for start, rows in (("0", [(1, 1.0), (2, 2.0), (3, 3.0)]), ("2", [(3, 30.0), (4, 40.0)])):
        folder = tmp_path / "postProcessing" / "f" / start
        folder.mkdir(parents=True)
        text = "# Time  sum(phi)\n" + "".join(f"{t} {v}\n" for t, v in rows)
        (folder / "surfaceFieldValue.dat").write_text(text)
    _, data = foam_output.function_object_table(tmp_path, "f", "surfaceFieldValue.dat")
    np.testing.assert_array_equal(data, [[1, 1.0], [2, 2.0], [3, 30.0], [4, 40.0]])


def test_missing_output_is_an_error_not_a_zero(tmp_path):
    with pytest.raises(ExternalRunError, match="wrote nothing"):
        gap_case.read_mass_flow_history(tmp_path)


# --- the channel against its analytic solution --------------------------------------------


def test_channel_study_extrapolates_to_plane_poiseuille_flow():
    rich = richardson(recorded_mass_flows(), PARAMS["refinement_ratio"])
    exact = leakage.plane_poiseuille_mass_flow(channel_point())
    # Second-order finite volumes: the observed order must be close to 2.
    assert rich.kind == "monotone"
    assert 1.7 < rich.order < 2.3
    # Richardson removes the h^2 error; what is left is the h^3 term and the iterative
    # convergence (~1e-4): 0.2 % is ten times the difference seen when recording.
    assert leakage.mismatches({"channel": rich.extrapolated}, {"channel": exact}, 2e-3) == []


def test_channel_comparison_fails_on_perturbed_data(tmp_path):
    # The same check on a fine-mesh flow 2 % high (both patches, so it still balances)
    # must fail: the comparison can tell a wrong answer from a right one.
    root = perturbed_copy(tmp_path, "fine", ("massFlowInlet", "massFlowOutlet"), 1.02)
    flows = recorded_mass_flows(root)
    assert flows[2] == pytest.approx(recorded_mass_flows()[2] * 1.02, rel=1e-9)
    rich = richardson(flows, PARAMS["refinement_ratio"])
    exact = leakage.plane_poiseuille_mass_flow(channel_point())
    assert leakage.mismatches({"channel": rich.extrapolated}, {"channel": exact}, 2e-3)


# --- failed runs --------------------------------------------------------------------------


def test_diverged_run_is_marked_failed_with_its_log_tail():
    walls = gap_walls.rotor_tip_gap(50e-6, 0.02)
    flow = gap_case.GapFlow(p_total_Pa=2.5e5, T_total_K=300.0, p_exit_Pa=1e5)
    case = gap_case.GapCase(walls, flow)
    quality = foam_mesh.parse_check_mesh((DATA / "log.checkMesh").read_text())
    result = gap_case.judge(DATA / "diverged", case, "laminar", quality, 50e-6, 1.0,
                            "rhoSimpleFoam failed (exit status -8)")
    assert result.status == "diverged"
    assert not result.ok
    assert "sigFpe" in result.log_tail


def test_divergence_signs_in_logs():
    assert foam_case.looks_diverged((DATA / "diverged" / "log.rhoSimpleFoam").read_text())
    assert foam_case.looks_diverged("Solving for e, Initial residual = nan, Final residual")
    assert not foam_case.looks_diverged("Solving for e, dynamic, finance, Initial residual = 1e-5")


# --- checkMesh ----------------------------------------------------------------------------


def test_check_mesh_report_of_a_good_mesh():
    q = foam_mesh.parse_check_mesh((DATA / "log.checkMesh").read_text())
    assert q.ok
    assert q.cells == 16 * 40  # cells across x (2 sides x 20 along)
    assert q.max_non_orthogonality_deg == 0.0  # a rectangular channel
    assert 1 < q.max_aspect_ratio < 1000


def test_check_mesh_report_of_a_rejected_mesh():
    q = foam_mesh.parse_check_mesh((DATA / "log.checkMesh.failed").read_text())
    assert not q.ok
    assert any("High aspect ratio" in c for c in q.failed_checks)
    assert q.max_aspect_ratio == 40000  # read from the flag's own line


def test_aspect_flag_is_judged_against_the_callers_limit(tmp_path):
    """Clearance grids may pass checkMesh's 1000 up to their own limit, not beyond it:
    the recorded log's 40000 is refused under 1e4 and passes only under 1e5."""
    log = DATA / "log.checkMesh.failed"
    with pytest.raises(foam_mesh.MeshCheckError, match="High aspect ratio"):
        foam_mesh.judge_check_mesh(tmp_path, log)
    with pytest.raises(foam_mesh.MeshCheckError, match="High aspect ratio"):
        foam_mesh.judge_check_mesh(tmp_path, log, max_aspect_ratio=1e4)
    assert foam_mesh.judge_check_mesh(tmp_path, log, max_aspect_ratio=1e5).max_aspect_ratio \
        == 40000


def test_unreadable_check_mesh_report_is_not_ok():
    assert not foam_mesh.parse_check_mesh("checkMesh was killed\n").ok


# --- finding OpenFOAM ---------------------------------------------------------------------


def test_missing_openfoam_is_a_case_error_naming_the_fix(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    foam.find_installation.cache_clear()
    try:
        with pytest.raises(foam.OpenFOAMNotFoundError, match="make openfoam") as err:
            foam.find_installation()
        assert isinstance(err.value, CaseError)  # the command line maps it to exit 2
        assert not foam.is_available()
    finally:
        foam.find_installation.cache_clear()


def test_a_study_with_a_failed_run_is_never_used():
    from dataclasses import replace

    from rotorflow.cases.gap_study import MeshStudy

    results = [gap_case.GapResult.from_json((STUDY / lvl / "result.json").read_text())
               for lvl in LEVELS]
    case = gap_case.GapCase(gap_walls.parallel_channel(PARAMS["gap_m"], PARAMS["length_m"]),
                            gap_case.GapFlow(PARAMS["p_total_Pa"], PARAMS["T_total_K"],
                                             PARAMS["p_exit_Pa"]))
    good = MeshStudy("good", case, tuple(results), 2.0)
    assert good.ok and good.leakage_point() is not None
    assert good.richardson.kind == "monotone"
    failed = replace(results[2], status="diverged", message="sigFpe")
    bad = MeshStudy("bad", case, (results[0], results[1], failed), 2.0)
    assert not bad.ok
    assert bad.failures == ["fine: diverged (sigFpe)"]
    assert bad.richardson is None and bad.leakage_point() is None
    assert bad.summary()["kind"] == "failed"
