"""What a simulation hands back: the figures, the traces, the plots."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .cycle import CycleSolution
from .events import trapped_liquid
from .performance import figures


@dataclass(frozen=True)
class SimulationResult:
    """A converged (or stopped) cycle of the chamber model.

    ``figures`` holds the performance figures (see :mod:`.performance`); ``machine`` holds
    the traces over one lobe period: ``theta_rad`` (outer-rotor angle) and per slot arrays
    ``volume_m3``, ``p_Pa``, ``T_K``, ``m_kg`` of shape (angles, slots); ``chamber`` holds
    one chamber's life from birth to death (the slots' traces joined by age);
    ``loads`` the rotors' gas loads over the period (:class:`.loads.GasLoads`, None when
    the chamber table has no load columns).
    """

    figures: dict
    machine: dict = field(repr=False)
    chamber: dict = field(repr=False)
    solution: CycleSolution = field(repr=False)
    loads: object = field(default=None, repr=False)

    @property
    def converged(self) -> bool:
        return bool(self.figures["converged"])

    def summary(self) -> dict:
        """The figures as a JSON-ready dict (floats, ints, None, nested dicts)."""
        return dict(self.figures)

    def write_traces(self, folder) -> list[Path]:
        """Write chamber_cycle.csv (one chamber, birth to death) and chambers.csv (every
        slot against the outer-rotor angle over one lobe period); returns the paths."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        c = self.chamber
        one = folder / "chamber_cycle.csv"
        np.savetxt(one, np.column_stack([c["angle_rad"], c["volume_m3"], c["p_Pa"], c["T_K"],
                                         c["m_kg"]]),
                   delimiter=",", header="angle_rad,volume_m3,p_Pa,T_K,m_kg", comments="",
                   fmt="%.10e")
        m = self.machine
        n = m["p_Pa"].shape[1]
        head = ["theta_rad"] + [f"{q}_{k}" for k in range(n)
                                for q in ("volume_m3", "p_Pa", "T_K", "m_kg")]
        cols = [m["theta_rad"]]
        for k in range(n):
            cols += [m["volume_m3"][:, k], m["p_Pa"][:, k], m["T_K"][:, k], m["m_kg"][:, k]]
        allp = folder / "chambers.csv"
        np.savetxt(allp, np.column_stack(cols), delimiter=",", header=",".join(head),
                   comments="", fmt="%.10e")
        return [one, allp]

    def plot(self, folder, stem: str = "quasi1d") -> list[Path]:
        """p against angle and p against V of one chamber, as PNG files."""
        return plot_cycle(self, Path(folder), stem)


def traces(sol: CycleSolution):
    """Machine traces over the period and one chamber's life from the recorded states."""
    model = sol.model
    th = np.asarray(sol.run.trace_theta)
    ys = np.asarray(sol.run.trace_y)
    order = np.argsort(th, kind="stable")
    th, ys = th[order], ys[order]
    ages, V, p, T, m = model.observe(th, ys)
    machine = {"theta_rad": th, "volume_m3": V, "p_Pa": p, "T_K": T, "m_kg": m}
    live = np.isfinite(p)
    a = ages[live]
    order = np.argsort(a, kind="stable")
    chamber = {"angle_rad": a[order], "volume_m3": V[live][order], "p_Pa": p[live][order],
               "T_K": T[live][order], "m_kg": m[live][order]}
    return machine, chamber


#: A chamber pressure above this multiple of the larger of the discharge pressure and
#: the built-in one (suction compressed isentropically to the discharge opening) is
#: warned of: the discharge port does not empty the chamber (a radial port alone on a
#: 4/6 at volume ratio 6 squeezed it to 62.6 bar against 4 bar).
OVERPRESSURE = 2.0
#: The delivered gas is what the chambers pushed out less what flowed back from the
#: discharge plenum, which holds a fixed state (:mod:`.plenums`).  Where that backflow is
#: large against the delivery, the delivered temperature is the fixed state's artefact,
#: not the gas's: -687 K on the trochoidal pump example, -20557 K on the vacuum pump at
#: 1 mbar, 682 K against its chambers' 643 K at 0.11 bar (11 % of their range above it).
#: Outside the chambers' range by more than this share of it, it comes with a warning;
#: the shipped compressors lie within 2.3 % (the traces are samples, and the fixed state
#: biases their small backflow too: 1.6 K on the R290 internal gear), a leakier internal
#: gear (eta_v 0.52) 6.7 %, the vacuum and involute pump examples 11 %.
DISCHARGE_T_SLACK = 0.05
#: Beyond this share it is not reported (None): no delivered gas is that far from its
#: chambers (the trochoidal's is 2.0 of their range below them).
DISCHARGE_T_ABSURD = 1.0
#: Figures of the delivered state, undefined together.
DISCHARGE_STATE_FIGURES = ("discharge_temperature_K", "discharge_mixture_temperature_K",
                           "discharge_quality", "discharge_vapour_fraction")


def make_result(sol: CycleSolution) -> SimulationResult:
    machine, chamber = traces(sol)
    return SimulationResult(_extremes(figures(sol), chamber, sol.model), machine, chamber,
                            sol)


def _gas_volume_ratio(model) -> float:
    """The gas's own built-in volume ratio: a liquid drawn in or oil injected keeps its
    volume, so the gas is squeezed further than the chamber (inf: no room left)."""
    geo = model.geo
    liquid = trapped_liquid(model) * model.inv_rho_liquid if model.oil else 0.0
    room = geo.v_discharge - liquid
    return (geo.v_trapped - liquid) / room if room > 0.0 else math.inf


def _extremes(fig: dict, chamber: dict, model) -> dict:
    """The chamber's highest pressure and temperature over its life, and warnings where
    the result is not a working machine's or lies beyond the fluid's model."""
    p, T = chamber["p_Pa"], chamber["T_K"]
    if len(p):
        fig = {**fig, "chamber_pressure_max_Pa": float(np.max(p)),
               "chamber_temperature_max_K": float(np.max(T))}
    else:
        p = T = np.zeros(1)  # (no trace: nothing to warn of but the delivery)
    suc = model.suc
    built_in = suc.p * _gas_volume_ratio(model) ** suc.kappa
    warn = []
    if not fig["mass_flow_kg_s"] > 0.0:
        warn.append("no delivery: the net flow runs from the discharge to the suction "
                    "(leakage and backflow exceed what the chambers carry)")
    limit = OVERPRESSURE * max(model.dis.p, built_in)
    if np.max(p) > limit:
        warn.append(f"the chamber reaches {np.max(p) / 1e5:.4g} bar, over {OVERPRESSURE:g} "
                    f"times the larger of the discharge and the built-in pressure "
                    f"({max(model.dis.p, built_in) / 1e5:.4g} bar): its discharge port does "
                    f"not empty it")
    T_dis = fig.get("discharge_temperature_K")
    if T_dis is not None and len(chamber["T_K"]):
        lo, hi = float(np.min(T)), float(np.max(T))
        out = max(lo - T_dis, T_dis - hi) / (hi - lo) if hi > lo else 0.0
        if out > DISCHARGE_T_SLACK:
            warn.append(_discharge_T_warning(T_dis, lo, hi, model, out > DISCHARGE_T_ABSURD))
        if out > DISCHARGE_T_ABSURD:
            fig = {**fig, **{k: None for k in DISCHARGE_STATE_FIGURES if k in fig}}
    t_fit = getattr(model.fluid, "T_fitted_max", None)
    if t_fit is not None and np.max(T) > t_fit:
        warn.append(f"the gas reaches {np.max(T):.0f} K, above the {t_fit:.0f} K its "
                    f"properties were fitted to")
    if warn:
        fig["warning"] = "; ".join(warn)
    return fig


def _discharge_T_warning(T_dis, lo, hi, model, dropped: bool) -> str:
    """The warning for a delivered gas's temperature outside every chamber's."""
    told = "is not reported" if dropped else "is not the gas's"
    return (f"the delivered gas's temperature ({T_dis:.0f} K) lies outside the chambers' "
            f"({lo:.0f}-{hi:.0f} K) and {told}: the gas flowing back from the "
            f"discharge is held at the plenum's fixed {model.dis.T:.0f} K, and where that "
            f"backflow is large against the delivery (vacuum pumps) the delivered enthalpy, "
            f"their difference, is not the delivered gas's ([ports] discharge_plenum = "
            f"\"delivered\" holds it at the delivered gas's own, for a dry gas)")


def plot_cycle(result: SimulationResult, folder: Path, stem: str = "quasi1d") -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    c = result.chamber
    geo = result.solution.model.geo
    op = result.solution.model.op
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.plot(np.degrees(c["angle_rad"]), c["p_Pa"] / 1e5, lw=1.4)
    marks = ((geo.suction_close, "suction closes"), (geo.discharge_open, "discharge opens"))
    for ang, lab in marks:
        ax.axvline(math.degrees(ang), color="0.6", ls="--", lw=0.8)
        ax.text(math.degrees(ang), ax.get_ylim()[1], lab, rotation=90, va="top", ha="right",
                fontsize=7, color="0.4")
    ax.axhline(op.p_discharge_Pa / 1e5, color="C3", lw=0.6, ls=":")
    ax.axhline(op.p_suction_Pa / 1e5, color="C2", lw=0.6, ls=":")
    ax.set_xlabel("outer-rotor angle since chamber birth [deg]")
    ax.set_ylabel("chamber pressure [bar]")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    p1 = folder / f"{stem}_p_angle.png"
    fig.savefig(p1, dpi=120)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.plot(c["volume_m3"] * 1e6, c["p_Pa"] / 1e5, lw=1.4)
    ax.set_xlabel("chamber volume [cm$^3$]")
    ax.set_ylabel("chamber pressure [bar]")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    p2 = folder / f"{stem}_p_V.png"
    fig.savefig(p2, dpi=120)
    plt.close(fig)
    return [p1, p2]
