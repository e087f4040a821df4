"""The ``cfd.machine`` workflow stage: the frozen-angle 3D CFD of the whole machine on three
grids per angle, against the quasi-1D model's frozen state (issue 16).

The case file's ``[cfd_machine]`` section (:class:`StudySettings`) names the angles and
the coarse grid; the medium and fine grids refine it by ``refinement_ratio`` in every
direction (columns, cells across every gap, layers; the end layer thinner by the same
ratio; ``grids = 2`` runs the coarse and medium ones only, the quick estimate).  Each
run is a :mod:`.machine_run` case under ``runs_dir``, reused by key when
the stage reruns, and its mass balance over all patches must hold to 0.5 % or the run
is flagged and left out.  Per angle, the quasi-1D model of the same case (end faces
sealed, as the CFD's end plates are: :mod:`.machine_setup`) is solved in the frozen
state under each leakage model, and :mod:`rotorflow.postprocess.machine_compare`
extrapolates the CFD's closed-chamber pressures, sealing-path flows and total leakage
and tabulates each model's error.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from rotorflow.errors import CaseError

from .machine_run import Controls, run_machine_case
from .machine_setup import (
    Grid,
    angle_name,
    case_table,
    frozen_machine,
    frozen_models,
    model_flows,
    slot_of,
    table_origin,
)
from .ogrid import OGridSpec
from .parallel import Decomposition

log = logging.getLogger(__name__)

SECTION = "cfd_machine"
KEYS = ("angles_deg", "gap_um", "columns", "cells_across_gap", "layers", "end_layer_mm",
        "refinement_ratio", "models", "flow_coefficient", "processes", "max_iterations",
        "moving_walls", "wall_clustering", "even_reach", "runs_dir", "grids")
MODELS = ("nozzle", "fanno", "cfd-calibrated", "rarefied")
LEVELS = ("coarse", "medium", "fine")


@dataclass(frozen=True)
class StudySettings:
    """The ``[cfd_machine]`` section."""

    angles_deg: tuple[float, ...]
    coarse: Grid
    ratio: float = 1.5
    gap_um: float | None = None  # None: [leakage] gap_um
    models: tuple[str, ...] = ("nozzle", "fanno", "cfd-calibrated")
    flow_coefficient: str | None = None
    processes: int = 2
    max_iterations: int = Controls.max_iterations
    moving_walls: bool = True
    #: The O-grid's tanh clustering toward the walls (:class:`.ogrid.OGridSpec`).  3, not
    #: its default 3.5: refined by 1.5 from 768 x 4, the 1152 x 6 and 1728 x 9 sections
    #: of the default machine at 20 um fail the chord-sag check (0.51-0.57 first cells) at
    #: 8 and 4 of 60 angles with 3.5; with 3 all three pass at every degree (sag 0.42-0.48)
    #: and the stacks pass checkMesh (skewness 3.3-3.8).
    wall_clustering: float = 3.0
    runs_dir: str | None = None
    #: :attr:`.ogrid.OGridSpec.even_reach`: 0 keeps the tanh law in the gaps too.
    even_reach: float = 0.0
    #: 3: coarse, medium and fine, extrapolated at the observed order; 2: the quick
    #: estimate, coarse and medium only, extrapolated at the formal order 2
    #: (:func:`rotorflow.postprocess.richardson.two_grid`).
    levels: int = 3

    def spec(self) -> OGridSpec:
        return OGridSpec(wall_clustering=self.wall_clustering, even_reach=self.even_reach)

    def grids(self) -> tuple[Grid, ...]:
        """The grids the study runs, coarse first."""
        every = (self.coarse, self.coarse.refined(self.ratio),
                 self.coarse.refined(self.ratio**2))
        return every[:self.levels]

    @classmethod
    def from_section(cls, d, where: str = "the case") -> StudySettings:
        if not isinstance(d, dict):
            raise CaseError(f"[{SECTION}] of {where} must be a table")
        unknown = sorted(set(d) - set(KEYS))
        if unknown:
            raise CaseError(f"unknown key(s) {', '.join(unknown)} in [{SECTION}] of {where}")

        def bad(key, what):
            return CaseError(f"key '{key}' in [{SECTION}] of {where} must be {what}, got "
                             f"{d[key]!r}")

        def number(key, default=None, whole=False):
            if key not in d:
                if default is None:
                    raise CaseError(f"missing key '{key}' in [{SECTION}] of {where}")
                return default
            v = d[key]
            if isinstance(v, bool) or not isinstance(v, int | float) or not v > 0 or (
                    whole and v != int(v)):
                raise bad(key, "a positive whole number" if whole else "a positive number")
            return int(v) if whole else float(v)

        angles = d.get("angles_deg")
        if not isinstance(angles, list) or not angles or not all(
                isinstance(a, int | float) and not isinstance(a, bool) and 0 <= a < 360
                for a in angles):
            raise CaseError(f"key 'angles_deg' in [{SECTION}] of {where} must be a list of "
                            "angles in [0, 360)")
        models = d.get("models", list(cls.models))
        if not isinstance(models, list) or not models or not set(models) <= set(MODELS):
            raise CaseError(f"key 'models' in [{SECTION}] of {where} must list leakage "
                            f"models of {', '.join(MODELS)}")
        for key in ("flow_coefficient", "runs_dir"):
            if key in d and not isinstance(d[key], str):
                raise bad(key, "a string")
        if not isinstance(d.get("moving_walls", True), bool):
            raise bad("moving_walls", "true or false")
        if d.get("grids", 3) not in (2, 3) or isinstance(d.get("grids"), bool):
            raise bad("grids", "2 (coarse and medium: the quick estimate) or 3")
        end = number("end_layer_mm", -1.0) if "end_layer_mm" in d else None
        grid = Grid(number("columns", whole=True), number("cells_across_gap", whole=True),
                    number("layers", whole=True), None if end is None else end * 1e-3)
        ratio = number("refinement_ratio", cls.ratio)
        if not ratio > 1.0:
            raise bad("refinement_ratio", "above 1")
        for r in (ratio, ratio**2):  # the refined counts exact, so the ratio is
            for key, v in (("columns", grid.columns), ("cells_across_gap",
                                                       grid.cells_across_gap),
                           ("layers", grid.layers)):
                if abs(v * r - round(v * r)) > 1e-9:
                    raise CaseError(f"[{SECTION}] of {where}: {key} = {v} refined by "
                                    f"{r:g} is not a whole number")
        return cls(tuple(float(a) for a in angles), grid, ratio,
                   number("gap_um", None) if "gap_um" in d else None, tuple(models),
                   d.get("flow_coefficient"), number("processes", 2, whole=True),
                   number("max_iterations", cls.max_iterations, whole=True),
                   d.get("moving_walls", True),
                   number("wall_clustering", cls.wall_clustering), d.get("runs_dir"),
                   number("even_reach", 0.0) if "even_reach" in d else 0.0,
                   int(d.get("grids", 3)))


def validate_section(data: dict, where: str, pair) -> None:
    """Check ``[cfd_machine]`` when the case is loaded (nothing is run)."""
    StudySettings.from_section(data[SECTION], where)
    if pair is not None and pair.family != "internal-gear":
        raise CaseError(f"[{SECTION}] of {where}: the 3D O-grid case is for the internal "
                        f"gear, not {pair.family}")


def run_angle(case, table, phi: float, settings: StudySettings, gap: float, runs: Path,
              correlation: Path | None, where: str) -> dict:
    """One angle: the three grids' runs and the quasi-1D models' frozen states, as the
    record :mod:`rotorflow.postprocess.machine_compare` reads."""
    from dataclasses import replace

    models = [m for m in settings.models if m != "cfd-calibrated" or correlation is not None]
    states = frozen_models(case, table, phi, models, correlation, where)
    period, origin = float(case.pair.period), table_origin(case)
    paths = {p.name: p for p in table.paths}
    ref = next(iter(states.values()))
    closed = [s for s, c in zip(slot_of(ref, phi, period, origin), ref.closed, strict=True)
              if c]
    record = {"angle_deg": round(math.degrees(phi), 9), "ratio": settings.ratio, "closed": closed,
              "models": {}, "runs": [], "grids": []}
    for name, state in states.items():
        pairs, total = model_flows(state, phi, period, origin, paths)
        record["models"][name] = {
            "pressures": {str(s): float(p) for s, p in zip(slot_of(state, phi, period, origin),
                                                           state.p, strict=True)},
            "pairs": {f"{a},{b}": f for (a, b), f in pairs.items()}, "total": total}
    controls = Controls(max_iterations=settings.max_iterations)
    folder = runs / f"machine-{case.pair.digest()}-{angle_name(phi)}-g{gap * 1e6:g}um"
    for level, grid in zip(LEVELS[:settings.levels], settings.grids(), strict=True):
        m = replace(frozen_machine(case, table, phi, gap, grid, settings.max_iterations,
                                   where, settings.spec()),
                    moving_walls=settings.moving_walls)
        label = (f"rotor angle {math.degrees(phi):.6g} deg, {level} grid {grid.label}")
        run = run_machine_case(m, folder / grid.label, controls,
                               Decomposition(settings.processes), label=label)
        record["runs"].append(asdict(run))
        record["grids"].append({"level": level, **asdict(grid), "label": grid.label})
    return record


def run_stage(ctx) -> dict:
    """Workflow stage ``cfd.machine``: every angle's three runs and their comparison.

    Writes ``angles.json`` (every run, failed ones with their log tails, and the models'
    frozen states), ``machine_errors.csv`` / ``.md`` and ``machine_summary.json`` (the
    angles whose three runs converged), and ``machine_figures.json``, the flat figures
    it returns.  A grid that cannot be made stops the stage with one line naming the
    angle, the grid and the measure.
    """
    from rotorflow.postprocess import machine_compare

    from .chamber_case import _resolve, flow_coefficient_path

    where = str(ctx.case_path)
    settings = StudySettings.from_section(ctx.raw.get(SECTION, {}), where)
    gap_um = settings.gap_um or ctx.raw.get("leakage", {}).get("gap_um")
    if not gap_um:
        raise CaseError(f"[{SECTION}] of {where}: no clearance (gap_um here or in [leakage])")
    correlation = (flow_coefficient_path(ctx, settings.flow_coefficient)
                   if "cfd-calibrated" in settings.models else None)
    runs = (_resolve(settings.runs_dir, ctx.case_path) if settings.runs_dir
            else ctx.out / "runs")
    table = case_table(ctx.case)
    records = []
    for deg in settings.angles_deg:
        records.append(run_angle(ctx.case, table, math.radians(deg), settings, gap_um * 1e-6,
                                 runs, correlation, where))
        (ctx.out / "angles.json").write_text(json.dumps(records, indent=2, allow_nan=True)
                                             + "\n")
    good = [r for r in records if all(run["status"] == "converged" for run in r["runs"])]
    figures: dict = {"angles": len(records), "angles_compared": len(good),
                     "failed_runs": sum(run["status"] != "converged"
                                        for r in records for run in r["runs"])}
    if good:
        result = machine_compare.write(good, ctx.out)
        figures["closest_model"] = result["closest_model"]
        figures["two_grid_leakage_error"] = result["two_grid"]["leakage"]["max_abs"]
        for m, e in result["models"].items():
            figures[f"rms_error[{m}]"] = e["all"]["rms"]
            figures[f"leakage_rms_error[{m}]"] = e["leakage"]["rms"]
    for r in records:
        deg = f"{r['angle_deg']:g}"
        figures[f"seconds[{deg}]"] = sum(run["run_time_s"] for run in r["runs"])
        figures[f"largest_imbalance[{deg}]"] = max(run["imbalance"] for run in r["runs"])
    (ctx.out / "machine_figures.json").write_text(json.dumps(figures, indent=2,
                                                             allow_nan=True) + "\n")
    return figures
