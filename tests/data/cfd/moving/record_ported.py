"""Record the ported section in motion towards its periodic state, in chunks (issue 17).

    .venv/bin/python tests/data/cfd/moving/record_ported.py RUNS_DIR GAP_UM [DEGREES]

(needs OpenFOAM).  The default pair of examples/default.toml, a slab 10 mm deep, ports
and plenums of the case (:mod:`rotorflow.cases.moving_ports`: suction 1 bar / 293 K on
the back face, discharge 2.6 bar on the front), 2500 rpm outer, from 13 deg.  The first
chunk starts from the quasi-1D model's periodic state of the same slab
(:func:`.moving_ported.initial_state`, model START_MODEL); every later one from the
fields its predecessor ended with (the grids are the same at that angle: the O-grid's
numbering does not change).  A chunk is CHUNK_DEG of turning; after each, its chamber
pressures (from the grid's topology at every written frame), its figures and the end
state are written next to this file (``ported_<GAP>um/``: ``chunks.json``,
``state.npz``), so that a run cut short goes on from the last chunk.  ``DEGREES``: how
far to turn in this call (default: up to TOTAL_DEG).  When the chunks span TOTAL_DEG
the comparison with the models (:func:`.moving_ported.comparison`) is written to
``ported_<GAP>um.json``.

    .venv/bin/python tests/data/cfd/moving/record_ported.py RUNS_DIR GAP_UM study

the time step's share of the error: the first chunk again at 1.5 times its steps
(:func:`study`);

    .venv/bin/python tests/data/cfd/moving/record_ported.py RUNS_DIR GAP_UM grid

the grid's: the first degrees on the grid halved and doubled (:func:`grid`);

    .venv/bin/python tests/data/cfd/moving/record_ported.py RUNS_DIR GAP_UM opening

the same over a discharge port's opening (GRID_OPENING);

    .venv/bin/python tests/data/cfd/moving/record_ported.py RUNS_DIR GAP_UM pimple

fewer, larger steps with PIMPLE outer correctors against the record (:func:`pimple`).
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from rotorflow.cases.moving_case import RunControls, end_fields, run_moving_section
from rotorflow.cases.moving_chambers import topology_pressures
from rotorflow.cases.moving_ported import (
    comparison,
    grid_error,
    initial_state,
    join,
    largest_differences,
    ported_models,
)
from rotorflow.cases.moving_ports import slab_ports
from rotorflow.cases.moving_section import MovingSection
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.workflow.case import case_from_raw, load_toml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
CASE = ROOT / "examples" / "default.toml"
FIT = ROOT / "tests" / "data" / "cfd" / "chamber" / "flow_coefficient.json"
MODELS = ("nozzle", "fanno", "cfd-calibrated")
START_DEG = 13.0
DEPTH = 0.01
OMEGA = 2500.0 * 2.0 * math.pi / 60.0
#: The start state's model: the one the closed runs found closest at each clearance
#: (nozzle at 100 um, Fanno at 20 um); only how soon the run is periodic depends on it.
START_MODEL = {100: "nozzle", 20: "fanno"}
#: Three lobe periods: the last is compared with the models and with the one before
#: (periodicity); the first carries the start's transient (from the model's state, the
#: newborn chamber's pressure differs from the next period's by 12 % of the swing at
#: 100 um; the third from the second by 1.0 %).
TOTAL_DEG = 180.0
#: Per clearance (um): (columns, cells across the gap, key frames per degree, steps per
#: frame, frames between written fields, degrees per chunk).  100 um: the closed lobe
#: period's grid and step (Courant 0.69); 20 um: its 1024 columns and 0.0625 deg frames,
#: 40 steps a frame.  The 20 um run's first five chunks (13-63 deg) went at 160 (Courant
#: 0.24-0.61); the cost-control study (:func:`pimple`) found 40 within 0.18 % of the
#: swing of them over the first chunk at a fifth of the solver's time, so the rest goes
#: at 40 (each chunk's record says its steps).
SETTINGS = {100: (512, 4, 4, 192, 2, 20.0), 20: (1024, 4, 16, 40, 8, 10.0)}
#: Largest Courant number a chunk may reach (RunControls.max_courant): PISO above 1 is
#: judged by the step study, which at 100 um found it stable to 7 and first order.
MAX_COURANT = {100: 1.0, 20: 4.0}
#: The chunks the step studies (:func:`study`, :func:`pimple`) start from and compare
#: with, per clearance: the first chunk at its own steps.
STEP_REFERENCE = {100: "ported_100um", 20: "ported_20um"}
#: Grid study (:func:`grid`), per clearance: degrees turned from the start, frames
#: between written fields, and the grids' refinement of the run's cells in both
#: directions (a constant ratio).  A grid 2x finer costs ~8x (cells, step), so the study
#: turns the first part of the first chunk: 4 deg (16 frames) at 100 um, the run's grid
#: halved and doubled; 1 deg (16 frames) at 20 um, where the halved grid (512 x 2) fails
#: the O-grid's skewness limit at 13 deg (5.8 against 4), so the run's grid is the
#: coarsest of three refined by 1.5 (1024 x 4, 1536 x 6, 2304 x 9).
GRID_SPAN = {100: (4.0, 2, (0.5, 1.0, 2.0)), 20: (1.0, 2, (1.0, 1.5, 2.25))}
#: The grid study again over a discharge port's opening (mode ``opening``): slot 2's
#: port opens at ~170 deg, where the run differs most from every model (its pressure
#: rises 1.5 deg on and rings), so the three grids turn through it, each from the
#: START_MODEL's periodic state at the first angle (``ported_<GAP>um_grid_opening.json``):
#: (first angle, degrees) per clearance; at 20 um to the peak only (its finest grid
#: took 8 min of solver a degree, 2,000 s for the 4 deg).
GRID_OPENING = {100: (166.0, 8.0), 20: (168.5, 4.0)}
#: Cost control (:func:`pimple`), per clearance: degrees from the start, and (steps per
#: frame, PIMPLE outer correctors) of each variant, against the recorded run (PISO at
#: Courant below 1; None: its own steps, run again).  100 um: the grid study's degrees;
#: 20 um: its whole first chunk, PISO only (at 100 um outer correctors only cost).
PIMPLE = {100: (4.0, ((None, 1), (64, 1), (64, 2), (64, 3), (32, 1), (32, 3), (32, 5),
                      (16, 1), (16, 5))),
          20: (10.0, ((40, 1), (20, 1)))}


def section(gap_um: int, start_deg: float, span_deg: float, ports, refine: float = 1.0,
            **start) -> MovingSection:
    """The recorded run's section (``refine``: its grid's cells in both directions)."""
    columns, across, per_deg, _, _, _ = SETTINGS[gap_um]
    return MovingSection(examples()["table1"], gap_um * 1e-6,
                         OGridSpec(columns=int(round(columns * refine)),
                                   cells_across_gap=int(round(across * refine))),
                         math.radians(start_deg), math.radians(span_deg),
                         int(round(span_deg * per_deg)), OMEGA, depth=DEPTH,
                         p0=ports.p_suction, T0=ports.T_suction, ports=ports, **start)


def _chunk_record(s: MovingSection, run, folder: Path) -> dict:
    flows = {k: np.asarray(v) for k, v in run.port_flow.items()}
    t = np.asarray(run.times_s)
    dt = np.diff(np.concatenate([[0.0], t]))
    return {"start_deg": math.degrees(s.start), "span_deg": math.degrees(s.span),
            "status": run.status, "message": run.message, "cells": run.cells,
            "time_steps": run.time_steps, "run_time_s": run.run_time_s,
            "mass_balance": run.mass_balance, "max_courant": run.max_courant,
            "max_gap_courant": run.max_gap_courant,
            # kg through each port over the chunk (inflow positive), as the solver
            # books it (:func:`.moving_run.mass_balance`)
            "port_mass_kg": {k: float(np.sum(v * dt)) for k, v in flows.items()},
            "chambers": topology_pressures(s, folder)}


def retopo(runs: Path, gap_um: int) -> Path:
    """Every recorded chunk's chamber pressures taken again from its run's written
    fields (the chamber labelling once merged the newborn chamber into its neighbour
    past one period, :func:`.machine_zones.column_slots`); the run folders must still be
    in ``runs``."""
    raw = load_toml(CASE)
    ports, _ = slab_ports(examples()["table1"], DEPTH, gap_um * 1e-6, PerfectGas(), raw,
                         CASE, case_from_raw)
    book = HERE / f"ported_{gap_um}um" / "chunks.json"
    chunks = json.loads(book.read_text())
    for c in chunks:
        s = section(gap_um, c["start_deg"], c["span_deg"], ports)
        c["chambers"] = topology_pressures(s, runs / f"ported-{gap_um}um-{c['start_deg']:g}deg")
    book.write_text(json.dumps(chunks, indent=1, allow_nan=True) + "\n")
    return book


def main(runs: Path, gap_um: int, degrees: float | None = None) -> Path:
    raw = load_toml(CASE)
    pair, gas = examples()["table1"], PerfectGas()
    out_dir = HERE / f"ported_{gap_um}um"
    out_dir.mkdir(exist_ok=True)
    book, state = out_dir / "chunks.json", out_dir / "state.npz"
    chunks = json.loads(book.read_text()) if book.is_file() else []
    ports, port_info = slab_ports(pair, DEPTH, gap_um * 1e-6, gas, raw, CASE, case_from_raw)
    models = ported_models(raw, CASE, DEPTH, gap_um * 1e-6, gas, MODELS, case_from_raw, FIT)
    steps, every, chunk = SETTINGS[gap_um][3:]
    done = sum(c["span_deg"] for c in chunks)
    goal = TOTAL_DEG if degrees is None else min(TOTAL_DEG, done + degrees)
    while done < goal - 1e-9:
        start = START_DEG + done
        span = min(chunk, goal - done)
        if chunks:
            with np.load(state) as z:
                if not math.isclose(float(z["angle_deg"]), start, abs_tol=1e-9):
                    raise SystemExit(f"the stored state is at {float(z['angle_deg'])} deg, "
                                     f"the next chunk starts at {start}")
                fields = {k: z[k] for k in ("p", "T", "U")}
            s = section(gap_um, start, span, ports, initial_fields=fields)
        else:
            p, T = initial_state(models[START_MODEL[gap_um]], math.radians(start))
            s = section(gap_um, start, span, ports, initial_p=p, initial_T=T)
        folder = runs / f"ported-{gap_um}um-{start:g}deg"
        t0 = time.perf_counter()
        run = run_moving_section(s, folder, RunControls(
            steps_per_frame=steps, write_every_frames=every,
            max_courant=MAX_COURANT[gap_um]))
        rec = _chunk_record(s, run, folder) if run.ok else {
            "start_deg": start, "span_deg": span, "status": run.status,
            "message": run.message, "log_tail": run.log_tail}
        rec["wall_clock_s"] = time.perf_counter() - t0
        rec["steps_per_frame"] = steps
        if not run.ok:
            raise SystemExit(f"chunk at {start} deg {run.status}: {run.message}\n"
                             f"{run.log_tail}")
        f = end_fields(folder)
        np.savez_compressed(state, angle_deg=start + span, **f)
        chunks.append(rec)
        book.write_text(json.dumps(chunks, indent=1, allow_nan=True) + "\n")
        done += span
        print(f"{gap_um} um: {start:g} -> {start + span:g} deg, {run.status}, "
              f"{run.time_steps} steps, {run.run_time_s:.0f} s, balance "
              f"{run.mass_balance:.1e}, Courant {run.max_courant:.2f}", flush=True)
    if done < TOTAL_DEG - 1e-9:
        return book
    cfd = join([c["chambers"] for c in chunks])
    rec = {"cfd": {"gap_m": gap_um * 1e-6, "depth_m": DEPTH, "start_deg": START_DEG,
                   "span_deg": done, "start_model": START_MODEL[gap_um],
                   "ports": port_info, "chambers": cfd,
                   "chunks": [{k: v for k, v in c.items() if k != "chambers"}
                              for c in chunks]},
           **comparison(cfd, float(pair.period), models)}
    path = HERE / f"ported_{gap_um}um.json"
    path.write_text(json.dumps(rec, indent=1, allow_nan=True) + "\n")
    return path


def _start(gap_um: int, start_deg: float = START_DEG):
    """(ports, {slot: p}, {slot: T}): the slab's ports and a run's start, the
    START_MODEL's periodic state at ``start_deg`` (the first chunk's: START_DEG)."""
    raw = load_toml(CASE)
    pair, gas = examples()["table1"], PerfectGas()
    ports, _ = slab_ports(pair, DEPTH, gap_um * 1e-6, gas, raw, CASE, case_from_raw)
    name = START_MODEL[gap_um]
    model = ported_models(raw, CASE, DEPTH, gap_um * 1e-6, gas, (name,), case_from_raw,
                          FIT)[name]
    return (ports, *initial_state(model, math.radians(start_deg)))


def _reference_chunks(gap_um: int) -> list:
    """The chunks recorded at the step the studies start from (STEP_REFERENCE)."""
    return json.loads((HERE / STEP_REFERENCE[gap_um] / "chunks.json").read_text())


def _steps_of(chunk: dict, gap_um: int) -> int:
    """A recorded chunk's time steps per key frame."""
    frames = chunk["span_deg"] * SETTINGS[gap_um][2]
    return int(round(chunk["time_steps"] / frames))


def study(runs: Path, gap_um: int, factor: float = 1.5) -> Path:
    """The first chunk again at ``factor`` times the steps per frame, from the same start:
    each chamber's largest difference from the recorded chunk over its written angles,
    as a share of the swing over all chambers (``ported_<GAP>um_dt.json``)."""
    first = _reference_chunks(gap_um)[0]
    ports, p, T = _start(gap_um)
    s = section(gap_um, START_DEG, first["span_deg"], ports, initial_p=p, initial_T=T)
    ref = _steps_of(first, gap_um)
    steps, every = int(round(ref * factor)), SETTINGS[gap_um][4]
    folder = runs / f"ported-{gap_um}um-{START_DEG:g}deg-s{steps}"
    run = run_moving_section(s, folder, RunControls(steps_per_frame=steps,
                                                    write_every_frames=every))
    if not run.ok:
        raise SystemExit(f"the study's run is {run.status}: {run.message}\n{run.log_tail}")
    fine = topology_pressures(s, folder)
    base = first["chambers"]
    swing = max(np.nanmax(v) for v in fine["p"].values()) - min(
        np.nanmin(v) for v in fine["p"].values())
    per = largest_differences(base, fine, swing)
    out = {"steps_per_frame": [ref, steps], "span_deg": first["span_deg"],
           "run_time_s": run.run_time_s, "time_steps": run.time_steps,
           "max_courant": run.max_courant, "mass_balance": run.mass_balance,
           "swing_Pa": float(swing), "max": max(per.values()), "chambers": per,
           "fine": fine}
    path = HERE / f"ported_{gap_um}um_dt.json"
    path.write_text(json.dumps(out, indent=1, allow_nan=True) + "\n")
    return path


def grid(runs: Path, gap_um: int, opening: bool = False) -> Path:
    """The first GRID_SPAN degrees from the recorded run's start (``opening``: the
    GRID_OPENING degrees) on three grids refined by a constant ratio in both directions,
    the step with the cell (the gap's Courant number held): the run's grid's error in
    each chamber's pressure against the Richardson extrapolation
    (:func:`.moving_ported.grid_error`, ``ported_<GAP>um_grid[_opening].json``)."""
    _, every, refines = GRID_SPAN[gap_um]
    start, span = GRID_OPENING[gap_um] if opening else (START_DEG, GRID_SPAN[gap_um][0])
    ports, p, T = _start(gap_um, start)
    rows, pressures = [], []
    for refine in refines:
        s = section(gap_um, start, span, ports, refine, initial_p=p, initial_T=T)
        steps = int(round(SETTINGS[gap_um][3] * refine))
        folder = runs / (f"ported-{gap_um}um-grid-{start:g}deg-"
                         f"{s.spec.columns}x{s.spec.cells_across_gap}")
        run = run_moving_section(s, folder, RunControls(
            steps_per_frame=steps, write_every_frames=every,
            max_courant=MAX_COURANT[gap_um]))
        if not run.ok:
            raise SystemExit(f"the grid study's run {folder.name} is {run.status}: "
                             f"{run.message}\n{run.log_tail}")
        rows.append({"columns": s.spec.columns, "cells_across": s.spec.cells_across_gap,
                     "cells": run.cells, "steps_per_frame": steps,
                     "time_steps": run.time_steps, "run_time_s": run.run_time_s,
                     "max_courant": run.max_courant, "mass_balance": run.mass_balance})
        pressures.append(topology_pressures(s, folder))
        print(f"{folder.name}: {run.run_time_s:.0f} s, Courant {run.max_courant:.2f}",
              flush=True)
    ratio, of = refines[1] / refines[0], refines.index(1.0)
    out = {"start_deg": start, "span_deg": span, "ratio": ratio, "run_grid": of,
           "runs": rows, "pressures": pressures, **grid_error(pressures, ratio, of)}
    path = HERE / f"ported_{gap_um}um_grid{'_opening' if opening else ''}.json"
    path.write_text(json.dumps(out, indent=1, allow_nan=True) + "\n")
    return path


def pimple(runs: Path, gap_um: int) -> Path:
    """The first degrees again with fewer, larger steps and PIMPLE outer correctors
    (PIMPLE): per variant its cost, Courant number, outcome, and each chamber's largest
    difference from the recorded run at its written angles as a share of the recorded
    first chunk's swing (``ported_<GAP>um_pimple.json``).  A variant that fails is a
    result, kept with its message."""
    first = _reference_chunks(gap_um)[0]
    ports, p, T = _start(gap_um)
    span, variants = PIMPLE[gap_um]
    every = SETTINGS[gap_um][4]
    base = first["chambers"]
    swing = max(np.nanmax(v) for v in base["p"].values()) - min(
        np.nanmin(v) for v in base["p"].values())
    rows = []
    for steps, outer in variants:
        steps = steps or _steps_of(first, gap_um)
        s = section(gap_um, START_DEG, span, ports, initial_p=p, initial_T=T)
        folder = runs / f"ported-{gap_um}um-pimple-s{steps}-o{outer}"
        run = run_moving_section(s, folder, RunControls(
            steps_per_frame=steps, write_every_frames=every, outer_correctors=outer,
            max_courant=math.inf))
        row = {"steps_per_frame": steps, "outer_correctors": outer, "status": run.status,
               "message": run.message, "time_steps": run.time_steps,
               "run_time_s": run.run_time_s, "max_courant": run.max_courant,
               "mass_balance": run.mass_balance}
        if run.ok:
            got = topology_pressures(s, folder)
            if not np.allclose(got["angles_deg"],
                               base["angles_deg"][:len(got["angles_deg"])], atol=1e-6):
                raise SystemExit(f"{folder.name} is written at other angles than the record")
            per = largest_differences(base, got, swing)
            row.update(chambers=per, max=max(per.values()), p=got["p"],
                       angles_deg=got["angles_deg"])
        rows.append(row)
        print(f"{folder.name}: {run.status} {run.message} {run.run_time_s:.0f} s, Courant "
              f"{run.max_courant:.2f}, {row.get('max', math.nan):.2e} of the swing",
              flush=True)
    out = {"span_deg": span, "swing_Pa": float(swing), "runs": rows}
    path = HERE / f"ported_{gap_um}um_pimple.json"
    path.write_text(json.dumps(out, indent=1, allow_nan=True) + "\n")
    return path


if __name__ == "__main__":
    runs_dir, gap, what = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3:4]
    mode = {"study": study, "grid": grid, "pimple": pimple, "retopo": retopo,
            "opening": lambda r, g: grid(r, g, opening=True)}.get(
        what[0] if what else "")
    print(mode(runs_dir, gap) if mode else main(runs_dir, gap,
                                                float(what[0]) if what else None))
