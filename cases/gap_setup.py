"""What the gap case writes into its folder: dictionaries, the gmsh mesh, initial fields.

The flow through a gap is estimated before any CFD (viscous and nozzle limits in
series), to choose the turbulence model and to start the solution near it: the pressure
of isothermal lubrication flow, p^2 linear in the resistance integral of dx / h^3, and
the estimated mass flow in a parabolic profile along the gap's centre line.
:func:`write_files` writes everything but the fields, which are written once the mesh
exists, from its cell centres (:data:`CELL_CENTRES`, a step of the gap case's plan, then
:func:`write_fields`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rotorflow.quasi1d.flows import isentropic_mass_flux

from .foam_dicts import (
    FRONT_AND_BACK,
    control_dict,
    field_value,
    fv_schemes,
    inlet_outlet,
    thermophysical_properties,
    turbulence_properties,
    uniform,
)
from .foam_files import write_dict, write_field
from .gap_mesh import GapMesh, write_msh
from .gap_walls import GapWalls

if TYPE_CHECKING:
    from .gap_case import GapCase, GapFlow, SolverControls

SOLVER = "rhoSimpleFoam"

#: Gap Reynolds number rho*U*h/mu (= mass flow per depth / mu) above which the flow is
#: computed with k-omega SST: plane channel flow turns turbulent near Re_Dh = 2300, and
#: the hydraulic diameter of a slot is twice its height.
RE_TURBULENT = 1150.0

#: Largest initial Mach number: the lubrication start may overestimate the flow near the
#: throat, and a supersonic start is a poor guess for a gap that may not choke.
INITIAL_MACH_CAP = 0.8

#: The step of the gap case's plan that writes the cell centres the fields start from.
CELL_CENTRES = ("postProcess", "-func", "writeCellCentres", "-time", "0")


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
    def flux(patch: str) -> dict[str, Any]:
        return field_value("surfaceFieldValue", "patch", "sum", ["phi"],
                           write_control="timeStep", write_interval=1, name=patch)

    return control_dict(
        SOLVER, start_from="latestTime", end_time=controls.max_iterations, delta_t=1,
        write_control="timeStep", write_interval=controls.max_iterations, purge_write=1,
        time_precision=8,
        run_time_modifiable=True,  # the convergence monitor stops the run through it
        # ...and the solver must see the change at once: OpenFOAM ignores edits younger
        # than fileModificationSkew (10 s by default) after its last read.
        switches={"OptimisationSwitches": {"fileModificationSkew": 0,
                                           "fileModificationChecking": "timeStamp"}},
        functions={
            "massFlowInlet": flux("inlet"),
            "massFlowOutlet": flux("outlet"),
            "solverInfo": {
                "type": "solverInfo",
                "libs": ["utilityFunctionObjects"],
                "fields": ["U", "p", "e"] + ([] if turbulence == "laminar" else ["k", "omega"]),
                "writeControl": "timeStep",
                "writeInterval": 1,
            },
        },
    )


def _fv_schemes() -> dict[str, Any]:
    bounded = ("bounded", "Gauss", "linearUpwind", "limited")
    return fv_schemes("steadyState", {
        "div(phi,U)": bounded,
        "div(phi,e)": bounded,
        "div(phi,h)": bounded,
        "div(phi,K)": ("bounded", "Gauss", "linear"),
        "div(phi,Ekp)": ("bounded", "Gauss", "linear"),
        "div(phid,p)": ("Gauss", "upwind"),
        "div(phi,k)": ("bounded", "Gauss", "upwind"),
        "div(phi,omega)": ("bounded", "Gauss", "upwind"),
    }, wall_distance=True)


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


def write_files(case: GapCase, case_dir: Path) -> tuple[str, GapMesh]:
    """Write what Python writes (dictionaries, gmsh's ``gap.msh``, the empty ``0/``);
    return the turbulence model chosen and the gmsh mesh."""
    turbulence = choose_turbulence(case.walls, case.flow)
    # The transonic pressure equation always: gap flows reach high subsonic speeds well
    # below the critical pressure ratio, where the plain formulation diverges on fine
    # meshes; at low speed both give the same mass flow (3e-5 apart in a 1.005 channel).
    transonic = True
    system, constant = case_dir / "system", case_dir / "constant"
    write_dict(system / "controlDict", _control_dict(case.controls, turbulence))
    write_dict(system / "fvSchemes", _fv_schemes())
    write_dict(system / "fvSolution", _fv_solution(transonic))
    write_dict(constant / "thermophysicalProperties", thermophysical_properties(case.flow.gas))
    write_dict(constant / "turbulenceProperties", turbulence_properties(turbulence))
    mesh = write_msh(case.walls, case.mesh, case_dir / "gap.msh")
    (case_dir / "0").mkdir(exist_ok=True)
    return turbulence, mesh



# --- fields -------------------------------------------------------------------------------


def _boundary(inlet: dict, outlet: dict, walls: dict | tuple[dict, dict]) -> dict[str, dict]:
    lower, upper = walls if isinstance(walls, tuple) else (walls, walls)
    return {"inlet": inlet, "outlet": outlet, "lowerWall": lower, "upperWall": upper,
            **FRONT_AND_BACK}


def write_fields(case_dir: Path, case: GapCase, turbulence: str, centres: dict) -> None:
    """The initial fields in ``case_dir/0`` (p, T, U; k, omega, nut, alphat when turbulent)
    at the cell and face centres ``centres`` (see :func:`read_cell_centres`)."""
    flow, gas = case.flow, case.flow.gas
    zero = case_dir / "0"
    p0, T0, p2 = flow.p_total_Pa, flow.T_total_K, flow.p_exit_Pa
    psi = {"psi": "thermo:psi", "gamma": gas.gamma}

    # Start from the isothermal lubrication solution p^2 linear in the resistance integral.
    frac = _resistance_fraction(case.walls, centres["internal"][:, 0])
    p_init = np.sqrt(p0**2 - (p0**2 - p2**2) * frac)
    write_field(zero / "p", (1, -1, -2), p_init, _boundary(
        {"type": "totalPressure", "p0": uniform(p0), **psi, "value": p0},
        {"type": "fixedValue", "value": p2},
        {"type": "zeroGradient"},
    ))
    write_field(zero / "T", (0, 0, 0, 1), T0, _boundary(
        {"type": "totalTemperature", "T0": uniform(T0), **psi, "value": T0},
        inlet_outlet(T0),
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
    write_field(zero / "U", (0, 1, -1), u_init, vector=True, boundary=_boundary(
        {"type": "pressureInletOutletVelocity", "value": zero_u},
        inlet_outlet(zero_u),
        wall_u,
    ))
    if turbulence != "laminar":
        _write_turbulence_fields(zero, case)


def _write_turbulence_fields(zero: Path, case: GapCase) -> None:
    flow, gas = case.flow, case.flow.gas
    p0, T0, p2 = flow.p_total_Pa, flow.T_total_K, flow.p_exit_Pa
    # Inflow turbulence: 5 % intensity of the nozzle velocity, length scale a tenth of the gap.
    u_ref = isentropic_mass_flux(p0, T0, p2, gas.gamma, gas.R) / gas.density(p2, T0)
    k_in = 1.5 * (0.05 * u_ref) ** 2
    omega_in = math.sqrt(k_in) / (0.09**0.25 * 0.1 * case.walls.min_gap)
    inflow = {"type": "turbulentIntensityKineticEnergyInlet", "intensity": 0.05,
              "value": k_in}
    write_field(zero / "k", (0, 2, -2), k_in, _boundary(
        inflow, inlet_outlet(k_in), {"type": "kqRWallFunction", "value": k_in},
    ))
    write_field(zero / "omega", (0, 0, -1), omega_in, _boundary(
        {"type": "fixedValue", "value": omega_in},
        inlet_outlet(omega_in),
        {"type": "omegaWallFunction", "value": omega_in},
    ))
    calc = {"type": "calculated", "value": 0.0}
    write_field(zero / "nut", (0, 2, -1), 0.0, _boundary(
        calc, calc, {"type": "nutUSpaldingWallFunction", "value": 0.0}))
    write_field(zero / "alphat", (1, -1, -1), 0.0, _boundary(
        calc, calc, {"type": "compressible::alphatWallFunction", "Prt": 0.85,
                     "value": 0.0}))


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


def read_cell_centres(case_dir: Path) -> dict[str, np.ndarray]:
    """Cell centres and wall/patch face centres, from what :data:`CELL_CENTRES` wrote
    (``0/C``); the centre fields are removed again (they are not initial fields)."""
    from foamlib import FoamFieldFile

    c = FoamFieldFile(case_dir / "0" / "C")
    out = {"internal": np.atleast_2d(np.asarray(c["internalField"], dtype=float))}
    for patch, entry in c["boundaryField"].items():
        if "value" in entry:
            out[patch] = np.atleast_2d(np.asarray(entry["value"], dtype=float))
    for name in ("C", "Cx", "Cy", "Cz"):
        (case_dir / "0" / name).unlink(missing_ok=True)
    return out
