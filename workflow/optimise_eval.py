"""One design of an optimisation, evaluated in process, and the store of evaluations.

A design is the base case with the variables' values set (by the sweep's key
addressing, :func:`.sweep_points.point_raw`).  It runs only the stages its objectives
and constraints need, in process and without files: the geometry stage's figures
(:func:`rotorflow.geometry.summary.geometry_figures`), or the chamber table and the
quasi-1D cycle's summary, and nothing else (no contact table, solids, pictures, traces).

The store (``<build>/<case>/evaluations.jsonl``) keeps every stage result under the
workflow's own stage key (:func:`.cache.stage_key`: the case parts the stage reads,
its upstream's key, the stage's version, the rotorflow version and its code's hash), so
a rerun, an extended run or another optimisation over the same designs recomputes
nothing already known, and a code change recomputes everything it could change.  Each
result is one line, appended and flushed as it arrives: a run killed at any moment
loses at most the line being written (a torn last line is ignored when read).
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from types import SimpleNamespace

from rotorflow.errors import RotorflowError

from . import stages as st
from .cache import code_hash, stage_key

STORE = "evaluations.jsonl"
#: Stages each evaluable stage runs, upstream first.
PIPELINE = {"geometry": ("geometry",), "quasi1d": ("table", "quasi1d")}


def with_values(raw: dict, values: dict) -> dict:
    """The case of a design: the base case with ``{"section.key": value}`` set."""
    from .sweep_points import point_raw

    raw = point_raw(SimpleNamespace(base_raw=raw, want=[]), values)
    del raw["outputs"]
    return raw


def _key(name: str, raw: dict, upstream: dict) -> str:
    stage = st.REGISTRY[name]
    return stage_key(name, stage.version, st.select(raw, stage.reads), upstream,
                     code_hash(stage.code_modules))


def stage_keys(raw: dict, stages) -> dict[str, str]:
    """The key of each evaluated stage of a design (the quasi-1D stage's upstream is
    the chamber table's key: in process there is no artifact to hash)."""
    keys = {}
    if "geometry" in stages:
        keys["geometry"] = _key("geometry", raw, {})
    if "quasi1d" in stages:
        keys["quasi1d"] = _key("quasi1d", raw, {"table": _key("table", raw, {})})
    return keys


def _flat(prefix: str, d: dict) -> dict:
    from .sweep_points import _flat

    return {f"{prefix}.{k}": v for k, v in _flat(d).items()
            if v is None or isinstance(v, bool | int | float | str)}


def _quasi1d(case, machine, raw: dict, where: str) -> dict:
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.quasi1d import case_settings, simulate

    settings = case_settings(raw, where)
    table = chamber_table(case, machine, port_areas=settings[2].reads_areas)
    result = simulate(table, *settings)
    return _flat("quasi1d", result.summary())


def evaluate_stages(raw: dict, where: str, stages) -> dict[str, dict]:
    """``{stage: {"figures", "error", "seconds"}}`` for the stages asked (in process;
    never raises: a design that cannot be built is a result with its error)."""
    from rotorflow.geometry.summary import build_machine, geometry_figures

    from .case import case_from_raw

    out: dict[str, dict] = {}
    t0 = time.perf_counter()
    try:
        case = case_from_raw(raw, Path(where))
        machine = build_machine(case)
        for stage in stages:
            if stage == "geometry":
                figures = _flat("geometry", geometry_figures(case, machine))
            else:
                figures = _quasi1d(case, machine, raw, where)
            out[stage] = {"figures": figures, "error": "",
                          "seconds": round(time.perf_counter() - t0, 4)}
            t0 = time.perf_counter()
    except Exception as exc:  # noqa: BLE001 - an infeasible design is a result
        msg = str(exc) if isinstance(exc, RotorflowError) else f"{type(exc).__name__}: {exc}"
        for stage in stages:
            out.setdefault(stage, {"figures": {}, "error": " ".join(msg.split()),
                                   "seconds": round(time.perf_counter() - t0, 4)})
    return out


def evaluate(raw: dict, where: str, stages) -> dict:
    """All figures of a design's stages, and the first error (empty: none)."""
    res = evaluate_stages(raw, where, stages)
    figures = {k: v for r in res.values() for k, v in r["figures"].items()}
    errors = [r["error"] for r in res.values() if r["error"]]
    return {"figures": figures, "error": errors[0] if errors else ""}


class EvaluationStore:
    """Stage results by key, read from and appended to one JSON-lines file."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.records: dict[str, dict] = {}
        if self.path.is_file():
            text = self.path.read_text()
            if text and not text.endswith("\n"):  # a killed run's torn last line:
                with open(self.path, "r+") as fh:  # cut it, so the next line starts clean
                    fh.truncate(len(text[: text.rfind("\n") + 1].encode()))
            for line in text.splitlines():
                try:
                    rec = json.loads(line)
                    self.records[rec["key"]] = rec
                except (ValueError, KeyError, TypeError):
                    continue  # the torn last line of a killed run

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def get(self, key: str) -> dict:
        return self.records[key]

    def put(self, key: str, stage: str, record: dict) -> None:
        rec = {"key": key, "stage": stage, **record}
        self.records[key] = rec
        with open(self.path, "a") as fh:
            fh.write(json.dumps(rec) + "\n")
            fh.flush()
            os.fsync(fh.fileno())
