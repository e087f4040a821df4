"""Mesh studies and matrices of gap cases: three meshes per point, Richardson extrapolation.

A :class:`MeshStudy` runs one :class:`~rotorflow.cases.gap_case.GapCase` on the meshes
``refinement * ratio**k`` for k = -1, 0, 1 (coarse, default, fine), extrapolates the mass
flow with the observed order and says how far the default mesh is from it.  A study with
a failed run has no extrapolation and gives no :class:`LeakagePoint`: failed runs are
never used in a fit or a comparison.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rotorflow.errors import CaseError
from rotorflow.postprocess.leakage import LeakagePoint
from rotorflow.postprocess.richardson import Richardson, richardson

from .gap_case import GapCase, GapFlow, GapResult, run_gap_case
from .gap_mesh import GapMeshSpec, rotor_tip_gap

log = logging.getLogger(__name__)

#: Refinement ratio between the meshes of a study: 2 halves every cell, so the coarse
#: mesh's nodes are a subset of the fine one's and the ratio is exact.
REFINEMENT_RATIO = 2.0

#: The issue's target: the default mesh within 2 % of the extrapolated mass flow.
DEFAULT_MESH_TOL = 0.02

LEVELS = ("coarse", "default", "fine")


@dataclass(frozen=True)
class MeshStudy:
    """Results of one gap case on three meshes."""

    name: str
    case: GapCase
    results: tuple[GapResult, GapResult, GapResult]
    ratio: float

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.results)

    @property
    def failures(self) -> list[str]:
        return [f"{lvl}: {r.status} ({r.message})" for lvl, r in zip(LEVELS, self.results,
                                                                     strict=True) if not r.ok]

    @property
    def richardson(self) -> Richardson | None:
        if not self.ok:
            return None
        return richardson([r.mass_flow_kg_s_m for r in self.results], self.ratio)

    @property
    def mass_flow_kg_s_m(self) -> float:
        """The extrapolated mass flow (nan for a failed study)."""
        rich = self.richardson
        return rich.extrapolated if rich else math.nan

    @property
    def default_error(self) -> float:
        """Default mesh against the extrapolated mass flow (relative)."""
        rich = self.richardson
        return rich.relative_errors()[1] if rich else math.nan

    def leakage_point(self) -> LeakagePoint | None:
        """The study as a point for comparisons and fits; None when it failed."""
        if not self.ok:
            return None
        flow = self.case.flow
        default = self.results[1]
        return LeakagePoint(
            name=self.name,
            gap_m=default.min_gap_m,
            length_m=default.gap_length_m,
            p_up_Pa=flow.p_total_Pa,
            T_up_K=flow.T_total_K,
            p_down_Pa=flow.p_exit_Pa,
            mu_Pa_s=flow.gas.mu(flow.T_total_K),
            R_J_kgK=flow.gas.R,
            gamma=flow.gas.gamma,
            wall_speed_m_s=0.5 * (flow.wall_speed_lower_m_s + flow.wall_speed_upper_m_s),
            mass_flow_kg_s_m=self.mass_flow_kg_s_m,
        )

    def summary(self) -> dict:
        rich = self.richardson
        return {
            "name": self.name,
            "ok": self.ok,
            "failures": self.failures,
            "mass_flow_kg_s_m": [r.mass_flow_kg_s_m for r in self.results],
            "cells": [r.cells for r in self.results],
            "run_time_s": [r.run_time_s for r in self.results],
            "imbalance": [r.imbalance for r in self.results],
            "kind": rich.kind if rich else "failed",
            "order": rich.order if rich else math.nan,
            "order_used": rich.order_used if rich else math.nan,
            "extrapolated_kg_s_m": self.mass_flow_kg_s_m,
            "default_error": self.default_error,
            "uncertainty": rich.uncertainty if rich else math.nan,
        }


def run_mesh_study(
    name: str,
    case: GapCase,
    root: Path,
    *,
    ratio: float = REFINEMENT_RATIO,
    progress: Callable[[str, float], None] | None = None,
) -> MeshStudy:
    """Run ``case`` on its coarse, default and fine meshes under ``root/name/``.

    Runs already stored with the same case key are reused.  ``progress`` receives the
    mesh level and its fraction done.
    """
    results = []
    for level, k in zip(LEVELS, (-1, 0, 1), strict=True):
        sub = case.refined(ratio**k)
        report = None if progress is None else (lambda f, lvl=level: progress(lvl, f))
        results.append(run_gap_case(sub, Path(root) / name / level, progress=report))
    study = MeshStudy(name, case, tuple(results), ratio)
    if study.ok:
        rich = study.richardson
        log.info("%s: %s, order %.2f, extrapolated %.5g kg/s/m, default mesh %+.2f%%",
                 name, rich.kind, rich.order, rich.extrapolated, 100 * study.default_error)
    else:
        log.warning("%s failed: %s", name, "; ".join(study.failures))
    return study


def run_matrix(
    cases: Sequence[tuple[str, GapCase]],
    root: Path,
    *,
    progress: Callable[[str, float], None] | None = None,
) -> list[MeshStudy]:
    """A mesh study per named case; computed cases are skipped (see run_mesh_study)."""
    studies = []
    for i, (name, case) in enumerate(cases):
        report = None
        if progress is not None:
            def report(level: str, f: float, i=i, name=name) -> None:
                progress(f"{name} ({level})", (i + (LEVELS.index(level) + f) / 3) / len(cases))
        studies.append(run_mesh_study(name, case, root, progress=report))
    return studies


# --- the leakage matrix -------------------------------------------------------------------

#: Default mesh of a rotor-tip gap: 20 cells across, 40 along each side of the throat,
#: end cells 20 times the throat cell.  With 16 across the viscous 5 um gaps came within
#: 1.2-1.8 % of the extrapolated mass flow (error ~ cells^-2): 20 leaves a margin under 2 %.
TIP_MESH = GapMeshSpec(cells_across=20, cells_along=40, along_grading=20.0)


@dataclass(frozen=True)
class MatrixPoint:
    """One point of the leakage matrix: a rotor-tip gap between two equal convex walls."""

    gap_um: float
    pressure_ratio: float
    radius_mm: float = 20.0
    wall_speed_m_s: float = 0.0
    """Speed of both walls along the flow (rolling rotor surfaces at the sealing line)."""
    p_exit_Pa: float = 1.0e5
    T_total_K: float = 300.0

    @property
    def name(self) -> str:
        return (f"g{self.gap_um:g}um-pr{self.pressure_ratio:g}-r{self.radius_mm:g}mm"
                f"-u{self.wall_speed_m_s:g}")

    def case(self, mesh: GapMeshSpec = TIP_MESH) -> GapCase:
        walls = rotor_tip_gap(self.gap_um * 1e-6, self.radius_mm * 1e-3)
        flow = GapFlow(p_total_Pa=self.pressure_ratio * self.p_exit_Pa, T_total_K=self.T_total_K,
                       p_exit_Pa=self.p_exit_Pa, wall_speed_lower_m_s=self.wall_speed_m_s,
                       wall_speed_upper_m_s=self.wall_speed_m_s)
        return GapCase(walls, flow, mesh)


def default_matrix() -> list[MatrixPoint]:
    """Gaps 5-200 um, pressure ratios 1.1 to choked, two wall radii (so that L/h varies
    apart from the gap), and a moving-wall subset."""
    points = [MatrixPoint(g, pr, r) for g in (5, 20, 50, 200) for pr in (1.1, 1.5, 2.5, 4.0)
              for r in (10, 40)]
    points += [MatrixPoint(g, pr, 20, 30.0) for g in (20, 50) for pr in (1.1, 2.5)]
    return points


def run_leakage_matrix(
    root: Path,
    points: Sequence[MatrixPoint] | None = None,
    *,
    progress: Callable[[str, float], None] | None = None,
) -> list[MeshStudy]:
    """Mesh studies of every matrix point under ``root`` (computed ones are reused)."""
    points = default_matrix() if points is None else points
    return run_matrix([(p.name, p.case()) for p in points], root, progress=progress)


# --- the workflow stage -------------------------------------------------------------------

#: Keys of the case file's [cfd] section (lists; each defaults to the default matrix's).
CFD_KEYS = ("gap_um", "pressure_ratio", "radius_mm", "wall_speed_m_s", "runs_dir")


def matrix_from_section(section: dict, where: str = "the case") -> list[MatrixPoint]:
    """The matrix a [cfd] section asks for: every combination of its lists.

    No list given: :func:`default_matrix`.  Unknown keys are a CaseError naming them.
    """
    unknown = sorted(set(section) - set(CFD_KEYS))
    if unknown:
        raise CaseError(f"unknown key(s) {', '.join(unknown)} in [cfd] of {where}")
    lists = {k: section[k] for k in CFD_KEYS[:4] if k in section}
    if not lists:
        return default_matrix()
    for key, values in lists.items():
        if not isinstance(values, list) or not values or not all(
                isinstance(v, int | float) and not isinstance(v, bool) for v in values):
            raise CaseError(f"key '{key}' in [cfd] of {where} must be a list of numbers")
    gaps = lists.get("gap_um", [5, 20, 50, 200])
    ratios = lists.get("pressure_ratio", [1.1, 1.5, 2.5, 4.0])
    radii = lists.get("radius_mm", [20.0])
    speeds = lists.get("wall_speed_m_s", [0.0])
    if min(gaps) <= 0 or min(radii) <= 0 or min(ratios) <= 1:
        raise CaseError(f"[cfd] of {where}: gaps and radii must be > 0, pressure ratios > 1")
    return [MatrixPoint(g, pr, r, u) for g in gaps for pr in ratios for r in radii
            for u in speeds]


def run_stage(ctx) -> dict:
    """Workflow stage ``cfd.leakage``: the leakage matrix, its comparison and fit.

    Writes into ``ctx.out``: ``studies.json`` (every mesh study, failed ones with their
    reasons), and through :func:`rotorflow.postprocess.leakage.write_report` the error
    table, the fitted flow coefficient (``flow_coefficient.json``) and its plot.  The runs
    live under ``[cfd] runs_dir`` (relative to the case file) when given, so that points
    already computed are reused when the stage reruns; else inside the stage's folder.
    """
    import json

    from rotorflow.postprocess import leakage

    section = ctx.raw.get("cfd", {})
    where = str(ctx.case_path)
    points = matrix_from_section(section, where)
    runs = Path(section["runs_dir"]) if "runs_dir" in section else ctx.out / "runs"
    if not runs.is_absolute():
        runs = Path(ctx.case_path).parent / runs
    studies = run_leakage_matrix(runs, points)
    (ctx.out / "studies.json").write_text(
        json.dumps([s.summary() for s in studies], indent=2, allow_nan=True) + "\n")
    good = [s.leakage_point() for s in studies if s.ok]
    try:
        models = leakage.quasi1d_models()
    except ImportError as exc:
        log.warning("quasi-1D leakage models unavailable, compared with the nozzle only: %s",
                    exc)
        models = {"nozzle": leakage.nozzle_model()}
    summary = leakage.write_report(good, ctx.out, models) if len(good) > 3 else {}
    return {"points": len(studies), "failed": sum(not s.ok for s in studies), **summary}
