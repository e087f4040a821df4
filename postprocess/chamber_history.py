"""The CFD chamber run's history: what :mod:`rotorflow.cases.chamber_case` makes OpenFOAM
write, read with plain text and numpy (so recorded outputs are tested without OpenFOAM).

The chamber's volume curve (:class:`VolumeCurve`, the piston table's: linear between the
samples of ``case.json``) turns the solver's time into outer-rotor angle; the function
objects' tables (chamber averages and integrals, the domain's mass, the outlet's flow)
are joined on their common sample times (:func:`read_history`).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from rotorflow.errors import ExternalRunError

from .foam_output import function_object_table


@dataclass(frozen=True)
class VolumeCurve:
    """Chamber volume against outer-rotor angle, linear between samples."""

    angle_rad: np.ndarray
    volume_m3: np.ndarray
    omega_outer_rad_s: float

    def time_s(self, angle_rad) -> np.ndarray:
        return (np.asarray(angle_rad, dtype=float) - self.angle_rad[0]) / self.omega_outer_rad_s

    def angle_of(self, time_s) -> np.ndarray:
        return self.angle_rad[0] + np.asarray(time_s, dtype=float) * self.omega_outer_rad_s

    @property
    def duration_s(self) -> float:
        return float(self.time_s(self.angle_rad[-1]))

    def volume(self, angle_rad) -> np.ndarray:
        return np.interp(angle_rad, self.angle_rad, self.volume_m3)

    @functools.cached_property
    def _spline(self):
        from scipy.interpolate import CubicSpline

        return CubicSpline(self.angle_rad, self.volume_m3)

    def smooth_dvdangle(self, angle_rad) -> np.ndarray:
        """dV/dangle of the cubic spline through the samples (it equals the linear curve at
        the samples, departs from it by ~V'' h^2 / 8 between them, ~1e-7 of the volume for
        0.1 deg samples, and has no kinks for an adaptive integrator to straddle)."""
        return self._spline(angle_rad, 1)


@dataclass(frozen=True)
class ChamberHistory:
    """The CFD run's samples (one row per sample time)."""

    time_s: np.ndarray
    angle_rad: np.ndarray
    p_Pa: np.ndarray
    """Volume average of p over the chamber zone."""
    T_K: np.ndarray
    volume_m3: np.ndarray
    """Chamber zone volume (integral of p over average of p)."""
    prescribed_volume_m3: np.ndarray
    """What the zone's volume should be: V(t) less the gap's volume upstream of its throat."""
    mass_kg: np.ndarray
    """Mass in the chamber zone."""
    domain_mass_kg: np.ndarray
    """Mass in the whole domain (chamber and gap)."""
    outflow_kg_s: np.ndarray
    """Mass flow out through the outlet (zero for a sealed chamber)."""

    def outflow_integral(self) -> np.ndarray:
        """Mass that has left through the outlet since the first sample (trapezoids)."""
        dm = 0.5 * (self.outflow_kg_s[1:] + self.outflow_kg_s[:-1]) * np.diff(self.time_s)
        return np.concatenate([[0.0], np.cumsum(dm)])

    def mass_error(self) -> float:
        """max |m_domain(t) + outflow until t - m_domain(t0)| / m_domain(t0)."""
        m0 = self.domain_mass_kg[0]
        return float(np.max(np.abs(self.domain_mass_kg + self.outflow_integral() - m0)) / m0)

    def volume_error(self) -> float:
        return float(np.max(np.abs(self.volume_m3 / self.prescribed_volume_m3 - 1.0)))

    def shifted(self, p_factor: float = 1.0) -> ChamberHistory:
        """A copy with the pressure scaled (perturbed data for tests of the checks)."""
        return replace(self, p_Pa=self.p_Pa * p_factor)


def _column(header: list[str], data: np.ndarray, needle: str, where: str) -> np.ndarray:
    for i, name in enumerate(header):
        if needle in name:
            return data[:, i]
    raise ExternalRunError(f"no column {needle} in {where} (columns: {', '.join(header)})")


def read_history(case_dir: Path, curve: VolumeCurve,
                 dead_volume_m3: float | None = None) -> ChamberHistory:
    """Join the chamber run's function-object tables on their common sample times.

    ``dead_volume_m3``: the gap's volume upstream of its throat, excluded from the
    chamber zone; None: read from ``case_dir/case.json``.
    """
    case_dir = Path(case_dir)
    avg_h, avg = function_object_table(case_dir, "chamberAverage", "volFieldValue.dat")
    int_h, integ = function_object_table(case_dir, "chamberIntegral", "volFieldValue.dat")
    dom_h, dom = function_object_table(case_dir, "domainMass", "volFieldValue.dat")
    tables = [avg, integ, dom]
    outlet = case_dir / "postProcessing" / "outletFlow"
    if outlet.is_dir():
        out_h, out = function_object_table(case_dir, "outletFlow", "surfaceFieldValue.dat")
        tables.append(out)
    common = tables[0][:, 0]
    for t in tables[1:]:
        common = np.intersect1d(common, t[:, 0])
    if len(common) < 2:
        raise ExternalRunError(f"chamber tables in {case_dir} share fewer than two samples")

    if dead_volume_m3 is None:
        desc = json.loads((case_dir / "case.json").read_text())
        dead_volume_m3 = desc["upstream_gap_area_m2"] * desc["depth_m"]

    def rows(t: np.ndarray) -> np.ndarray:
        return t[np.searchsorted(t[:, 0], common)]

    avg, integ, dom = rows(avg), rows(integ), rows(dom)
    p = _column(avg_h, avg, "(p)", "chamberAverage")
    p_int = _column(int_h, integ, "(p)", "chamberIntegral")
    angle = curve.angle_of(common)
    flow = (_column(out_h, rows(out), "(phi)", "outletFlow") if len(tables) == 4
            else np.zeros_like(common))
    return ChamberHistory(
        time_s=common,
        angle_rad=angle,
        p_Pa=p,
        T_K=_column(avg_h, avg, "(T)", "chamberAverage"),
        volume_m3=p_int / p,
        prescribed_volume_m3=curve.volume(angle) - dead_volume_m3,
        mass_kg=_column(int_h, integ, "(rho)", "chamberIntegral"),
        domain_mass_kg=_column(dom_h, dom, "(rho)", "domainMass"),
        outflow_kg_s=flow,
    )


def volume_curve(desc: Mapping) -> VolumeCurve:
    """The volume curve of a run, from its ``case.json``."""
    return VolumeCurve(np.asarray(desc["angle_rad"], dtype=float),
                       np.asarray(desc["volume_m3"], dtype=float), float(desc["omega_outer_rad_s"]))
