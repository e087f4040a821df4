"""The CFD cases' OpenFOAM commands as data, drained by the runner, without OpenFOAM.

Each case plans its commands (:func:`rotorflow.cases.gap_case.plan`,
:func:`rotorflow.cases.chamber_case.plan`); :func:`rotorflow.cases.foam.drain` runs them
through a launcher, here a fake one that writes a scripted log and exit status.  The
shared routine (:func:`rotorflow.cases.foam_case.run_case`) is driven the same way.
Plain tier: no OpenFOAM, no gmsh.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rotorflow.cases import chamber_case, foam, foam_case, gap_case, gap_walls
from rotorflow.cases.foam import Step
from rotorflow.errors import ExternalRunError

CHAMBER_RUN = Path(__file__).resolve().parent / "data" / "cfd" / "chamber" / "leaking"


class FakeProcess:
    """What the runner needs of a process: it has already finished."""

    def __init__(self, argv, returncode: int) -> None:
        self.args, self.returncode = list(argv), returncode

    def wait(self, timeout=None) -> int:
        return self.returncode

    def kill(self) -> None:
        pass


class FakeLauncher:
    """Writes ``lines`` of output per program into its log; ``fail`` exits with 1."""

    def __init__(self, fail: str | None = None, fatal: str | None = None) -> None:
        self.fail, self.fatal, self.launched = fail, fatal, []

    def __call__(self, argv, case_dir: Path, out) -> FakeProcess:
        program = argv[0]
        self.launched.append(list(argv))
        for i in range(60):
            out.write(f"{program} line {i}\n".encode())
        if program == self.fatal:
            out.write(b"--> FOAM FATAL ERROR: cannot find patch outlet\n")
        if program == self.fail:
            out.write(f"{program}: the last words\n".encode())
        return FakeProcess(argv, 1 if program == self.fail else 0)


def _case_folder(tmp_path: Path) -> Path:
    (tmp_path / "system").mkdir(parents=True)
    (tmp_path / "system" / "controlDict").write_text("FoamFile {}\n")
    return tmp_path


def _gap_case() -> gap_case.GapCase:
    flow = gap_case.GapFlow(p_total_Pa=2.0e5, T_total_K=300.0, p_exit_Pa=1.0e5)
    return gap_case.GapCase(gap_walls.rotor_tip_gap(50e-6, 0.02), flow)


def _chamber_case(gap_m: float | None = None) -> chamber_case.ChamberCase:
    desc = json.loads((CHAMBER_RUN / "case.json").read_text())
    comp = chamber_case.Compression(
        angle_rad=tuple(desc["angle_rad"]), volume_m3=tuple(desc["volume_m3"]),
        omega_outer_rad_s=desc["omega_outer_rad_s"], p_suction_Pa=desc["p_suction_Pa"],
        T_suction_K=desc["T_suction_K"], seal_length_m=desc["seal_length_m"],
        gap_m=desc["gap_m"] if gap_m is None else gap_m)
    return chamber_case.ChamberCase(comp)


# --- the plans ----------------------------------------------------------------------------


def test_gap_case_plan():
    case = _gap_case()
    plan = gap_case.plan(case, Path("/tmp/x"), mesh_cells=320)
    assert plan.commands() == [
        ["gmshToFoam", "gap.msh"],
        ["checkMesh"],
        ["postProcess", "-func", "writeCellCentres", "-time", "0"],
        ["rhoSimpleFoam"],
    ]
    assert [s.program for s in plan.setup] == ["gmshToFoam", "checkMesh", "postProcess"]
    # Every setup step checks or completes what its program wrote; the solver is watched
    # by the convergence monitor and stopped at the case's time limit.
    assert all(s.then is not None for s in plan.setup)
    assert plan.solve.on_poll is not None and plan.solve.timeout_s == case.controls.timeout_s


@pytest.mark.parametrize("sealed", [False, True])
def test_chamber_case_plan(sealed):
    case = _chamber_case(0.0 if sealed else None)
    plan = chamber_case.plan(case, mesh_cells=1000)
    assert plan.commands() == [["gmshToFoam", "chamber.msh"], ["checkMesh"], ["topoSet"],
                               ["rhoPimpleFoam"]]
    assert all(s.then is not None for s in plan.setup)
    assert plan.solve.on_time is not None and plan.solve.timeout_s == case.controls.timeout_s


def test_steps_are_argument_lists():
    with pytest.raises(ValueError):
        Step(())
    with pytest.raises(ValueError):
        Step(("postProcess", 3))  # type: ignore[arg-type]


# --- draining -----------------------------------------------------------------------------


def test_drain_runs_in_order_with_one_log_per_program(tmp_path):
    folder = _case_folder(tmp_path)
    seen = []
    steps = [Step(("gmshToFoam", "gap.msh"), then=lambda d, log: seen.append(log.name) or 7),
             Step(("checkMesh",)), Step(("rhoSimpleFoam",))]
    launcher = FakeLauncher()
    values = foam.drain(steps, folder, launch=launcher)
    assert launcher.launched == [["gmshToFoam", "gap.msh"], ["checkMesh"], ["rhoSimpleFoam"]]
    assert seen == ["log.gmshToFoam"]
    assert values == {"gmshToFoam": 7, "checkMesh": folder / "log.checkMesh",
                      "rhoSimpleFoam": folder / "log.rhoSimpleFoam"}
    assert (folder / "log.checkMesh").read_text().splitlines()[-1] == "checkMesh line 59"


def test_a_failing_step_stops_the_drain_with_its_log_tail(tmp_path):
    folder = _case_folder(tmp_path)
    then_called = []
    steps = [Step(("gmshToFoam", "gap.msh")),
             Step(("checkMesh",), then=lambda d, log: then_called.append(log)),
             Step(("rhoSimpleFoam",))]
    launcher = FakeLauncher(fail="checkMesh")
    with pytest.raises(ExternalRunError) as err:
        foam.drain(steps, folder, launch=launcher)
    message = str(err.value)
    assert "checkMesh failed (exit status 1)" in message
    # The tail of its log: the last lines, not the first.
    assert "checkMesh: the last words" in message and "checkMesh line 59" in message
    assert "checkMesh line 0\n" not in message
    assert launcher.launched == [["gmshToFoam", "gap.msh"], ["checkMesh"]]
    assert then_called == [] and not (folder / "log.rhoSimpleFoam").exists()


def test_a_fatal_message_fails_a_step_that_exits_zero(tmp_path):
    folder = _case_folder(tmp_path)
    with pytest.raises(ExternalRunError, match="(?s)reported a fatal error.*cannot find patch"):
        foam.drain([Step(("topoSet",)), Step(("rhoPimpleFoam",))], folder,
                   launch=FakeLauncher(fatal="topoSet"))


def test_a_failing_gmshtofoam_stops_the_chamber_plan(tmp_path):
    folder = _case_folder(tmp_path)
    launcher = FakeLauncher(fail="gmshToFoam")
    with pytest.raises(ExternalRunError, match="gmshToFoam failed"):
        foam.drain(chamber_case.plan(_chamber_case(), 1000).steps, folder, launch=launcher)
    # Its patch types were never set (no boundary file to read), nothing else ran.
    assert launcher.launched == [["gmshToFoam", "chamber.msh"]]


# --- the shared routine -------------------------------------------------------------------


class _Result:
    def __init__(self, status: str, message: str = "", log_tail: str = "") -> None:
        self.status, self.message, self.log_tail = status, message, log_tail

    def to_json(self) -> str:
        return json.dumps(vars(self)) + "\n"

    @classmethod
    def from_json(cls, text: str) -> _Result:
        return cls(**json.loads(text))


def _routine(folder: Path, launcher: FakeLauncher, key: str = "k1"):
    def build(tmp: Path):
        _case_folder(tmp)
        (tmp / "written.txt").write_text("what Python writes\n")
        return foam_case.Plan((Step(("checkMesh",), then=lambda d, log: "quality"),),
                              Step(("rhoSimpleFoam",))), "context"

    def judge(tmp: Path, context, values, elapsed, failure):
        assert context == "context" and values == {"checkMesh": "quality"}
        v = foam_case.verdict(tmp, "rhoSimpleFoam", failure, ("converged", ""), "converged")
        return _Result(v.status, v.message, v.log_tail)

    return foam_case.run_case(folder, key, build, judge, _Result.from_json,
                              launch=launcher)


def test_routine_keeps_a_failed_run_with_its_log_tail_and_reuses_it(tmp_path):
    folder = tmp_path / "run"
    launcher = FakeLauncher(fail="rhoSimpleFoam")
    result = _routine(folder, launcher)
    assert result.status == "crashed" and "rhoSimpleFoam failed" in result.message
    assert "rhoSimpleFoam: the last words" in result.log_tail
    # Renamed into place with its result and key; no temporary folder left.
    assert (folder / "written.txt").is_file() and (folder / "case.key").read_text() == "k1\n"
    assert json.loads((folder / "result.json").read_text())["status"] == "crashed"
    assert not folder.with_name("run.tmp").exists()
    # The same key: the stored (failed) result, nothing run again...
    again = FakeLauncher()
    assert vars(_routine(folder, again)) == vars(result) and again.launched == []
    # ...another key: built and run anew.
    assert _routine(folder, again, key="k2").status == "converged"
    assert (folder / "case.key").read_text() == "k2\n"


def test_routine_raises_on_a_failed_setup_and_leaves_nothing_finished(tmp_path):
    folder = tmp_path / "run"
    with pytest.raises(ExternalRunError, match="checkMesh failed"):
        _routine(folder, FakeLauncher(fail="checkMesh"))
    assert not folder.exists()  # the half-built case stays in run.tmp, never taken
    assert (tmp_path / "run.tmp" / "log.checkMesh").is_file()
    assert foam_case.stored_result(tmp_path / "run.tmp", "k1", _Result.from_json) is None


def test_keys_are_the_digest_of_what_determines_the_result():
    case = _gap_case()
    # The keys name stored runs (runs_dir folders are reused by them): these are the
    # keys the code before the shared routine gave the same cases; the gap case's since
    # its walls are keyed to the picometre (2026-12-01: their last bits followed the
    # CPU; it was 5e06d427bda245f7c35e, so stored gap runs were recomputed once).
    assert case.key() == "a52b4be3e3cb91356fdf"
    assert _chamber_case().key() == "80a1b74340be6f775265"
    assert case.key() == gap_case.GapCase(case.walls, case.flow).key()
    assert len(case.key()) == 20 and case.refined(2).key() != case.key()
    assert foam_case.digest({"a": 1, "b": 2}) == foam_case.digest({"b": 2, "a": 1})
