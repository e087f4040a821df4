"""`rotorflow run`: plan the stages a case asks for, skip what is cached, run the rest.

The execution record ``<build>/<case>/run.json`` says, for every planned stage, whether
it was ``executed``, ``cached`` (skipped: its artifact has the same key), ``failed`` or
``blocked`` (an upstream stage failed); ``executed`` and ``skipped`` list the names.
It is rewritten after every stage, so a killed run leaves ``"status": "running"``.
"""

from __future__ import annotations

import importlib
import logging
import os
import shutil
import time
import traceback
from collections.abc import Callable
from pathlib import Path

from rotorflow import __version__
from rotorflow.errors import RotorflowError

from . import stages as st
from .cache import CaseBuild, StageContext, code_hash, file_hash, read_stamp, seal, stage_key

log = logging.getLogger(__name__)

DEFAULT_BUILD = Path("build")


def resolve(ref: str) -> Callable:
    module, _, func = ref.partition(":")
    return getattr(importlib.import_module(module), func)


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")


def plan_case(case_path: Path, extra: list[str] | None = None):
    """(case, want, order): the case loaded and its stages planned (CaseError on what
    loading and planning refuse; the stages' own checks are :func:`check`'s)."""
    from .case import load_case

    case = load_case(case_path)
    want = st.wanted(case.raw, case_path, extra)
    return case, want, st.plan(case.raw, want, case_path)


def fresh_stages(case, order: list[str], build: CaseBuild,
                 forced: frozenset[str] = frozenset()) -> dict[str, str]:
    """{stage: artifact hash} of the planned stages a run would skip: stamped with the key
    their inputs give now, upstream stages all fresh too, not forced."""
    fresh: dict[str, str] = {}
    for name in order:  # upstream first, so every upstream hash is known
        ups = st.upstream(name, order)
        stamp = build.stamp(name)
        if (name in forced or stamp is None or any(u not in fresh for u in ups)
                or stamp["key"] != _key(case, st.REGISTRY[name], ups, fresh)):
            continue
        fresh[name] = stamp["artifact_hash"]
    return fresh


def check(case, case_path: Path, order: list[str], build: CaseBuild,
          fresh: dict[str, str]) -> None:
    """Every planned stage's refusals (CaseError, exit 2) before any stage writes.

    A fresh stage is not checked again: its key covers its inputs and its code, so it
    passed these checks when it ran.  (Checking it rebuilt a twin screw's chamber table,
    ~5 s, on every rerun and for every point a sweep found cached.)  A check gets the
    artifact folders of its fresh upstream stages, to read rather than recompute.  (A
    stage found fresh here but stale under the run's lock, another run having changed
    the build in between, runs unchecked: its run refuses the same input, as a failed
    stage.)"""
    for name in order:
        stage = st.REGISTRY[name]
        if stage.check and name not in fresh:
            cached = {u: build.artifact(u) for u in st.upstream(name, order) if u in fresh}
            resolve(stage.check)(case, case_path, cached)


def prepare(case_path: Path, extra: list[str] | None = None, root: Path = DEFAULT_BUILD,
            force: tuple[str, ...] = ()):
    """Validate the case and plan its stages; CaseError (exit 2) on bad input.  (case,
    want, order, build, the stages forced to rerun.)"""
    case, want, order = plan_case(case_path, extra)
    build = CaseBuild(Path(root), case.name)
    forced = frozenset(order if "all" in force else force)
    check(case, case_path, order, build, fresh_stages(case, order, build, forced))
    return case, want, order, build, forced


def _key(case, stage: st.Stage, ups: list[str], hashes: dict[str, str | None]) -> str:
    """A stage's key, once the artifact hashes of its upstream stages are known: with
    the contents of the files its inputs name (a missing one is the case loader's
    refusal)."""
    inputs = st.select(case.raw, stage.reads)
    files = {str(p): file_hash(p) for p in stage.files(case.raw, case.path) if p.is_file()}
    if files:
        inputs = {**inputs, "files": files}
    return stage_key(stage.name, stage.version, inputs, {u: hashes[u] for u in ups},
                     code_hash(stage.code_modules))


def up_to_date(case_path: Path, root: Path = DEFAULT_BUILD,
               extra: list[str] | None = None) -> bool:
    """True when a run of the case would execute nothing (raises CaseError on what
    loading and planning refuse; a stage that would run is not checked here: its run
    refuses it)."""
    case, _, order = plan_case(case_path, extra)
    return len(fresh_stages(case, order, CaseBuild(Path(root), case.name))) == len(order)


def run_case(case_path: Path, root: Path = DEFAULT_BUILD, extra: list[str] | None = None,
             force: tuple[str, ...] = (), on_stage: Callable[[str, dict], None] | None = None,
             keep_going: bool = True) -> dict:
    """Run what ``case_path`` asks for under ``root``; return the execution record.

    ``force`` names stages to rerun even if cached (``"all"``: every one).  A failing
    stage blocks its downstream stages; independent ones go on (``keep_going``).
    """
    case_path = Path(case_path)
    case, want, order, build, forced = prepare(case_path, extra, root, force)
    record = {
        "case": str(case_path), "name": case.name, "rotorflow": __version__,
        "build": str(build.folder), "pid": os.getpid(), "started": _now(),
        "status": "running", "want": want, "plan": order,
        "stages": {}, "executed": [], "skipped": [], "failed": [],
    }
    with build.lock():
        build.clean_stale()
        build.write_record(record)
        hashes: dict[str, str | None] = {}
        for name in order:
            stage = st.REGISTRY[name]
            ups = st.upstream(name, order)
            entry: dict = {"upstream": ups}
            record["stages"][name] = entry
            bad = [u for u in ups if hashes.get(u) is None]
            if bad:
                entry.update(status="blocked", error=f"upstream stage {bad[0]} failed")
                hashes[name] = None
            else:
                key = entry["key"] = _key(case, stage, ups, hashes)
                stamp = build.stamp(name)
                if stamp is not None and stamp["key"] == key and name not in forced:
                    entry.update(status="cached", artifact_hash=stamp["artifact_hash"])
                    hashes[name] = stamp["artifact_hash"]
                    record["skipped"].append(name)
                else:
                    if on_stage:
                        on_stage(name, {"status": "running"})
                    hashes[name] = _execute(case, case_path, stage, key, ups, build, entry)
                    record["executed" if hashes[name] else "failed"].append(name)
            if on_stage:
                on_stage(name, entry)
            build.write_record(record)
            if hashes[name] is None and not keep_going:
                break
        record["status"] = "failed" if record["failed"] else "complete"
        record["finished"] = _now()
        build.write_record(record)
    return record


def _execute(case, case_path, stage: st.Stage, key: str, ups: list[str], build: CaseBuild,
             entry: dict) -> str | None:
    """Run one stage into a temporary folder and move it into place; the artifact hash."""
    tmp = build.new_tmp(stage.name)
    ctx = StageContext(stage=stage.name, case_path=case_path, raw=case.raw, out=tmp,
                       inputs={u: build.artifact(u) for u in ups}, _case=case)
    t0 = time.perf_counter()
    try:
        summary = resolve(stage.run)(ctx) or {}
        seconds = time.perf_counter() - t0
        seal(tmp, stage.name, key, {"seconds": round(seconds, 3), "summary": summary,
                                    "upstream": ups})
        build.commit(tmp, stage.name)
    except Exception as exc:  # noqa: BLE001 - recorded, and reported by the caller
        shutil.rmtree(tmp, ignore_errors=True)
        entry.update(status="failed", seconds=round(time.perf_counter() - t0, 3),
                     error=str(exc) if isinstance(exc, RotorflowError)
                     else f"{type(exc).__name__}: {exc}",
                     user_error=isinstance(exc, RotorflowError))
        if not isinstance(exc, RotorflowError):
            entry["traceback"] = traceback.format_exc()
        log.info("stage %s of %s failed: %s", stage.name, case.name, exc)
        return None
    stamp = read_stamp(build.artifact(stage.name))
    entry.update(status="executed", seconds=round(seconds, 3),
                 artifact_hash=stamp["artifact_hash"])
    return stamp["artifact_hash"]
