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
from .gap_mesh import GapMeshSpec
from .gap_walls import GapWalls, rotor_tip_gap

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
