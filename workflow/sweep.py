"""`rotorflow sweep SWEEP.toml`: many cases from one base case, run in parallel on Dask.

The sweep file (:mod:`.sweep_file`) names a base case and the values to vary; every
point becomes a case file ``<build>/<sweep>/cases/pt-<hash>.toml`` (:mod:`.sweep_points`)
run under ``<build>/<sweep>/points/``.  Points whose stages are all cached are not sent
to the cluster (:mod:`.dask_cluster`).  A point that fails (a bad value, a stage error,
a lost worker) is recorded with its error and the others go on.  Results
(:mod:`.sweep_results`): ``summary.csv`` (one row per point), ``sweep.json`` and
``report/index.html``.

On a cluster the build folder must be on a file system the workers share, and the
workers need the same rotorflow installed (a stage's key includes its code's hash, so
a worker with other code recomputes rather than reuses).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

from . import stages as st
from .cache import CaseBuild, write_json_atomic
from .dask_cluster import as_completed_results, local_workers, open_client
from .sweep_file import SweepSpec, load_sweep
from .sweep_points import failed, figures_of, point_raw, run_point, write_point
from .sweep_results import point_rows, sweep_record, write_report, write_summary

log = logging.getLogger(__name__)


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
    cases_dir, points_dir = folder / "cases", folder / "points"
    cases_dir.mkdir(parents=True, exist_ok=True)
    points_dir.mkdir(parents=True, exist_ok=True)
    results, todo = _write_points(spec, cases_dir, points_dir)
    log.info("sweep %s: %d points, %d cached, %d to run", spec.name, len(spec.points),
             len(results), len(todo))
    if not todo:
        where = "nothing to run"
    elif serial:
        where = "in this process"
    else:
        where = spec.cluster.describe(local_workers(spec.cluster, len(todo)))
    _run_points(spec, todo, points_dir, serial, progress, results)
    rows = point_rows(spec, results)
    csv_path = write_summary(folder / "summary.csv", rows, spec.params)
    report = write_report(folder, spec, rows) if spec.report else None
    record = sweep_record(spec, rows, where, time.perf_counter() - t0, csv_path, report)
    write_json_atomic(folder / "sweep.json", record)
    return record


def _write_points(spec: SweepSpec, cases_dir: Path, points_dir: Path):
    """Write every point's case file; the records of the points that are cached, and
    (point id, case file) of those to run."""
    from .runner import up_to_date

    results: dict[str, dict] = {}
    todo = []
    for i, (pid, values) in enumerate(spec.points):
        case_file = cases_dir / f"{pid}.toml"
        note = f"point {i} of sweep {spec.path}: " + ", ".join(
            f"{k} = {v!r}" for k, v in values.items())
        raw = point_raw(spec, values)
        write_point(case_file, raw, note)
        try:
            cached = up_to_date(case_file, points_dir)
        except Exception:  # noqa: BLE001 - the worker reports the error properly
            cached = False
        if cached:
            results[pid] = {"status": "cached", "error": "", "executed": [], "seconds": 0.0,
                            "figures": figures_of(points_dir / pid,
                                                  st.plan(raw, spec.want, case_file))}
        else:
            todo.append((pid, case_file))
    return results, todo


def _run_points(spec: SweepSpec, todo: list, points_dir: Path, serial: bool,
                progress: bool, results: dict[str, dict]) -> None:
    """Run the points of ``todo`` here or on the cluster, adding their records to
    ``results`` as they complete."""
    close = None
    if todo and not serial:
        client, close = open_client(spec.cluster, len(todo))
    bar = _bar(len(spec.points), len(results), spec.name, progress)
    try:
        if todo and serial:
            for pid, case_file in todo:
                results[pid] = run_point(str(case_file), str(points_dir))
                _report_point(bar, pid, results[pid])
        elif todo:
            jobs = [(pid, (str(cf), str(points_dir))) for pid, cf in todo]
            for pid, res, exc in as_completed_results(client, run_point, jobs, spec.name):
                results[pid] = res if exc is None else failed(exc)
                _report_point(bar, pid, results[pid])
    finally:
        bar.close()
        if close:
            close()


def _report_point(bar, pid: str, result: dict) -> None:
    if result["status"] == "failed":
        bar.write(f"{pid}: failed: {result['error']}")
    bar.update(1)


def _bar(total, done, name, enabled):
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc=f"sweep {name}", unit="point",
                disable=not enabled, dynamic_ncols=True)
