"""A seeded fuzzing run of the command line: mutated versions of shipped case files
through every command.  Whatever the input, a command either refuses it (exit status
2, one line on stderr, nothing written) or gives figures inside physical bounds, never
a traceback, and never runs past its time budget.

The mutations are the slips a user makes: a unit slip of 1e3 or 1e5, a sign, a zero, a
number too large for a float, a string or a list where a number belongs, a key or a
section removed, an unknown key, and small nudges that must be accepted.  The commands
run in this process (the command line's own ``main``), so that hundreds of them fit in
a few minutes; the full pipeline (``run``) only on the quicker share.
"""

from __future__ import annotations

import json
import math
import random
import signal
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from rotorflow.workflow.sweep_points import dumps_toml

from .conftest import CASES, run_cli

#: Wall-clock budget of one command [s]: a full `run` of the default case (render,
#: solids, report) takes about 10 s here, and the cycle solver stops at the
#: [numerics] max_seconds the bases are given (SOLVER_S).
BUDGET_S = 60
SOLVER_S = 10
BASES = ("default.toml", "crc60.toml")
#: Commands each base goes through in the quick run: the conical CRC.60's cycle (real
#: air, 12 chambers) takes 10-15 s a point, the default's about 1 s.
QUICK = {"default.toml": ("geometry", "table", "simulate", "export", "run"),
         "crc60.toml": ("geometry", "table", "export")}
MUTATIONS = 300
#: Commands and their weights: most mutations go through the cheap commands.
COMMANDS = (("geometry", 4), ("table", 2), ("simulate", 4), ("export", 1), ("run", 1))


def _leaves(raw: dict, prefix=()):
    for k, v in raw.items():
        if isinstance(v, dict):
            yield from _leaves(v, (*prefix, k))
        else:
            yield (*prefix, k), v


def _set(raw: dict, path: tuple, value) -> None:
    for k in path[:-1]:
        raw = raw[k]
    raw[path[-1]] = value


def _drop(raw: dict, path: tuple) -> None:
    for k in path[:-1]:
        raw = raw[k]
    del raw[path[-1]]


def mutate(rng: random.Random, raw: dict) -> tuple[dict, str]:
    """One mutation of ``raw`` (a deep copy) and its description."""
    raw = json.loads(json.dumps(raw))
    leaves = [(p, v) for p, v in _leaves(raw) if p[0] not in ("optimise",)]
    path, value = rng.choice(leaves)
    kind = rng.choice(["x1e3", "x1e-3", "x1e5", "neg", "zero", "int400", "f300", "string",
                       "list", "bool", "drop_key", "drop_section", "unknown", "nudge",
                       "nudge", "nudge"])
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if kind.startswith("x") and number:
        _set(raw, path, value * float(kind[1:]))
    elif kind == "neg" and number:
        _set(raw, path, -value)
    elif kind == "zero" and number:
        _set(raw, path, 0)
    elif kind == "int400":
        _set(raw, path, 10**400)
    elif kind == "f300":
        _set(raw, path, 1e300)
    elif kind == "string":
        _set(raw, path, "abc")
    elif kind == "list":
        _set(raw, path, [value, value])
    elif kind == "bool":
        _set(raw, path, True)
    elif kind == "drop_key":
        _drop(raw, path)
    elif kind == "drop_section":
        del raw[path[0]]
    elif kind == "unknown":
        _set(raw, (*path[:-1], "colour"), "red")
    elif number:  # a nudge by up to 5 %: most must be accepted
        nudged = value * rng.uniform(0.95, 1.05)
        _set(raw, path, round(nudged) if isinstance(value, int) else nudged)
    else:
        kind = "none"
    return raw, f"{kind} {'.'.join(map(str, path))}"


class Budget(Exception):
    pass


def _alarm(signum, frame):
    raise Budget(f"past its {BUDGET_S} s budget")


def invoke(argv: list[str]) -> tuple[int, str, str]:
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(BUDGET_S)
    try:
        out = run_cli(*argv)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return out.returncode, out.stdout, out.stderr


def _finite(x) -> bool:
    return x is None or isinstance(x, str | bool) or (isinstance(x, int | float)
                                                     and math.isfinite(x))


def check_accepted(command: str, stdout: str, work: Path, raw: dict) -> None:
    """Bounds an accepted run's figures must lie in, whatever the input."""
    if command == "geometry":
        fig = json.loads(stdout)
        assert all(_finite(v) for v in fig.values() if not isinstance(v, dict | list))
        assert 0.0 < fig["V_sw_bar"] <= 1.0 and fig["swept_volume_m3"] > 0.0
        assert 0.0 <= fig["Pi_max"] < 10.0
    elif command == "table":
        data = np.genfromtxt(work / "out" / "t.csv", delimiter=",", names=True)
        assert np.all(np.isfinite(data.view(float))) and data["volume_m3"].min() >= 0.0
    elif command == "simulate":
        fig = json.loads(stdout)
        t_suction = raw["operating"].get("T_suction_K", 293.15)
        if not fig["converged"]:
            assert fig.get("message")  # flagged, not passed off as a result
            return
        assert fig["mass_balance_error"] < 1e-4
        assert fig["indicated_power_W"] > 0.0
        assert -0.05 <= fig["volumetric_efficiency"] <= 1.05
        if fig["discharge_temperature_K"] is None:  # (beyond its chambers: flagged)
            assert "is not reported" in fig["warning"]
            return
        assert 0.5 * t_suction < fig["discharge_temperature_K"] < 3000.0
    elif command == "export":
        manifest = json.loads((work / "out" / "export.json").read_text())
        for name in manifest["files"]:
            assert (work / "out" / name).stat().st_size > 0


def _argv(command: str, case: Path, work: Path) -> list[str]:
    return {"geometry": ["geometry", str(case), "--json"],
            "table": ["table", str(case), "--out", str(work / "out" / "t.csv")],
            "simulate": ["simulate", str(case), "--json"],
            "export": ["export", str(case), "--out", str(work / "out")],
            "run": ["run", str(case), "--build", str(work / "build"), "--json"]}[command]


def fuzz(seed: int, count: int, tmp_path: Path, only: dict | None = None) -> dict:
    rng = random.Random(seed)
    bases = {b: tomllib.loads((CASES / b).read_text()) for b in BASES}
    for raw in bases.values():  # a stated budget, as a user bounding a run would set
        raw.setdefault("numerics", {})["max_seconds"] = SOLVER_S
    tally = {"refused": 0, "accepted": 0, "seconds": {}}
    for i in range(count):
        base = rng.choice(BASES)
        raw, what = mutate(rng, bases[base])
        allowed = [(c, w) for c, w in COMMANDS if only is None or c in only[base]]
        command = rng.choices(*zip(*allowed, strict=True))[0]
        work = tmp_path / f"m{i}"
        work.mkdir()
        case = work / "case.toml"
        case.write_text(dumps_toml(raw))
        label = f"mutation {i} ({base}: {what}) through {command}"
        t0 = time.perf_counter()
        try:
            code, stdout, stderr = invoke(_argv(command, case, work))
        except Budget as exc:
            pytest.fail(f"{label}: {exc}")
        except Exception as exc:  # noqa: BLE001 - the defect this test looks for
            pytest.fail(f"{label}: traceback {type(exc).__name__}: {exc}")
        if code == 2:
            lines = stderr.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith("rotorflow: error: "), \
                f"{label}: {stderr!r}"
            assert sorted(p.name for p in work.iterdir()) == ["case.toml"], \
                f"{label}: a refusal wrote {sorted(p.name for p in work.iterdir())}"
            tally["refused"] += 1
        else:
            assert code == 0, f"{label}: exit {code}: {stderr[-500:]}"
            try:
                check_accepted(command, stdout, work, raw)
            except AssertionError as exc:
                pytest.fail(f"{label}: accepted, but implausible: {exc}")
            tally["accepted"] += 1
        tally["seconds"][label] = time.perf_counter() - t0
    return tally


def test_fuzzing_the_command_line(tmp_path):
    tally = fuzz(seed=2026, count=MUTATIONS, tmp_path=tmp_path, only=QUICK)
    # Both outcomes are exercised: the nudges are accepted, the slips refused.
    assert tally["refused"] > MUTATIONS // 3 and tally["accepted"] > MUTATIONS // 10, tally


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_fuzzing_the_command_line_more_seeds(tmp_path, seed):
    fuzz(seed=seed, count=MUTATIONS, tmp_path=tmp_path)
