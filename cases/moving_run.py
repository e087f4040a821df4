"""What a run of the section in motion produced, and the judge of it (issue 17).

:func:`judge` reads the tables :mod:`.moving_case` asks OpenFOAM to write every step and
accepts a run ("completed") that reached its end time with finite pressures, a largest
Courant number at most ``max_courant`` and a mass that stayed within ``mass_tol`` of its
start (closed) or of its start plus what its ports let through (:func:`mass_balance`);
otherwise it is "incomplete", "inconsistent", "diverged" or "crashed", kept with its log
tail and never used.  :func:`end_fields` reads a run's end state, the start of a run that
goes on from there.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rotorflow.errors import ExternalRunError
from rotorflow.postprocess.foam_output import function_object_table

from . import foam_case
from .foam_case import count_time_steps
from .machine_case import slot_name

if TYPE_CHECKING:  # the case writer's types: it imports this module
    from .moving_case import Built, RunControls

SOLVER = "rhoPimpleFoam"


@dataclass(frozen=True)
class MovingRun:
    """What a moving-section run produced.  Use only runs with :attr:`ok`."""

    status: str  # completed, incomplete, inconsistent, diverged or crashed
    message: str
    cells: int
    gap_cells: int
    end_time_s: float
    time_steps: int
    run_time_s: float
    mass_drift: float  # max |m(t) / m(0) - 1|
    max_gap_courant: float
    max_courant: float
    min_dt_s: float
    chamber_p: dict  # str(slot) -> [p at every step], Pa
    times_s: list
    interpolation: dict
    wall_velocity: dict
    log_tail: str = ""
    #: With ports: the mass flow into the domain through each port patch at every
    #: step (kg/s), and :func:`mass_balance`.
    port_flow: dict = field(default_factory=dict)
    mass_balance: float = math.nan

    @property
    def ok(self) -> bool:
        return self.status == "completed"

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1, allow_nan=True) + "\n"

    @classmethod
    def from_json(cls, text: str) -> MovingRun:
        return cls(**json.loads(text))


def _series(case_dir: Path, name: str, kind: str = "volFieldValue") -> np.ndarray:
    return function_object_table(case_dir, name, f"{kind}.dat")[1][:, :2]


def mass_balance(t: np.ndarray, mass: np.ndarray, inflow: np.ndarray) -> float:
    """Largest |m(t) - m(t1) - integral of the port inflow from t1 to t| / m(t1) over the
    run, t1 the first recorded step (the tables start after it).  The integral is
    rhoPimpleFoam's own: its Euler continuity equation changes a step's mass by the step
    times the inflow at the step's end, (rho V)^n - (rho V)^(n-1) = dt^n inflow^n, so
    the sum of dt^n inflow^n balances the table to the pressure equation's residual and
    the tables' 11 digits (5e-11 over the 2 deg test run).  The trapezoid would be off by
    dt (inflow(t1) - inflow(t)) / 2, bounded, not growing with the run, but 2.3e-4 of
    the mass on that run, whose inflow jumps from rest."""
    added = np.concatenate([[0.0], np.cumsum(inflow[1:] * np.diff(t))])
    return float(np.max(np.abs(mass - mass[0] - added)) / mass[0])


def judge(case_dir: Path, built: Built, controls: RunControls, elapsed: float,
          failure: str) -> MovingRun:
    """The run's result from its tables (see the module docstring)."""
    got: dict[str, Any] = {"end_time_s": math.nan, "mass_drift": math.nan,
                           "max_gap_courant": math.nan, "max_courant": math.nan,
                           "min_dt_s": math.nan, "chamber_p": {}, "times_s": []}
    outcome: tuple[str, str] | ExternalRunError
    try:
        mass = _series(case_dir, "mass")
        t = mass[:, 0]
        pressures = {str(c): _series(case_dir, f"p_{slot_name(c)}")[:, 1].tolist()
                     for c in built.chambers}
        dt = np.diff(np.concatenate([[0.0], t]))
        got = {"end_time_s": float(t[-1]),
               "mass_drift": float(np.max(np.abs(mass[:, 1] / mass[0, 1] - 1.0))),
               "max_gap_courant": float(_series(case_dir, "Co_gaps")[:, 1].max()),
               "max_courant": float(_series(case_dir, "Co_all")[:, 1].max()),
               "min_dt_s": float(dt.min()), "chamber_p": pressures, "times_s": t.tolist()}
        if built.ports:
            flows = {z: _series(case_dir, f"port_{z}", "surfaceFieldValue") for z in built.ports}
            if any(len(f) != len(t) or np.any(f[:, 0] != t) for f in flows.values()):
                raise ExternalRunError("the port flow tables do not match the mass table's "
                                       "time steps")
            # phi is outward: the inflow is its negative
            got["port_flow"] = {z: (-f[:, 1]).tolist() for z, f in flows.items()}
            got["mass_balance"] = mass_balance(t, mass[:, 1], -sum(f[:, 1] for f in
                                                                  flows.values()))
        check = "mass_balance" if built.ports else "mass_drift"
        values = np.concatenate([mass[:, 1], *map(np.asarray, pressures.values())])
        if not (np.all(np.isfinite(values)) and values.min() > 0.0):
            outcome = ("diverged", "non-finite or negative mass or pressure")
        elif t[-1] < built.duration * (1.0 - 1e-9):
            outcome = ("incomplete", f"stopped at {t[-1]:.6g} s of {built.duration:.6g} s")
        elif not got["max_courant"] <= controls.max_courant:
            outcome = ("inconsistent", f"Courant number {got['max_courant']:.3g} above "
                       f"{controls.max_courant:g}")
        elif not got[check] <= controls.mass_tol:
            outcome = ("inconsistent", f"mass of the {'ported' if built.ports else 'closed'}"
                       f" domain drifts by {got[check]:.2e}"
                       f"{' from its port flows' if built.ports else ''}, above "
                       f"{controls.mass_tol:g}")
        else:
            outcome = ("completed", "")
    except ExternalRunError as exc:
        outcome = exc
    v = foam_case.verdict(case_dir, SOLVER, failure, outcome, ok="completed")
    return MovingRun(
        status=v.status, message=v.message, cells=built.cells, gap_cells=built.gap_cells,
        time_steps=count_time_steps(case_dir / f"log.{SOLVER}"), run_time_s=elapsed,
        interpolation=built.interpolation, wall_velocity=built.wall_velocity,
        log_tail=v.log_tail, **got)


def end_fields(case_dir: Path) -> dict:
    """{"p", "T", "U"}: the cell values of a run's last written time (its end when it
    completed), the start state of a run that goes on from there."""
    from foamlib import FoamFieldFile

    from .moving_chambers import written_times

    _, folder = written_times(case_dir)[-1]
    out = {}
    for name in ("p", "T", "U"):
        v = FoamFieldFile(folder / name)["internalField"]
        out[name] = np.asarray(v, float)
    return out
