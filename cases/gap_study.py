"""Mesh studies and matrices of gap cases: three meshes per point, Richardson extrapolation.

A :class:`MeshStudy` runs one :class:`~rotorflow.cases.gap_case.GapCase` on the meshes
``refinement * ratio**k`` for k = -1, 0, 1 (coarse, default, fine), extrapolates the mass
flow with the observed order and says how far the default mesh is from it.  A study with
a failed run has no extrapolation and gives no :class:`LeakagePoint`: failed runs are
never used in a fit or a comparison.

The leakage matrix mixes two kinds of point: :class:`MatrixPoint`, a rotor-tip gap
between two equal convex walls, and :class:`SectionPoint`, the real gap at the sealing
line of the case's own rotors at a chosen outer-rotor angle, whose walls may slide at
the rotor surface speeds (the pair's gap sections, e.g.
:mod:`rotorflow.geometry.internal_gear.sealing_gap`).  Each point's name is its folder
under the runs directory: tip names start with ``g``, section names with
``seal-`` and a digest of the profile pair, so no two points ever share a folder.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rotorflow.errors import CaseError
from rotorflow.geometry.family import RotorPair
from rotorflow.postprocess.leakage import LeakagePoint
from rotorflow.postprocess.richardson import Richardson, richardson

from .gap_case import GapCase, GapFlow, GapResult, run_gap_case
from .gap_mesh import GapMeshSpec, GapWalls, rotor_tip_gap

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
            "wall_speeds_m_s": [self.case.flow.wall_speed_lower_m_s,
                                self.case.flow.wall_speed_upper_m_s],
            "min_gap_um": self.case.walls.min_gap * 1e6,
            "length_over_gap": self.results[1].gap_length_m / self.results[1].min_gap_m,
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

#: Default mesh of a gap at a sealing line of the rotors: that of the tip gaps, whose
#: throats have the same shape (two curved walls, locally parabolic).
SECTION_MESH = TIP_MESH

#: Where the matrix's gaps end downstream: where the walls have opened to this multiple of
#: the minimum gap, as the jet leaves them.  Farther on, the walls form a 2D diffuser whose
#: angle grows with the gap (16 deg included at 3 h for 200 um on 20 mm radii), where a
#: turbulent jet stalls on one wall or the other (the transitory and bistable stall of
#: Kline's diffuser map): a steady RANS solution then picks a branch by mesh, and the
#: three-mesh study has no observed order.  Cut at 3 h, the 200 um gap at PR 1.1 attached
#: up, down, down and central on meshes refined 0.5/1/2/4 (mass flow 0.02905 / 0.02950 /
#: 0.02872 / 0.02900 kg/s/m); at 2 h it still oscillates (0.02837 / 0.02840 /
#: 0.02774 / 0.02742); at 1.5 h it converges (0.02725 / 0.02719 / 0.02717 / 0.02719).
#: Pressure recovery past the cut belongs to the downstream chamber, as in the quasi-1D
#: nozzle, which discharges at the chamber pressure.
OUTLET_GAP_RATIO = 1.5


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
        walls = rotor_tip_gap(self.gap_um * 1e-6, self.radius_mm * 1e-3,
                              outlet_gap_ratio=OUTLET_GAP_RATIO)
        flow = GapFlow(p_total_Pa=self.pressure_ratio * self.p_exit_Pa, T_total_K=self.T_total_K,
                       p_exit_Pa=self.p_exit_Pa, wall_speed_lower_m_s=self.wall_speed_m_s,
                       wall_speed_upper_m_s=self.wall_speed_m_s)
        return GapCase(walls, flow, mesh)


@dataclass(frozen=True)
class RotorMachine:
    """The rotor pair that section points are cut from, and how fast it turns."""

    pair: RotorPair
    omega_outer_rad_s: float | None = None
    """Reference-rotor speed [rad/s] (counter-clockwise); None: unknown, no moving walls."""

    @property
    def tag(self) -> str:
        """A short digest of the profile pair: section points of different machines in
        one runs_dir never share a folder."""
        return self.pair.digest()


@dataclass(frozen=True)
class SectionPoint:
    """One point of the leakage matrix on the real gap at a sealing line of the rotors:
    the section of the pair's :meth:`~rotorflow.geometry.family.RotorPair.gap_walls` at outer-rotor
    angle ``rotor_angle_deg`` with the clearance ``gap_um`` on the outer rotor; with
    ``moving_walls`` the walls slide at the rotors' surface speeds relative to the
    contact (:meth:`~rotorflow.geometry.family.RotorPair.wall_speeds`)."""

    gap_um: float
    pressure_ratio: float
    rotor_angle_deg: float
    machine: RotorMachine
    moving_walls: bool = False
    p_exit_Pa: float = 1.0e5
    T_total_K: float = 300.0

    @property
    def outer_rpm(self) -> float:
        return (self.machine.omega_outer_rad_s or 0.0) * 30.0 / math.pi

    @property
    def name(self) -> str:
        motion = f"n{self.outer_rpm:.6g}rpm" if self.moving_walls else "static"
        return (f"seal-{self.machine.tag}-a{self.rotor_angle_deg:g}deg-g{self.gap_um:g}um"
                f"-pr{self.pressure_ratio:g}-{motion}")

    @property
    def wall_speeds_m_s(self) -> tuple[float, float]:
        """(lower = inner rotor, upper = outer rotor) speeds along the flow."""
        if not self.moving_walls:
            return 0.0, 0.0
        if self.machine.omega_outer_rad_s is None:
            raise CaseError("moving walls need the rotor speed ([operating] speed_rpm)")
        return self.machine.pair.wall_speeds(math.radians(self.rotor_angle_deg),
                                             self.machine.omega_outer_rad_s)

    def walls(self) -> GapWalls:
        lower, upper = self.machine.pair.gap_walls(math.radians(self.rotor_angle_deg),
                                                   self.gap_um * 1e-6,
                                                   outlet_ratio=OUTLET_GAP_RATIO)
        return GapWalls(lower, upper)

    def case(self, mesh: GapMeshSpec = SECTION_MESH) -> GapCase:
        lower, upper = self.wall_speeds_m_s
        flow = GapFlow(p_total_Pa=self.pressure_ratio * self.p_exit_Pa, T_total_K=self.T_total_K,
                       p_exit_Pa=self.p_exit_Pa, wall_speed_lower_m_s=lower,
                       wall_speed_upper_m_s=upper)
        return GapCase(self.walls(), flow, mesh)


def default_matrix() -> list[MatrixPoint]:
    """Gaps 5-200 um, pressure ratios 1.1 to choked, two wall radii (so that L/h varies
    apart from the gap), and a moving-wall subset."""
    points = [MatrixPoint(g, pr, r) for g in (5, 20, 50, 200) for pr in (1.1, 1.5, 2.5, 4.0)
              for r in (10, 40)]
    points += [MatrixPoint(g, pr, 20, 30.0) for g in (20, 50) for pr in (1.1, 2.5)]
    return points


def run_leakage_matrix(
    root: Path,
    points: Sequence[MatrixPoint | SectionPoint] | None = None,
    *,
    progress: Callable[[str, float], None] | None = None,
) -> list[MeshStudy]:
    """Mesh studies of every matrix point under ``root`` (computed ones are reused)."""
    points = default_matrix() if points is None else points
    return run_matrix([(p.name, p.case()) for p in points], root, progress=progress)


# --- the workflow stage -------------------------------------------------------------------

#: Keys of the case file's [cfd] section.  Lists, each defaulting to the default matrix's:
#: rotor-tip gaps for every gap_um x pressure_ratio x radius_mm x wall_speed_m_s, and
#: sealing-line sections for every rotor_gap_um x rotor_pressure_ratio x
#: rotor_angle_deg x moving_walls.  Tip gaps are made when radius_mm or wall_speed_m_s
#: is given or rotor_angle_deg is not; sections when rotor_angle_deg is given.
CFD_KEYS = ("gap_um", "pressure_ratio", "radius_mm", "wall_speed_m_s", "runs_dir",
            "rotor_angle_deg", "rotor_gap_um", "rotor_pressure_ratio", "moving_walls")
TIP_KEYS = ("gap_um", "pressure_ratio", "radius_mm", "wall_speed_m_s")
SECTION_KEYS = ("rotor_angle_deg", "rotor_gap_um", "rotor_pressure_ratio")


def _numbers(section: dict, key: str, where: str) -> list[float]:
    values = section[key]
    if not isinstance(values, list) or not values or not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in values):
        raise CaseError(f"key '{key}' in [cfd] of {where} must be a list of numbers")
    return values


def matrix_from_section(
    section: dict, where: str = "the case", machine: RotorMachine | None = None
) -> list[MatrixPoint | SectionPoint]:
    """The matrix a [cfd] section asks for: every combination of its lists.

    No list given: :func:`default_matrix`.  Unknown keys are a CaseError naming them.
    Section points (``rotor_angle_deg``) need ``machine``; their sections are cut here,
    so an angle where none exists is a CaseError naming it and the reason.
    """
    unknown = sorted(set(section) - set(CFD_KEYS))
    if unknown:
        raise CaseError(f"unknown key(s) {', '.join(unknown)} in [cfd] of {where}")
    lists = {k: _numbers(section, k, where) for k in TIP_KEYS + SECTION_KEYS if k in section}
    moving = section.get("moving_walls", False)
    moving = moving if isinstance(moving, list) else [moving]
    if not moving or not all(isinstance(m, bool) for m in moving):
        raise CaseError(f"key 'moving_walls' in [cfd] of {where} must be true, false or a "
                        "list of them")
    if "moving_walls" in section and "rotor_angle_deg" not in section:
        raise CaseError(f"key 'moving_walls' in [cfd] of {where} needs rotor_angle_deg "
                        "(tip gaps take wall_speed_m_s)")
    if not lists:
        return default_matrix()
    gaps = lists.get("gap_um", [5, 20, 50, 200])
    ratios = lists.get("pressure_ratio", [1.1, 1.5, 2.5, 4.0])
    radii = lists.get("radius_mm", [20.0])
    speeds = lists.get("wall_speed_m_s", [0.0])
    angles = lists.get("rotor_angle_deg", [])
    rotor_gaps = lists.get("rotor_gap_um", gaps)
    rotor_ratios = lists.get("rotor_pressure_ratio", ratios)
    if min(gaps + rotor_gaps) <= 0 or min(radii) <= 0 or min(ratios + rotor_ratios) <= 1:
        raise CaseError(f"[cfd] of {where}: gaps and radii must be > 0, pressure ratios > 1")
    if any(not 0.0 <= a < 360.0 for a in angles):
        raise CaseError(f"key 'rotor_angle_deg' in [cfd] of {where}: angles must lie in "
                        f"[0, 360), got {angles}")
    tips = not angles or "radius_mm" in section or "wall_speed_m_s" in section
    points: list[MatrixPoint | SectionPoint] = []
    if tips:
        points += [MatrixPoint(g, pr, r, u) for g in gaps for pr in ratios for r in radii
                   for u in speeds]
    if angles:
        if machine is None:
            raise CaseError(f"rotor_angle_deg in [cfd] of {where} needs the case's [machine]")
        if any(moving) and machine.omega_outer_rad_s is None:
            raise CaseError(f"moving_walls in [cfd] of {where} needs the rotor speed: "
                            "[operating] speed_rpm")
        for a in angles:
            for g in rotor_gaps:
                try:  # cut each section once: a bad angle is named before anything runs
                    machine.pair.gap_walls(math.radians(a), g * 1e-6)
                except CaseError as exc:
                    raise CaseError(f"rotor_angle_deg = {a:g} in [cfd] of {where}, gap "
                                    f"{g:g} um: {exc}") from None
        points += [SectionPoint(g, pr, a, machine, m) for a in angles for g in rotor_gaps
                   for pr in rotor_ratios for m in dict.fromkeys(moving)]
    return points


def validate_section(data: dict, where: str, pair: RotorPair | None) -> None:
    """Check a case file's [cfd] section when the case is loaded (nothing is run).

    Section points are cut from ``pair``; moving walls need [operating] speed_rpm, whose
    conversion to the outer-rotor speed (which may need the power split) waits for the
    stage, so a placeholder speed stands in for it here.
    """
    if not isinstance(data["cfd"], dict):
        raise CaseError(f"[cfd] in {where} must be a table")
    speed = data.get("operating", {}).get("speed_rpm")
    machine = None if pair is None else RotorMachine(pair, None if speed is None else 1.0)
    matrix_from_section(data["cfd"], where, machine)


def rotor_machine(case, *, with_speed: bool = True) -> RotorMachine:
    """The case's rotor pair and outer-rotor speed: [operating] speed_rpm is the speed of
    the driven rotor ([operating] driven; "auto" decides by the power split as the chamber
    table does); the outer rotor turns N2/N1 times as fast as a driven inner rotor."""
    speed = case.raw.get("operating", {}).get("speed_rpm")
    if speed is None or not with_speed:
        return RotorMachine(case.pair)
    driven = case.driven
    if driven == "auto":
        from rotorflow.geometry.forces import power_split
        from rotorflow.geometry.summary import build_machine

        driven = power_split(build_machine(case), case.volume_ratio).driven
    # the reference (outer) rotor turns N_driven / N_reference times as fast as the driven
    ratio = 1.0 / case.pair.rotor(driven).speed_ratio
    return RotorMachine(case.pair, float(speed) * ratio * math.pi / 30.0)


def run_stage(ctx) -> dict:
    """Workflow stage ``cfd.leakage``: the leakage matrix, its comparison and fit.

    Writes into ``ctx.out``: ``studies.json`` (every mesh study, failed ones with their
    reasons), and through :func:`rotorflow.postprocess.leakage_report.write_report` the error
    table, the fitted flow coefficient (``flow_coefficient.json``) and its plot.  The runs
    live under ``[cfd] runs_dir`` (relative to the case file) when given, so that points
    already computed are reused when the stage reruns; else inside the stage's folder.
    """
    import json

    from rotorflow.postprocess import leakage, leakage_report

    section = ctx.raw.get("cfd", {})
    where = str(ctx.case_path)
    machine = None
    if "rotor_angle_deg" in section:
        moving = section.get("moving_walls", False)
        machine = rotor_machine(ctx.case, with_speed=moving is True or (
            isinstance(moving, list) and any(moving)))
    points = matrix_from_section(section, where, machine)
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
    summary = leakage_report.write_report(good, ctx.out, models) if len(good) > 3 else {}
    return {"points": len(studies), "failed": sum(not s.ok for s in studies), **summary}
