"""The `rotorflow` command.

Every user error (a bad case file, an impossible geometry) ends with one line on
stderr and exit status 2, and nothing written.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

from rotorflow import __version__
from rotorflow.errors import CaseError, RotorflowError, RunFailure


def cmd_geometry(args) -> int:
    from rotorflow.geometry.summary import geometry_figures
    from rotorflow.workflow.builtin import finite
    from rotorflow.workflow.case import load_case

    figures = geometry_figures(load_case(args.case))
    if args.json:
        print(json.dumps(finite(figures), indent=2))
    else:
        width = max(len(k) for k in figures)
        for key, value in figures.items():
            shown = f"{value:.6g}" if isinstance(value, float) else value
            print(f"{key:<{width}}  {shown}")
    return 0


def cmd_table(args) -> int:
    from rotorflow.geometry import table
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.workflow.case import load_case

    case = load_case(args.case)
    tab = chamber_table(case)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    # Write beside the target and rename, so a killed run leaves no half table.
    tmp = Path(tempfile.mkdtemp(prefix=".table-", dir=out.parent))
    try:
        table.write(tab, tmp / out.name)
        for suffix in (".json", ".csv"):
            os.replace(tmp / out.with_suffix(suffix).name, out.with_suffix(suffix))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(out)
    return 0


def cmd_contacts(args) -> int:
    from rotorflow.geometry.contacts import write_csv
    from rotorflow.workflow.case import load_case

    if not args.step_deg > 0.0:
        raise CaseError(f"--step-deg must be positive, got {args.step_deg}")
    case = load_case(args.case)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    print(write_csv(case.pair.contact_table(args.step_deg), out))
    return 0


def cmd_simulate(args) -> int:
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.quasi1d import case_settings, simulate
    from rotorflow.workflow.builtin import finite
    from rotorflow.workflow.case import load_case

    case = load_case(args.case)
    raw, where = case.raw, str(args.case)
    if "p_suction_bar" not in raw.get("operating", {}):
        raise CaseError(f"[operating] of {where} needs p_suction_bar (and the rest of the "
                        "operating point) to simulate")
    settings = case_settings(raw, where)  # (refused before the geometry's time is spent)
    result = simulate(chamber_table(case, port_areas=settings[2].reads_areas), *settings)
    if args.traces:
        out = Path(args.traces)
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=".traces-", dir=out.parent))
        try:
            result.write_traces(tmp)
            result.plot(tmp)
            if out.exists():
                shutil.rmtree(out)
            os.replace(tmp, out)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    figures = result.summary()
    if args.json:
        print(json.dumps(finite(figures), indent=2))
    else:
        for key, value in figures.items():
            print(f"{key:<32} {value:.6g}" if isinstance(value, float) else f"{key:<32} {value}")
    if figures.get("warning"):
        print(f"rotorflow: warning: {figures['warning']}", file=sys.stderr)
    if not figures.get("converged", True):
        # (figures of a cycle that did not settle are no result: as `map` counts them)
        print(f"rotorflow: the cycle did not converge: {figures.get('message', '')}",
              file=sys.stderr)
        return 1
    return 0


def _log_setup(verbose: bool) -> None:
    import logging

    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING,
                        format="rotorflow: %(levelname)s: %(message)s")


def cmd_run(args) -> int:
    from rotorflow.workflow.runner import run_case

    _log_setup(args.verbose)
    width = 10

    def show(name, entry):
        if args.json or entry["status"] == "running":
            return
        secs = f"  {entry['seconds']:.2f} s" if "seconds" in entry else ""
        print(f"{name:<{width}} {entry['status']}{secs}", flush=True)

    force = tuple(args.force or ())
    record = run_case(args.case, args.build, extra=args.want, force=force, on_stage=show)
    if args.json:
        print(json.dumps(record, indent=2))
    failed = [(n, e) for n, e in record["stages"].items() if e["status"] == "failed"]
    for name, entry in failed:
        print(f"rotorflow: error: stage {name} failed: {entry['error']}", file=sys.stderr)
    if failed:
        return 2 if all(e.get("user_error") for _, e in failed) else 1
    report = Path(record["build"]) / "report" / "index.html"
    if "report" in record["plan"] and not args.json:
        print(f"report: {report}")
    return 0


def _cluster(args) -> dict:
    """The Dask cluster the command line asks for (see _cluster_args)."""
    return {"address": args.scheduler, "jobqueue": args.jobqueue, "workers": args.workers,
            "jobs": args.jobs}


def cmd_sweep(args) -> int:
    from rotorflow.workflow.sweep import run_sweep

    _log_setup(args.verbose)
    cluster = _cluster(args)
    record = run_sweep(args.sweep, args.build, cluster=cluster, serial=args.serial,
                       progress=not args.no_progress)
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(f"sweep {Path(args.sweep).stem}: {record['points']} points, {record['ok']} run, "
              f"{record['cached']} cached, {record['failed']} failed, {record['seconds']:.1f} s "
              f"({record['where']})")
        print(f"summary: {record['summary']}")
        if record["report"]:
            print(f"report: {record['report']}")
    return 0


def cmd_optimise(args) -> int:
    from rotorflow.workflow.optimise import run_optimise

    _log_setup(args.verbose)
    cluster = _cluster(args)
    record = run_optimise(args.case, args.build, cluster=cluster, serial=args.serial,
                          progress=not args.no_progress)
    if args.json:
        print(json.dumps({k: v for k, v in record.items() if k != "pareto_set"}, indent=2))
    else:
        print(f"optimise {Path(args.case).stem}: {record['generations']} generations, "
              f"{record['evaluations']} designs, {record['computed']} computed, "
              f"{record['cached']} cached, {record['failed']} failed, "
              f"{record['seconds']:.1f} s ({record['where']})")
        print(f"Pareto set: {record['pareto_size']} designs, hypervolume "
              f"{record['hypervolume']:.6g}: {record['pareto']}")
        print(f"report: {record['report']}")
    return 0


def cmd_map(args) -> int:
    from rotorflow.workflow.perf_map_run import run_map

    _log_setup(args.verbose)
    record = run_map(args.case, args.build / "map" / Path(args.case).stem,
                     cluster=_cluster(args), serial=args.serial, progress=not args.no_progress)
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(f"map {Path(args.case).stem}: {record['points']} points, {record['converged']} "
              f"converged, {record['seconds']:.1f} s ({record['where']})")
        for line in record["failed"]:
            print(f"  not converged: {line}")
        print(f"csv: {record['csv']}\nreport: {record['report']}")
    return 0 if not record["failed"] else 1


def cmd_export(args) -> int:
    from rotorflow.geometry.export.driver import export
    from rotorflow.geometry.export.settings import Export
    from rotorflow.workflow.case import load_case

    case = load_case(args.case)
    # Without an [export] section: the two rotor STLs at the default tolerance.
    settings = Export.from_section(case.raw.get("export", {"formats": ["stl"]}), str(args.case))
    out = Path(args.out)
    if out.exists() and (not out.is_dir() or (any(out.iterdir())
                                              and not (out / "export.json").is_file())):
        raise CaseError(f"{out} exists and is not a rotorflow export folder: not replacing it")
    # Build in a temporary folder beside the target and rename it when complete; on
    # failure remove it and any parent folder made for it, so nothing is left behind.
    made = [p for p in reversed(out.absolute().parents) if not p.exists()]
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".export-", dir=out.parent))
    try:
        export(case, settings, tmp)
        if out.exists():
            shutil.rmtree(out)
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        for p in reversed(made):
            with contextlib.suppress(OSError):
                p.rmdir()
        raise
    print(out)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rotorflow", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"rotorflow {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    g = sub.add_parser("geometry", help="profile, chamber and power-split figures of a case")
    g.add_argument("case", type=Path)
    g.add_argument("--json", action="store_true", help="one JSON object on stdout")
    g.set_defaults(func=cmd_geometry)
    t = sub.add_parser("table", help="write the chamber table (CSV + JSON side-car)")
    t.add_argument("case", type=Path)
    t.add_argument("--out", type=Path, required=True, help="path of the CSV to write")
    t.set_defaults(func=cmd_table)
    c = sub.add_parser("contacts", help="write every contact point against outer-rotor angle "
                       "(CSV, one lobe period)")
    c.add_argument("case", type=Path)
    c.add_argument("--out", type=Path, required=True, help="path of the CSV to write")
    c.add_argument("--step-deg", type=float, default=1.0, help="angle step (default 1)")
    c.set_defaults(func=cmd_contacts)
    q = sub.add_parser("simulate", help="quasi-1D model of the case's operating point")
    q.add_argument("case", type=Path)
    q.add_argument("--json", action="store_true", help="one JSON object on stdout")
    q.add_argument("--traces", type=Path, help="folder for p, T, m traces (CSV) and plots")
    q.set_defaults(func=cmd_simulate)
    x = sub.add_parser("export", help="rotor solids and machining files ([export] section)")
    x.add_argument("case", type=Path)
    x.add_argument("--out", type=Path, required=True, help="folder to write (replaced whole)")
    x.set_defaults(func=cmd_export)
    r = sub.add_parser("run", help="every stage the case asks for ([outputs]), skipping "
                       "what is cached")
    r.add_argument("case", type=Path)
    r.add_argument("--build", type=Path, default=Path("build"),
                   help="build folder (default: build); artifacts go to BUILD/<case>/<stage>/")
    r.add_argument("--want", action="append", metavar="STAGE",
                   help="also run this stage (repeatable), e.g. --want report")
    r.add_argument("--force", action="append", metavar="STAGE",
                   help="rerun this stage even if cached (repeatable; 'all' for every one)")
    r.add_argument("--json", action="store_true", help="print the execution record as JSON")
    r.add_argument("-v", "--verbose", action="store_true", help="log progress")
    r.set_defaults(func=cmd_run)
    w = sub.add_parser("sweep", help="run the points of a sweep file on Dask; summary CSV "
                       "and report")
    w.add_argument("sweep", type=Path)
    _cluster_args(w, "BUILD/<sweep>/", "run the points one after another in this process "
                  "(no Dask)")
    w.add_argument("--json", action="store_true", help="print the sweep record as JSON")
    w.set_defaults(func=cmd_sweep)
    o = sub.add_parser("optimise", help="multi-objective search of a case's [optimise] "
                       "section (NSGA-II) on Dask; Pareto set, points, front, report")
    o.add_argument("case", type=Path)
    _cluster_args(o, "BUILD/<case>/optimise/ (the store of evaluations beside it)",
                  "evaluate one design after another in this process (no Dask)")
    o.add_argument("--json", action="store_true", help="print the run's record as JSON")
    o.set_defaults(func=cmd_optimise)
    m = sub.add_parser("map", help="performance map over speed and discharge (or suction) "
                       "pressure ([map] section): CSV, contour plots, report page")
    m.add_argument("case", type=Path)
    m.add_argument("--json", action="store_true", help="the run's record as JSON")
    _cluster_args(m, "BUILD/map/<case>/", "compute the points in this process, no Dask")
    m.set_defaults(func=cmd_map)
    return parser


def _cluster_args(p: argparse.ArgumentParser, where: str, serial: str) -> None:
    """The options of a command that runs on Dask (sweep, optimise)."""
    p.add_argument("--build", type=Path, default=Path("build"),
                   help=f"build folder (default: build); results go to {where}")
    p.add_argument("--scheduler", metavar="ADDRESS", help="address of a running Dask scheduler")
    p.add_argument("--jobqueue", metavar="KIND",
                   help="a dask-jobqueue cluster: slurm, pbs, sge, lsf, htcondor, moab, oar")
    p.add_argument("--jobs", type=int, help="jobqueue jobs to start")
    p.add_argument("--workers", type=int, help="worker processes of the local cluster")
    p.add_argument("--serial", action="store_true", help=serial)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-v", "--verbose", action="store_true", help="log progress")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except CaseError as exc:
        # Bad input is one line, even where a library's message (CoolProp's) spans lines.
        print(f"rotorflow: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    except RunFailure as exc:  # accepted input that failed to run: its log tail, as it came
        print(f"rotorflow: error: {exc}", file=sys.stderr)
        return 1
    except RotorflowError as exc:
        print(f"rotorflow: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
