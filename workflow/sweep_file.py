"""The sweep file: its schema, and the points it expands to.

A sweep file::

    [study]
    base = "default.toml"        # the base case, relative to this file
    want = ["quasi1d"]           # stages of every point (default: the base case's
                                 # [outputs], else its default stages without pictures)
    report = true                # the sweep's HTML report (default true)

    [grid]                       # every combination of the listed values, or
    "machine.lambda" = [1.2, 1.3, 1.4]
    "sweep.wrap_outer_deg" = [90, 120, 150]

    [random]                     # seeded random samples
    samples = 50
    seed = 1
    "machine.lambda" = [1.2, 1.8]              # uniform in [1.2, 1.8] (ints: integers)
    "machine.lobes_outer" = { choices = [4, 5, 6] }

    [[points]]                   # single points, added to the grid or samples
    "machine.lambda" = 0.95

    [cluster]                    # where the points run (default: a local Dask cluster)
    workers = 2                  # local worker processes (default: the cores)
    address = "tcp://host:8786"  # an existing Dask scheduler, or
    jobqueue = "slurm"           # a batch-system cluster through dask-jobqueue
    jobs = 4                     # (slurm, pbs, sge, lsf, htcondor, moab, oar)
    [cluster.options]            # keyword arguments of the dask-jobqueue cluster
    cores = 8
    memory = "16GB"

Keys are ``"section.key"`` of the case file, checked against the keys the section
accepts (for [machine]: those of the base case's machine family).  A point is named
``pt-<hash>`` by its values, so it keeps its name, and its cache, when the grid around
it changes.  Everything wrong in the file is a CaseError of one line.
"""

from __future__ import annotations

import itertools
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

from rotorflow.errors import CaseError

from . import stages as st
from .cache import digest

log = logging.getLogger(__name__)

SWEEP_SECTIONS = ("study", "grid", "random", "points", "cluster")
STUDY_KEYS = ("base", "want", "report")
CLUSTER_KEYS = ("workers", "threads_per_worker", "address", "jobqueue", "jobs", "options")
JOBQUEUE = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster",
            "lsf": "LSFCluster", "htcondor": "HTCondorCluster", "moab": "MoabCluster",
            "oar": "OARCluster"}
#: Stages a sweep point runs by default are the base case's defaults without these
#: (pictures of every point are rarely wanted and cost seconds each).
SWEEP_SKIPS = ("render", "solids", "report")
#: Characters of the value hash naming a point (1e-12 collision odds at 1e3 points).
POINT_ID_CHARS = 10


@dataclass(frozen=True)
class ClusterSpec:
    workers: int | None = None
    threads_per_worker: int = 1
    address: str | None = None
    jobqueue: str | None = None
    jobs: int = 1
    options: dict = field(default_factory=dict)

    def describe(self, local_workers: int | None = None) -> str:
        if self.address:
            return f"Dask scheduler at {self.address}"
        if self.jobqueue:
            return f"dask-jobqueue {self.jobqueue} cluster, {self.jobs} job(s)"
        return f"local Dask cluster, {local_workers or self.workers} worker process(es)"


@dataclass(frozen=True)
class SweepSpec:
    path: Path
    name: str
    base: Path
    base_raw: dict
    want: list[str]
    report: bool
    params: list[str]  # every key a point sets (columns of the summary)
    axes: list[str]  # the keys of [grid] or [random] (the axes of the report's plots)
    points: list[tuple[str, dict]]  # (point id, {"section.key": value})
    cluster: ClusterSpec


def _err(path, msg) -> CaseError:
    return CaseError(f"{msg} in {path}")


def known_keys(section: str, machine_type: str | None = None) -> set[str] | None:
    """Keys a case section accepts (None: not known here, so not checked);
    [machine] keys depend on the family of ``machine_type``."""
    from . import case as c

    if section == "machine":
        from rotorflow.geometry.family import families

        family = families().get(machine_type)
        return None if family is None else set(c.MACHINE_KEYS) | set(family.keys)
    if section == "sweep":
        return set(c.SWEEP_KEYS)
    if section in ("operating", "leakage", "ports", "numerics"):
        from rotorflow.quasi1d import settings

        keys = set(getattr(settings, section.capitalize()).KEYS)
        return keys | c.OPERATING_GEOMETRY_KEYS if section == "operating" else keys
    if section == "export":
        from rotorflow.geometry.export.settings import KEYS

        return set(KEYS)
    return None


def _check_param(path, name: str, base_raw: dict):
    from .case import SECTIONS

    section, dot, key = name.partition(".")
    if not dot or not key or "." in key:
        raise _err(path, f"sweep key '{name}' must be \"section.key\" of the case file")
    if section not in SECTIONS or section == "outputs":
        raise _err(path, f"sweep key '{name}' names no case section")
    keys = known_keys(section, base_raw["machine"].get("type"))
    if section == "sweep" and keys is not None and key not in keys:
        keys = keys | _rotor_wrap_keys(path, base_raw)
    if keys is not None and key not in keys:
        raise _err(path, f"sweep key '{name}': unknown key '{key}' in [{section}]")


def _rotor_wrap_keys(path, base_raw: dict) -> set[str]:
    """The wrap keys the case loader takes by rotor name (wrap_male_deg, ...): they need
    the base case's pair, built only when a [sweep] key is not one of every family's."""
    from .case import _machine, _wrap_keys

    return set(_wrap_keys(_machine(base_raw, Path(path))[0]))


def _scalar(v) -> bool:
    return isinstance(v, str | int | float | bool)


def load_sweep(path: Path, cluster_overrides: dict | None = None) -> SweepSpec:
    """Read and check a sweep file; CaseError (one line) on anything wrong."""
    from .case import load_toml

    path = Path(path)
    if not path.is_file():
        raise CaseError(f"sweep file not found: {path}")
    data = load_toml(path)
    for name in data:
        if name not in SWEEP_SECTIONS:
            raise _err(path, f"unknown section [{name}]")
    base, base_raw, want, report = _study(path, data)
    params, axes, rows = _rows(path, data, base_raw)
    return SweepSpec(path=path, name=path.stem, base=base, base_raw=base_raw, want=want,
                     report=report, params=params, axes=axes, points=_named(path, rows),
                     cluster=cluster_spec(path, data.get("cluster", {}), cluster_overrides or {}))


def _study(path: Path, data: dict) -> tuple[Path, dict, list[str], bool]:
    """[study]: the base case (path and contents), the stages of a point, the report."""
    from .case import load_case

    study = data.get("study")
    if not isinstance(study, dict):
        raise _err(path, "missing section [study]")
    for k in study:
        if k not in STUDY_KEYS:
            raise _err(path, f"unknown key '{k}' in [study]")
    if not isinstance(study.get("base"), str):
        raise _err(path, "missing key 'base' (the base case file) in [study]")
    base = (path.parent / study["base"]).resolve()
    try:
        case = load_case(base)
    except CaseError as exc:
        raise CaseError(f"base case of {path}: {exc}") from None
    report = study.get("report", True)
    if not isinstance(report, bool):
        raise _err(path, "'report' in [study] must be true or false")
    if "want" in study:
        want = study["want"]
        if not isinstance(want, list) or not all(isinstance(w, str) for w in want):
            raise _err(path, "'want' in [study] must be a list of stage names")
        for w in want:
            if w not in st.REGISTRY:
                raise _err(path, f"unknown stage '{w}' in [study] want "
                                 f"(one of: {', '.join(st.REGISTRY)})")
    elif "outputs" in case.raw:
        want = list(case.raw["outputs"]["want"])
    else:
        want = [w for w in st.default_outputs(case.raw) if w not in SWEEP_SKIPS]
    return base, case.raw, want, report


def _rows(path: Path, data: dict, base_raw: dict) -> tuple[list[str], list[str], list[dict]]:
    """The values of every point (grid or samples, then [[points]]), every key a point
    sets, and the axes of the report's plots."""
    has_grid, has_random = "grid" in data, "random" in data
    if has_grid and has_random:
        raise _err(path, "give [grid] or [random], not both")
    if not (has_grid or has_random or data.get("points")):
        raise _err(path, "no points: give [grid], [random] or [[points]]")
    rows: list[dict] = []
    params: list[str] = []
    if has_grid:
        params, rows = _grid(path, data["grid"], base_raw)
    if has_random:
        params, rows = _random(path, data["random"], base_raw)
    extra = data.get("points", [])
    if not isinstance(extra, list) or not all(isinstance(p, dict) for p in extra):
        raise _err(path, "[[points]] must be an array of tables")
    for p in extra:
        if not p:
            raise _err(path, "a [[points]] table is empty")
        for name, v in p.items():
            _check_param(path, name, base_raw)
            if not _scalar(v):
                raise _err(path, f"value of '{name}' in [[points]] must be a number or string")
        rows.append(dict(p))
    axes = list(params) if (has_grid or has_random) else []
    for p in extra:
        for name in p:
            if name not in params:
                params.append(name)
    return params, axes or params[:2], rows


def _grid(path, grid, base_raw) -> tuple[list[str], list[dict]]:
    if not isinstance(grid, dict) or not grid:
        raise _err(path, "[grid] must list at least one \"section.key\" = [values]")
    for name, values in grid.items():
        _check_param(path, name, base_raw)
        if not isinstance(values, list) or not values or not all(map(_scalar, values)):
            raise _err(path, f"grid values of '{name}' must be a non-empty list of numbers "
                             "or strings")
    params = list(grid)
    return params, [dict(zip(params, combo, strict=True))
                    for combo in itertools.product(*grid.values())]


def _named(path, rows: list[dict]) -> list[tuple[str, dict]]:
    """(point id, values) of every distinct row; the id is a hash of the values."""
    points, seen = [], set()
    for row in rows:
        pid = "pt-" + digest(row)[:POINT_ID_CHARS]
        if pid in seen:
            log.warning("sweep %s: duplicate point %s skipped", path, row)
            continue
        seen.add(pid)
        points.append((pid, row))
    return points


def _random(path, spec, base_raw) -> tuple[list[str], list[dict]]:
    import numpy as np

    if not isinstance(spec, dict):
        raise _err(path, "[random] must be a table")
    n = spec.get("samples")
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise _err(path, "'samples' in [random] must be a positive integer")
    seed = spec.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _err(path, "'seed' in [random] must be a non-negative integer")
    rng = np.random.default_rng(seed)
    params = [k for k in spec if k not in ("samples", "seed")]
    if not params:
        raise _err(path, "[random] must give at least one \"section.key\" range")
    columns = {}
    for name in params:
        _check_param(path, name, base_raw)
        columns[name] = _samples(path, name, spec[name], rng, n)
    rows = [{p: columns[p][i] for p in params} for i in range(n)]
    return params, rows


def _samples(path, name: str, r, rng, n: int) -> list:
    """``n`` values of one [random] key: from { choices = [...] }, or in [min, max]
    (integers when both bounds are)."""
    if isinstance(r, dict):
        choices = r.get("choices")
        if set(r) != {"choices"} or not isinstance(choices, list) or not choices \
                or not all(map(_scalar, choices)):
            raise _err(path, f"'{name}' in [random] must be [min, max] or "
                             "{ choices = [...] }")
        return [choices[i] for i in rng.integers(0, len(choices), n)]
    ok = (isinstance(r, list) and len(r) == 2
          and all(isinstance(x, int | float) and not isinstance(x, bool) for x in r)
          and all(abs(x) < 1e300 and math.isfinite(x) for x in r) and r[0] < r[1])
    if not ok:
        raise _err(path, f"'{name}' in [random] must be [min, max] with min < max")
    if all(isinstance(x, int) for x in r):
        return [int(v) for v in rng.integers(r[0], r[1] + 1, n)]
    return [float(v) for v in rng.uniform(r[0], r[1], n)]


def cluster_spec(path, spec, overrides) -> ClusterSpec:
    """The cluster of a [cluster] table with command-line ``overrides`` (None: unset)."""
    if not isinstance(spec, dict):
        raise _err(path, "[cluster] must be a table")
    for k in spec:
        if k not in CLUSTER_KEYS:
            raise _err(path, f"unknown key '{k}' in [cluster]")
    merged = {**spec, **{k: v for k, v in overrides.items() if v is not None}}
    if merged.get("address") and merged.get("jobqueue"):
        raise _err(path, "give a scheduler address or a jobqueue cluster, not both")
    for k in ("workers", "threads_per_worker", "jobs"):
        v = merged.get(k)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
            raise _err(path, f"'{k}' in [cluster] must be a positive integer")
    jq = merged.get("jobqueue")
    if jq is not None and jq not in JOBQUEUE:
        raise _err(path, f"unknown jobqueue '{jq}' in [cluster] (one of: {', '.join(JOBQUEUE)})")
    options = merged.get("options", {})
    if not isinstance(options, dict):
        raise _err(path, "[cluster.options] must be a table")
    addr = merged.get("address")
    if addr is not None and not isinstance(addr, str):
        raise _err(path, "'address' in [cluster] must be a string")
    return ClusterSpec(workers=merged.get("workers"),
                       threads_per_worker=merged.get("threads_per_worker", 1),
                       address=addr, jobqueue=jq, jobs=merged.get("jobs", 1), options=options)
