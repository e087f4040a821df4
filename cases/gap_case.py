"""Case A: steady compressible leakage through a 2D clearance gap, with OpenFOAM.

:func:`run_gap_case` builds the case in a temporary folder (mesh, dictionaries, initial
fields), runs rhoSimpleFoam, judges the run from its outputs and renames the folder into
place with ``result.json``; an interrupted run never leaves a folder that looks finished.

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

import hashlib
import json
import logging
import math
import re
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError, ExternalRunError
from rotorflow.postprocess.foam_output import PatchFlowHistory, read_patch_flows
from rotorflow.quasi1d.flows import isentropic_mass_flux
from rotorflow.quasi1d.perfect_gas import PerfectGas

from . import foam
from .gap_mesh import GapMeshSpec, GapWalls, build_foam_mesh

log = logging.getLogger(__name__)

SOLVER = "rhoSimpleFoam"

#: Gap Reynolds number rho*U*h/mu (= mass flow per depth / mu) above which the flow is
#: computed with k-omega SST: plane channel flow turns turbulent near Re_Dh = 2300, and
#: the hydraulic diameter of a slot is twice its height.
RE_TURBULENT = 1150.0

#: Version of the case this module writes: bump it when dictionaries or judgement change,
#: so that stored results of older cases are recomputed rather than reused.
CASE_FORMAT = 2

#: Log lines kept in a failed result.
RESULT_LOG_LINES = 30


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
        payload = {
            "format": CASE_FORMAT,
            "lower": self.walls.lower.tolist(),
            "upper": self.walls.upper.tolist(),
            "flow": asdict(self.flow),
            "mesh": asdict(self.mesh),
            "controls": asdict(self.controls),
        }
        text = json.dumps(payload, sort_keys=True, allow_nan=True)
        return hashlib.sha256(text.encode()).hexdigest()[:20]


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


# --- estimates ----------------------------------------------------------------------------


def estimate_mass_flow(walls: GapWalls, flow: GapFlow) -> float:
    """A rough mass flow per depth (kg/s/m): viscous and nozzle limits in series.

    The viscous limit is isothermal lubrication flow, m' = (p0^2 - p^2) / (24 mu R T I)
    with I = integral of dx / h(x)^3; the nozzle limit the isentropic flux through the
    minimum gap.  Only used to choose the turbulence model and to start the solution.
    """
    gas, T0 = flow.gas, flow.T_total_K
    x = walls.sample_x(2001)
    resistance = np.trapezoid(walls.gap(x) ** -3.0, x)
    viscous = (flow.p_total_Pa**2 - flow.p_exit_Pa**2) / (24 * gas.mu(T0) * gas.R * T0 * resistance)
    nozzle = walls.min_gap * isentropic_mass_flux(flow.p_total_Pa, T0, flow.p_exit_Pa,
                                                  gas.gamma, gas.R)
    return 1.0 / math.hypot(1.0 / viscous, 1.0 / nozzle)


def gap_reynolds(mass_flow_kg_s_m: float, flow: GapFlow) -> float:
    """rho U h / mu = mass flow per depth / mu, with mu at the total temperature."""
    return abs(mass_flow_kg_s_m) / flow.gas.mu(flow.T_total_K)


def choose_turbulence(walls: GapWalls, flow: GapFlow) -> str:
    if flow.turbulence != "auto":
        return flow.turbulence
    re = gap_reynolds(estimate_mass_flow(walls, flow), flow)
    return "kOmegaSST" if re > RE_TURBULENT else "laminar"


# --- dictionaries -------------------------------------------------------------------------


def _control_dict(controls: SolverControls, turbulence: str) -> dict[str, Any]:
    flux = {
        "type": "surfaceFieldValue",
        "libs": ["fieldFunctionObjects"],
        "writeControl": "timeStep",
        "writeInterval": 1,
        "log": False,
        "writeFields": False,
        "regionType": "patch",
        "operation": "sum",
        "fields": ["phi"],
    }
    return {
        "application": SOLVER,
        "startFrom": "latestTime",
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": controls.max_iterations,
        "deltaT": 1,
        "writeControl": "timeStep",
        "writeInterval": controls.max_iterations,
        "purgeWrite": 1,
        "writeFormat": "ascii",
        "writePrecision": 10,
        "writeCompression": False,
        "timeFormat": "general",
        "timePrecision": 8,
        "runTimeModifiable": True,  # the convergence monitor stops the run through it
        # ...and the solver must see the change at once: OpenFOAM ignores edits younger
        # than fileModificationSkew (10 s by default) after its last read.
        "OptimisationSwitches": {"fileModificationSkew": 0, "fileModificationChecking":
                                 "timeStamp"},
        "functions": {
            "massFlowInlet": {**flux, "name": "inlet"},
            "massFlowOutlet": {**flux, "name": "outlet"},
            "solverInfo": {
                "type": "solverInfo",
                "libs": ["utilityFunctionObjects"],
                "fields": ["U", "p", "e"] + ([] if turbulence == "laminar" else ["k", "omega"]),
                "writeControl": "timeStep",
                "writeInterval": 1,
            },
        },
    }


def _fv_schemes() -> dict[str, Any]:
    bounded = ("bounded", "Gauss", "linearUpwind", "limited")
    return {
        "ddtSchemes": {"default": "steadyState"},
        "gradSchemes": {"default": ("Gauss", "linear"), "limited": ("cellLimited", "Gauss",
                                                                   "linear", 1)},
        "divSchemes": {
            "default": "none",
            "div(phi,U)": bounded,
            "div(phi,e)": bounded,
            "div(phi,h)": bounded,
            "div(phi,K)": ("bounded", "Gauss", "linear"),
            "div(phi,Ekp)": ("bounded", "Gauss", "linear"),
            "div(phid,p)": ("Gauss", "upwind"),
            "div(phi,k)": ("bounded", "Gauss", "upwind"),
            "div(phi,omega)": ("bounded", "Gauss", "upwind"),
            "div(((rho*nuEff)*dev2(T(grad(U)))))": ("Gauss", "linear"),
        },
        "laplacianSchemes": {"default": ("Gauss", "linear", "corrected")},
        "interpolationSchemes": {"default": "linear"},
        "snGradSchemes": {"default": "corrected"},
        "wallDist": {"method": "meshWave"},
    }


def _fv_solution(transonic: bool) -> dict[str, Any]:
    # Normalised residuals of a compressible case plateau near 1e-10 (p) and 1e-5 (a
    # velocity component that is zero in the solution), so they cannot stop the run;
    # the mass-flow monitor does.  Linear solvers: relative tolerances with a cap.
    return {
        "solvers": {
            "p": {"solver": "GAMG", "smoother": "GaussSeidel", "tolerance": 1e-12,
                  "relTol": 0.01, "maxIter": 100},
            '"(U|e|k|omega)"': {"solver": "smoothSolver", "smoother": "symGaussSeidel",
                              "tolerance": 1e-14, "relTol": 0.1, "maxIter": 100},
        },
        "SIMPLE": {
            "nNonOrthogonalCorrectors": 0,
            "consistent": True,
            "transonic": transonic,
            "pMinFactor": 0.1,
            "pMaxFactor": 2.0,
        },
        "relaxationFactors": {
            "fields": {"p": 1.0},  # SIMPLEC (consistent): no pressure relaxation
            # U at 0.7: 0.9 diverges on the coarse meshes of laminar jets.  e at 0.95:
            # in long viscous gaps the energy equation converges slowly under relaxation
            # (0.7 took 4000 iterations where 0.95 takes 250, to the same flow).
            "equations": {"U": 0.7, "e": 0.95, '"(k|omega)"': 0.7, "p": 1.0},
        },
    }


def thermophysical_properties(gas: PerfectGas) -> dict[str, Any]:
    """constant/thermophysicalProperties of ``gas``: a perfect gas with constant cp and
    Sutherland or constant viscosity (hePsiThermo, sensible internal energy)."""
    transport = (
        {"mu": gas.mu_Pa_s, "Pr": gas.prandtl}
        if gas.transport == "const"
        else {"As": gas.sutherland_As, "Ts": gas.sutherland_Ts_K}
    )
    return {
        "thermoType": {
            "type": "hePsiThermo",
            "mixture": "pureMixture",
            "transport": gas.transport,
            "thermo": "hConst",
            "equationOfState": "perfectGas",
            "specie": "specie",
            "energy": "sensibleInternalEnergy",
        },
        "mixture": {
            "specie": {"molWeight": gas.molar_mass_kg_kmol},
            "thermodynamics": {"Cp": gas.cp_J_kgK, "Hf": 0},
            "transport": transport,
        },
    }


def _turbulence_properties(model: str) -> dict[str, Any]:
    if model == "laminar":
        return {"simulationType": "laminar"}
    return {"simulationType": "RAS", "RAS": {"RASModel": model, "turbulence": True,
                                             "printCoeffs": True}}


# --- fields -------------------------------------------------------------------------------

_EMPTY = {"frontAndBack": {"type": "empty"}}


def _uniform(value: Any) -> tuple[str, Any]:
    """A field-valued entry other than value/inletValue (foamlib adds those itself)."""
    return ("uniform", value)


def _boundary(inlet: dict, outlet: dict, walls: dict | tuple[dict, dict]) -> dict[str, dict]:
    lower, upper = walls if isinstance(walls, tuple) else (walls, walls)
    return {"inlet": inlet, "outlet": outlet, "lowerWall": lower, "upperWall": upper, **_EMPTY}


def _write_fields(case_dir: Path, case: GapCase, turbulence: str, centres: dict) -> None:
    flow, gas = case.flow, case.flow.gas
    zero = case_dir / "0"
    p0, T0, p2 = flow.p_total_Pa, flow.T_total_K, flow.p_exit_Pa
    psi = {"psi": "thermo:psi", "gamma": gas.gamma}

    # Start from the isothermal lubrication solution p^2 linear in the resistance integral.
    frac = _resistance_fraction(case.walls, centres["internal"][:, 0])
    p_init = np.sqrt(p0**2 - (p0**2 - p2**2) * frac)
    foam.write_field(zero / "p", (1, -1, -2), p_init, _boundary(
        {"type": "totalPressure", "p0": _uniform(p0), **psi, "value": p0},
        {"type": "fixedValue", "value": p2},
        {"type": "zeroGradient"},
    ))
    foam.write_field(zero / "T", (0, 0, 0, 1), T0, _boundary(
        {"type": "totalTemperature", "T0": _uniform(T0), **psi, "value": T0},
        {"type": "inletOutlet", "inletValue": T0, "value": T0},
        {"type": "zeroGradient"},
    ))
    wall_u = tuple(
        _wall_velocity(speed, slope(centres[patch][:, 0]))
        for patch, speed, slope in (
            ("lowerWall", flow.wall_speed_lower_m_s, case.walls.slope_lower),
            ("upperWall", flow.wall_speed_upper_m_s, case.walls.slope_upper),
        )
    )
    zero_u = np.zeros(3)
    u_init = _initial_velocity(case, centres["internal"], gas.density(p_init, T0))
    foam.write_field(zero / "U", (0, 1, -1), u_init, vector=True, boundary=_boundary(
        {"type": "pressureInletOutletVelocity", "value": zero_u},
        {"type": "inletOutlet", "inletValue": zero_u, "value": zero_u},
        wall_u,
    ))
    if turbulence == "laminar":
        return
    # Inflow turbulence: 5 % intensity of the nozzle velocity, length scale a tenth of the gap.
    u_ref = isentropic_mass_flux(p0, T0, p2, gas.gamma, gas.R) / gas.density(p2, T0)
    k_in = 1.5 * (0.05 * u_ref) ** 2
    omega_in = math.sqrt(k_in) / (0.09**0.25 * 0.1 * case.walls.min_gap)
    inflow = {"type": "turbulentIntensityKineticEnergyInlet", "intensity": 0.05,
              "value": k_in}
    foam.write_field(zero / "k", (0, 2, -2), k_in, _boundary(
        inflow, {"type": "inletOutlet", "inletValue": k_in, "value": k_in},
        {"type": "kqRWallFunction", "value": k_in},
    ))
    foam.write_field(zero / "omega", (0, 0, -1), omega_in, _boundary(
        {"type": "fixedValue", "value": omega_in},
        {"type": "inletOutlet", "inletValue": omega_in, "value": omega_in},
        {"type": "omegaWallFunction", "value": omega_in},
    ))
    calc = {"type": "calculated", "value": 0.0}
    foam.write_field(zero / "nut", (0, 2, -1), 0.0, _boundary(
        calc, calc, {"type": "nutUSpaldingWallFunction", "value": 0.0}))
    foam.write_field(zero / "alphat", (1, -1, -1), 0.0, _boundary(
        calc, calc, {"type": "compressible::alphatWallFunction", "Prt": 0.85,
                     "value": 0.0}))


#: Largest initial Mach number: the lubrication start may overestimate the flow near the
#: throat, and a supersonic start is a poor guess for a gap that may not choke.
INITIAL_MACH_CAP = 0.8


def _initial_velocity(case: GapCase, cells: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """A starting velocity: the estimated mass flow in a parabolic profile at each x,
    along the local centre-line direction, capped at :data:`INITIAL_MACH_CAP`."""
    walls, flow = case.walls, case.flow
    x, y = cells[:, 0], cells[:, 1]
    h = walls.gap(x)
    eta = np.clip((y - walls.y_lower(x)) / h, 0.0, 1.0)
    u_mean = estimate_mass_flow(walls, flow) / (rho * h)
    speed = 6.0 * u_mean * eta * (1.0 - eta)
    sound = math.sqrt(flow.gas.gamma * flow.gas.R * flow.T_total_K)
    speed = np.minimum(speed, INITIAL_MACH_CAP * sound)
    slope = 0.5 * (walls.slope_lower(x) + walls.slope_upper(x))
    norm = np.sqrt(1.0 + slope**2)
    return np.column_stack([speed / norm, speed * slope / norm, np.zeros_like(x)])


def _wall_velocity(speed: float, slope: np.ndarray) -> dict[str, Any]:
    if speed == 0:
        return {"type": "noSlip"}
    # Slide along the wall: velocity tangent to it, so no flow through it.
    norm = np.sqrt(1 + slope**2)
    u = speed * np.column_stack([1 / norm, slope / norm, np.zeros_like(slope)])
    return {"type": "fixedValue", "value": u}


def _resistance_fraction(walls: GapWalls, x: np.ndarray) -> np.ndarray:
    """Fraction of the viscous resistance integral of dx/h^3 upstream of each x."""
    xs = walls.sample_x(4001)
    integrand = walls.gap(xs) ** -3.0
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (integrand[1:] + integrand[:-1])
                                                  * np.diff(xs))])
    return np.interp(x, xs, cumulative / cumulative[-1])


def _cell_centres(case_dir: Path) -> dict[str, np.ndarray]:
    """Cell centres and wall/patch face centres, from ``postProcess -func writeCellCentres``."""
    from foamlib import FoamFieldFile

    (case_dir / "0").mkdir(exist_ok=True)
    foam.run(case_dir, "postProcess", ["-func", "writeCellCentres", "-time", "0"])
    c = FoamFieldFile(case_dir / "0" / "C")
    out = {"internal": np.atleast_2d(np.asarray(c["internalField"], dtype=float))}
    for patch, entry in c["boundaryField"].items():
        if "value" in entry:
            out[patch] = np.atleast_2d(np.asarray(entry["value"], dtype=float))
    for name in ("C", "Cx", "Cy", "Cz"):
        (case_dir / "0" / name).unlink(missing_ok=True)
    return out


# --- running ------------------------------------------------------------------------------


def write_case(case: GapCase, case_dir: Path) -> tuple[str, foam.MeshQuality, float]:
    """Write the full OpenFOAM case into ``case_dir`` (mesh included).

    Returns the turbulence model chosen, checkMesh's verdict and the mesh depth.
    """
    case_dir = Path(case_dir)
    turbulence = choose_turbulence(case.walls, case.flow)
    # The transonic pressure equation always: gap flows reach high subsonic speeds well
    # below the critical pressure ratio, where the plain formulation diverges on fine
    # meshes; at low speed both give the same mass flow (3e-5 apart in a 1.005 channel).
    transonic = True
    system, constant = case_dir / "system", case_dir / "constant"
    foam.write_dict(system / "controlDict", _control_dict(case.controls, turbulence))
    foam.write_dict(system / "fvSchemes", _fv_schemes())
    foam.write_dict(system / "fvSolution", _fv_solution(transonic))
    mesh, quality = build_foam_mesh(case_dir, case.walls, case.mesh)
    foam.write_dict(constant / "thermophysicalProperties",
                    thermophysical_properties(case.flow.gas))
    foam.write_dict(constant / "turbulenceProperties", _turbulence_properties(turbulence))
    _write_fields(case_dir, case, turbulence, _cell_centres(case_dir))
    return turbulence, quality, mesh.depth_m


def run_gap_case(
    case: GapCase,
    case_dir: Path,
    *,
    progress: Callable[[float], None] | None = None,
    reuse: bool = True,
) -> GapResult:
    """Build and run one gap case in ``case_dir``; return (and store) its result.

    The case is built in ``<case_dir>.tmp`` and renamed to ``case_dir`` when judged, with
    ``result.json`` and ``case.key`` inside; with ``reuse``, a folder whose key matches is
    not run again (failed results included: they are kept, never retried silently).
    ``progress`` receives the fraction of ``max_iterations`` done (the run usually stops
    well before, once converged).  Mesh problems raise (CaseError, MeshCheckError);
    solver failures return a failed result.
    """
    case_dir = Path(case_dir)
    foam.check_case_path(case_dir)
    key = case.key()
    if reuse and (case_dir / "case.key").is_file() and (case_dir / "result.json").is_file():
        if (case_dir / "case.key").read_text().strip() == key:
            log.info("gap case %s: reusing the stored result", case_dir.name)
            return GapResult.from_json((case_dir / "result.json").read_text())
    tmp = case_dir.with_name(case_dir.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    turbulence, quality, depth = write_case(case, tmp)
    start = time.monotonic()
    failure = ""
    try:
        foam.run(tmp, SOLVER, timeout_s=case.controls.timeout_s,
                 on_poll=_Monitor(tmp, case.controls, progress))
    except ExternalRunError as exc:
        failure = str(exc)
    elapsed = time.monotonic() - start
    result = judge(tmp, case, turbulence, quality, depth, elapsed, failure)
    (tmp / "result.json").write_text(result.to_json())
    (tmp / "case.key").write_text(key + "\n")
    if case_dir.exists():
        shutil.rmtree(case_dir)
    tmp.rename(case_dir)
    log.info("gap case %s: %s, %.4g kg/s/m, imbalance %.2e, %d iterations, %.1f s",
             case_dir.name, result.status, result.mass_flow_kg_s_m, result.imbalance,
             result.iterations, result.run_time_s)
    return result


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


def judge(case_dir: Path, case: GapCase, turbulence: str, quality: foam.MeshQuality,
          depth: float, elapsed: float, failure: str) -> GapResult:
    """Build the result of a finished (or failed) solver run from its outputs."""
    log_path = case_dir / f"log.{SOLVER}"
    status, message = ("crashed", failure) if failure else ("", "")
    m_in = m_out = imbalance = math.nan
    iterations = 0
    try:
        history = read_mass_flow_history(case_dir)
        iterations = int(history.iteration[-1])
        judged = assess_history(history, case.controls)
        if not failure:
            status, message = judged[0], judged[1]
        m_in, m_out, imbalance = judged[2:]
    except ExternalRunError as exc:
        if not failure:
            status, message = "crashed", str(exc)
    if status == "crashed" and looks_diverged(foam.log_tail(log_path, 60)):
        status = "diverged"
    return GapResult(
        status=status,
        message=message.splitlines()[0] if message else "",
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
        log_tail="" if status == "converged" else foam.log_tail(log_path, RESULT_LOG_LINES),
    )


#: What a log tail shows when the solution blew up rather than the program failing.
_DIVERGENCE = re.compile(
    r"sigFpe|Floating point exception|Maximum number of iterations exceeded"
    r"|Negative initial temperature|\bnan\b|\binf\b",
    re.IGNORECASE,
)


def looks_diverged(log_text: str) -> bool:
    """True when a solver log shows the solution blowing up (FPE trap, nan, runaway T).

    The banner line ``trapFpe: Floating point exception trapping enabled`` that starts
    every log is left out: a run that fails in its first lines has not diverged.
    """
    text = "\n".join(ln for ln in log_text.splitlines() if not ln.startswith("trapFpe"))
    return _DIVERGENCE.search(text) is not None
