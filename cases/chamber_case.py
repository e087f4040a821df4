"""Case B: pressure in a chamber that is compressed while it leaks, with OpenFOAM.

One working chamber of an internal-gear machine is followed through its compression
phase, from suction closing to discharge opening, as a 2D section (one cell thick):

* **Scaling.**  The slab's depth D is a representative sealing-line length L_s (by
  default the mean, over the compression phase, of the lines across which the chamber
  leaks toward suction: ``seal_prev_m + seal_lp_face_m`` of the chamber table).  Then
  the gap's flow area is h_min x D = gap x L_s, which is the leakage area the quasi-1D
  model gives those lines, and the chamber's area A(t) = V(t) / D makes its volume the
  table's V(t).
* **Geometry.**  A rectangular chamber (square at the start) whose top wall is a piston,
  and case A's rotor-tip gap (minimum gap h from ``[leakage] gap_um``) opening from the
  bottom wall into a plenum at suction pressure (the gap's outlet, a static-pressure
  boundary); see :mod:`rotorflow.cases.chamber_mesh`.  The chamber's area is reduced by
  the gap's area upstream of its throat, so that the gas upstream of the throat (the
  control volume of the quasi-1D chamber) has exactly the table's volume.
* **Motion.**  Time is angle over the outer rotor's angular speed, t = (theta -
  theta_sc) / omega_outer.  The piston's displacement d(t) = (V(t) - V(0)) / (D W) is a
  table in time; ``dynamicMotionSolverFvMesh`` with the stock ``displacementInterpolation``
  solver moves every point by linear interpolation in y between two face zones made by
  topoSet: the piston (the table) and a line of faces at the top of the chamber's fixed
  lower part (zero), so the cells around the opening, the gap and the outlet never move
  and the structured block above is squeezed uniformly.  (``displacementLaplacian`` on
  the whole chamber squeezed the unstructured cells near the opening too: their
  non-orthogonality rose from 30 to 52 deg and the run diverged late in the compression.)
* **Flow.**  rhoPimpleFoam, laminar, perfect gas with Sutherland viscosity, adiabatic
  walls; at rest at suction pressure and temperature at the start.
* **Outputs.**  Function objects sample, every ``sample_deg`` of rotor angle: the
  chamber zone's volume average of p and T (``volFieldValue``, cellZone ``chamber``
  made by gmshToFoam from gmsh's physical volume: cell zones keep their orientation,
  only face zones come flipped), its integrals of p and rho (chamber volume = integral
  of p / average of p; chamber mass), the mass in the whole domain and the mass flow
  out through the outlet.

:func:`run_chamber_case` runs a case through the routine every CFD case shares
(:func:`rotorflow.cases.foam_case.run_case`: built in a temporary folder, judged (end time
reached, mass conserved, chamber volume as prescribed), renamed into place with
``result.json``, reused by key).  A crashed or diverged run is kept with its log tail and
is never compared.  Its OpenFOAM commands are planned as data (:func:`plan`)::

    gmshToFoam chamber.msh   then the patch types
    checkMesh                then its report (and gmsh's cell count)
    topoSet                  then the motion's two face zones
    rhoPimpleFoam            its progress from the solver's time

The case's definition is :mod:`~rotorflow.cases.chamber_spec`, what it writes
:mod:`~rotorflow.cases.chamber_setup`.  :func:`run_stage` is the workflow's
``cfd.chamber`` stage.
"""

from __future__ import annotations

import functools
import json
import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError, ExternalRunError
from rotorflow.postprocess import chamber_compare as cc
from rotorflow.postprocess.chamber_history import ChamberHistory, read_history

from . import foam, foam_case
from .chamber_mesh import patch_types
from .chamber_setup import SOLVER, TOPO_SET, check_motion_zones, write_files
from .chamber_spec import (
    TIP_RADIUS_M,
    ChamberCase,
    Compression,
    TransientControls,
    compression_from_table,
)
from .foam import Step
from .foam_case import Plan, count_time_steps
from .foam_mesh import MeshQuality, mesh_steps

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ChamberResult:
    """What a chamber run produced.  Use only results with :attr:`ok`."""

    status: str
    """'completed', 'inconsistent' (a mass or volume check failed), 'incomplete' (stopped
    before the end), 'diverged' or 'crashed'."""
    message: str
    end_angle_deg: float
    """Rotor angle the run reached (since the chamber's birth)."""
    samples: int
    mass_error: float
    """max |m(t) + mass out until t - m(0)| / m(0) over the run."""
    volume_error: float
    """max |V_zone(t) / V_prescribed(t) - 1| of the chamber zone over the run."""
    final_pressure_Pa: float
    run_time_s: float
    time_steps: int
    cells: int
    cells_gap: int
    mesh_refinement: float
    max_aspect_ratio: float = math.nan
    max_non_orthogonality_deg: float = math.nan
    log_tail: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "completed"

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2, allow_nan=True) + "\n"

    @classmethod
    def from_json(cls, text: str) -> ChamberResult:
        return cls(**json.loads(text))


def load_result(case_dir: Path) -> ChamberResult | None:
    """The stored result of a finished case folder, or None when there is none."""
    path = Path(case_dir) / "result.json"
    return ChamberResult.from_json(path.read_text()) if path.is_file() else None


class _Progress:
    """The solver's time as the fraction of the compression done."""

    def __init__(self, duration: float, progress: Callable[[float], None] | None) -> None:
        self.duration, self.progress = duration, progress

    def __call__(self, t: float) -> None:
        if self.progress is not None:
            self.progress(min(1.0, t / self.duration))


def plan(case: ChamberCase, mesh_cells: int | None = None,
         progress: Callable[[float], None] | None = None) -> Plan:
    """The OpenFOAM commands of ``case`` (see the module docstring).

    ``mesh_cells``: gmsh's cell count, which checkMesh must find (None: not checked);
    ``progress`` receives the fraction of the compression done.
    """
    return Plan(
        setup=(*mesh_steps("chamber.msh", patch_types(case.with_gap), mesh_cells),
               Step(TOPO_SET, then=check_motion_zones)),
        solve=Step((SOLVER,), timeout_s=case.controls.timeout_s,
                   on_time=_Progress(case.compression.duration_s, progress)),
    )


def _build(case: ChamberCase, progress, case_dir: Path) -> tuple[Plan, int]:
    mesh = write_files(case, case_dir)
    return plan(case, mesh.cells, progress), mesh.cells_gap


def write_case(case: ChamberCase, case_dir: Path) -> tuple[MeshQuality, int]:
    """Write the full OpenFOAM case into ``case_dir`` (mesh and motion zones included: the
    plan's setup steps are drained), without running the solver; return checkMesh's
    verdict and the number of gap cells."""
    case_dir = Path(case_dir)
    the_plan, cells_gap = _build(case, None, case_dir)
    return foam.drain(the_plan.setup, case_dir)["checkMesh"], cells_gap


def run_chamber_case(case: ChamberCase, case_dir: Path, *,
                     progress: Callable[[float], None] | None = None,
                     reuse: bool = True) -> ChamberResult:
    """Build and run one chamber case in ``case_dir``; return (and store) its result.

    Built in ``<case_dir>.tmp`` and renamed to ``case_dir`` once judged, with
    ``result.json``, ``case.json`` and ``case.key``; with ``reuse`` a folder whose key
    matches is not run again (failed results are kept, never retried silently).
    ``progress`` receives the fraction of the compression done.  Mesh problems raise
    (CaseError, MeshCheckError); solver failures give a failed result.
    """
    def judged(folder: Path, cells_gap: int, values: Mapping[str, Any], elapsed: float,
               failure: str) -> ChamberResult:
        steps = count_time_steps(folder / f"log.{SOLVER}")
        return judge(folder, case, values["checkMesh"], cells_gap, elapsed, steps, failure)

    return foam_case.run_case(
        case_dir, case.key(), functools.partial(_build, case, progress), judged,
        ChamberResult.from_json, reuse=reuse, label="chamber case",
        summary=lambda r: (f"{r.status} at {r.end_angle_deg:.1f} deg, p_end "
                           f"{r.final_pressure_Pa:.4g} Pa, mass error {r.mass_error:.1e}, "
                           f"volume error {r.volume_error:.1e}, {r.time_steps} steps, "
                           f"{r.run_time_s:.1f} s"))


def judge(case_dir: Path, case: ChamberCase, quality: MeshQuality, cells_gap: int,
          elapsed: float, steps: int, failure: str) -> ChamberResult:
    """The result of a finished (or failed) run, from its tables."""
    c, ctl = case.compression, case.controls
    end_deg = mass_err = vol_err = p_end = math.nan
    samples = 0
    outcome: tuple[str, str] | ExternalRunError
    try:
        hist = read_history(case_dir, c.volume_curve())
        samples = len(hist.time_s)
        end_deg = float(np.degrees(hist.angle_rad[-1]))
        p_end = float(hist.p_Pa[-1])
        mass_err = hist.mass_error()
        vol_err = hist.volume_error()
        outcome = _assess(hist, c, ctl, mass_err, vol_err)
    except ExternalRunError as exc:
        outcome = exc
    v = foam_case.verdict(case_dir, SOLVER, failure, outcome, ok="completed")
    return ChamberResult(
        status=v.status,
        message=v.message,
        end_angle_deg=end_deg,
        samples=samples,
        mass_error=mass_err,
        volume_error=vol_err,
        final_pressure_Pa=p_end,
        run_time_s=elapsed,
        time_steps=steps,
        cells=quality.cells,
        cells_gap=cells_gap,
        mesh_refinement=case.mesh.refinement,
        max_aspect_ratio=quality.max_aspect_ratio,
        max_non_orthogonality_deg=quality.max_non_orthogonality_deg,
        log_tail=v.log_tail,
    )


def _assess(hist: ChamberHistory, c: Compression, ctl: TransientControls,
            mass_err: float, vol_err: float) -> tuple[str, str]:
    if not (np.all(np.isfinite(hist.p_Pa)) and np.all(hist.p_Pa > 0)):
        return "diverged", "non-finite or negative chamber pressure"
    end = c.angle_rad[-1]
    if hist.angle_rad[-1] < end - 0.5 * math.radians(ctl.sample_deg):
        return "incomplete", (f"stopped at {math.degrees(hist.angle_rad[-1]):.2f} deg, before "
                              f"{math.degrees(end):.2f} deg")
    if not mass_err <= ctl.mass_tol:
        return "inconsistent", f"mass not conserved: error {mass_err:.2e} > {ctl.mass_tol:g}"
    if not vol_err <= ctl.volume_tol:
        return "inconsistent", (f"chamber volume off the prescribed curve by {vol_err:.2e} > "
                                f"{ctl.volume_tol:g}")
    return "completed", ""


# --- the workflow stage -------------------------------------------------------------------

#: The case file's section for this stage, and its keys.
SECTION = "cfd_chamber"
CHAMBER_KEYS = ("seal_length_mm", "tip_radius_mm", "refinement", "end_deg", "sample_deg",
                "max_courant", "runs_dir", "flow_coefficient")


@dataclass(frozen=True)
class ChamberSettings:
    """The ``[cfd_chamber]`` section: what the chamber run may change from its defaults."""

    seal_length_m: float | None = None
    """Slab depth; None: the mean sealing-line length toward suction (see the module)."""
    tip_radius_m: float = TIP_RADIUS_M
    refinement: float = 1.0
    end_deg: float | None = None
    """Stop this many degrees after suction closing (None: at discharge opening)."""
    sample_deg: float = TransientControls.sample_deg
    max_courant: float = TransientControls.max_courant
    runs_dir: str | None = None
    """Where runs live (relative to the case file); None: inside the stage's folder."""
    flow_coefficient: str | None = None
    """A fitted correlation (flow_coefficient.json) for the "cfd-calibrated" model; None:
    the cfd.leakage stage's when it ran."""

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> ChamberSettings:
        if not isinstance(d, dict):
            raise CaseError(f"[{SECTION}] of {where} must be a table")
        unknown = sorted(set(d) - set(CHAMBER_KEYS))
        if unknown:
            raise CaseError(f"unknown key(s) {', '.join(unknown)} in [{SECTION}] of {where}")

        def number(key: str, default):
            if key not in d:
                return default
            v = d[key]
            if isinstance(v, bool) or not isinstance(v, int | float) or not v > 0:
                raise CaseError(f"key '{key}' in [{SECTION}] of {where} must be a positive "
                                f"number, got {v!r}")
            return float(v)

        def text(key: str) -> str | None:
            v = d.get(key)
            if v is not None and not isinstance(v, str):
                raise CaseError(f"key '{key}' in [{SECTION}] of {where} must be a string")
            return v

        seal = number("seal_length_mm", None)
        return cls(
            seal_length_m=None if seal is None else 1e-3 * seal,
            tip_radius_m=1e-3 * number("tip_radius_mm", 1e3 * TIP_RADIUS_M),
            refinement=number("refinement", 1.0),
            end_deg=number("end_deg", None),
            sample_deg=number("sample_deg", TransientControls.sample_deg),
            max_courant=number("max_courant", TransientControls.max_courant),
            runs_dir=text("runs_dir"),
            flow_coefficient=text("flow_coefficient"),
        )


def case_from_settings(table, operating, leakage, settings: ChamberSettings) -> ChamberCase:
    """The chamber case a case file asks for."""
    comp = compression_from_table(table, operating, leakage,
                                  seal_length_m=settings.seal_length_m,
                                  tip_radius_m=settings.tip_radius_m)
    if settings.end_deg is not None:
        comp = comp.limited_to(settings.end_deg)
    controls = TransientControls(max_courant=settings.max_courant,
                                 sample_deg=settings.sample_deg)
    return ChamberCase(comp, controls=controls).refined(settings.refinement)


def _resolve(path: str, case_path: Path) -> Path:
    p = Path(path)
    return p if p.is_absolute() else Path(case_path).parent / p


def flow_coefficient_path(ctx, given: str | None) -> Path | None:
    """Where the "cfd-calibrated" correlation is: ``given`` (relative to the case file),
    else the cfd.leakage stage's fit when that stage ran; None (with a warning) when
    there is none."""
    if given is not None:
        return _resolve(given, ctx.case_path)
    if "cfd.leakage" in ctx.inputs:
        return ctx.inputs["cfd.leakage"] / "flow_coefficient.json"
    log.warning("no fitted flow coefficient: compared without the cfd-calibrated model")
    return None


def _load_fit(ctx, settings: ChamberSettings):
    """The correlation for "cfd-calibrated" (:func:`flow_coefficient_path`); None (with
    a warning) when there is none or it does not load."""
    from rotorflow.quasi1d.calibrated import FlowCoefficientFit

    path = flow_coefficient_path(ctx, settings.flow_coefficient)
    if path is None:
        return None
    try:
        return FlowCoefficientFit.load(path)
    except (OSError, ValueError, KeyError) as exc:
        log.warning("cannot load the fitted flow coefficient %s (%s): compared without the "
                    "cfd-calibrated model", path, exc)
        return None


def run_stage(ctx) -> dict:
    """Workflow stage ``cfd.chamber``: the chamber run and its comparison.

    Reads ``[operating]``, ``[leakage]`` and ``[cfd_chamber]`` (see
    :class:`ChamberSettings`), and the chamber table from the ``table`` stage when it is
    upstream (else computes it).  Writes into ``ctx.out``: ``chamber_result.json`` (the
    run's status, checks and, for a failed run, its log tail) and, for a completed run,
    ``chamber_comparison.json``, ``chamber_pressure.csv`` and ``chamber_pressure.png``
    (:func:`rotorflow.postprocess.chamber_compare.write_comparison`); always
    ``chamber_figures.json``, the flat scalars it returns (status, run time, max and RMS
    difference per model, the closest model).  A failed run is recorded, never compared.
    """
    from rotorflow.quasi1d import Leakage, Operating

    raw, where = ctx.raw, str(ctx.case_path)
    settings = ChamberSettings.from_section(raw.get(SECTION, {}), where)
    if "operating" not in raw:
        raise CaseError(f"the chamber CFD case needs an [operating] section in {where}")
    operating = Operating.from_section(raw["operating"], where)
    leakage = Leakage.from_section(raw.get("leakage", {}), where)
    if "table" in ctx.inputs:
        from rotorflow.geometry import table as chamber_table_io

        tab = chamber_table_io.read(ctx.input("table") / "chamber_table.csv")
    else:
        from rotorflow.geometry.summary import chamber_table

        tab = chamber_table(ctx.case)
    case = case_from_settings(tab, operating, leakage, settings)
    runs = (_resolve(settings.runs_dir, ctx.case_path) if settings.runs_dir
            else ctx.out / "runs")
    run_dir = runs / f"chamber-r{settings.refinement:g}"
    result = run_chamber_case(case, run_dir)
    _write_json(ctx.out / "chamber_result.json", asdict(result))
    figures: dict[str, Any] = {"status": result.status, "run_time_s": result.run_time_s,
                               "cells": result.cells}
    if not result.ok:
        log.warning("chamber run %s %s: %s", run_dir, result.status, result.message)
        figures["message"] = result.message
        _write_json(ctx.out / "chamber_figures.json", figures)
        return figures
    history, comparison = cc.compare_run(run_dir, leakage, _load_fit(ctx, settings))
    checks = {"mass_error": result.mass_error, "volume_error": result.volume_error,
              "run_time_s": result.run_time_s, "time_steps": result.time_steps,
              "cells": result.cells}
    summary = cc.write_comparison(comparison, history, ctx.out, checks)
    for d in summary["models"]:
        figures[f"rms_Pa[{d['model']}]"] = d["rms_Pa"]
        figures[f"max_abs_Pa[{d['model']}]"] = d["max_abs_Pa"]
    figures["closest_model"] = summary["closest_model"]
    _write_json(ctx.out / "chamber_figures.json", figures)
    return figures


def _write_json(path: Path, data: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, allow_nan=True) + "\n")
    tmp.replace(path)
