"""The ``cfd.leakage`` workflow stage: a case file's [cfd] section as a leakage matrix
(:mod:`.gap_study`), run, compared with the quasi-1D leakage models and fitted."""

from __future__ import annotations

import logging
import math
from pathlib import Path

from rotorflow.errors import CaseError
from rotorflow.geometry.family import RotorPair

from .gap_study import (
    MatrixPoint,
    RotorMachine,
    SectionPoint,
    default_matrix,
    run_leakage_matrix,
)

log = logging.getLogger(__name__)


#: Keys of the case file's [cfd] section.  Lists, each defaulting to the default matrix's:
#: rotor-tip gaps for every gap_um x pressure_ratio x radius_mm x wall_speed_m_s, and
#: sealing-line sections for every rotor_gap_um x rotor_pressure_ratio x
#: rotor_angle_deg x moving_walls.  Tip gaps are made when radius_mm or wall_speed_m_s
#: is given or rotor_angle_deg is not; sections when rotor_angle_deg is given.
CFD_KEYS = ("gap_um", "pressure_ratio", "radius_mm", "wall_speed_m_s", "runs_dir",
            "rotor_angle_deg", "rotor_gap_um", "rotor_pressure_ratio", "moving_walls", "matrix")
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

    ``matrix = "default"``: :func:`default_matrix`; no list and no ``matrix``: an error.
    Unknown keys are a CaseError naming them.
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
    if "matrix" in section and (section["matrix"] != "default" or lists):
        raise CaseError(f"key 'matrix' in [cfd] of {where} takes \"default\" alone (the "
                        "built-in study); else give the lists of the matrix")
    if not lists:
        if section.get("matrix") != "default":
            # The built-in study is dozens of OpenFOAM runs (hours here): asked, not implied.
            raise CaseError(f"[cfd] of {where} asks for no runs: give gap_um and "
                            "pressure_ratio (tip gaps) or rotor_angle_deg (sealing-line "
                            "sections), or matrix = \"default\" for the built-in study")
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
        from rotorflow.geometry.summary import build_machine, case_power_split

        driven = case_power_split(case, build_machine(case)).driven
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
