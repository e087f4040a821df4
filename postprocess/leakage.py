"""Leakage through a clearance gap: CFD against quasi-1D models, and the fit of the flow
coefficient.

Every model is a callable ``model(point) -> mass flow per metre of gap depth (kg/s/m)``,
so the comparison does not depend on where a model lives: the reference formulas here,
rotorflow.quasi1d's leakage models through :func:`quasi1d_models`, or the fitted
correlation (:meth:`~rotorflow.quasi1d.calibrated.FlowCoefficientFit.model`).

The correlation itself, its definitions (pressure ratio, ideal flow, Cd, Re, wall speed
ratio, ...) and its JSON file belong to the quasi-1D model that evaluates it
(:mod:`rotorflow.quasi1d.calibrated`); here are the CFD points, the comparison and the
least-squares fit.  The report of the ``cfd.leakage`` stage is
:mod:`rotorflow.postprocess.leakage_report`.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from rotorflow.quasi1d.calibrated import (
    DEFAULT_INERTIAL,
    INERTIAL_FEATURES,
    FlowCoefficientFit,
    couette_parameter,
    viscous_parameter,
)
from rotorflow.quasi1d.flows import isentropic_mass_flux

Model = Callable[["LeakagePoint"], float]


@dataclass(frozen=True)
class LeakagePoint:
    """One operating point of a gap, with its CFD mass flow when known, and the perfect
    gas of the point (R, gamma; :class:`rotorflow.quasi1d.perfect_gas.PerfectGas`)."""

    name: str
    gap_m: float
    length_m: float
    p_up_Pa: float
    T_up_K: float
    p_down_Pa: float
    mu_Pa_s: float
    """Viscosity at T_up."""
    R_J_kgK: float
    gamma: float
    wall_speed_m_s: float = 0.0
    mass_flow_kg_s_m: float = math.nan
    """CFD mass flow per metre of depth (Richardson-extrapolated where available)."""

    @property
    def pressure_ratio(self) -> float:
        return self.p_up_Pa / self.p_down_Pa

    @property
    def length_over_gap(self) -> float:
        return self.length_m / self.gap_m

    @property
    def ideal_mass_flow(self) -> float:
        return self.gap_m * isentropic_mass_flux(self.p_up_Pa, self.T_up_K, self.p_down_Pa,
                                                 self.gamma, self.R_J_kgK)

    @property
    def reynolds(self) -> float:
        return self.ideal_mass_flow / self.mu_Pa_s

    @property
    def flow_coefficient(self) -> float:
        return self.mass_flow_kg_s_m / self.ideal_mass_flow

    @property
    def wall_speed_ratio(self) -> float:
        """V = U sqrt(rho_up / p_up): the wall speed over sqrt(R T_up)."""
        return self.wall_speed_m_s / math.sqrt(self.R_J_kgK * self.T_up_K)

    @property
    def couette_parameter(self) -> float:
        """W = rho_c U h / m_id (see the definitions in rotorflow.quasi1d.calibrated)."""
        return float(couette_parameter(self.wall_speed_ratio, self.pressure_ratio, self.gamma))


# --- reference formulas -------------------------------------------------------------------


def plane_poiseuille_mass_flow(point: LeakagePoint) -> float:
    """Isothermal, fully developed laminar flow between parallel plates (per metre depth):
    m' = h^3 (p_up^2 - p_down^2) / (24 mu R T L), the compressible form of
    m' = rho h^3 dp / (12 mu L) with rho varying along the channel as p does."""
    p = point
    return p.gap_m**3 * (p.p_up_Pa**2 - p.p_down_Pa**2) / (
        24 * p.mu_Pa_s * p.R_J_kgK * p.T_up_K * p.length_m
    )


def nozzle_model(coefficient: float = 1.0) -> Model:
    """The isentropic nozzle through the minimum gap times ``coefficient``."""
    return lambda p: coefficient * p.ideal_mass_flow


def quasi1d_models(coefficient: float | None = None, zeta: float | None = None) -> dict[str, Model]:
    """rotorflow.quasi1d's leakage models as callables, with its default parameters.

    Uses ``rotorflow.quasi1d.flows`` (``nozzle_f``, ``fanno_f``, ``fanno_choke_ratio``)
    and the defaults of ``rotorflow.quasi1d.Leakage``; raises ImportError naming what is
    missing when that module does not provide them.
    """
    try:
        from rotorflow.quasi1d import Leakage, flows
    except ImportError as exc:  # pragma: no cover - depends on the other package's state
        raise ImportError(f"rotorflow.quasi1d leakage models unavailable: {exc}") from exc
    missing = [n for n in ("nozzle_f", "fanno_f", "fanno_choke_ratio") if not hasattr(flows, n)]
    if missing:
        raise ImportError(f"rotorflow.quasi1d.flows lacks {', '.join(missing)}")
    defaults = Leakage()
    cd = defaults.coefficient if coefficient is None else coefficient
    z = defaults.zeta if zeta is None else zeta
    x_choke = flows.fanno_choke_ratio(z)

    def scale(p: LeakagePoint) -> float:  # gap * sqrt(p1 rho1), rho1 at the upstream state
        return cd * p.gap_m * math.sqrt(p.p_up_Pa * p.p_up_Pa / (p.R_J_kgK * p.T_up_K))

    def nozzle(p: LeakagePoint) -> float:
        return scale(p) * float(flows.nozzle_f(1.0 / p.pressure_ratio, p.gamma))

    def fanno(p: LeakagePoint) -> float:
        return scale(p) * float(flows.fanno_f(1.0 / p.pressure_ratio, z, x_choke))

    return {"quasi1d-nozzle": nozzle, f"quasi1d-fanno(zeta={z:g})": fanno}



# --- comparison ---------------------------------------------------------------------------


@dataclass(frozen=True)
class ModelSummary:
    model: str
    max_abs_error: float
    rms_error: float
    mean_error: float


@dataclass(frozen=True)
class ComparisonTable:
    """CFD mass flow against each model: ``errors[model][i]`` = model / CFD - 1."""

    points: tuple[LeakagePoint, ...]
    predictions: Mapping[str, np.ndarray]
    errors: Mapping[str, np.ndarray]

    def summary(self) -> list[ModelSummary]:
        out = []
        for name, err in self.errors.items():
            out.append(ModelSummary(name, float(np.max(np.abs(err))),
                                    float(np.sqrt(np.mean(err**2))), float(np.mean(err))))
        return out

    def rows(self) -> list[dict[str, float | str]]:
        rows = []
        for i, p in enumerate(self.points):
            row: dict[str, float | str] = {
                "point": p.name,
                "gap_um": p.gap_m * 1e6,
                "L_over_h": p.length_over_gap,
                "pressure_ratio": p.pressure_ratio,
                "wall_speed_m_s": p.wall_speed_m_s,
                "reynolds": p.reynolds,
                "cfd_kg_s_m": p.mass_flow_kg_s_m,
                "cfd_Cd": p.flow_coefficient,
            }
            for name in self.predictions:
                row[f"{name}_kg_s_m"] = float(self.predictions[name][i])
                row[f"{name}_error"] = float(self.errors[name][i])
            rows.append(row)
        return rows

    def write_csv(self, path: Path) -> Path:
        rows = self.rows()
        path = Path(path)
        with path.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        return path

    def markdown(self) -> str:
        """The summary as a Markdown table (one row per model)."""
        lines = ["| model | max abs error | RMS error | mean error |", "| --- | --- | --- | --- |"]
        for s in self.summary():
            lines.append(f"| {s.model} | {s.max_abs_error:.1%} | {s.rms_error:.1%} | "
                         f"{s.mean_error:+.1%} |")
        return "\n".join(lines) + "\n"


def compare(points: Sequence[LeakagePoint], models: Mapping[str, Model]) -> ComparisonTable:
    """Evaluate every model at every point with a finite, positive CFD mass flow."""
    pts = tuple(points)
    if not pts:
        raise ValueError("no leakage points to compare")
    bad = [p.name for p in pts if not (math.isfinite(p.mass_flow_kg_s_m) and
                                       p.mass_flow_kg_s_m > 0)]
    if bad:
        raise ValueError(f"points without a valid CFD mass flow: {', '.join(bad)}")
    cfd = np.array([p.mass_flow_kg_s_m for p in pts])
    preds = {name: np.array([float(m(p)) for p in pts]) for name, m in models.items()}
    return ComparisonTable(pts, preds, {name: v / cfd - 1.0 for name, v in preds.items()})


def mismatches(
    measured: Mapping[str, float], reference: Mapping[str, float], rtol: float
) -> list[str]:
    """Names (with values) where ``measured`` differs from ``reference`` by more than rtol,
    or is missing or non-finite; an empty list means agreement."""
    out = []
    for name, ref in reference.items():
        val = measured.get(name, math.nan)
        if not math.isfinite(val) or abs(val - ref) > rtol * abs(ref):
            out.append(f"{name}: {val:.6g} against {ref:.6g} (rtol {rtol:g})")
    return out


# --- fit ----------------------------------------------------------------------------------
#
# The form A Cd|Cd| + b X (Cd - w W) = 1 and why it is linear in its coefficients:
# rotorflow.quasi1d.calibrated.

def _solve(points: Sequence[LeakagePoint], features: Sequence[str], gamma: float,
           wall: bool) -> FlowCoefficientFit:
    pr = np.array([p.pressure_ratio for p in points])
    cd = np.array([p.flow_coefficient for p in points])
    x = viscous_parameter([p.reynolds for p in points], pr,
                          [p.length_over_gap for p in points], gamma)
    # Residual A Cd|Cd| + b X Cd - bw X W - 1 changes by (1 + A Cd^2) dCd/Cd, between one
    # and two times the relative error of Cd: plain least squares weighs points evenly.
    columns = [cd * np.abs(cd) * INERTIAL_FEATURES[f](pr) for f in features] + [x * cd]
    if wall:
        columns.append(-x * np.array([p.couette_parameter for p in points]))
    coef, *_ = np.linalg.lstsq(np.column_stack(columns), np.ones(len(points)), rcond=None)
    n = len(features)
    b = float(coef[n])
    # A column of zeros (no moving wall left in a leave-one-out fit) gets a zero
    # coefficient from lstsq: w = 0, the static form.
    w = float(coef[n + 1]) / b if wall and b != 0.0 else 0.0
    return FlowCoefficientFit(tuple(features), tuple(float(c) for c in coef[:n]), b, gamma,
                              wall=w)


def fit_flow_coefficient(
    points: Sequence[LeakagePoint],
    features: Sequence[str] = DEFAULT_INERTIAL,
    *,
    wall: bool | None = None,
) -> FlowCoefficientFit:
    """Least-squares fit of the series-resistance form, with leave-one-out errors.

    ``wall``: fit the wall-drag coefficient w (default: when any point has moving walls;
    False fits the static form to every point, as the correlation did before).
    """
    pts = [p for p in points if math.isfinite(p.mass_flow_kg_s_m) and p.mass_flow_kg_s_m > 0]
    moving = [p.wall_speed_m_s != 0 for p in pts]
    wall = any(moving) if wall is None else wall
    n_coef = len(features) + 1 + int(wall)
    if len(pts) < n_coef + 1:
        raise ValueError(f"{len(pts)} valid points cannot fit {n_coef} coefficients "
                         "and leave one out")
    gammas = {p.gamma for p in pts}
    if len(gammas) != 1:
        raise ValueError("all points of a fit must share one gas (gamma)")
    gamma = gammas.pop()
    fit = _solve(pts, tuple(features), gamma, wall)
    loo = []
    for i, p in enumerate(pts):
        pred = _solve(pts[:i] + pts[i + 1 :], tuple(features), gamma, wall).model()(p)
        loo.append(pred / p.mass_flow_kg_s_m - 1.0)

    def span(values) -> tuple[float, float]:
        values = list(values)
        return (float(min(values)), float(max(values)))

    return replace(
        fit,
        ranges={
            "reynolds": span(p.reynolds for p in pts),
            "pressure_ratio": span(p.pressure_ratio for p in pts),
            "length_over_gap": span(p.length_over_gap for p in pts),
            "wall_speed_ratio": span(p.wall_speed_ratio for p in pts),
        },
        leave_out_errors=tuple(float(e) for e in loo),
        leave_out_moving=tuple(moving),
    )


