"""The quasi-1D model of the section in motion with its ports open (issue 17), for the
comparison with a ported run of :mod:`.moving_case`.

With ports the slab is what the product models anyway: a straight machine as long as the
slab is deep, the suction port on its low-pressure end plate (the CFD's back face) and
the discharge port on its high-pressure one (the front face), each the product's own port
(:func:`rotorflow.geometry.ports.ports`; the CFD opens the faces inside those polygons).
So, unlike the closed section (:mod:`.moving_quasi1d`, which carries every chamber
through its vanishing), the product's cycle runs unchanged: :func:`ported_models` is its
periodic state under each leakage model, end faces sealed (the slab has no end
clearances), the rotors' drag in the gaps on, the CFD's perfect gas and plenums.

A periodic state is the same for every chamber shifted by a lobe period, so the CFD's
slot ``s`` (the chamber of machine age ``phi + s * period``, :mod:`.moving_chambers`) at
machine angle ``phi`` is the model's chamber at table age ``phi + s * period - origin``
(:func:`slot_pressures`).  The same map gives the CFD its starting state
(:func:`initial_state`): every chamber at the model's periodic pressure and temperature,
so that the run starts near its own periodic state and the turns it needs to reach it are
few (how few is measured, :func:`periodicity`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

#: Ports of the product's model for the comparison: "ideal" is the chamber at the
#: plenum's pressure while open, as the CFD's port faces, held at the plenum pressure
#: over the whole open face section, come close to; "nozzle" throttles.
PORT_MODEL = "ideal"


@dataclass(frozen=True)
class PortedModel:
    result: object  # rotorflow.quasi1d.result.SimulationResult (periodic state)
    origin: float  # machine angle at table age zero, rad
    period: float  # lobe period, rad (outer rotor)
    chambers: int  # N, the outer rotor's lobes
    plenums: dict  # "suction" / "discharge" -> (p Pa, T K): what the CFD's ports hold


def ported_raw(raw: dict, depth: float, gap: float, gas, model: str,
               correlation: Path | None = None) -> dict:
    """The case file's sections for the ported slab under leakage ``model``."""
    from .machine_setup import comparison_raw
    from .moving_quasi1d import slab_raw

    out = comparison_raw(slab_raw(raw, depth, gap, gas), model, correlation)
    out["ports"] = {"model": PORT_MODEL}
    return out


def ported_models(raw: dict, where: Path, depth: float, gap: float, gas, models, case_of,
                  correlation: Path | None = None) -> dict:
    """{leakage model: PortedModel}: the product's periodic state of the ported slab
    (the module docstring); ``case_of`` is the workflow's case_from_raw."""
    from rotorflow.quasi1d.simulate import case_settings, simulate

    from .machine_setup import case_table, table_origin

    out = {}
    table = origin = None
    for name in models:
        r = ported_raw(raw, depth, gap, gas, name, correlation)
        case = case_of(r, Path(where))
        if table is None:  # the leakage model does not change the geometry
            table, origin = case_table(case), table_origin(case)
        result = simulate(table, *case_settings(r, str(where)))
        if not result.figures.get("converged", False):
            raise CaseError(f"the ported slab's quasi-1D cycle under {name!r} did not "
                            f"converge: {result.figures.get('message', '')}")
        model = result.solution.model
        period = float(model.geo.period)
        out[name] = PortedModel(result, origin, period, int(round(2 * math.pi / period)),
                                {"suction": (model.suc.p, model.suc.T),
                                 "discharge": (model.dis.p, model.dis.T)})
    return out


def _chamber_at(pm: PortedModel, key: str, ages: np.ndarray) -> np.ndarray:
    """The model's one-chamber trace ``key`` at table ``ages``; NaN outside its life."""
    ch = pm.result.chamber
    a = np.asarray(ch["angle_rad"], float)
    v = np.asarray(ch[key], float)
    out = np.interp(ages, a, v)
    return np.where((ages >= a[0]) & (ages <= a[-1]), out, np.nan)


def slot_pressures(pm: PortedModel, angles, key: str = "p_Pa") -> np.ndarray:
    """(len(angles), N): the model's periodic ``key`` of CFD slot s (1..N) at machine
    ``angles`` (rad): its chamber of table age phi + s P - origin, taken modulo the
    chamber's turn (NaN while a slot holds no chamber: between death and birth)."""
    phi = np.asarray(angles, float)[:, None]
    ages = phi + pm.period * np.arange(1, pm.chambers + 1)[None, :] - pm.origin
    turn = pm.period * pm.chambers
    a0 = float(pm.result.chamber["angle_rad"][0])
    ages = a0 + np.mod(ages - a0, turn)
    return _chamber_at(pm, key, ages)


def initial_state(pm: PortedModel, phi: float) -> tuple[dict, dict]:
    """({slot: p Pa}, {slot: T K}) of the chambers alive at machine angle ``phi`` in the
    model's periodic state: the CFD's start."""
    p = slot_pressures(pm, [phi])[0]
    T = slot_pressures(pm, [phi], "T_K")[0]
    live = np.isfinite(p) & np.isfinite(T)
    return ({s + 1: float(p[s]) for s in np.flatnonzero(live)},
            {s + 1: float(T[s]) for s in np.flatnonzero(live)})


def periodicity(angles_deg, p: dict, period: float) -> dict:
    """How far a run's chamber pressures are from periodic over its last two lobe
    periods: slot s at angle phi + P against slot s + 1 at phi (a chamber one lobe
    period on is where its neighbour was), phi in the last period but one; per pair of
    slots the largest difference as a share of the pressure swing over all slots
    ({"max": ..., "pairs": {"s": ...}}; empty when the run spans less than a period)."""
    a = np.radians(np.asarray(angles_deg, float))
    swing = np.nanmax([np.nanmax(v) for v in p.values()]) - np.nanmin(
        [np.nanmin(v) for v in p.values()])
    n = len(p)
    later = (a + period <= a[-1] + 1e-9) & (a >= a[-1] - 2.0 * period - 1e-9)
    out = {}
    for s in range(1, n + 1):
        here = np.asarray(p[str(s + 1 if s < n else 1)], float)[later]
        there = np.interp(a[later] + period, a, np.asarray(p[str(s)], float))
        ok = np.isfinite(here) & np.isfinite(there)
        if ok.any():
            out[str(s)] = float(np.abs(there[ok] - here[ok]).max() / swing)
    return {"max": max(out.values()) if out else math.nan, "pairs": out}


def join(chunks: list) -> dict:
    """One topology-pressure record ({"angles_deg", "p"}) of runs that go on from each
    other's end (:func:`.moving_chambers.topology_pressures` of each, in order): a
    chunk's first angle is its predecessor's last, kept once."""
    angles, p = [], {}
    for k, c in enumerate(chunks):
        skip = 1 if k and math.isclose(c["angles_deg"][0], angles[-1], abs_tol=1e-9) else 0
        angles += list(c["angles_deg"][skip:])
        for slot, v in c["p"].items():
            p.setdefault(slot, []).extend(v[skip:])
    return {"angles_deg": angles, "p": p}


def differences(cfd: dict, model_p: np.ndarray) -> dict:
    """Per slot, the largest and the RMS difference between the model's pressures
    (``model_p``, (angles, N), at ``cfd["angles_deg"]``) and the CFD's, as a share of the
    cycle's pressure swing (the CFD's largest less its least pressure over all slots and
    angles: over a lobe period the slots together hold one chamber's whole life, while a
    slot's own swing may be a suction chamber's few per cent); angles where either has no
    chamber are left out (and counted); "max_at_deg": the machine angle of the largest.
    "all": the same over every slot at once."""
    p = np.array([np.asarray(cfd["p"][str(c)], float) for c in range(1, model_p.shape[1] + 1)]).T
    q = np.asarray(model_p, float)
    angles = np.asarray(cfd["angles_deg"], float)
    ok = np.isfinite(p) & np.isfinite(q)
    swing = float(np.nanmax(p) - np.nanmin(p))
    out = {}
    for c in range(p.shape[1]):
        d = (q[:, c] - p[:, c])[ok[:, c]]
        if d.size:
            worst = int(np.argmax(np.abs(d)))
            out[str(c + 1)] = {"max": float(np.abs(d[worst])) / swing,
                               "max_at_deg": float(angles[ok[:, c]][worst]),
                               "rms": float(np.sqrt(np.mean(d * d))) / swing,
                               "left_out": int((~ok[:, c]).sum())}
    d = (q - p)[ok]
    out["all"] = {"max": float(np.abs(d).max()) / swing,
                  "rms": float(np.sqrt(np.mean(d * d))) / swing, "swing_Pa": swing}
    return out


def comparison(cfd: dict, period: float, models: dict) -> dict:
    """A ported run's chamber pressures (``cfd``: {"angles_deg", "p"}, from the grid's
    topology) against the models' periodic state: how far the run is from periodic
    (:func:`periodicity`), and per model its pressures at the run's angles and their
    differences (:func:`differences`) over the run's last lobe period, the one nearest
    periodic.  Small, and re-checkable offline."""
    angles = np.radians(cfd["angles_deg"])
    last = angles >= angles[-1] - period - 1e-9
    tail = {"angles_deg": list(np.asarray(cfd["angles_deg"])[last]),
            "p": {c: list(np.asarray(v, float)[last]) for c, v in cfd["p"].items()}}
    rec = {"periodicity": periodicity(cfd["angles_deg"], cfd["p"], period), "models": {}}
    for name, pm in models.items():
        p = slot_pressures(pm, angles)
        rec["models"][name] = {"p": np.where(np.isfinite(p), p, None).tolist(),
                               "errors": differences(tail, p[last])}
    return rec


def largest_differences(base: dict, other: dict, swing: float) -> dict:
    """Per slot, the largest difference between two runs' chamber pressures
    ({"angles_deg", "p"}) at the angles both were written at, as a share of ``swing``
    (slots and angles where either has no chamber are left out)."""
    a_deg, b_deg = np.asarray(base["angles_deg"], float), np.asarray(other["angles_deg"], float)
    ia = np.flatnonzero(np.isclose(a_deg[:, None], b_deg[None, :], atol=1e-6).any(axis=1))
    ib = np.array([int(np.argmin(np.abs(b_deg - a_deg[i]))) for i in ia], dtype=int)
    if ia.size == 0:
        raise ValueError("the two runs have no written angle in common")
    out = {}
    for c, v in other["p"].items():
        if c not in base["p"]:
            continue
        a = np.asarray(base["p"][c], float)[ia]
        b = np.asarray(v, float)[ib]
        ok = np.isfinite(a) & np.isfinite(b)
        if ok.any():
            out[c] = float(np.abs(a - b)[ok].max() / swing)
    return out


def grid_error(runs: list, ratio: float = 2.0, of: int = 1) -> dict:
    """Run ``of``'s error in the chamber pressures (0: the coarsest), from three runs from
    the same start on grids refined by ``ratio`` (``runs``: coarse, middle, fine
    {"angles_deg", "p"} at the same angles).  At every angle and slot: Richardson's
    extrapolation with the observed order where the three converge monotonically, else
    the three's spread as the error (no extrapolation is sound there); as a share of the
    swing over every slot and angle of the fine run, per slot the largest over the
    angles, and how many points converged how."""
    from rotorflow.postprocess.richardson import richardson

    if len(runs) != 3 or any(not np.allclose(r["angles_deg"], runs[0]["angles_deg"],
                                             atol=1e-6) for r in runs):
        raise ValueError("a grid study needs three runs written at the same angles")
    fine = np.array([np.asarray(v, float) for v in runs[2]["p"].values()])
    swing = float(np.nanmax(fine) - np.nanmin(fine))
    per, kinds = {}, {}
    for slot in runs[2]["p"]:
        trio = np.array([np.asarray(r["p"][slot], float) for r in runs]).T
        errs = []
        for f in trio[np.isfinite(trio).all(axis=1)]:
            r = richardson(f, ratio)
            kinds[r.kind] = kinds.get(r.kind, 0) + 1
            errs.append(abs(f[of] - r.extrapolated) if r.kind in ("monotone", "converged")
                        else np.ptp(f))
        if errs:
            per[slot] = float(max(errs) / swing)
    return {"max": max(per.values()), "chambers": per, "kinds": kinds, "swing_Pa": swing}
