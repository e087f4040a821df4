"""The `rotorflow` command.

Every user error (a bad case file, an impossible geometry) ends with one line on
stderr and exit status 2, and nothing written.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
from pathlib import Path

from rotorflow import __version__
from rotorflow.errors import CaseError, RotorflowError


def _finite(obj):
    """JSON has no NaN or infinity: report them as null rather than emit invalid JSON."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    return obj


def cmd_geometry(args) -> int:
    from rotorflow.geometry.summary import geometry_figures
    from rotorflow.workflow.case import load_case

    figures = geometry_figures(load_case(args.case))
    if args.json:
        print(json.dumps(_finite(figures), indent=2))
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


def cmd_simulate(args) -> int:
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
    from rotorflow.workflow.case import load_case

    case = load_case(args.case)
    raw, where = case.raw, str(args.case)
    if "p_suction_bar" not in raw.get("operating", {}):
        raise CaseError(f"[operating] of {where} needs p_suction_bar (and the rest of the "
                        "operating point) to simulate")
    operating = Operating.from_section(raw["operating"], where)
    leakage = Leakage.from_section(raw.get("leakage", {}), where)
    ports = Ports.from_section(raw.get("ports", {}), where)
    numerics = Numerics.from_section(raw.get("numerics", {}), where)
    result = simulate(chamber_table(case), operating, leakage, ports, numerics)
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
        print(json.dumps(_finite(figures), indent=2))
    else:
        for key, value in figures.items():
            print(f"{key:<32} {value:.6g}" if isinstance(value, float) else f"{key:<32} {value}")
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
    q = sub.add_parser("simulate", help="quasi-1D model of the case's operating point")
    q.add_argument("case", type=Path)
    q.add_argument("--json", action="store_true", help="one JSON object on stdout")
    q.add_argument("--traces", type=Path, help="folder for p, T, m traces (CSV) and plots")
    q.set_defaults(func=cmd_simulate)
    return parser




def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except CaseError as exc:
        print(f"rotorflow: error: {exc}", file=sys.stderr)
        return 2
    except RotorflowError as exc:
        print(f"rotorflow: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
