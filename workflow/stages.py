"""The stage graph: what each stage reads, what it needs upstream, and how it runs.

A case file names what it wants in its ``[outputs]`` section::

    [outputs]
    want = ["geometry", "quasi1d", "report"]   # any registered stage names

and every stage those need upstream runs too (``rotorflow run`` skips what is cached).
Without ``[outputs]`` a case runs every stage whose ``default`` says yes and whose input
it has: geometry, table, render and report always, quasi1d with an operating point,
solids with an [export] section.

A stage is registered once, here, with

* ``reads``: the case-file parts it depends on, as selectors: ``"machine"`` (a whole
  section) or ``"operating.volume_ratio"`` (one key), or ``"*"`` (the whole file);
* ``needs``: upstream stages whose artifact folders it reads (always run first);
* ``after``: upstream stages it reads *if they are planned* (``"*"``: every other
  planned stage; the report uses this to collect whatever ran);
* ``run``: ``"module:function"``, called as ``function(ctx)`` with a
  :class:`rotorflow.workflow.cache.StageContext`; it writes its files into ``ctx.out``
  (a private temporary folder that is renamed into place when the function returns) and
  may return a small JSON-ready dict that is kept in the stage's record;
* ``report``: ``"module:function"`` giving the stage's section of the HTML report,
  called as ``function(artifact_dir, report_dir, case)`` and returning a
  :class:`rotorflow.postprocess.report.Section` (or None).  A stage with a report hook
  appears in every report of a case that planned it, CFD stages included;
* ``code``: modules or packages whose source, with the run function's module, is part
  of the stage's key (a stage reruns when its code changes);
* ``figures``: a JSON file of scalar results in the artifact folder, whose values
  become columns of a sweep's summary CSV;
* ``missing(raw)``: why this case cannot run the stage (None: it can), and
  ``default(raw)``: whether the stage runs when the case has no ``[outputs]``.

Functions are named by strings and imported only when a stage runs, so planning and a
no-op rerun load nothing heavy.  Adding a stage (solids, a CFD stage) is one
:func:`register` call below.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from rotorflow.errors import CaseError

OUTPUT_KEYS = ("want",)


def _always(raw: dict) -> str | None:
    return None


def _yes(raw: dict) -> bool:
    return True


def _no_files(raw: dict, case_path) -> list:
    return []


def _leakage_files(raw: dict, case_path) -> list:
    """The CFD flow-coefficient fits [leakage] and its paths name (``correlation``,
    relative to the case file): a refit must rerun the model, not only a renamed file."""
    leak = raw.get("leakage")
    sections = [leak] if isinstance(leak, dict) else []
    sections += [v for v in (leak or {}).values() if isinstance(v, dict)]
    names = [d["correlation"] for d in sections if isinstance(d.get("correlation"), str)]
    if not names:  # (the quasi-1D package takes ~0.15 s to import: planning does not)
        return []
    from rotorflow.quasi1d.calibrated import correlation_path

    return [correlation_path(n, str(case_path)) for n in names]


@dataclass(frozen=True)
class Stage:
    name: str
    run: str
    description: str
    reads: tuple[str, ...] = ()
    needs: tuple[str, ...] = ()
    after: tuple[str, ...] = ()
    report: str | None = None
    #: Where the stage's section goes in the report (low first; ties: registration order).
    report_rank: int = 50
    #: A JSON file of the stage's scalar results: the columns of a sweep's summary.csv.
    figures: str | None = None
    missing: Callable[[dict], str | None] = field(default=_always, repr=False)
    default: Callable[[dict], bool] = field(default=_yes, repr=False)
    #: ``files(raw, case_path)``: the files the stage reads whose paths the case names;
    #: their contents are part of the key (the case holds only their names).
    files: Callable[[dict, object], list] = field(default=_no_files, repr=False)
    #: Modules and packages whose source is part of the key (with the run function's
    #: module): a stage reruns when its code changes.
    code: tuple[str, ...] = ()
    #: Bump to rebuild old artifacts even where the code hash cannot see a change.
    version: int = 1
    #: "module:function" of ``f(case, case_path, cached)``: everything the stage would
    #: refuse in its input, found before any stage of a run writes anything (CaseError);
    #: ``cached`` maps the fresh upstream stages to their artifact folders.  Only a stage
    #: that will run is checked (:func:`rotorflow.workflow.runner.check`).
    check: str | None = None

    @property
    def code_modules(self) -> tuple[str, ...]:
        return tuple(sorted({self.run.partition(":")[0], *self.code}))


REGISTRY: dict[str, Stage] = {}


def register(stage: Stage, *, replace: bool = False) -> Stage:
    if stage.name in REGISTRY and not replace:
        raise ValueError(f"stage '{stage.name}' is already registered")
    for up in stage.needs + stage.after:
        if up != "*" and up not in REGISTRY:
            raise ValueError(f"stage '{stage.name}' needs '{up}', which is not registered")
    REGISTRY[stage.name] = stage
    return stage


def select(raw: dict, selectors: tuple[str, ...]) -> dict:
    """The parts of a case file a stage reads, as a JSON-ready dict (missing: None)."""
    if "*" in selectors:
        return {"*": raw}
    out = {}
    for sel in selectors:
        section, _, key = sel.partition(".")
        part = raw.get(section)
        if key:
            part = part.get(key) if isinstance(part, dict) else None
        out[sel] = part
    return out


# ------------------------------------------------------------------------ planning
def default_outputs(raw: dict) -> list[str]:
    """The stages a case without [outputs] runs: every stage it has the input for."""
    return [s.name for s in REGISTRY.values() if s.default(raw) and s.missing(raw) is None]


def validate_outputs(section, path) -> list[str]:
    """Check an [outputs] table: ``want`` is a list of registered stage names."""
    if not isinstance(section, dict):
        raise CaseError(f"[outputs] in {path} must be a table")
    for key in section:
        if key not in OUTPUT_KEYS:
            raise CaseError(f"unknown key '{key}' in [outputs] of {path}")
    want = section.get("want")
    if want is None:
        raise CaseError(f"missing key 'want' in [outputs] of {path}")
    if not isinstance(want, list) or not want or not all(isinstance(w, str) for w in want):
        raise CaseError(f"'want' in [outputs] of {path} must be a non-empty list of stage "
                        "names")
    for name in want:
        if name not in REGISTRY:
            known = ", ".join(REGISTRY)
            raise CaseError(f"unknown output '{name}' in [outputs] of {path} (one of: {known})")
    return list(want)


def wanted(raw: dict, path, extra: list[str] | None = None) -> list[str]:
    """What a case asks for: its [outputs] (or the default), plus ``extra``."""
    want = validate_outputs(raw["outputs"], path) if "outputs" in raw else default_outputs(raw)
    for name in extra or []:
        if name not in REGISTRY:
            raise CaseError(f"unknown stage '{name}' (one of: {', '.join(REGISTRY)})")
        if name not in want:
            want.append(name)
    return want


def plan(raw: dict, want: list[str], path) -> list[str]:
    """Every stage needed for ``want``, upstream first; CaseError if one cannot run."""
    chosen: set[str] = set()

    def add(name, by):
        stage = REGISTRY[name]
        if name in chosen:
            return
        reason = stage.missing(raw)
        if reason:
            asked = f" (needed by {by})" if by else ""
            raise CaseError(f"{path} asks for '{name}'{asked}, but {reason}")
        chosen.add(name)
        for up in stage.needs:
            add(up, name)

    for name in want:
        add(name, None)
    order: list[str] = []
    visiting: set[str] = set()

    def visit(name):
        if name in order:
            return
        if name in visiting:
            raise ValueError(f"stage cycle through '{name}'")
        visiting.add(name)
        for up in upstream(name, chosen):
            visit(up)
        visiting.discard(name)
        order.append(name)

    # Registration order breaks ties, so the plan reads like the pipeline.
    for name in REGISTRY:
        if name in chosen:
            visit(name)
    return order


def upstream(name: str, planned) -> list[str]:
    """The stages whose artifacts ``name`` reads in a plan: needs, and planned afters."""
    stage = REGISTRY[name]
    ups = list(stage.needs)
    for a in stage.after:
        if a == "*":
            ups += [s for s in REGISTRY if s in planned and s != name and s not in ups
                    and "*" not in REGISTRY[s].after]
        elif a in planned and a not in ups:
            ups.append(a)
    return ups


# ------------------------------------------------------------------ built-in stages
def _needs_operating_point(raw: dict) -> str | None:
    op = raw.get("operating", {})
    if isinstance(op, dict) and "p_suction_bar" in op:
        return None
    return "its [operating] section has no operating point (p_suction_bar, ...)"


def _needs_section(section: str, operating_point: bool = False):
    """A stage's ``missing``: the case lacks [section] (or, with ``operating_point``, an
    operating point)."""
    def missing(raw: dict) -> str | None:
        if section not in raw:
            return f"it has no [{section}] section"
        return _needs_operating_point(raw) if operating_point else None
    return missing


# The port timing keys: a family whose table carries its port areas (the twin screw)
# cuts the ports where the case opens and closes them, and those the case asks for.
GEOMETRY_READS = ("machine", "sweep", "operating.volume_ratio", "operating.driven",
                  "operating.discharge_early_opening_deg", "operating.suction_close_deg",
                  "operating.discharge_open_deg", "operating.discharge_port")
_IMPL = "rotorflow.workflow.builtin"
_REPORT = "rotorflow.postprocess.report"

register(Stage(
    name="geometry",
    run=f"{_IMPL}:run_geometry",
    description=("profile, chamber and power-split figures (geometry.json), contact points "
                 "(contacts.csv)"),
    reads=GEOMETRY_READS,
    code=("rotorflow.geometry",),
    report=f"{_REPORT}:geometry_section",
    report_rank=10,
    figures="geometry.json",
))
register(Stage(
    name="table",
    run=f"{_IMPL}:run_table",
    description="chamber table for the quasi-1D model (chamber_table.csv + .json)",
    reads=GEOMETRY_READS,
    code=("rotorflow.geometry",),
    report=f"{_REPORT}:table_section",
    report_rank=30,
))
register(Stage(
    name="quasi1d",
    run=f"{_IMPL}:run_quasi1d",
    description="quasi-1D chamber model: summary.json, traces (CSV), p-angle and p-V plots",
    reads=("operating", "leakage", "ports", "numerics", "mechanical"),
    needs=("table",),
    code=("rotorflow.quasi1d", "rotorflow.geometry.table"),
    report=f"{_REPORT}:quasi1d_section",
    report_rank=40,
    figures="summary.json",
    missing=_needs_operating_point,
    default=lambda raw: _needs_operating_point(raw) is None,
    check=f"{_IMPL}:check_quasi1d",
    files=_leakage_files,
))
register(Stage(
    name="render",
    run=f"{_IMPL}:run_render",
    description="rotor and chamber pictures rendered off-screen (pyvista)",
    reads=("machine", "sweep"),
    needs=("geometry",),
    code=("rotorflow.postprocess.render", "rotorflow.geometry"),
    report=f"{_REPORT}:render_section",
    report_rank=20,
))
register(Stage(
    name="solids",
    run=f"{_IMPL}:run_solids",
    description="solids and machining files of the [export] section (rotorflow export)",
    # The fluid domain's port pockets follow the port timing of [operating].
    reads=("machine", "sweep", "export", "operating.volume_ratio",
           "operating.suction_close_deg", "operating.discharge_open_deg",
           "operating.discharge_early_opening_deg"),
    code=("rotorflow.geometry",),
    report=f"{_REPORT}:solids_section",
    missing=_needs_section("export"),
    default=lambda raw: "export" in raw,
    check=f"{_IMPL}:check_solids",
))
register(Stage(
    name="cfd.leakage",
    run="rotorflow.cases.leakage_stage:run_stage",
    description="OpenFOAM leakage matrix, Richardson studies, quasi-1D comparison, Cd fit",
    # Tip gaps are generic (gap, pressure ratio, wall radius, wall speed); sealing-line
    # sections are cut from [machine], their walls move at the rotor speed of
    # [operating] (driven "auto" reads the power split: the sweep and volume ratio).
    # Runs are reused point by point through [cfd] runs_dir.
    reads=("cfd", "machine", "sweep", "operating.speed_rpm", "operating.driven",
           "operating.volume_ratio"),
    code=("rotorflow.cases", "rotorflow.postprocess.leakage",
          "rotorflow.postprocess.leakage_report", "rotorflow.quasi1d.flows",
          "rotorflow.quasi1d.calibrated", "rotorflow.quasi1d.perfect_gas",
          "rotorflow.geometry.internal_gear", "rotorflow.geometry.curves"),
    report="rotorflow.postprocess.leakage_report:report_section",
    report_rank=60,
    missing=_needs_section("cfd"),
    default=lambda raw: "cfd" in raw,
))
register(Stage(
    name="cfd.chamber",
    run="rotorflow.cases.chamber_case:run_stage",
    description="OpenFOAM compression of one leaking chamber against the quasi-1D models",
    reads=("machine", "sweep", "operating", "leakage", "cfd_chamber"),
    needs=("table",),
    # Uses the cfd.leakage stage's fitted flow coefficient when that stage runs too.
    after=("cfd.leakage",),
    code=("rotorflow.cases", "rotorflow.postprocess.chamber_compare",
          "rotorflow.postprocess.chamber_history", "rotorflow.postprocess.chamber_model",
          "rotorflow.quasi1d", "rotorflow.geometry.table"),
    report="rotorflow.postprocess.chamber_compare:report_section",
    report_rank=70,
    figures="chamber_figures.json",
    missing=_needs_section("cfd_chamber", operating_point=True),
    default=lambda raw: "cfd_chamber" in raw,
))
register(Stage(
    name="cfd.machine",
    run="rotorflow.cases.machine_study:run_stage",
    description=("OpenFOAM 3D runs of the whole machine at frozen angles on three grids "
                 "(Richardson) against the quasi-1D models' frozen states"),
    reads=("machine", "sweep", "operating", "leakage", "ports", "numerics", "cfd_machine"),
    # Uses the cfd.leakage stage's fitted flow coefficient when that stage runs too.
    after=("cfd.leakage",),
    code=("rotorflow.cases", "rotorflow.postprocess.machine_compare",
          "rotorflow.postprocess.richardson", "rotorflow.quasi1d", "rotorflow.geometry"),
    report="rotorflow.postprocess.machine_compare:report_section",
    report_rank=75,
    figures="machine_figures.json",
    missing=_needs_section("cfd_machine", operating_point=True),
    default=lambda raw: "cfd_machine" in raw,
))
register(Stage(
    name="report",
    run="rotorflow.workflow.report_stage:run_report",
    description="static HTML report of every planned stage (report/index.html)",
    reads=("*",),
    needs=("geometry", "render"),
    code=("rotorflow.postprocess",),
    after=("*",),
))
