"""`rotorflow run`: stages planned from [outputs], cached by content, written atomically.

Everything is judged from the execution record ``<build>/<case>/run.json`` and the
artifact stamps, never from log output.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .conftest import CASES

DEMO_PLAN = ["geometry", "table", "quasi1d", "render", "solids", "report"]


def rotorflow(*args, env=None, **kw):
    return subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", *map(str, args)],
                          capture_output=True, text=True, env=env, **kw)


def record(build: Path, name: str) -> dict:
    return json.loads((build / name / "run.json").read_text())


def case_copy(tmp_path: Path, name: str = "demo", edit=None, extra: str = "") -> Path:
    text = (CASES / "default.toml").read_text()
    if edit:
        text = text.replace(*edit)
    path = tmp_path / f"{name}.toml"
    path.write_text(text + extra)
    return path


@pytest.fixture(scope="module")
def demo_build(tmp_path_factory):
    """The demo case run once, end to end, into a private build folder."""
    build = tmp_path_factory.mktemp("build")
    out = rotorflow("run", CASES / "default.toml", "--build", build)
    assert out.returncode == 0, out.stderr
    return build


def test_demo_runs_every_stage_then_nothing(demo_build):
    first = record(demo_build, "default")
    assert first["status"] == "complete"
    assert first["plan"] == DEMO_PLAN
    assert first["executed"] == DEMO_PLAN and first["skipped"] == []
    out = rotorflow("run", CASES / "default.toml", "--build", demo_build)
    assert out.returncode == 0, out.stderr
    second = record(demo_build, "default")
    assert second["executed"] == [] and second["skipped"] == DEMO_PLAN
    assert all(e["status"] == "cached" for e in second["stages"].values())
    # The keys did not change either: the same inputs hash to the same key.
    for name in DEMO_PLAN:
        assert second["stages"][name]["key"] == first["stages"][name]["key"]


def test_discharge_pressure_reruns_only_what_depends_on_it(tmp_path):
    build = tmp_path / "build"
    case = case_copy(tmp_path)
    assert rotorflow("run", case, "--build", build).returncode == 0
    first = record(build, "demo")
    before = json.loads((build / "demo" / "quasi1d" / "summary.json").read_text())
    case.write_text(case.read_text().replace("p_discharge_bar = 2.6", "p_discharge_bar = 3.0"))
    out = rotorflow("run", case, "--build", build)
    assert out.returncode == 0, out.stderr
    second = record(build, "demo")
    assert second["executed"] == ["quasi1d", "report"]
    assert second["skipped"] == ["geometry", "table", "render", "solids"]
    assert second["stages"]["quasi1d"]["key"] != first["stages"]["quasi1d"]["key"]
    summary = json.loads((build / "demo" / "quasi1d" / "summary.json").read_text())
    # A higher discharge pressure takes more work per kg: the rerun really used 3.0 bar.
    assert summary["specific_power_J_kg"] > 1.05 * before["specific_power_J_kg"]
    html = (build / "demo" / "report" / "index.html").read_text()
    assert "p_discharge_bar = 3.0" in html
    # ... and a geometry key reruns the geometry, the table and everything after them.
    case.write_text(case.read_text().replace("length_mm = 100", "length_mm = 90"))
    assert rotorflow("run", case, "--build", build).returncode == 0
    assert record(build, "demo")["executed"] == DEMO_PLAN


def test_outputs_select_stages_and_their_upstream_only(tmp_path):
    build = tmp_path / "build"
    case = case_copy(tmp_path, extra='\n[outputs]\nwant = ["table"]\n')
    out = rotorflow("run", case, "--build", build)
    assert out.returncode == 0, out.stderr
    rec = record(build, "demo")
    assert rec["plan"] == ["table"] and rec["executed"] == ["table"]
    assert sorted(p.name for p in (build / "demo").iterdir() if p.is_dir()) == ["table"]
    # quasi1d needs the table: asking for it reuses the cached table.
    out = rotorflow("run", case, "--build", build, "--want", "quasi1d")
    assert out.returncode == 0, out.stderr
    rec = record(build, "demo")
    assert rec["executed"] == ["quasi1d"] and rec["skipped"] == ["table"]


def test_damaged_artifact_is_rebuilt_and_identical_content_stops_the_cascade(tmp_path):
    build = tmp_path / "build"
    case = case_copy(tmp_path, extra='\n[outputs]\nwant = ["geometry", "quasi1d"]\n')
    assert rotorflow("run", case, "--build", build).returncode == 0
    (build / "demo" / "table" / "chamber_table.csv").unlink()
    assert rotorflow("run", case, "--build", build).returncode == 0
    rec = record(build, "demo")
    # The table is rebuilt byte for byte, so nothing downstream of it has a new key.
    assert rec["executed"] == ["table"]
    assert (build / "demo" / "table" / "chamber_table.csv").is_file()
    # A stamp that does not match its files is no stamp.
    (build / "demo" / "geometry" / "geometry.json").write_text("{}")
    assert rotorflow("run", case, "--build", build).returncode == 0
    assert "geometry" in record(build, "demo")["executed"]


def test_checks_read_fresh_artifacts_and_skip_fresh_stages(tmp_path, monkeypatch):
    """A rerun checks only the stages it will run, and the quasi-1D check reads a fresh
    table from its artifact: building the chamber table is then an error here.  A stale
    stage's refusal still comes, before anything is written.  (A port timing outside the
    chamber's life cannot be asked with a fresh table: the table reads the timing.)"""
    from rotorflow.errors import CaseError
    from rotorflow.workflow import builtin, runner

    build = tmp_path / "build"
    case = case_copy(tmp_path, extra='\n[outputs]\nwant = ["quasi1d"]\n')
    assert runner.run_case(case, build)["executed"] == ["table", "quasi1d"]

    def rebuilt(_case):
        raise AssertionError("the chamber table was built again")

    monkeypatch.setattr(builtin, "_table", rebuilt)
    assert runner.run_case(case, build)["skipped"] == ["table", "quasi1d"]
    assert runner.up_to_date(case, build)
    case.write_text(case.read_text().replace("p_discharge_bar = 2.6", "p_discharge_bar = 3.0"))
    assert not runner.up_to_date(case, build)
    assert runner.run_case(case, build)["executed"] == ["quasi1d"]
    stamp = (build / "demo" / "quasi1d" / ".stage.json").read_text()
    case.write_text(case.read_text().replace("p_discharge_bar = 3.0", "p_discharge_bar = -3"))
    with pytest.raises(CaseError, match="p_discharge_bar"):
        runner.run_case(case, build)
    assert (build / "demo" / "quasi1d" / ".stage.json").read_text() == stamp


def test_a_refitted_flow_coefficient_reruns_the_model(tmp_path):
    """The case names the CFD fit's file; the key holds its contents, so a refit (the
    same name) reruns the quasi-1D model and moves its result."""
    from rotorflow.quasi1d.calibrated import FlowCoefficientFit
    from rotorflow.workflow import runner

    def refit(cd):  # a constant flow coefficient cd (A = 1 / cd^2, no viscous term)
        fit = FlowCoefficientFit(inertial_features=("1",), inertial=(1.0 / cd**2,),
                                 viscous=0.0)
        (tmp_path / "fit.json").write_text(fit.to_json())

    refit(0.7)
    case = case_copy(tmp_path, edit=('model = "nozzle"',
                                     'model = "cfd-calibrated"\ncorrelation = "fit.json"'),
                     extra='\n[outputs]\nwant = ["quasi1d"]\n')
    build = tmp_path / "build"
    summary = build / "demo" / "quasi1d" / "summary.json"
    assert runner.run_case(case, build)["executed"] == ["table", "quasi1d"]
    before = json.loads(summary.read_text())["leakage_kg_s"]
    assert runner.run_case(case, build)["executed"] == []
    refit(0.3)
    assert not runner.up_to_date(case, build)
    assert runner.run_case(case, build)["executed"] == ["quasi1d"]
    after = json.loads(summary.read_text())["leakage_kg_s"]
    assert sum(after.values()) < 0.6 * sum(before.values())  # the leakage scales with Cd


@pytest.mark.parametrize("extra, word", [
    ('\n[outputs]\nwant = ["volume_curve"]\n', "volume_curve"),
    ('\n[outputs]\nwant = "table"\n', "want"),
    ('\n[outputs]\nwant = ["table"]\nformat = "png"\n', "format"),
    ('\n[outputs]\n', "want"),
    ('\n[outputs]\nwant = []\n', "want"),
])
def test_bad_outputs_exit_2_with_one_line(tmp_path, extra, word):
    case = case_copy(tmp_path, extra=extra)
    out = rotorflow("run", case, "--build", tmp_path / "build")
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0], out.stderr
    assert not (tmp_path / "build").exists()  # nothing written


def test_asking_for_a_stage_without_its_input_exits_2(tmp_path):
    case = tmp_path / "geo.toml"
    case.write_text((CASES / "table1_inner_ev2.toml").read_text()
                    + '\n[outputs]\nwant = ["quasi1d"]\n')
    out = rotorflow("run", case, "--build", tmp_path / "build")
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "quasi1d" in lines[0] and "p_suction_bar" in lines[0]
    bad = tmp_path / "bad.toml"
    bad.write_text((CASES / "default.toml").read_text().replace("lambda = 1.39934",
                                                                "lambda = 0.9"))
    out = rotorflow("run", bad, "--build", tmp_path / "build")
    assert out.returncode == 2 and "lambda" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    out = rotorflow("run", tmp_path / "missing.toml")
    assert out.returncode == 2 and "not found" in out.stderr


@pytest.mark.parametrize("edit, word", [
    # refused by the quasi-1D stage (the timing against the chamber's life), which runs
    # after the geometry, table, render and solids stages
    (("volume_ratio = 2", "volume_ratio = 2\nsuction_close_deg = 0"), "chamber's life"),
    # refused by the solids stage: a casing bore inside the rotor
    (("tolerance_um = 20", "tolerance_um = 20\nbore_diameter_mm = 50"), "bore_diameter_mm"),
])
def test_a_late_stage_refusal_stops_the_run_before_any_stage_writes(tmp_path, edit, word):
    out = rotorflow("run", case_copy(tmp_path, edit=edit), "--build", tmp_path / "build")
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0], out.stderr
    assert not (tmp_path / "build").exists()


def test_a_disc_cutter_that_cannot_be_made_stops_the_run_before_any_stage_writes(tmp_path):
    # The 4/6 pin-cycloid male's pitch circle is its root, so its default setting angle
    # (the helix angle there, 54.39 deg) is the least that reaches its whole flank: at 53.4
    # no tool circle meets the flank near the root.  (Until session 38 the default itself
    # failed, on a defect.)  The run wrote the geometry, table, quasi-1D and render stages
    # before the solids stage found such a tool.
    case = tmp_path / "cutter.toml"
    case.write_text((CASES / "twin_screw_4_6.toml").read_text() + (
        '\n[export]\nformats = ["cutter"]\nclearance_um = 40\nclearance_on = "female"\n'
        'cutter_setting_angle_deg = { male = 53.4 }\n'))
    out = rotorflow("run", case, "--build", tmp_path / "build")
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "form cutter and the male rotor" in lines[0], out.stderr
    assert not (tmp_path / "build").exists()

# ---------------------------------------------------------------- SIGKILL mid-stage
SLOW_STAGE = '''
import os, sys, time
from pathlib import Path
from rotorflow.workflow import stages
from rotorflow.workflow.cli import main

def slow(ctx):
    (ctx.out / "half.txt").write_text("written before the pause")
    Path(os.environ["MARKER"]).write_text(str(ctx.out))
    if os.environ.get("PAUSE"):
        time.sleep(120)
    (ctx.out / "done.txt").write_text(os.environ.get("LABEL", ""))

stages.register(stages.Stage(name="slow", run="__main__:slow", description="test stage",
                             reads=("machine",), needs=("geometry",)))
sys.exit(main(sys.argv[1:]))
'''


def _kill_mid_stage(script, case, build, marker, env):
    """Start a run that pauses inside the slow stage, and SIGKILL it there."""
    marker.unlink(missing_ok=True)
    proc = subprocess.Popen([sys.executable, str(script), "run", str(case), "--build",
                             str(build)], env={**env, "PAUSE": "1"},
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while not marker.exists():
        assert proc.poll() is None, "the run ended before reaching the slow stage"
        assert time.monotonic() < deadline, "the slow stage never started"
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    return Path(marker.read_text())


def test_stage_killed_mid_way_is_rerun_never_reused(tmp_path):
    script = tmp_path / "with_slow_stage.py"
    script.write_text(SLOW_STAGE)
    case = case_copy(tmp_path, extra='\n[outputs]\nwant = ["slow"]\n')
    build, marker = tmp_path / "build", tmp_path / "marker"
    env = {**os.environ, "MARKER": str(marker)}
    folder = build / "demo"

    # 1. Killed in a first run: no result folder, only the temporary one.
    tmp = _kill_mid_stage(script, case, build, marker, env)
    assert tmp.is_dir() and (tmp / "half.txt").is_file() and tmp.name.startswith(".tmp-")
    assert not (folder / "slow").exists()
    assert record(build, "demo")["status"] == "running"  # the record says it never ended
    out = subprocess.run([sys.executable, str(script), "run", str(case), "--build", str(build)],
                         env={**env, "LABEL": "first"}, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    rec = record(build, "demo")
    assert rec["status"] == "complete" and rec["executed"] == ["slow"]
    assert rec["skipped"] == ["geometry"]  # finished before the kill: kept
    assert (folder / "slow" / "done.txt").read_text() == "first"
    assert not tmp.exists()
    assert not [p for p in folder.iterdir() if p.name.startswith((".tmp-", ".old-"))]

    # 2. Killed while replacing an older result: the old one keeps its old key.
    case.write_text(case.read_text().replace("length_mm = 100", "length_mm = 80"))
    tmp = _kill_mid_stage(script, case, build, marker, env)
    assert (folder / "slow" / "done.txt").read_text() == "first"
    out = subprocess.run([sys.executable, str(script), "run", str(case), "--build", str(build)],
                         env={**env, "LABEL": "second"}, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    rec = record(build, "demo")
    assert rec["executed"] == ["slow"] and rec["skipped"] == ["geometry"]
    assert (folder / "slow" / "done.txt").read_text() == "second"
    assert not tmp.exists()


def test_real_stage_killed_mid_way(tmp_path):
    """SIGKILL inside the render stage of the demo; the rerun redoes render and report."""
    build = tmp_path / "build"
    case = case_copy(tmp_path)
    proc = subprocess.Popen([sys.executable, "-m", "rotorflow.workflow.cli", "run", str(case),
                             "--build", str(build)], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    for line in proc.stdout:  # the render stage starts right after quasi1d is done
        if line.startswith("quasi1d"):
            break
    time.sleep(0.3)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    proc.stdout.close()
    folder = build / "demo"
    assert not (folder / "render").exists() and not (folder / "report").exists()
    assert (folder / "quasi1d" / ".stage.json").is_file()
    out = rotorflow("run", case, "--build", build)
    assert out.returncode == 0, out.stderr
    rec = record(build, "demo")
    assert rec["executed"] == ["render", "solids", "report"]
    assert rec["skipped"] == ["geometry", "table", "quasi1d"]
    assert (folder / "render" / "rotors.png").stat().st_size > 0


def test_solids_stage_ignores_the_operating_point(tmp_path):
    """Solids come from [export]; the discharge pressure does not rebuild them."""
    build = tmp_path / "build"
    extra = '\n[outputs]\nwant = ["solids"]\n'  # the demo case has an [export] section
    case = case_copy(tmp_path, extra=extra)
    out = rotorflow("run", case, "--build", build)
    assert out.returncode == 0, out.stderr
    rec = record(build, "demo")
    assert rec["plan"] == ["solids"] and rec["executed"] == ["solids"]
    assert (build / "demo" / "solids" / "outer.stl").stat().st_size > 0
    case.write_text(case.read_text().replace("p_discharge_bar = 2.6", "p_discharge_bar = 3.0"))
    assert rotorflow("run", case, "--build", build).returncode == 0
    assert record(build, "demo")["skipped"] == ["solids"]


def test_code_hash_follows_the_source(tmp_path, monkeypatch):
    from rotorflow.workflow.cache import code_hash

    pkg = tmp_path / "somepkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "mod.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    first = code_hash(("somepkg",))
    assert code_hash(("somepkg.mod",)) != first
    (pkg / "mod.py").write_text("X = 2\n")
    code_hash.cache_clear()
    assert code_hash(("somepkg",)) != first
