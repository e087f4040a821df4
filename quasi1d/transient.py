"""One pass of the chamber equations from a given state, without cycle convergence.

:func:`~rotorflow.quasi1d.simulate` seeks the machine's periodic state: it integrates lobe
periods until the state at the start of one repeats.  :func:`simulate_transient`
integrates one lobe period once, from a state the caller gives (by default the model's
own start: the chambers of the no-leakage cycle, the one born at the period's start
taking the suction state), and reports the chambers at the angles asked for.  It is the
same model (:func:`~rotorflow.quasi1d.simulate.build_model`: the table, the operating
point, the declared leakage paths and the ports), the same right-hand side and the same
integrator (:func:`~rotorflow.quasi1d.integrate.integrate_period`); only the cycle
iteration is left out.

A one-chamber table makes it the transient of a single chamber: with ``lobes_outer`` 1
and a life shorter than a revolution the period holds the chamber's whole life, slot 0
from its birth (with the suction state) to its death.  This is how the CFD chamber
comparison runs the product's model (:mod:`rotorflow.postprocess.chamber_model`).

Output angles.  The integrator ends a step exactly at each angle asked for: the period's
segments are split there, which changes no equation (a split is not an event) but makes
the reported states integrated ones, not interpolated.  The state at an angle is the
state reached there, before any event at that angle; at the period's start it is the
state after the start's events (the birth).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from rotorflow.errors import CaseError

from .integrate import integrate_period
from .model import ChamberModel
from .settings import Leakage, Numerics, Operating, Ports
from .simulate import build_model

#: Angles closer than this fraction of the lobe period are one angle: a requested angle
#: that close to a segment's end does not split it (no step of zero length).
ANGLE_TOL = 1e-12


@dataclass(frozen=True)
class TransientResult:
    """The chambers at the requested angles (rows), per slot (columns).

    ``volume_m3``, ``p_Pa``, ``T_K``, ``m_kg``: NaN where a slot holds no chamber;
    ``y``: the integrated states (slot states, then the accumulators,
    :meth:`ChamberModel.acc`), one row per angle; ``model``: the equations integrated.
    """

    angle_rad: np.ndarray
    volume_m3: np.ndarray
    p_Pa: np.ndarray
    T_K: np.ndarray
    m_kg: np.ndarray
    y: np.ndarray = field(repr=False)
    model: ChamberModel = field(repr=False)
    method: str = ""
    n_rhs: int = 0


def simulate_transient(table, operating: Operating, angles_rad, leakage: Leakage | None = None,
                       ports: Ports | None = None, numerics: Numerics | None = None,
                       y0: np.ndarray | None = None) -> TransientResult:
    """Integrate one lobe period of the machine whose chamber is ``table`` once, from
    ``y0``, and report the chambers at ``angles_rad`` (outer-rotor angles within the
    period that starts at the chamber's birth).

    ``y0``: a state of the model (:attr:`ChamberModel.n_state` values, slot states then
    accumulators) at the period's start, before its events; None: the model's
    ``initial_state()``.  The defaults of the other arguments are
    :func:`~rotorflow.quasi1d.simulate`'s; ``numerics`` gives the integrator and its
    tolerances (its cycle settings do not apply).  Bad input raises CaseError, an
    integration that cannot proceed IntegrationError.
    """
    num = numerics or Numerics()
    model = build_model(table, operating, leakage, ports, num)
    geo = model.geo
    tol = ANGLE_TOL * geo.period
    start, end = geo.birth, geo.birth + geo.period
    angles = np.asarray(angles_rad, dtype=float)
    if angles.ndim != 1 or angles.size == 0 or not np.all(np.isfinite(angles)):
        raise CaseError("simulate_transient needs a non-empty list of finite angles")
    if np.any(angles < start - tol) or np.any(angles > end + tol):
        raise CaseError(f"output angles must lie within the lobe period from the birth, "
                        f"{start:.6g} to {end:.6g} rad")
    stops = np.clip(angles, start, end)
    y_start = model.initial_state() if y0 is None else np.array(y0, dtype=float)
    if y_start.shape != (model.n_state,):
        raise CaseError(f"y0 must hold the model's {model.n_state} state values")
    split = replace(model, segments=_split(model.segments, np.unique(stops), tol), cache={},
                    fast={})
    run = integrate_period(split, y_start[None, :], num.integrator, num.rtol,
                           num.atol * model.atol_scales(), record=True,
                           max_steps=num.max_steps)
    theta = np.asarray(run.trace_theta)
    ys = np.asarray(run.trace_y)
    rows = np.searchsorted(theta, stops - tol, side="left")  # the trace is in angle order
    if np.any(rows >= theta.size) or np.any(np.abs(theta[np.minimum(rows, theta.size - 1)]
                                                   - stops) > tol):
        raise RuntimeError("an output angle is missing from the integrator's trace")
    y = ys[rows]
    _, V, p, T, m = model.observe(stops, y)
    return TransientResult(angles, V, p, T, m, y, model, run.method, run.n_rhs)


def _split(segments, stops: np.ndarray, tol: float) -> tuple:
    """The segments cut at ``stops`` (their events stay with the first piece)."""
    out = []
    for seg in segments:
        cuts = stops[(stops > seg.start + tol) & (stops < seg.end - tol)]
        bounds = [seg.start, *cuts.tolist(), seg.end]
        for j, (a, b) in enumerate(zip(bounds[:-1], bounds[1:], strict=True)):
            out.append(replace(seg, start=a, end=b, events=seg.events if j == 0 else ()))
    return tuple(out)
