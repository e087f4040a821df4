"""The points of a sweep as case files, and the run of one point (on a worker).

Every point becomes a case file ``<build>/<sweep>/cases/<point id>.toml``: the base
case with the point's values and ``[outputs] want`` set, run under
``<build>/<sweep>/points/`` like any case, so a point reuses its cache between runs.
"""

from __future__ import annotations

import copy
import io
import json
import math
import os
import time
import uuid
from pathlib import Path
from typing import TYPE_CHECKING

from rotorflow.errors import CaseError

from . import stages as st

if TYPE_CHECKING:
    from .sweep_file import SweepSpec


def dumps_toml(data: dict) -> str:
    """TOML for case files: tables of scalars, lists of scalars, nested tables."""
    out = io.StringIO()

    def table(prefix, d):
        scalars = {k: v for k, v in d.items() if not isinstance(v, dict)}
        if prefix:
            out.write(f"\n[{prefix}]\n")
        for k, v in scalars.items():
            out.write(f"{json.dumps(k)} = {_toml_value(v)}\n")
        for k, v in d.items():
            if isinstance(v, dict):
                table(f"{prefix}.{json.dumps(k)}" if prefix else json.dumps(k), v)

    table("", data)
    return out.getvalue()


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def base_value(raw: dict, name: str):
    """The base case's value of "section.key" (None where it is not set)."""
    section, _, key = name.partition(".")
    part = raw.get(section)
    return part.get(key) if isinstance(part, dict) else None


def point_raw(spec: SweepSpec, values: dict) -> dict:
    """The case file of a point: the base case, the point's values, the sweep's stages."""
    raw = copy.deepcopy(spec.base_raw)
    for name, v in values.items():
        section, _, key = name.partition(".")
        raw.setdefault(section, {})[key] = v
    raw["outputs"] = {"want": list(spec.want)}
    return raw


def write_point(path: Path, raw: dict, note: str) -> None:
    """Write a point's case file (atomically), leaving an unchanged one untouched."""
    text = f"# {note}\n" + dumps_toml(raw)
    if path.is_file() and path.read_text() == text:
        return
    tmp = path.with_name(f".tmp-{path.name}-{uuid.uuid4().hex[:8]}")
    tmp.write_text(text)
    os.replace(tmp, path)


def figures_of(build_folder: Path, stages: list[str]) -> dict:
    """Flat scalar results of a point's stages (their ``figures`` JSON files)."""
    out = {}
    for name in stages:
        stage = st.REGISTRY.get(name)
        if stage is None or not stage.figures:
            continue
        f = Path(build_folder) / name / stage.figures
        try:
            data = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        for k, v in _flat(data).items():
            if v is None or isinstance(v, bool | int | float | str):
                out[f"{name}.{k}"] = v
    return out


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        elif not isinstance(v, list):
            out[f"{prefix}{k}"] = v
    return out


def failed(exc: BaseException) -> dict:
    """The record of a point whose run never came back (a lost worker, say)."""
    return {"status": "failed", "executed": [], "figures": {}, "seconds": None,
            "error": " ".join(f"{type(exc).__name__}: {exc}".split())}


def run_point(case_file: str, root: str) -> dict:
    """Run one point (on a worker); never raises: failures come back as a record."""
    from .runner import run_case

    t0 = time.perf_counter()
    res = {"status": "failed", "error": "", "executed": [], "figures": {}}
    try:
        rec = run_case(Path(case_file), Path(root))
        res["executed"] = rec["executed"]
        bad = [(n, e) for n, e in rec["stages"].items() if e["status"] == "failed"]
        if bad:
            res["error"] = f"stage {bad[0][0]}: {bad[0][1].get('error', '')}"
        else:
            res["status"] = "ok"
        res["figures"] = figures_of(Path(rec["build"]), rec["plan"])
    except Exception as exc:  # noqa: BLE001 - a point's failure must not stop the sweep
        res["error"] = f"{type(exc).__name__}: {exc}" if not isinstance(exc, CaseError) \
            else str(exc)
    res["error"] = " ".join(res["error"].split())
    res["seconds"] = round(time.perf_counter() - t0, 3)
    return res
