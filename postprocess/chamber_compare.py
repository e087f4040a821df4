"""Chamber pressure against rotor angle: the CFD run of case B against the quasi-1D model.

Reads what :mod:`rotorflow.cases.chamber_case` makes OpenFOAM write (plain text and numpy,
so recorded outputs are tested without OpenFOAM), integrates the quasi-1D equations of the
same single closed chamber, and compares.

The quasi-1D chamber: one control volume of volume V(t) (the CFD's volume curve, linear
between its samples, as the piston table is), adiabatic, perfect gas, at rest at the
suction state at t = 0, leaking through a gap of flow area A = h x L_s into a plenum at
suction pressure and temperature.  With its mass m and internal energy U as state:

    dm/dt = -mdot,     dU/dt = -mdot h_up - p dV/dt,     p = (gamma - 1) U / V

where mdot = A sqrt(p_up rho_up) f(p_down / p_up) (times a coefficient) for the
quasi-1D model's leakage models (:mod:`rotorflow.quasi1d.flows`: isentropic nozzle,
isothermal Fanno flow), and mdot = L_s m'(point) for the CFD-calibrated correlation of
:mod:`rotorflow.quasi1d.calibrated` (a mass flow per metre of sealing line).  h_up is
the enthalpy of the side the gas comes from.  Time is angle over the outer rotor's speed.

Differences are p_model(theta) - p_CFD(theta) at the CFD's samples; "max" is the largest
magnitude, "RMS" the root mean square over the samples, both also relative to the CFD
pressure rise p_CFD(end) - p_suction, the figure the leakage changes.
"""

from __future__ import annotations

import csv
import functools
import json
import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import ExternalRunError

from .foam_output import function_object_table

log = logging.getLogger(__name__)

#: Mass flow out of the chamber (kg/s) as a function of the chamber's p (Pa) and T (K).
LeakFlow = Callable[[float, float], float]

#: Relative tolerance of the quasi-1D integration: far below any difference reported
#: (the sealed chamber then follows p V^gamma to ~1e-8).
ODE_RTOL = 1e-9

#: LSODA: the smoothed nozzle flux is stiff near equal pressures (at the start), the
#: rest of the compression is not; LSODA switches between the two regimes.
ODE_METHOD = "LSODA"


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

    def smooth_volume(self, angle_rad) -> np.ndarray:
        """The cubic spline through the samples: what the quasi-1D chamber integrates.

        It equals the linear curve at the samples and departs from it between them by
        ~V'' h^2 / 8, ~1e-7 of the volume for 0.1 deg samples; unlike the linear curve it
        has no kinks, which would make an adaptive integrator straddle one every step.
        """
        return self._spline(angle_rad)

    def smooth_dvdt(self, angle_rad) -> np.ndarray:
        return self._spline(angle_rad, 1) * self.omega_outer_rad_s


# --- the CFD history ----------------------------------------------------------------------


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
        from dataclasses import replace

        return replace(self, p_Pa=self.p_Pa * p_factor)


def _column(header: list[str], data: np.ndarray, needle: str, where: str) -> np.ndarray:
    for i, name in enumerate(header):
        if needle in name:
            return data[:, i]
    raise ExternalRunError(f"no column {needle} in {where} (columns: {', '.join(header)})")


def _table(case_dir: Path, name: str, file_name: str) -> tuple[list[str], np.ndarray]:
    return function_object_table(case_dir, name, file_name)


def read_history(case_dir: Path, curve: VolumeCurve,
                 dead_volume_m3: float | None = None) -> ChamberHistory:
    """Join the chamber run's function-object tables on their common sample times.

    ``dead_volume_m3``: the gap's volume upstream of its throat, excluded from the
    chamber zone; None: read from ``case_dir/case.json``.
    """
    case_dir = Path(case_dir)
    avg_h, avg = _table(case_dir, "chamberAverage", "volFieldValue.dat")
    int_h, integ = _table(case_dir, "chamberIntegral", "volFieldValue.dat")
    dom_h, dom = _table(case_dir, "domainMass", "volFieldValue.dat")
    tables = [avg, integ, dom]
    outlet = case_dir / "postProcessing" / "outletFlow"
    if outlet.is_dir():
        out_h, out = _table(case_dir, "outletFlow", "surfaceFieldValue.dat")
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


# --- the quasi-1D single chamber ----------------------------------------------------------


@dataclass(frozen=True)
class SingleChamber:
    """One closed chamber leaking into a plenum at the suction state."""

    curve: VolumeCurve
    p_suction_Pa: float
    T_suction_K: float
    R_J_kgK: float
    gamma: float

    @property
    def cv(self) -> float:
        return self.R_J_kgK / (self.gamma - 1.0)

    def adiabatic_pressure(self, angle_rad) -> np.ndarray:
        """The sealed chamber: p V^gamma constant from the suction state."""
        v0 = self.curve.volume_m3[0]
        return self.p_suction_Pa * (v0 / self.curve.volume(angle_rad)) ** self.gamma

    def simulate(self, leak: LeakFlow | None, angle_rad) -> dict[str, np.ndarray]:
        """p, T and m at the given angles, integrating from the suction state."""
        from scipy.integrate import solve_ivp

        c = self.curve
        v0 = float(c.volume_m3[0])
        m0 = self.p_suction_Pa * v0 / (self.R_J_kgK * self.T_suction_K)
        y0 = np.array([m0, m0 * self.cv * self.T_suction_K])
        cp = self.cv * self.gamma
        h_plenum = cp * self.T_suction_K

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            theta = float(c.angle_of(t))
            V = float(c.smooth_volume(theta))
            m, U = y
            p = (self.gamma - 1.0) * U / V
            T = U / (m * self.cv)
            mdot = 0.0 if leak is None else leak(p, T)
            h_up = cp * T if mdot >= 0 else h_plenum
            return np.array([-mdot, -mdot * h_up - p * float(c.smooth_dvdt(theta))])

        times = c.time_s(angle_rad)
        sol = solve_ivp(rhs, (0.0, float(times[-1])), y0, method=ODE_METHOD, t_eval=times,
                        rtol=ODE_RTOL, atol=[ODE_RTOL * m0, ODE_RTOL * y0[1]],
                        )
        if not sol.success:
            raise RuntimeError(f"single-chamber integration failed: {sol.message}")
        m, U = sol.y
        V = c.smooth_volume(angle_rad)
        return {"p_Pa": (self.gamma - 1.0) * U / V, "T_K": U / (m * self.cv), "m_kg": m}


def flux_leak(area_m2: float, chamber: SingleChamber, model: str, coefficient: float = 1.0,
              zeta: float = 2.0) -> LeakFlow:
    """The quasi-1D model's leakage (``"nozzle"`` or ``"fanno"``, rotorflow.quasi1d.flows)
    through ``area_m2`` times ``coefficient``, into the plenum at the suction state."""
    from rotorflow.quasi1d import flows

    x_choke = flows.fanno_choke_ratio(zeta) if model == "fanno" else 0.0
    ps = chamber.p_suction_Pa
    rho_s = ps / (chamber.R_J_kgK * chamber.T_suction_K)
    k = chamber.gamma
    cl = area_m2 * coefficient

    def leak(p: float, T: float) -> float:
        rho = p / (chamber.R_J_kgK * T)
        return cl * float(flows.signed_flux(p, rho, k, ps, rho_s, k, model, zeta, x_choke))

    return leak


def correlation_leak(fit, gap_m: float, gap_length_m: float, seal_length_m: float,
                     chamber: SingleChamber, mu: Callable[[float], float]) -> LeakFlow:
    """A fitted flow-coefficient correlation
    (:class:`~rotorflow.quasi1d.calibrated.FlowCoefficientFit`) as a leakage: its mass flow
    per metre times the sealing-line length; back flow from the plenum is the same law with
    the plenum upstream."""
    from .leakage import LeakagePoint

    model = fit.model()
    ps, Ts = chamber.p_suction_Pa, chamber.T_suction_K

    def per_metre(p_up: float, T_up: float, p_down: float) -> float:
        if p_up <= p_down * (1.0 + 1e-12):  # the correlation's X is 0/0 at PR = 1
            return 0.0
        point = LeakagePoint("chamber", gap_m, gap_length_m, p_up, T_up, p_down, mu(T_up),
                             chamber.R_J_kgK, chamber.gamma)
        return float(model(point))

    def leak(p: float, T: float) -> float:
        if p >= ps:
            return seal_length_m * per_metre(p, T, ps)
        return -seal_length_m * per_metre(ps, Ts, p)

    return leak


# --- comparison ---------------------------------------------------------------------------


@dataclass(frozen=True)
class PressureDifference:
    """p_model - p_CFD over the CFD's samples."""

    model: str
    max_abs_Pa: float
    rms_Pa: float
    mean_Pa: float
    max_rel_rise: float
    """max |difference| / (p_CFD(end) - p_suction)."""
    rms_rel_rise: float
    final_Pa: float
    """The difference at the last sample (discharge opening)."""


@dataclass(frozen=True)
class Comparison:
    """The CFD pressure and each model's at the CFD's samples."""

    angle_rad: np.ndarray
    p_cfd_Pa: np.ndarray
    predictions: Mapping[str, np.ndarray]
    p_suction_Pa: float
    references: Mapping[str, np.ndarray]
    """Curves drawn but not ranked (the sealed adiabatic chamber)."""

    def differences(self) -> list[PressureDifference]:
        rise = float(self.p_cfd_Pa[-1] - self.p_suction_Pa)
        out = []
        for name, p in self.predictions.items():
            d = p - self.p_cfd_Pa
            out.append(PressureDifference(
                name, float(np.max(np.abs(d))), float(np.sqrt(np.mean(d**2))),
                float(np.mean(d)), float(np.max(np.abs(d)) / rise),
                float(np.sqrt(np.mean(d**2)) / rise), float(d[-1])))
        return out

    @property
    def closest(self) -> str:
        """The model with the smallest RMS difference."""
        return min(self.differences(), key=lambda d: d.rms_Pa).model

    def summary(self) -> dict:
        return {
            "models": [asdict(d) for d in self.differences()],
            "closest_model": self.closest,
            "p_cfd_end_Pa": float(self.p_cfd_Pa[-1]),
            "p_suction_Pa": self.p_suction_Pa,
            "angle_start_deg": float(np.degrees(self.angle_rad[0])),
            "angle_end_deg": float(np.degrees(self.angle_rad[-1])),
            "samples": int(len(self.angle_rad)),
        }


def compare(history: ChamberHistory, chamber: SingleChamber,
            leaks: Mapping[str, LeakFlow]) -> Comparison:
    """Integrate the single chamber with each leakage model and compare with the CFD."""
    if not leaks:
        raise ValueError("no leakage models to compare")
    preds = {name: chamber.simulate(leak, history.angle_rad)["p_Pa"]
             for name, leak in leaks.items()}
    return Comparison(history.angle_rad, history.p_Pa, preds, chamber.p_suction_Pa,
                      {"sealed (p V^gamma const)": chamber.adiabatic_pressure(history.angle_rad)})


def write_comparison(comparison: Comparison, history: ChamberHistory, out_dir: Path,
                     checks: Mapping[str, float] | None = None) -> dict:
    """Write ``chamber_pressure.csv``, ``chamber_comparison.json`` and
    ``chamber_pressure.png`` into ``out_dir``; return the JSON's content."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    curves = {**comparison.predictions, **comparison.references}
    with (out_dir / "chamber_pressure.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["angle_deg", "time_s", "p_cfd_Pa", "T_cfd_K", "volume_cfd_m3",
                    *[f"p_{name}_Pa" for name in curves]])
        for i in range(len(comparison.angle_rad)):
            w.writerow([f"{math.degrees(comparison.angle_rad[i]):.6f}",
                        f"{history.time_s[i]:.9e}", f"{history.p_Pa[i]:.8g}",
                        f"{history.T_K[i]:.8g}", f"{history.volume_m3[i]:.8g}",
                        *[f"{curves[n][i]:.8g}" for n in curves]])
    summary = {**comparison.summary(), "checks": dict(checks or {})}
    text = json.dumps(summary, indent=2, allow_nan=True) + "\n"
    tmp = out_dir / "chamber_comparison.json.tmp"
    tmp.write_text(text)
    tmp.replace(out_dir / "chamber_comparison.json")
    plot_overlay(comparison, out_dir / "chamber_pressure.png")
    return summary


def plot_overlay(comparison: Comparison, path: Path) -> Path:
    """p against angle: CFD, each model, the sealed chamber; differences below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    deg = np.degrees(comparison.angle_rad)
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 1.4]})
    ax.plot(deg, comparison.p_cfd_Pa / 1e5, "k-", lw=2.2, label="CFD (rhoPimpleFoam)")
    for name, p in comparison.predictions.items():
        ax.plot(deg, p / 1e5, "--", lw=1.3, label=f"quasi-1D, {name}")
        ax2.plot(deg, (p - comparison.p_cfd_Pa) / 1e5, "--", lw=1.3, label=name)
    for name, p in comparison.references.items():
        ax.plot(deg, p / 1e5, ":", color="0.5", lw=1.2, label=name)
    ax.set_ylabel("chamber pressure (bar)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax2.axhline(0.0, color="k", lw=0.8)
    ax2.set_ylabel("model - CFD (bar)")
    ax2.set_xlabel("outer-rotor angle since chamber birth (deg)")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


# --- a finished run -----------------------------------------------------------------------


def volume_curve(desc: Mapping) -> VolumeCurve:
    """The volume curve of a run, from its ``case.json``."""
    return VolumeCurve(np.asarray(desc["angle_rad"], dtype=float),
                       np.asarray(desc["volume_m3"], dtype=float), float(desc["omega_outer_rad_s"]))


def single_chamber(desc: Mapping) -> SingleChamber:
    """The quasi-1D chamber of a run, from its ``case.json``."""
    return SingleChamber(volume_curve(desc), float(desc["p_suction_Pa"]),
                         float(desc["T_suction_K"]), float(desc["R_J_kgK"]),
                         float(desc["gamma"]))


def leak_models(desc: Mapping, leakage=None, fit=None) -> dict[str, LeakFlow | None]:
    """The leakage models compared with a run, named for the table.

    ``leakage``: the case's quasi-1D :class:`~rotorflow.quasi1d.Leakage` (None: its
    defaults).  Its coefficient applies to the model it names; the other model takes the
    quasi-1D default coefficient.  ``fit``: a fitted flow-coefficient correlation
    (:class:`~.leakage.FlowCoefficientFit`) or None.  A sealed run (gap 0) has the one
    model "sealed".
    """
    from rotorflow.quasi1d import Leakage

    if float(desc["gap_m"]) == 0.0:
        return {"sealed": None}
    chamber = single_chamber(desc)
    leakage = leakage or Leakage()
    default = Leakage()
    area = float(desc["gap_m"]) * float(desc["seal_length_m"])
    cd_nozzle = leakage.coefficient if leakage.model == "nozzle" else default.coefficient
    cd_fanno = leakage.coefficient if leakage.model == "fanno" else default.coefficient
    models: dict[str, LeakFlow | None] = {
        f"nozzle (Cd={cd_nozzle:g})": flux_leak(area, chamber, "nozzle", cd_nozzle),
        f"fanno (zeta={leakage.zeta:g}, Cd={cd_fanno:g})": flux_leak(
            area, chamber, "fanno", cd_fanno, leakage.zeta),
    }
    if fit is not None:
        from rotorflow.quasi1d.perfect_gas import PerfectGas

        models["cfd-calibrated"] = correlation_leak(
            fit, float(desc["gap_m"]), float(desc["gap_length_m"]),
            float(desc["seal_length_m"]), chamber, PerfectGas(**desc["gas"]).mu)
    return models


def compare_run(case_dir: Path, leakage=None, fit=None) -> tuple[ChamberHistory, Comparison]:
    """Read a finished chamber run and compare it with each leakage model."""
    case_dir = Path(case_dir)
    desc = json.loads((case_dir / "case.json").read_text())
    history = read_history(case_dir, volume_curve(desc))
    return history, compare(history, single_chamber(desc), leak_models(desc, leakage, fit))


def report_section(artifact: Path, report_dir: Path, case):
    """The ``cfd.chamber`` stage's part of the HTML report: the run's status and checks,
    the difference table and the p-angle overlay."""
    from rotorflow.postprocess.report import Section, esc, figure, table

    artifact = Path(artifact)
    body = []
    result_path = artifact / "chamber_result.json"
    result = json.loads(result_path.read_text()) if result_path.is_file() else {}
    if result and result.get("status") != "completed":
        body.append(f"<p class='warn'>The chamber run failed ({esc(result.get('status'))}: "
                    f"{esc(result.get('message'))}); it is not compared.</p>"
                    f"<pre>{esc(result.get('log_tail', ''))}</pre>")
    comparison = artifact / "chamber_comparison.json"
    if comparison.is_file():
        summary = json.loads(comparison.read_text())
        checks = summary.get("checks", {})
        body.append(
            f"<p>Chamber-averaged CFD pressure against the quasi-1D model of the same chamber "
            f"({summary['samples']} samples, {summary['angle_start_deg']:.1f} to "
            f"{summary['angle_end_deg']:.1f} deg); closest model: "
            f"<b>{esc(summary['closest_model'])}</b>.  Mass conservation "
            f"{checks.get('mass_error', math.nan):.1e}, volume "
            f"{checks.get('volume_error', math.nan):.1e} (relative).</p>")
        body.append(table(
            ["model", "max |dp| (Pa)", "RMS dp (Pa)", "mean dp (Pa)", "max / rise",
             "RMS / rise", "dp at end (Pa)"],
            [[m["model"], m["max_abs_Pa"], m["rms_Pa"], m["mean_Pa"], m["max_rel_rise"],
              m["rms_rel_rise"], m["final_Pa"]] for m in summary["models"]]))
    if (artifact / "chamber_pressure.png").is_file():
        name = "cfd_chamber_pressure.png"
        (Path(report_dir) / name).write_bytes((artifact / "chamber_pressure.png").read_bytes())
        body.append(figure(name, "Chamber pressure against rotor angle: CFD and quasi-1D"))
    return Section("CFD: chamber compressed while it leaks", "".join(body))
