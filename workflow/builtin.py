"""The built-in stages' functions: each writes its files into ``ctx.out``.

They are thin: the work is done by the geometry, quasi-1D and report modules, which
know nothing of caching.  See :mod:`rotorflow.workflow.stages` for the graph.
"""

from __future__ import annotations

import json
import logging
import math
from collections import OrderedDict

from .cache import StageContext, digest

log = logging.getLogger(__name__)

#: The table stage's chamber table (the quasi-1D stage and its check read it).
TABLE_CSV = "chamber_table.csv"
#: Machines and chamber tables kept in memory per process: the geometry and table stages
#: of one case (and of consecutive sweep points on one worker) share one computation.
MEMO_SIZE = 8
_memo_items: OrderedDict = OrderedDict()


def finite(obj):
    """JSON has no NaN or infinity: write them as null rather than emit invalid JSON."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [finite(v) for v in obj]
    return obj


def write_json(path, obj) -> None:
    path.write_text(json.dumps(finite(obj), indent=2) + "\n")


def machine_of(ctx: StageContext):
    """The case's machine (profile, chamber curves), computed once per process."""
    return _machine(ctx.case)


def _memo(case, kind: str, make):
    from .stages import GEOMETRY_READS, select

    key = (kind, digest(select(case.raw, GEOMETRY_READS)))
    if key not in _memo_items:
        _memo_items[key] = make()
        while len(_memo_items) > MEMO_SIZE:
            _memo_items.popitem(last=False)
    return _memo_items[key]


def _machine(case):
    from rotorflow.geometry.summary import build_machine

    return _memo(case, "machine", lambda: build_machine(case))


def _table(case):
    """The chamber table, once per process: the run's input check and the table stage
    share it."""
    from rotorflow.geometry.summary import chamber_table

    return _memo(case, "table", lambda: chamber_table(case, _machine(case)))


def check_quasi1d(case, case_path, cached: dict) -> None:
    """The quasi-1D stage's refusals: its settings, and the port timing against the
    chamber's life, on the chamber table: the table stage's artifact where it is fresh
    (``cached``), else the one the table stage then reuses."""
    from rotorflow.geometry import table
    from rotorflow.quasi1d import case_settings
    from rotorflow.quasi1d.simulate import chamber_of

    operating, _, _, numerics, _ = case_settings(case.raw, str(case_path))
    tab = (table.read(cached["table"] / TABLE_CSV) if "table" in cached
           else _table(case))
    chamber_of(tab, operating, numerics)


def check_solids(case, case_path, cached: dict) -> None:
    """The solids stage's refusals (its settings against the rotors: clearances, bores,
    cutter set-ups), without building a solid."""
    from rotorflow.geometry.export.driver import check
    from rotorflow.geometry.export.settings import Export

    check(case, Export.from_section(case.raw["export"], str(case_path)), cutters=True)


#: Angle step of the contact table the geometry stage writes (one lobe period).
CONTACT_STEP_DEG = 0.5


def run_geometry(ctx: StageContext) -> dict:
    from rotorflow.geometry.contacts import write_csv
    from rotorflow.geometry.summary import geometry_figures

    figures = geometry_figures(ctx.case, machine_of(ctx))
    write_json(ctx.out / "geometry.json", figures)
    write_csv(ctx.case.pair.contact_table(CONTACT_STEP_DEG), ctx.out / "contacts.csv")
    return {"swept_volume_m3": figures["swept_volume_m3"], "driven": figures["driven"]}


def run_table(ctx: StageContext) -> dict:
    from rotorflow.geometry import table

    tab = _table(ctx.case)
    table.write(tab, ctx.out / TABLE_CSV)
    return {"rows": int(len(tab.angle_rad))}


def run_quasi1d(ctx: StageContext) -> dict:
    from rotorflow.geometry import table
    from rotorflow.quasi1d import case_settings, simulate

    tab = table.read(ctx.input("table") / TABLE_CSV)
    result = simulate(tab, *case_settings(ctx.raw, str(ctx.case_path)))
    summary = result.summary()
    write_json(ctx.out / "summary.json", summary)
    result.write_traces(ctx.out)
    result.plot(ctx.out)
    if not result.converged:
        log.warning("quasi-1D cycle of %s did not converge", ctx.case_path)
    return {"converged": bool(summary.get("converged")),
            "mass_flow_kg_s": summary.get("mass_flow_kg_s")}


def run_render(ctx: StageContext) -> dict:
    from rotorflow.postprocess.render import render_case

    figures = json.loads((ctx.input("geometry") / "geometry.json").read_text())
    reference = ctx.case.pair.rotors[0].name
    files = render_case(ctx.case, ctx.out, wrap_outer_deg=figures[f"wrap_{reference}_deg"])
    return {"images": [p.name for p in files]}


def run_solids(ctx: StageContext) -> dict:
    """Solids and machining files of the [export] section (as `rotorflow export`)."""
    from rotorflow.geometry.export.driver import export
    from rotorflow.geometry.export.settings import Export

    settings = Export.from_section(ctx.raw["export"], str(ctx.case_path))
    export(ctx.case, settings, ctx.out)
    return {"files": sorted(p.name for p in ctx.out.iterdir() if p.is_file())}
