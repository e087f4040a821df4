"""One frozen-angle 3D machine run (:mod:`.machine_case`), built, run, judged and stored by
the routine every CFD case shares (:func:`.foam_case.run_case`: a temporary folder
renamed into place with ``result.json`` and ``case.key``, reused by key, a failed run
kept with its log tail and never used).

The solver runs until the machine's leakage has settled and its mass balance holds, or
to ``max_iterations``: a monitor reads the patch flows while it runs and stops it once
the total leakage has changed by less than ``settle_tol`` over the last ``window``
iterations with the net flow over all patches within ``stop_balance_tol`` of the
inflow.  The run is accepted ("converged") when the leakage has settled to
``settle_accept_tol`` and the balance is within ``balance_tol``, the issue's 0.5 %;
otherwise it is flagged "not-converged" with the reason and kept out of every
extrapolation and comparison.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import re
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError, ExternalRunError

from . import foam, foam_case
from .machine_case import SOLVER, FrozenMachine, read_outputs, write_case
from .parallel import SERIAL, Decomposition, parallel_plan

#: Bump when the case or its judgement changes, so stored runs are recomputed.
CASE_FORMAT = 2

#: The monitor reads the run's tables at most this often (s): they are dozens of files.
MONITOR_EVERY_S = 5.0


@dataclass(frozen=True)
class Controls:
    """When to stop iterating and what counts as converged."""

    max_iterations: int = 3000
    #: Iterations over which the leakage must have stopped changing (the default machine
    #: at 20 um, 73,728 cells, settled to 1e-4 within 150 iterations from the quasi-1D
    #: start)...
    window: int = 100
    #: ...by less than this (relative) for the monitor to stop the run: a twentieth of
    #: the 2 % the grids are asked to be within of the extrapolated leakage...
    settle_tol: float = 1e-3
    #: ...and this to accept it (the monitor looks every few seconds, the solver takes an
    #: output interval to stop).
    settle_accept_tol: float = 2e-3
    #: |net flow over all patches| / inflow at which the monitor may stop...
    stop_balance_tol: float = 2e-3
    #: ...and the issue's 0.5 % that an accepted run must meet.
    balance_tol: float = 5e-3
    timeout_s: float | None = None


@dataclass(frozen=True)
class MachineRun:
    """What a frozen-angle run produced.  Use only runs with :attr:`ok`."""

    status: str  # converged, not-converged, crashed or diverged
    message: str
    cells: int
    processes: int
    iterations: int
    run_time_s: float  # wall time of the solver (and reconstructPar)
    cpu_time_s: float  # the solver's own ExecutionTime (per process)
    leakage_kg_s: float
    imbalance: float
    drift: float
    patches: dict  # patch -> net flow out, kg/s
    seals: list  # [a, b, kg/s from slot a into slot b]
    chamber_p: dict  # str(slot) -> Pa
    open_area: dict  # port -> {str(slot): m2}
    max_non_orthogonality_deg: float = math.nan
    max_skewness: float = math.nan
    log_tail: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "converged"

    def seal_flows(self) -> dict:
        return {(int(a), int(b)): float(f) for a, b, f in self.seals}

    def pressures(self) -> dict:
        return {int(s): float(p) for s, p in self.chamber_p.items()}

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2, allow_nan=True) + "\n"

    @classmethod
    def from_json(cls, text: str) -> MachineRun:
        return cls(**json.loads(text))


def case_key(m: FrozenMachine, controls: Controls) -> str:
    """A digest of everything that determines the run's result.

    The ports enter as how they were cut (the machine's points per period and the port
    timing's ages, to 1e-9 rad), not as their polygons: the polygons' vertices follow
    the CPU's SIMD paths through Clipper's integer grid (0.37 um apart between numpy's
    AVX-512 and AVX2 sine and cosine, 2026-12-01), so a digest of them matched the
    recorded study on one machine only.  A change to how the
    ports are cut must bump CASE_FORMAT, as any change to the grid does.  A machine
    built without them is keyed by its polygons."""
    sweep = m.sweep
    return foam_case.digest({
        "format": CASE_FORMAT, "pair": m.pair.digest(),
        "sweep": [sweep.kind, sweep.length, sweep.wrap, sweep.scale_end, sweep.lead_ratio],
        "phi": m.phi, "gap": m.gap, "layers": m.layers, "spec": m.spec.key(),
        "end_layer": m.end_layer, "ports": _ports_key(m),
        "plenums": [m.p_suction, m.p_discharge, m.T_suction, m.T_discharge],
        "omega": m.omega_outer, "gas": asdict(m.gas), "moving_walls": m.moving_walls,
        # The starting pressures to the mPa: they come from the quasi-1D model's frozen
        # solve, whose last bits follow the CPU's BLAS kernels (1.4e-14 relative between
        # OpenBLAS's Haswell, Sandybridge, Prescott and Atom kernels, 2026-12-01), and the
        # recorded study's keys, made on an AVX-512 machine, failed on an AVX2 one.  A
        # run's start is not its result: it converges from them.
        "initial_p": sorted((int(k), round(float(v), 3))
                            for k, v in (m.initial_p or {}).items()),
        "controls": asdict(replace(controls, timeout_s=None)),
    })


def _ports_key(m: FrozenMachine) -> list[float] | str:
    if m.port_cut:
        return [int(m.port_cut[0]), *(round(float(t), 9) for t in m.port_cut[1:])]
    ports = hashlib.sha256()
    for region in m.ports:
        for ring in region:
            ports.update(np.ascontiguousarray(np.round(np.asarray(ring, float), 12)).tobytes())
    return ports.hexdigest()


class _Monitor:
    """Called while the solver runs: stops it once the leakage settled and balances."""

    def __init__(self, case_dir: Path, built, controls: Controls):
        self.case_dir, self.built, self.controls = case_dir, built, controls
        self.next_check = time.monotonic() + MONITOR_EVERY_S
        self.stopped = False

    def __call__(self) -> None:
        if self.stopped or time.monotonic() < self.next_check:
            return
        self.next_check = time.monotonic() + MONITOR_EVERY_S
        try:
            out = read_outputs(self.case_dir, self.built, self.controls.window)
        except ExternalRunError:
            return  # nothing written yet
        c = self.controls
        if (out.iterations >= c.window and out.drift < c.settle_tol
                and out.imbalance < c.stop_balance_tol):
            foam.request_stop(self.case_dir)
            self.stopped = True


def _cpu_time(log_path: Path) -> float:
    found = re.findall(r"^ExecutionTime = ([0-9.eE+-]+) s", log_path.read_text(errors="replace")
                       if log_path.is_file() else "", re.MULTILINE)
    return float(found[-1]) if found else math.nan


def judge(case_dir: Path, built, controls: Controls, processes: int,
          values: Mapping[str, Any], elapsed: float, failure: str) -> MachineRun:
    """The run's result from its outputs (see the module docstring)."""
    quality = values["checkMesh"]
    got: dict[str, Any] = {"iterations": 0, "leakage_kg_s": math.nan, "imbalance": math.nan,
                           "drift": math.nan, "patches": {}, "seals": [], "chamber_p": {}}
    outcome: tuple[str, str] | ExternalRunError
    try:
        out = read_outputs(case_dir, built, controls.window)
        got = {"iterations": out.iterations, "leakage_kg_s": out.leakage,
               "imbalance": out.imbalance, "drift": out.drift, "patches": out.patches,
               "seals": [[a, b, f] for (a, b), f in out.seals.items()],
               "chamber_p": {str(s): p for s, p in out.chamber_p.items()}}
        values_ok = all(math.isfinite(v) for v in (*out.patches.values(), *out.seals.values(),
                                                   *out.chamber_p.values()))
        if not values_ok:
            outcome = ("diverged", "non-finite flow or pressure")
        elif not out.imbalance <= controls.balance_tol:
            outcome = ("not-converged", f"mass balance {out.imbalance:.2%} over all patches, "
                       f"above {controls.balance_tol:.1%}")
        elif not out.drift <= controls.settle_accept_tol:
            outcome = ("not-converged", f"leakage still changes by {out.drift:.2e} over the "
                       f"last {controls.window} iterations")
        else:
            outcome = ("converged", "")
    except ExternalRunError as exc:
        outcome = exc
    v = foam_case.verdict(case_dir, SOLVER, failure, outcome, ok="converged")
    return MachineRun(
        status=v.status, message=v.message, cells=built.cells, processes=processes,
        run_time_s=elapsed, cpu_time_s=_cpu_time(case_dir / f"log.{SOLVER}"),
        open_area={p: {str(s): a for s, a in d.items()} for p, d in built.open_area.items()},
        max_non_orthogonality_deg=quality.max_non_orthogonality_deg,
        max_skewness=quality.max_skewness, log_tail=v.log_tail, **got)


def _build(m: FrozenMachine, controls: Controls, dec: Decomposition, label: str,
           folder: Path):
    try:
        plan, built = write_case(m, folder)
    except CaseError as exc:
        raise CaseError(f"{label}: {exc}") from None
    solve = replace(plan.solve, timeout_s=controls.timeout_s,
                    on_poll=_Monitor(folder, built, controls))
    return parallel_plan(replace(plan, solve=solve), folder, dec), built


def recorded_run(m: FrozenMachine, case_dir: Path, controls: Controls = Controls()
                 ) -> MachineRun | None:
    """The finished run of ``m`` in ``case_dir`` under the key :func:`run_machine_case`
    gives it (None: not finished, or another case): a recorded study read back without
    OpenFOAM."""
    _, key = _keyed(m, controls)
    return foam_case.stored_result(case_dir, key, MachineRun.from_json)


def _keyed(m: FrozenMachine, controls: Controls) -> tuple[FrozenMachine, str]:
    """``m`` as the controls run it, and its key."""
    m = replace(m, iterations=controls.max_iterations)
    return m, case_key(m, controls)


def run_machine_case(m: FrozenMachine, case_dir: Path, controls: Controls = Controls(),
                     decomposition: Decomposition = SERIAL, *, reuse: bool = True,
                     label: str | None = None) -> MachineRun:
    """Build, run and judge ``m`` in ``case_dir`` (reused when its key matches); a grid
    that cannot be made raises CaseError naming ``label`` (default: the angle)."""
    label = label or f"rotor angle {math.degrees(m.phi):.6g} deg"
    m, key = _keyed(m, controls)

    def judged(folder, built, values, elapsed, failure):
        return judge(folder, built, controls, decomposition.processes, values, elapsed,
                     failure)

    return foam_case.run_case(
        case_dir, key,
        functools.partial(_build, m, controls, decomposition, label), judged,
        MachineRun.from_json, reuse=reuse, label="machine case",
        summary=lambda r: (f"{r.status} {r.message}, {r.cells} cells, leakage "
                           f"{r.leakage_kg_s:.4g} kg/s, balance {r.imbalance:.1e}, "
                           f"{r.iterations} iterations, {r.run_time_s:.0f} s"))

