"""The chamber model's leakage network at a frozen rotor angle: steady chamber pressures.

A steady CFD run of the machine at one rotor angle (issue 16) holds every chamber's volume
fixed: the chambers open to a port take that plenum's pressure, and each closed chamber
settles where the leakage into it balances the leakage out.  This module puts the
product's own model (:class:`.model.ChamberModel`: its paths, gaps, flow laws and, with
``wall_motion``, the rotors' drag along the interlobe lines) into that same state, so the
comparison tests the model, not a re-implementation of it.

At model angle ``theta`` (outer-rotor angle within one lobe period from birth; slot k
holds the chamber of age ``theta + k * period``) the segment's topology says which slots
are open: slots below ``k_sc`` to suction, from ``k_do`` on to discharge.  Open slots are
held at their plenum's state.  The closed slots' pressures and temperatures solve

    sum over paths of mass flow into the slot      = 0
    sum over paths of enthalpy flow into the slot  = 0

(steady, volume fixed: no p dV work; adiabatic walls, as the CFD's; the wall drag's
viscous heating is not in the chamber model and so not here).  The flows are the model's
own :meth:`~.model.ChamberModel.path_flows`, so every leakage model ("nozzle", "fanno",
"cfd-calibrated", "rarefied") serves unchanged.  Unknowns are ln p and ln T of the closed
slots; scipy's hybrid Powell method solves the residuals scaled by the largest flow of
the network, from pressures interpolated between the plenums by age.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

#: Residual tolerance: net mass and enthalpy flow of every closed chamber over the
#: largest path flow (resp. its enthalpy flow).  1e-10 leaves the pressures exact to far
#: below any CFD error (the CFD's own mass balance is held to 0.5 %).
RESIDUAL_TOL = 1e-10


@dataclass(frozen=True)
class FrozenState:
    """The steady leakage network at one angle.  Slot k's chamber has age ``ages[k]``."""

    theta: float  # model angle, rad
    ages: np.ndarray  # (n_act,) chamber ages, rad
    volumes: np.ndarray  # (n_act,) m3
    p: np.ndarray  # (n_act,) Pa; open slots at their plenum's
    T: np.ndarray  # (n_act,) K
    closed: np.ndarray  # (n_act,) bool
    names: tuple  # per flow: the path's name
    ia: np.ndarray  # per flow: from node (0 suction, k + 1 slot k, n_act + 1 discharge)
    ib: np.ndarray  # to node
    flows: np.ndarray  # per flow, kg/s from ia to ib
    residual: float  # largest scaled residual of the closed slots

    def by_path(self) -> dict:
        """Net mass flow (kg/s) per path name, summed over its flows (from ia to ib)."""
        out: dict = {}
        for name, f in zip(self.names, self.flows, strict=True):
            out[name] = out.get(name, 0.0) + float(f)
        return out


def segment_at(model, theta: float):
    """The segment of ``model`` whose span holds ``theta`` (taken modulo the period)."""
    P, t0 = model.geo.period, model.geo.birth
    th = t0 + (theta - t0) % P
    for seg in model.segments:
        if seg.start <= th < seg.end or (seg is model.segments[-1] and th <= seg.end):
            return th, seg
    raise CaseError(f"no segment of the chamber model holds theta = {math.degrees(theta):g} deg")


def _state(model, seg, V, p, T):
    """State vector with the active slots at (p, T)."""
    y = np.zeros(model.n_state)
    for k in range(seg.n_act):
        rho, u, _ = model.fluid.state_pT(float(p[k]), float(T[k]))
        y[k] = rho * V[k]
        y[model.n + k] = rho * V[k] * u
    return y


def solve_frozen(model, theta: float) -> FrozenState:
    """Steady pressures and temperatures of the closed chambers at model angle ``theta``
    (see the module docstring).  Raises CaseError with oil injected (the CFD is dry) or
    where the solve does not reach RESIDUAL_TOL."""
    from scipy.optimize import root

    if model.oil:
        raise CaseError("frozen leakage network: oil injection is not modelled here")
    theta, seg = segment_at(model, theta)
    na, n = seg.n_act, model.n
    V = np.asarray(model.geo.evaluate(theta + seg.kP)[0], dtype=float)
    ages = theta + seg.kP
    closed = np.zeros(na, dtype=bool)
    closed[seg.k_sc:seg.k_do] = True
    p = np.where(np.arange(na) < seg.k_sc, model.suc.p, model.dis.p).astype(float)
    T = np.where(np.arange(na) < seg.k_sc, model.suc.T, model.dis.T).astype(float)
    idx = np.flatnonzero(closed)
    # Start: ln p linear in age between the plenums over the closed run, at T_dis.
    frac = (np.arange(idx.size) + 1.0) / (idx.size + 1.0)
    p[idx] = model.suc.p * (model.dis.p / model.suc.p) ** frac
    T[idx] = model.dis.T

    def flows(x):
        pp, TT = p.copy(), T.copy()
        pp[idx], TT[idx] = np.exp(x[:idx.size]), np.exp(x[idx.size:])
        y = _state(model, seg, V, pp, TT)
        F, E = model.path_flows(theta, y, seg, enthalpy=True)
        return F, E

    def residual(x):
        F, E = flows(x)
        mass = (F @ seg.mm)[idx]
        energy = (E @ seg.me)[n + idx]
        fs = max(float(np.abs(F).max()), 1e-300)
        es = max(float(np.abs(E).max()), 1e-300)
        return np.concatenate([mass / (fs * seg.mm.max()), energy / (es * seg.me.max())])

    if idx.size and not seg.n_leak:
        raise CaseError(f"frozen leakage network at theta = {math.degrees(theta):g} deg: the "
                        "closed chambers have no leakage path (a sealed machine has no "
                        "steady state to find)")
    x0 = np.concatenate([np.log(p[idx]), np.log(T[idx])])
    res = 0.0
    if idx.size:
        sol = root(residual, x0, method="hybr", options={"xtol": 1e-13})
        res = float(np.abs(residual(sol.x)).max())
        if not np.isfinite(res) or res > RESIDUAL_TOL:
            raise CaseError(f"frozen leakage network at theta = {math.degrees(theta):g} deg "
                            f"did not converge (scaled residual {res:.2e}: {sol.message})")
        x0 = sol.x
        p[idx], T[idx] = np.exp(x0[:idx.size]), np.exp(x0[idx.size:])
    F, _ = flows(x0)
    return FrozenState(theta, ages, V, p, T, closed, tuple(seg.names), seg.ia.copy(),
                       seg.ib.copy(), np.asarray(F, dtype=float), res)
