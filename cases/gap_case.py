"""Case A: steady compressible leakage through a 2D clearance gap, with OpenFOAM.

:func:`run_gap_case` runs a case through the routine every CFD case shares
(:func:`rotorflow.cases.foam_case.run_case`: built in a temporary folder, judged from its
outputs, renamed into place with ``result.json``, reused by key).  Its OpenFOAM commands
are planned as data (:func:`plan`)::

    gmshToFoam gap.msh      then the patch types
    checkMesh               then its report (and gmsh's cell count)
    postProcess -func writeCellCentres -time 0    then the initial fields
    rhoSimpleFoam           watched by the convergence monitor

Boundary conditions: total pressure and total temperature at the inlet, static pressure
at the outlet, adiabatic no-slip walls that may slide along themselves (the rotor surface
speeds).  The gas is rotorflow's one perfect gas,
:class:`~rotorflow.quasi1d.perfect_gas.PerfectGas` (air by default); laminar unless the
estimated gap Reynolds number asks for k-omega SST.

The mass flow is taken from both patches by ``surfaceFieldValue sum(phi)`` every
iteration.  A run counts as converged only when the inlet and outlet flows agree within
:attr:`SolverControls.balance_tol` and the inlet flow has stopped changing; a crash, a
floating-point trap, a non-finite flow or a flow that keeps drifting marks the result
failed, with the log tail, and :attr:`GapResult.ok` keeps it out of every fit and table.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError, ExternalRunError
from rotorflow.postprocess.foam_output import PatchFlowHistory, read_patch_flows
from rotorflow.quasi1d.perfect_gas import PerfectGas

from . import foam, foam_case
from .foam import Step
from .foam_case import Plan
from .foam_mesh import MeshQuality, mesh_steps
from .gap_mesh import PATCH_TYPES, GapMeshSpec
from .gap_setup import (
    CELL_CENTRES,
    SOLVER,
    choose_turbulence,
    gap_reynolds,
    read_cell_centres,
    write_fields,
    write_files,
)
from .gap_walls import GapWalls
from .parallel import SERIAL, Decomposition, parallel_plan

#: Version of the case this module writes: bump it when dictionaries or judgement change,
#: so that stored results of older cases are recomputed rather than reused.
CASE_FORMAT = 2
#: Decimals of a metre the walls' coordinates are keyed to (:meth:`GapCase.key`).
KEY_DECIMALS = 12


@dataclass(frozen=True)
class GapFlow:
    """Operating point of a gap: upstream total state, downstream static pressure, walls."""

    p_total_Pa: float
    T_total_K: float
    p_exit_Pa: float
    wall_speed_lower_m_s: float = 0.0
    """Speed of the lower wall along itself, positive from inlet to outlet."""
    wall_speed_upper_m_s: float = 0.0
    gas: PerfectGas = field(default_factory=PerfectGas)
    turbulence: str = "auto"
    """'laminar', 'kOmegaSST' or 'auto' (by the estimated gap Reynolds number)."""

    def __post_init__(self) -> None:
        if not (self.p_total_Pa > self.p_exit_Pa > 0 and self.T_total_K > 0):
            raise CaseError("a gap needs p_total > p_exit > 0 and T_total > 0")
        if self.turbulence not in ("auto", "laminar", "kOmegaSST"):
            raise CaseError(f"turbulence must be auto, laminar or kOmegaSST: {self.turbulence}")

    @property
    def pressure_ratio(self) -> float:
        return self.p_total_Pa / self.p_exit_Pa


@dataclass(frozen=True)
class SolverControls:
    """When to stop iterating and what counts as converged.

    The solver is stopped by a monitor that reads the mass-flow tables while it runs, as
    soon as the inlet flow has settled and the two patch flows agree within
    ``stop_balance_tol``; the result is accepted if they agree within ``balance_tol``.
    """

    max_iterations: int = 6000
    settle_window: int = 200
    """Iterations over which the inlet mass flow must have stopped changing: its range
    (max - min) over the window, over its last value, below..."""
    settle_tol: float = 1e-4
    """...this to stop the run (far below the 0.5 % balance and the 2 % mesh target)..."""
    settle_accept_tol: float = 3e-4
    """...and this to accept it: the solver takes a few iterations to notice the stop."""
    stop_balance_tol: float = 1e-3
    """|inlet - outlet| / inlet at which the monitor stops the run: a margin under..."""
    balance_tol: float = 5e-3
    """...the issue's 0.5 % mass balance that an accepted result must meet."""
    timeout_s: float | None = 900.0


@dataclass(frozen=True)
class GapCase:
    """Everything that defines one leakage run."""

    walls: GapWalls
    flow: GapFlow
    mesh: GapMeshSpec = field(default_factory=GapMeshSpec)
    controls: SolverControls = field(default_factory=SolverControls)

    def refined(self, factor: float) -> GapCase:
        return replace(self, mesh=self.mesh.refined(factor))

    def key(self) -> str:
        """A digest of everything that determines the result (reuse of finished runs)."""
        return foam_case.digest({
            "format": CASE_FORMAT,
            # The walls to the picometre: their last bits follow numpy's SIMD paths
            # (1e-19 m apart on 610 of 804 coordinates between its AVX-512 and SSE sine
            # and cosine, 2026-12-01), and the recorded sections must key alike on any CPU.
            "lower": np.round(self.walls.lower, KEY_DECIMALS).tolist(),
            "upper": np.round(self.walls.upper, KEY_DECIMALS).tolist(),
            "flow": asdict(self.flow),
            "mesh": asdict(self.mesh),
            "controls": asdict(self.controls),
        })


@dataclass(frozen=True)
class GapResult:
    """What a leakage run produced.  Use only results with :attr:`ok`."""

    status: str
    """'converged', 'not-converged', 'diverged' or 'crashed'."""
    message: str
    mass_flow_inlet_kg_s_m: float
    """Mass flow per metre of gap depth (the 2D mesh's depth divided out)."""
    mass_flow_outlet_kg_s_m: float
    imbalance: float
    iterations: int
    run_time_s: float
    turbulence: str
    reynolds: float
    min_gap_m: float
    gap_length_m: float
    """Length of the narrow part of the gap (see GapWalls.narrow_length)."""
    pressure_ratio: float
    cells: int
    mesh_refinement: float
    max_aspect_ratio: float = math.nan
    max_non_orthogonality_deg: float = math.nan
    log_tail: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "converged"

    @property
    def mass_flow_kg_s_m(self) -> float:
        """Mean of inlet and outlet mass flow per metre of depth."""
        return 0.5 * (self.mass_flow_inlet_kg_s_m + self.mass_flow_outlet_kg_s_m)

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2, allow_nan=True) + "\n"

    @classmethod
    def from_json(cls, text: str) -> GapResult:
        return cls(**json.loads(text))



# --- building, planning, running ----------------------------------------------------------


@dataclass(frozen=True)
class _Built:
    """What the judge needs of a built gap case."""

    turbulence: str
    depth_m: float


def plan(case: GapCase, case_dir: Path, mesh_cells: int | None = None,
         progress: Callable[[float], None] | None = None) -> Plan:
    """The OpenFOAM commands of ``case`` built in ``case_dir`` (see the module docstring).

    ``mesh_cells``: gmsh's cell count, which checkMesh must find (None: not checked);
    ``progress`` receives the fraction of ``max_iterations`` done.
    """
    turbulence = choose_turbulence(case.walls, case.flow)

    def fields(folder: Path, _log: Path) -> None:
        write_fields(folder, case, turbulence, read_cell_centres(folder))

    return Plan(
        setup=(*mesh_steps("gap.msh", PATCH_TYPES, mesh_cells), Step(CELL_CENTRES, then=fields)),
        solve=Step((SOLVER,), timeout_s=case.controls.timeout_s,
                   on_poll=_Monitor(Path(case_dir), case.controls, progress)),
    )


def _build(case: GapCase, progress, dec: Decomposition, case_dir: Path
           ) -> tuple[Plan, _Built]:
    turbulence, mesh = write_files(case, case_dir)
    return (parallel_plan(plan(case, case_dir, mesh.cells, progress), case_dir, dec),
            _Built(turbulence, mesh.depth_m))


def write_case(case: GapCase, case_dir: Path) -> tuple[str, MeshQuality, float]:
    """Write the full OpenFOAM case into ``case_dir`` (mesh included: the plan's setup
    steps are drained), without running the solver.

    Returns the turbulence model chosen, checkMesh's verdict and the mesh depth.
    """
    case_dir = Path(case_dir)
    the_plan, built = _build(case, None, SERIAL, case_dir)
    values = foam.drain(the_plan.setup, case_dir)
    return built.turbulence, values["checkMesh"], built.depth_m


def run_gap_case(
    case: GapCase,
    case_dir: Path,
    *,
    progress: Callable[[float], None] | None = None,
    reuse: bool = True,
    decomposition: Decomposition = SERIAL,
) -> GapResult:
    """Build and run one gap case in ``case_dir``; return (and store) its result.

    The routine of :func:`rotorflow.cases.foam_case.run_case`: built in
    ``<case_dir>.tmp``, renamed to ``case_dir`` when judged, with ``result.json`` and
    ``case.key``; with ``reuse``, a folder whose key matches is not run again (failed
    results included: they are kept, never retried silently).  ``progress`` receives the
    fraction of ``max_iterations`` done (the run usually stops well before, once
    converged).  Mesh problems raise (CaseError, MeshCheckError); solver failures return
    a failed result.  ``decomposition``: run the solver on that many processes
    (:mod:`.parallel`; the case and its key are the same as the serial run's).
    """
    def judged(folder: Path, built: _Built, values: Mapping[str, Any], elapsed: float,
               failure: str) -> GapResult:
        return judge(folder, case, built.turbulence, values["checkMesh"], built.depth_m,
                     elapsed, failure)

    return foam_case.run_case(
        case_dir, case.key(), functools.partial(_build, case, progress, decomposition), judged,
        GapResult.from_json, reuse=reuse, label="gap case",
        summary=lambda r: (f"{r.status}, {r.mass_flow_kg_s_m:.4g} kg/s/m, imbalance "
                           f"{r.imbalance:.2e}, {r.iterations} iterations, "
                           f"{r.run_time_s:.1f} s"))


def load_result(case_dir: Path) -> GapResult | None:
    """The stored result of a finished case folder, or None when there is none."""
    path = Path(case_dir) / "result.json"
    return GapResult.from_json(path.read_text()) if path.is_file() else None


def read_mass_flow_history(case_dir: Path) -> PatchFlowHistory:
    """The inlet and outlet mass-flow tables of a gap case, joined per iteration."""
    return read_patch_flows(case_dir, "massFlowInlet", "massFlowOutlet")


def assess_history(
    history: PatchFlowHistory, controls: SolverControls, *, stopping: bool = False
) -> tuple[str, str, float, float, float]:
    """Judge a mass-flow history: (status, message, inlet, outlet, imbalance).

    Converged: finite, positive, the inlet flow varied by less than the settle tolerance
    over the last ``settle_window`` iterations, and inlet and outlet agree within the
    balance tolerance; ``stopping`` applies the monitor's tighter tolerances.
    """
    balance_tol = controls.stop_balance_tol if stopping else controls.balance_tol
    settle_tol = controls.settle_tol if stopping else controls.settle_accept_tol
    m_in, m_out = history.inlet, history.outlet
    if not (np.all(np.isfinite(m_in)) and np.all(np.isfinite(m_out))):
        return "diverged", "non-finite mass flow", math.nan, math.nan, math.nan
    last_in, last_out = float(m_in[-1]), float(m_out[-1])
    if last_in <= 0 or last_out <= 0:
        return ("not-converged",
                f"mass flow not from inlet to outlet ({last_in:.4g}, {last_out:.4g})",
                last_in, last_out, math.nan)
    imbalance = abs(last_in - last_out) / last_in
    if len(m_in) <= controls.settle_window:
        return ("not-converged", f"only {len(m_in)} iterations", last_in, last_out, imbalance)
    drift = float(np.ptp(m_in[-controls.settle_window - 1 :])) / last_in
    if drift > settle_tol:
        return ("not-converged",
                f"inlet mass flow still varies by {drift:.2e} over the last "
                f"{controls.settle_window} iterations", last_in, last_out, imbalance)
    if imbalance > balance_tol:
        return ("not-converged",
                f"inlet and outlet mass flow differ by {imbalance:.2%}", last_in, last_out,
                imbalance)
    return "converged", "", last_in, last_out, imbalance


class _Monitor:
    """Called while the solver runs: reports progress, stops the run once converged."""

    def __init__(self, case_dir: Path, controls: SolverControls,
                 progress: Callable[[float], None] | None) -> None:
        self.case_dir = case_dir
        self.controls = controls
        self.progress = progress
        self.stopped = False

    def __call__(self) -> None:
        try:
            history = read_mass_flow_history(self.case_dir)
        except ExternalRunError:
            return  # nothing written yet
        if self.progress is not None:
            self.progress(min(1.0, history.iteration[-1] / self.controls.max_iterations))
        status = assess_history(history, self.controls, stopping=True)[0]
        if status == "converged" and not self.stopped:
            foam.request_stop(self.case_dir)
            self.stopped = True


def judge(case_dir: Path, case: GapCase, turbulence: str, quality: MeshQuality,
          depth: float, elapsed: float, failure: str) -> GapResult:
    """Build the result of a finished (or failed) solver run from its outputs."""
    m_in = m_out = imbalance = math.nan
    iterations = 0
    outcome: tuple[str, str] | ExternalRunError
    try:
        history = read_mass_flow_history(case_dir)
        iterations = int(history.iteration[-1])
        judged = assess_history(history, case.controls)
        outcome = judged[:2]
        m_in, m_out, imbalance = judged[2:]
    except ExternalRunError as exc:
        outcome = exc
    v = foam_case.verdict(case_dir, SOLVER, failure, outcome, ok="converged")
    return GapResult(
        status=v.status,
        message=v.message,
        mass_flow_inlet_kg_s_m=m_in / depth,
        mass_flow_outlet_kg_s_m=m_out / depth,
        imbalance=imbalance,
        iterations=iterations,
        run_time_s=elapsed,
        turbulence=turbulence,
        reynolds=gap_reynolds(m_in / depth, case.flow) if math.isfinite(m_in) else math.nan,
        min_gap_m=case.walls.min_gap,
        gap_length_m=case.walls.narrow_length(),
        pressure_ratio=case.flow.pressure_ratio,
        cells=quality.cells,
        mesh_refinement=case.mesh.refinement,
        max_aspect_ratio=quality.max_aspect_ratio,
        max_non_orthogonality_deg=quality.max_non_orthogonality_deg,
        log_tail=v.log_tail,
    )
