"""The quasi-1D model of the closed transverse section in motion (issue 17), for the
comparison with :mod:`.moving_case`.

The machine is the CFD's: the case file's pair, straight, as long as the slab is deep,
the sealing lines its clearance, the end faces closed (``[leakage.end-face] model =
"none"``, :func:`.machine_setup.comparison_raw`), the rotors' drag in the gaps on
(``wall_motion``), the CFD's perfect gas.  Its chamber table and equations are the
product's (:func:`.machine_setup.case_table`, :func:`.machine_setup.quasi1d_model`):
volumes, their rates, sealing-line areas, Couette drag and every leakage law are
evaluated by :meth:`ChamberModel.path_flows <rotorflow.quasi1d.model.ChamberModel.path_flows>`.

What differs from the product's cycle, and why.  The section has no ports: the gas of a
chamber stays in the section all its life and beyond.  The product's cycle lets a chamber
die into the discharge plenum at its vanishing volume and be born from the suction
plenum; here each of the ``N`` chambers between the outer rotor's lobes is carried
through its whole turn (its age grows by 2 pi per turn, so age ``a`` and ``a - 2 pi`` are
the same chamber).  Between death and the next birth (the vanished chamber, ages past
``death``) it keeps the death volume and its own gas, and it stands in for both plenums
of the model's network: the paths the model ends at a plenum are the sealing lines to
the chamber not yet born or just died, which in the closed section is this one.  No port
flow is taken.  Mass and energy change only by the flows between chambers (and p dV
work), so the section's mass is conserved by construction (checked).

Integration: dm/dt and dU/dt of every chamber by scipy's LSODA between the segments'
boundaries (the network changes there), in time, to the CFD's write angles.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

#: Relative tolerance of the integration: far below any CFD-model difference looked at.
RTOL = 1e-7


@dataclass(frozen=True)
class SectionModel:
    model: object  # rotorflow.quasi1d.model.ChamberModel
    origin: float  # machine angle at table angle zero, rad
    chambers: int  # N, the outer rotor's lobes
    targets: dict  # leakage path name -> its target (chambers apart)


def slab_raw(raw: dict, depth: float, gap: float, gas) -> dict:
    """The case file's sections for the slab: straight, ``depth`` long, clearance
    ``gap``, the perfect gas ``gas`` (the CFD's), the drag of the walls on."""
    out = copy.deepcopy(raw)
    out["machine"]["length_mm"] = depth * 1e3
    out["sweep"] = {"kind": "straight"}
    out.pop("export", None)
    out["leakage"] = {**out.get("leakage", {}), "gap_um": gap * 1e6, "wall_motion": True}
    out["operating"] = {**out["operating"], "heat_capacity": "constant",
                        "molar_mass_g_mol": gas.molar_mass_kg_kmol, "cp_J_kgK": gas.cp_J_kgK}
    return out


def section_models(raw: dict, where: Path, depth: float, gap: float, gas, models, case_of,
                   correlation: Path | None = None) -> dict:
    """{leakage model: SectionModel} of the slab (see the module docstring); ``case_of``
    makes the case of a parsed case file (the workflow's case_from_raw: the cases layer
    does not read case files itself)."""
    from .machine_setup import case_table, comparison_raw, quasi1d_model, table_origin

    case = case_of(slab_raw(raw, depth, gap, gas), Path(where))
    table = case_table(case)
    origin = table_origin(case)
    out = {}
    for name in models:
        m = quasi1d_model(table, comparison_raw(case.raw, name, correlation), str(where))
        out[name] = SectionModel(m, origin, int(round(2 * math.pi / m.geo.period)),
                                 {p.name: p.target for p in table.paths})
    return out


def _plenum(model, p: float, T: float):
    from rotorflow.quasi1d.plenums import Plenum

    rho, u, h = model.fluid.state_pT(p, T)
    return Plenum(p, T, rho, u, h, float(model.fluid.gamma))


def _rates(sm: SectionModel, phi: float, m: np.ndarray, U: np.ndarray, segment_at):
    """(dm/dt, dU/dt) of the N chambers (chamber c: CFD slot c, age phi - origin + c P)."""
    model, N = sm.model, sm.chambers
    P = model.geo.period
    th, seg = segment_at(model, phi - sm.origin)
    ages = phi - sm.origin + P * np.arange(1, N + 1)
    # slot of each chamber in the model's period (age th + k P), modulo a whole turn
    k = np.rint(((ages - th) % (2 * math.pi)) / P).astype(int) % N
    na = seg.n_act
    live = k < na
    if live.sum() != na:
        raise CaseError(f"{na} active slots but {live.sum()} chambers in their life at "
                        f"{math.degrees(phi):.6g} deg")
    order = np.empty(na, int)
    order[k[live]] = np.flatnonzero(live)
    y = np.zeros(model.n_state)
    y[:na], y[model.n:model.n + na] = m[order], U[order]
    V = _volumes(sm, phi)
    p, T, _ = model.fluid.props(m / V, U / m)
    nl = seg.n_leak  # the leakage paths come first; the rest are ports: closed here
    ia, ib = seg.ia[:nl], seg.ib[:nl]
    # a plenum end is the chamber |target| younger (suction) or older (discharge) than
    # the live end, a turn away: its own state stands in for the plenum's
    target = np.array([abs(int(sm.targets[name])) for name in seg.names[:nl]])
    live_end = np.where(ia == 0, ib, ia) - 1
    sign = np.where(ia == 0, -1, np.where(ib == na + 1, 1, 0))
    partner = (order[np.clip(live_end, 0, na - 1)] + sign * target) % N
    F = np.zeros(nl)
    E = np.zeros(nl)
    for j in [None, *sorted(set(partner[sign != 0].tolist()))]:
        sel = sign == 0 if j is None else (sign != 0) & (partner == j)
        mj = model
        if j is not None:
            pl = _plenum(model, float(p[j]), float(T[j]))
            mj = replace(model, suc=pl, dis=pl)
        Fj, Ej = mj.path_flows(th, y, seg, enthalpy=True)
        F[sel], E[sel] = Fj[:nl][sel], Ej[:nl][sel]
    node = np.full(na + 2, -1)
    node[1:na + 1] = order
    src = np.where(ia == 0, partner, node[ia])
    dst = np.where(ib == na + 1, partner, node[ib])
    dm, dU = np.zeros(N), np.zeros(N)
    src, dst = src.astype(int), dst.astype(int)  # empty when sealed
    np.add.at(dm, src, -F)
    np.add.at(dm, dst, F)
    np.add.at(dU, src, -E)
    np.add.at(dU, dst, E)
    Vt = model._geometry(th, seg)[3]
    dU[order] -= p[order] * Vt  # p dV/dt work on the gas; the vanished one keeps its volume
    return dm, dU


def simulate_closed(sm: SectionModel, start: float, span: float, omega: float,
                    p0: float, T0: float, angles) -> dict:
    """Every chamber's pressure (Pa, (len(angles), N)) at the machine ``angles`` (rad,
    within [start, start + span]), the section closed, at rest at (p0, T0) at ``start``;
    and the largest relative change of the section's mass."""
    from scipy.integrate import solve_ivp

    from rotorflow.quasi1d.frozen import segment_at

    model, N = sm.model, sm.chambers
    P = model.geo.period
    vol = _volumes(sm, start)
    rho, u, _ = model.fluid.state_pT(p0, T0)
    y0 = np.concatenate([rho * vol, rho * u * vol])

    def rhs(t, y):
        dm, dU = _rates(sm, start + omega * t, y[:N], y[N:], segment_at)
        return np.concatenate([dm, dU])

    # the network changes at the segments' ends: integrate between them
    cuts = sorted({start, start + span} | {
        sm.origin + b + j * P for seg in model.segments for b in (seg.start, seg.end)
        for j in range(-2, int(span / P) + 3)
        if start < sm.origin + b + j * P < start + span})
    cuts = [c for i, c in enumerate(cuts) if i == 0 or c - cuts[i - 1] > 1e-9]
    # written times carry round-off: an angle a hair past the end is the end's
    angles = np.clip(np.asarray(angles, float), start, start + span)
    out = np.full((len(angles), N), np.nan)
    atol = RTOL * 1e-3 * np.abs(y0)  # per chamber: mass and energy on their own scales
    mass = []
    y = y0
    for a0, a1 in zip(cuts[:-1], cuts[1:], strict=True):
        inside = np.flatnonzero((angles >= a0) & (angles <= a1))
        t1 = (a1 - start) / omega
        t_eval = np.append((angles[inside] - start) / omega, t1)
        sol = solve_ivp(rhs, ((a0 - start) / omega, t1), y, method="LSODA", rtol=RTOL,
                        atol=atol, t_eval=np.unique(np.minimum(t_eval, t1)))
        if not sol.success:
            raise CaseError(f"the closed-section model failed at "
                            f"{math.degrees(a0):.6g} deg: {sol.message}")
        for idx in inside:
            yj = sol.y[:, np.searchsorted(sol.t, min((angles[idx] - start) / omega, t1))]
            out[idx] = _pressures(sm, angles[idx], yj[:N], yj[N:])
            mass.append(yj[:N].sum())
        y = sol.y[:, -1]
    drift = float(np.max(np.abs(np.array(mass) / y0[:N].sum() - 1.0))) if mass else 0.0
    return {"p": out, "mass_drift": drift}


def _volumes(sm: SectionModel, phi: float) -> np.ndarray:
    geo, P = sm.model.geo, sm.model.geo.period
    ages = phi - sm.origin + P * np.arange(1, sm.chambers + 1)
    a = ages % (2 * math.pi)
    a = np.where(a < geo.birth, a + 2 * math.pi, a)  # the same chamber a turn older
    return np.array([float(geo.volume(x)) if x <= geo.death else float(geo.volume(geo.death))
                     for x in a])


def _pressures(sm: SectionModel, phi: float, m, U) -> np.ndarray:
    V = _volumes(sm, phi)
    p, _, _ = sm.model.fluid.props(m / V, U / m)
    return np.asarray(p, float) * np.ones(sm.chambers)
