"""`rotorflow sweep SWEEP.toml`: many cases from one base case, run in parallel on Dask.

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

Keys are ``"section.key"`` of the case file.  Every point becomes a case file
``<build>/<sweep>/cases/pt-<hash>.toml`` (named by its values, so a point keeps its
name, and its cache, when the grid around it changes) run under
``<build>/<sweep>/points/``.  Points whose stages are all cached are not sent to the
cluster.  A point that fails (a bad value, a stage error, a lost worker) is recorded
with its error and the others go on.  Results: ``summary.csv`` (one row per point),
``sweep.json`` and ``report/index.html``.

On a cluster the build folder must be on a file system the workers share, and the
workers need the same rotorflow installed (a stage's key includes its code's hash, so
a worker with other code recomputes rather than reuses).
"""

from __future__ import annotations

import copy
import csv
import io
import itertools
import json
import logging
import math
import os
import shutil
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

from rotorflow.errors import CaseError, RotorflowError

from . import stages as st
from .cache import CaseBuild, digest, write_json_atomic

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
#: Seconds to wait for a named scheduler before giving up.
SCHEDULER_TIMEOUT_S = 20
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


# ------------------------------------------------------------------ reading
def _err(path, msg) -> CaseError:
    return CaseError(f"{msg} in {path}")


def known_keys(section: str) -> set[str] | None:
    """Keys a case section accepts (None: not known here, so not checked)."""
    from . import case as c

    if section == "machine":  # the base case's family checks its own when each point loads
        from rotorflow.geometry.family import families

        return set(c.MACHINE_KEYS).union(*(f.keys for f in families().values()))
    if section == "sweep":
        return set(c.SWEEP_KEYS)
    if section in ("operating", "leakage", "ports", "numerics"):
        from rotorflow.quasi1d import settings

        keys = set(getattr(settings, section.capitalize()).KEYS)
        return keys | c.OPERATING_GEOMETRY_KEYS if section == "operating" else keys
    if section == "export":
        from rotorflow.geometry.export import settings as export_settings

        return set(export_settings.KEYS)
    return None


def _check_param(path, name: str):
    from .case import SECTIONS

    section, dot, key = name.partition(".")
    if not dot or not key or "." in key:
        raise _err(path, f"sweep key '{name}' must be \"section.key\" of the case file")
    if section not in SECTIONS or section == "outputs":
        raise _err(path, f"sweep key '{name}' names no case section")
    keys = known_keys(section)
    if keys is not None and key not in keys:
        raise _err(path, f"sweep key '{name}': unknown key '{key}' in [{section}]")


def _scalar(v) -> bool:
    return isinstance(v, str | int | float | bool)


def load_sweep(path: Path, cluster_overrides: dict | None = None) -> SweepSpec:
    """Read and check a sweep file; CaseError (one line) on anything wrong."""
    from .case import load_case, load_toml

    path = Path(path)
    if not path.is_file():
        raise CaseError(f"sweep file not found: {path}")
    data = load_toml(path)
    for name in data:
        if name not in SWEEP_SECTIONS:
            raise _err(path, f"unknown section [{name}]")
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

    has_grid, has_random = "grid" in data, "random" in data
    if has_grid and has_random:
        raise _err(path, "give [grid] or [random], not both")
    if not (has_grid or has_random or data.get("points")):
        raise _err(path, "no points: give [grid], [random] or [[points]]")
    rows: list[dict] = []
    params: list[str] = []
    if has_grid:
        grid = data["grid"]
        if not isinstance(grid, dict) or not grid:
            raise _err(path, "[grid] must list at least one \"section.key\" = [values]")
        for name, values in grid.items():
            _check_param(path, name)
            if not isinstance(values, list) or not values or not all(map(_scalar, values)):
                raise _err(path, f"grid values of '{name}' must be a non-empty list of numbers "
                                 "or strings")
        params = list(grid)
        for combo in itertools.product(*grid.values()):
            rows.append(dict(zip(params, combo, strict=True)))
    if has_random:
        params, rows = _random(path, data["random"])
    extra = data.get("points", [])
    if not isinstance(extra, list) or not all(isinstance(p, dict) for p in extra):
        raise _err(path, "[[points]] must be an array of tables")
    for p in extra:
        if not p:
            raise _err(path, "a [[points]] table is empty")
        for name, v in p.items():
            _check_param(path, name)
            if not _scalar(v):
                raise _err(path, f"value of '{name}' in [[points]] must be a number or string")
        rows.append(dict(p))
    axes = list(params) if (has_grid or has_random) else []
    for p in extra:
        for name in p:
            if name not in params:
                params.append(name)
    axes = axes or params[:2]
    points, seen = [], set()
    for row in rows:
        pid = "pt-" + digest(row)[:POINT_ID_CHARS]
        if pid in seen:
            log.warning("sweep %s: duplicate point %s skipped", path, row)
            continue
        seen.add(pid)
        points.append((pid, row))
    return SweepSpec(path=path, name=path.stem, base=base, base_raw=case.raw, want=want,
                     report=report, params=params, axes=axes, points=points,
                     cluster=_cluster(path, data.get("cluster", {}), cluster_overrides or {}))


def _random(path, spec):
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
        _check_param(path, name)
        r = spec[name]
        if isinstance(r, dict):
            choices = r.get("choices")
            if set(r) != {"choices"} or not isinstance(choices, list) or not choices \
                    or not all(map(_scalar, choices)):
                raise _err(path, f"'{name}' in [random] must be [min, max] or "
                                 "{ choices = [...] }")
            columns[name] = [choices[i] for i in rng.integers(0, len(choices), n)]
            continue
        ok = (isinstance(r, list) and len(r) == 2
              and all(isinstance(x, int | float) and not isinstance(x, bool) for x in r)
              and all(math.isfinite(x) for x in r) and r[0] < r[1])
        if not ok:
            raise _err(path, f"'{name}' in [random] must be [min, max] with min < max")
        if all(isinstance(x, int) for x in r):
            columns[name] = [int(v) for v in rng.integers(r[0], r[1] + 1, n)]
        else:
            columns[name] = [float(v) for v in rng.uniform(r[0], r[1], n)]
    rows = [{p: columns[p][i] for p in params} for i in range(n)]
    return params, rows


def _cluster(path, spec, overrides) -> ClusterSpec:
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


# ------------------------------------------------------------------ point cases
def dumps_toml(data: dict) -> str:
    """TOML for case files: tables of scalars, lists of scalars, nested tables."""

    def value(v):
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
            return "[" + ", ".join(value(x) for x in v) + "]"
        raise TypeError(f"cannot write {type(v).__name__} to TOML")

    out = io.StringIO()

    def table(prefix, d):
        scalars = {k: v for k, v in d.items() if not isinstance(v, dict)}
        if prefix:
            out.write(f"\n[{prefix}]\n")
        for k, v in scalars.items():
            out.write(f"{json.dumps(k)} = {value(v)}\n")
        for k, v in d.items():
            if isinstance(v, dict):
                table(f"{prefix}.{json.dumps(k)}" if prefix else json.dumps(k), v)

    table("", data)
    return out.getvalue()


def base_value(raw: dict, name: str):
    """The base case's value of "section.key" (None where it is not set)."""
    section, _, key = name.partition(".")
    part = raw.get(section)
    return part.get(key) if isinstance(part, dict) else None


def point_raw(spec: SweepSpec, values: dict) -> dict:
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


# ------------------------------------------------------------------ running
def local_workers(spec: ClusterSpec, n_points: int) -> int:
    return spec.workers or max(1, min(os.cpu_count() or 1, n_points))


def jobqueue_cluster(spec: ClusterSpec):
    """The dask-jobqueue cluster a sweep names (not yet scaled: no job submitted)."""
    try:
        import dask_jobqueue
    except ImportError as exc:
        raise CaseError(f"[cluster] jobqueue = '{spec.jobqueue}' needs dask-jobqueue "
                        "(pip install dask-jobqueue)") from exc
    try:
        return getattr(dask_jobqueue, JOBQUEUE[spec.jobqueue])(**spec.options)
    except (TypeError, ValueError) as exc:
        raise CaseError(f"[cluster.options] of the {spec.jobqueue} cluster: {exc}") from None


def open_client(spec: ClusterSpec, n_points: int):
    """A Dask client for the sweep, and a closer."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise RotorflowError("sweeps run on Dask: pip install 'dask[distributed]' "
                             "(or run with --serial)") from exc

    if not log.isEnabledFor(logging.INFO):  # Dask logs every worker's start and stop
        logging.getLogger("distributed").setLevel(logging.WARNING)

    if spec.address:
        try:
            client = Client(spec.address, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError) as exc:
            raise RotorflowError(f"cannot reach the Dask scheduler at {spec.address}: "
                                 f"{exc}") from None
        return client, client.close
    if spec.jobqueue:
        cluster = jobqueue_cluster(spec)
        cluster.scale(jobs=spec.jobs)
        client = Client(cluster)

        def close():
            client.close()
            cluster.close()

        return client, close
    workers = local_workers(spec, n_points)
    # Each point is single-threaded numpy: no oversubscription from BLAS threads.
    cluster = LocalCluster(n_workers=workers, threads_per_worker=spec.threads_per_worker,
                           processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR,
                           env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                                "MKL_NUM_THREADS": "1"})
    client = Client(cluster)

    def close():
        client.close()
        cluster.close()

    return client, close


def run_sweep(path: Path, root: Path = Path("build"), *, cluster: dict | None = None,
              serial: bool = False, progress: bool = True) -> dict:
    """Run every point of a sweep; return its record (also in ``sweep.json``)."""
    t0 = time.perf_counter()
    spec = load_sweep(path, cluster)
    sweep_build = CaseBuild(Path(root).resolve(), spec.name)
    with sweep_build.lock():  # one run of a sweep at a time; then clear what a kill left
        sweep_build.clean_stale()
        CaseBuild(sweep_build.folder, "cases").clean_stale()
        return _run_sweep(spec, sweep_build.folder, serial, progress, t0)


def _run_sweep(spec: SweepSpec, folder: Path, serial: bool, progress: bool, t0: float) -> dict:
    from .runner import up_to_date

    cases_dir, points_dir = folder / "cases", folder / "points"
    cases_dir.mkdir(parents=True, exist_ok=True)
    points_dir.mkdir(parents=True, exist_ok=True)
    results: dict[str, dict] = {}
    todo = []
    for i, (pid, values) in enumerate(spec.points):
        case_file = cases_dir / f"{pid}.toml"
        note = f"point {i} of sweep {spec.path}: " + ", ".join(
            f"{k} = {v!r}" for k, v in values.items())
        write_point(case_file, point_raw(spec, values), note)
        try:
            cached = up_to_date(case_file, points_dir)
        except Exception:  # noqa: BLE001 - the worker reports the error properly
            cached = False
        if cached:
            results[pid] = {"status": "cached", "error": "", "executed": [], "seconds": 0.0,
                            "figures": figures_of(points_dir / pid,
                                                  st.plan(point_raw(spec, values), spec.want,
                                                          case_file))}
        else:
            todo.append((pid, case_file))
    log.info("sweep %s: %d points, %d cached, %d to run", spec.name, len(spec.points),
             len(results), len(todo))
    if not todo:
        where = "nothing to run"
    elif serial:
        where = "in this process"
    else:
        where = spec.cluster.describe(local_workers(spec.cluster, len(todo)))
    client = close = None
    if todo and not serial:
        client, close = open_client(spec.cluster, len(todo))
    bar = _bar(len(spec.points), len(results), spec.name, progress)
    try:
        if todo and serial:
            for pid, case_file in todo:
                results[pid] = run_point(str(case_file), str(points_dir))
                _report_point(bar, pid, results[pid])
        elif todo:
            from dask.distributed import as_completed

            futures = {client.submit(run_point, str(cf), str(points_dir),
                                     key=f"{spec.name}-{pid}", pure=False): pid
                       for pid, cf in todo}
            for fut in as_completed(futures):
                pid = futures[fut]
                try:
                    results[pid] = fut.result()
                except Exception as exc:  # noqa: BLE001 - a lost worker, say
                    results[pid] = {"status": "failed", "executed": [], "figures": {},
                                    "seconds": None,
                                    "error": " ".join(f"{type(exc).__name__}: {exc}".split())}
                _report_point(bar, pid, results[pid])
    finally:
        bar.close()
        if close:
            close()
    rows = []
    for i, (pid, values) in enumerate(spec.points):
        r = results[pid]
        full = {p: values.get(p, base_value(spec.base_raw, p)) for p in spec.params}
        rows.append({"index": i, "point": pid, "status": r["status"], **full,
                     "seconds": r.get("seconds"), "executed": " ".join(r.get("executed", [])),
                     "error": r.get("error", ""), **r.get("figures", {})})
    csv_path = write_summary(folder / "summary.csv", rows, spec.params)
    report = None
    if spec.report:
        report = _write_report(folder, spec, rows)
    record = {"sweep": str(spec.path), "base": str(spec.base), "want": spec.want,
              "params": spec.params, "axes": spec.axes, "points": len(rows), "where": where,
              "ok": sum(r["status"] == "ok" for r in rows),
              "cached": sum(r["status"] == "cached" for r in rows),
              "failed": sum(r["status"] == "failed" for r in rows),
              "seconds": round(time.perf_counter() - t0, 2), "summary": str(csv_path),
              "report": str(report) if report else None,
              "failures": {r["point"]: r["error"] for r in rows if r["status"] == "failed"}}
    write_json_atomic(folder / "sweep.json", record)
    return record


def _report_point(bar, pid: str, result: dict) -> None:
    if result["status"] == "failed":
        bar.write(f"{pid}: failed: {result['error']}")
    bar.update(1)


def _bar(total, done, name, enabled):
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc=f"sweep {name}", unit="point",
                disable=not enabled, dynamic_ncols=True)


def write_summary(path: Path, rows: list[dict], params: list[str]) -> Path:
    head = ["index", "point", "status", *params, "seconds", "executed", "error"]
    figs = sorted({k for r in rows for k in r} - set(head))
    tmp = path.with_name(f".tmp-{path.name}-{uuid.uuid4().hex[:8]}")
    with open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=head + figs, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})
    os.replace(tmp, path)
    return path


def _write_report(folder: Path, spec: SweepSpec, rows: list[dict]) -> Path:
    from rotorflow.postprocess.report import sweep_report

    tmp = folder / f".tmp-report-{uuid.uuid4().hex[:8]}"
    try:
        sweep_report(tmp, spec.name, spec.params, spec.axes, rows)
        final = folder / "report"
        old = None
        if final.exists():
            old = folder / f".old-report-{uuid.uuid4().hex[:8]}"
            os.rename(final, old)
        os.rename(tmp, final)
        if old:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return folder / "report" / "index.html"
