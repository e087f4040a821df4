"""A steady 3D case of the internal-gear machine at a frozen rotor angle (issue 16).

The helical stack of O-grid sections (:mod:`.polymesh`) with its end faces split by the
ports of :mod:`..geometry.ports`: on the low-pressure plate (z = 0) the faces whose
centre lies in the suction port form the patch ``suction``, on the high-pressure plate
those in the discharge port ``discharge``, the rest of both plates ``endPlates`` (a
static wall).  Each rotor is a rotating wall about its own axis (stock
``rotatingWallVelocity``, which keeps only the velocity's tangential part, so no flow
crosses a wall: the rotors are frozen).  rhoSimpleFoam, laminar, the gas a perfect gas;
both ports at their plenum's total pressure, so each chamber open to a port takes its
pressure and the closed ones settle where their leakage in and out balances.

:func:`write_case` writes the case; :func:`mass_flows` reads the flow through every
patch from the ``surfaceFieldValue`` tables the run writes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.quasi1d.perfect_gas import PerfectGas

from .foam_dicts import (
    control_dict,
    field_value,
    fv_schemes,
    inlet_outlet,
    thermophysical_properties,
    turbulence_properties,
    uniform,
)
from .foam_files import write_dict, write_field
from .grid3d_quality import stack_nodes
from .grid3d_zones import find_zones, write_zones
from .ogrid import OGridSpec
from .polymesh import build_polymesh, helical_stack, write_mesh

SOLVER = "rhoSimpleFoam"
PORTS = ("suction", "discharge")
#: Clipping bounds during the run (:func:`_limits`): temperature between these shares
#: of the suction and discharge temperatures, speed below this Mach number at suction.
LIMIT_T = (0.5, 2.0)
LIMIT_MACH = 1.5
#: ``limited`` coefficient of the Laplacian's non-orthogonal correction.
NON_ORTH_LIMIT = 0.333


@dataclass(frozen=True)
class Frozen3DCase:
    """What the 3D case is: the machine at one angle and the run's settings."""

    machine: Any  # geometry.machine.SweptMachine (helical or straight)
    phi: float  # outer-rotor angle of the section at z = 0 [rad]
    gap: float  # clearance [m]
    layers: int
    p_suction_Pa: float
    p_discharge_Pa: float
    T_suction_K: float
    speed_outer_rad_s: float
    volume_ratio: float = 2.0
    spec: OGridSpec = field(default_factory=OGridSpec)
    end_layer: float | None = None  # thin end layers [m], :func:`.polymesh.graded_heights`
    gas: PerfectGas = field(default_factory=PerfectGas)
    iterations: int = 500

    @property
    def T_discharge_K(self) -> float:
        """The discharge plenum's temperature: the isentrope from suction (the gas that
        comes back in through the discharge port)."""
        g = self.gas.gamma
        return self.T_suction_K * (self.p_discharge_Pa / self.p_suction_Pa) ** ((g - 1.0) / g)


def port_polygons(machine, volume_ratio: float) -> dict[str, list[np.ndarray]]:
    """The suction and discharge ports as polygon rings (counter-clockwise outlines,
    clockwise holes), fixed frame, metres."""
    from rotorflow.geometry.ports import port_timing, ports

    timing = port_timing(machine, volume_ratio)
    regions = dict(zip(PORTS, ports(machine, timing), strict=True))
    return {name: [np.asarray(q, float) for q in region.to_polygons()]
            for name, region in regions.items()}


def inside(points: np.ndarray, rings: list[np.ndarray]) -> np.ndarray:
    """Whether each point lies in the region the rings bound (even-odd rule: a hole's
    ring cancels its outline's)."""
    x, y = points[:, 0][:, None], points[:, 1][:, None]
    odd = np.zeros(len(points), bool)
    for ring in rings:
        a, b = ring, np.roll(ring, -1, axis=0)
        ya, yb = a[:, 1][None, :], b[:, 1][None, :]
        crosses = (ya > y) != (yb > y)
        with np.errstate(invalid="ignore", divide="ignore"):
            xc = a[:, 0][None, :] + (y - ya) * (b[:, 0] - a[:, 0])[None, :] / (yb - ya)
        odd ^= (np.sum(crosses & (x < xc), axis=1) % 2).astype(bool)
    return odd


def end_labels(polygons: dict[str, list[np.ndarray]]):
    """The end-face namer :func:`.polymesh.build_polymesh` takes: suction on the
    low-pressure plate, discharge on the high-pressure one, endPlates elsewhere."""

    def name(xy: np.ndarray, end: str):
        port = "suction" if end == "lp" else "discharge"
        names = np.where(inside(xy, polygons[port]), port, "endPlates")
        return names, {port: "patch", "endPlates": "wall"}

    return name


def _control_dict(case: Frozen3DCase, patches: list[str], zones: dict) -> dict[str, Any]:
    every = {"write_control": "timeStep", "write_interval": 1}
    functions = {f"flow_{p}": field_value("surfaceFieldValue", "patch", "sum", ["phi"],
                                          name=p, **every) for p in patches}
    for zone in zones:
        if zone.startswith("chamber"):
            functions[f"pressure_{zone}"] = field_value(
                "volFieldValue", "cellZone", "volAverage", ["p"], name=zone, **every)
        else:
            functions[f"flow_{zone}"] = field_value(
                "surfaceFieldValue", "faceZone", "sum", ["phi"], name=zone, **every)
    return control_dict(
        SOLVER, start_from="latestTime", end_time=case.iterations, delta_t=1,
        write_control="timeStep", write_interval=case.iterations, purge_write=1,
        time_precision=8, run_time_modifiable=False, functions=functions)


def _fv_solution() -> dict[str, Any]:
    # The gap case's solvers and transonic pressure equation (cases/gap_setup.py: a
    # sealing gap between the plenums chokes); plain SIMPLE with the pressure relaxed:
    # with SIMPLEC (consistent, p unrelaxed) gas at rest between resting walls on the
    # helical stack (faces at 47 deg on average, 78 at most) blew up within 10 to 130
    # iterations, whatever the non-orthogonal correction.
    return {
        "solvers": {
            "p": {"solver": "GAMG", "smoother": "GaussSeidel", "tolerance": 1e-12,
                  "relTol": 0.01, "maxIter": 100},
            '"(U|e)"': {"solver": "smoothSolver", "smoother": "symGaussSeidel",
                        "tolerance": 1e-14, "relTol": 0.1, "maxIter": 100},
        },
        "SIMPLE": {"nNonOrthogonalCorrectors": 1, "consistent": False, "transonic": True,
                   "pMinFactor": 0.5, "pMaxFactor": 1.5},
        "relaxationFactors": {"fields": {"p": 0.3},
                              "equations": {"U": 0.5, "e": 0.5}},
    }


def _limits(case: Frozen3DCase) -> dict[str, Any]:
    """Stock clipping of T and |U| (limitTemperature, limitVelocity): the first SIMPLE
    corrections overshoot in the sealing gaps (1650 m/s at the first iteration of the
    coarse test case, though the Darcy start holds the chambers at their pressures),
    the kinetic energy then drives the internal energy negative and the thermo fails.
    The bounds are far outside the converged solution: a run that ends on them is not
    converged (:func:`mass_flows` checks the balance)."""
    sound = math.sqrt(case.gas.gamma * case.gas.R * case.T_suction_K)
    return {
        "limitT": {"type": "limitTemperature", "active": True, "selectionMode": "all",
                   "min": LIMIT_T[0] * case.T_suction_K,
                   "max": LIMIT_T[1] * case.T_discharge_K},
        "limitU": {"type": "limitVelocity", "active": True, "selectionMode": "all",
                   "max": LIMIT_MACH * sound},
    }


def _fv_schemes() -> dict[str, Any]:
    bounded = ("bounded", "Gauss", "linearUpwind", "limited")
    out = fv_schemes("steadyState", {
        "div(phi,U)": bounded, "div(phi,e)": bounded,
        "div(phi,K)": ("bounded", "Gauss", "linear"),
        "div(phi,Ekp)": ("bounded", "Gauss", "linear"),
        "div(phid,p)": ("Gauss", "upwind"),
    })
    # The non-orthogonal correction limited to a third of the orthogonal part (the
    # usual choice past 70 deg: the full correction is unstable there).
    out["laplacianSchemes"] = {"default": ("Gauss", "linear", "limited", NON_ORTH_LIMIT)}
    out["snGradSchemes"] = {"default": ("limited", NON_ORTH_LIMIT)}
    return out


def write_case(case: Frozen3DCase, case_dir: Path) -> dict:
    """Write the mesh, dictionaries and initial fields; returns the mesh counts."""
    m = case.machine
    if m.pair.family != "internal-gear":
        raise CaseError(f"3D O-grid cases are for the internal gear, not {m.pair.family}")
    case_dir = Path(case_dir)
    sections, z = helical_stack(m.pair, case.phi, case.gap, m.sweep, case.layers, case.spec,
                                case.end_layer)
    polygons = port_polygons(m, case.volume_ratio)
    mesh = build_polymesh(sections, z, end_labels(polygons))
    counts = write_mesh(case_dir, mesh)
    patches = list(counts["patches"])
    for port in PORTS:
        if port not in patches:
            raise CaseError(f"no end face of the grid at {math.degrees(case.phi):.4g} deg "
                            f"lies in the {port} port")
    X = stack_nodes(sections, z)
    found = find_zones(X, case.gap, mesh)
    zones = write_zones(case_dir, found)
    counts["zones"] = zones
    # The area through which each chamber opens to each port (the rest are closed).
    pts, faces, owner = mesh[0], mesh[1], mesh[2]
    counts["open_to"] = {}
    for name, _, start, count in mesh[4]:
        if name in PORTS:
            q = pts[faces[start:start + count]]
            area = 0.5 * np.linalg.norm(np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]), axis=1)
            c = found.chamber[owner[start:start + count]]
            counts["open_to"][name] = {f"chamber{k}": float(area[c == k].sum())
                                       for k in np.unique(c)}
    system, constant = case_dir / "system", case_dir / "constant"
    write_dict(system / "controlDict", _control_dict(case, patches, zones))
    write_dict(system / "fvSchemes", _fv_schemes())
    write_dict(system / "fvSolution", _fv_solution())
    write_dict(system / "fvOptions", _limits(case))
    write_dict(constant / "thermophysicalProperties", thermophysical_properties(case.gas))
    write_dict(constant / "turbulenceProperties", turbulence_properties("laminar"))
    p_init = initial_pressure(X, mesh, {
        "suction": case.p_suction_Pa, "discharge": case.p_discharge_Pa})
    _write_fields(case, case_dir / "0", patches, p_init)
    return counts


def initial_pressure(X: np.ndarray, mesh: tuple, plenums: dict[str, float]) -> np.ndarray:
    """A starting pressure per cell: isothermal Darcy flow (p^2 harmonic) through a
    medium whose permeability is the square of the local width between the rotors, the
    ports held at their plenums' pressures.  The chambers (millimetres wide) come out
    at about uniform pressure and the pressure falls across the sealing gaps, as the
    lubrication start of the gap case (:mod:`.gap_setup`).  Started from a uniform
    pressure instead, the first SIMPLE correction drove 2e5 m/s through the cells next
    to the discharge port (the momentum equation's diagonal there is only the viscous
    one of a millimetre cell) and the run failed at the second iteration."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve

    pts, faces, owner, nei, patches = mesh
    width = np.linalg.norm(X[:, :, -1] - X[:, :, 0], axis=-1)  # (layers + 1, columns)
    w = 0.25 * (width[:-1] + width[1:] + np.roll(width[:-1], -1, 1) + np.roll(width[1:], -1, 1))
    rows = X.shape[2] - 1
    perm = np.repeat(w[:, :, None] ** 2, rows, axis=2).ravel()  # cell order k, i, j
    centre = 0.125 * sum(np.roll(np.roll(X, -di, 1), 0, 0)[dk:X.shape[0] - 1 + dk, :,
                                                             dj:rows + dj]
                         for di in (0, 1) for dj in (0, 1) for dk in (0, 1)).reshape(-1, 3)
    q = pts[faces]
    area = 0.5 * np.linalg.norm(np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]), axis=1)
    fc = q.mean(1)
    n_int, n = len(nei), len(centre)
    own_i = owner[:n_int]
    g = area[:n_int] / np.linalg.norm(centre[nei] - centre[own_i], axis=1) * np.minimum(
        perm[own_i], perm[nei])
    diag = np.bincount(own_i, g, n) + np.bincount(nei, g, n)
    rhs = np.zeros(n)
    for name, _, start, count in patches:
        if name in plenums:
            f = np.arange(start, start + count)
            c = owner[f]
            gb = area[f] / np.linalg.norm(fc[f] - centre[c], axis=1) * perm[c]
            diag += np.bincount(c, gb, n)
            rhs += np.bincount(c, gb * plenums[name] ** 2, n)
    a = coo_matrix((np.concatenate([diag, -g, -g]),
                    (np.concatenate([np.arange(n), own_i, nei]),
                     np.concatenate([np.arange(n), nei, own_i]))), shape=(n, n)).tocsr()
    return np.sqrt(spsolve(a, rhs))


def _write_fields(case: Frozen3DCase, zero: Path, patches: list[str], p_init) -> None:
    outer, inner = case.machine.pair.rotors
    psi = {"psi": "thermo:psi", "gamma": case.gas.gamma}
    ps, pd, Ts, Td = case.p_suction_Pa, case.p_discharge_Pa, case.T_suction_K, case.T_discharge_K
    zero_u = np.zeros(3)

    def rotating(rotor) -> dict[str, Any]:
        axis = np.asarray(rotor.axis, float)
        return {"type": "rotatingWallVelocity", "origin": [axis[0], axis[1], 0.0],
                "axis": [0.0, 0.0, 1.0], "omega": case.speed_outer_rad_s * rotor.speed_ratio,
                "value": zero_u}

    def by_patch(suction, discharge, rotors, plates):
        out = {"suction": suction, "discharge": discharge,
               "innerRotor": rotors[1] if isinstance(rotors, tuple) else rotors,
               "outerRotor": rotors[0] if isinstance(rotors, tuple) else rotors,
               "endPlates": plates}
        return {p: out[p] for p in patches}

    grad = {"type": "zeroGradient"}
    write_field(zero / "p", (1, -1, -2), p_init, by_patch(
        {"type": "totalPressure", "p0": uniform(ps), **psi, "value": ps},
        {"type": "totalPressure", "p0": uniform(pd), **psi, "value": pd}, grad, grad))
    write_field(zero / "T", (0, 0, 0, 1), Ts, by_patch(
        inlet_outlet(Ts), inlet_outlet(Td), grad, grad))
    write_field(zero / "U", (0, 1, -1), zero_u, vector=True, boundary=by_patch(
        {"type": "pressureInletOutletVelocity", "value": zero_u},
        {"type": "pressureInletOutletVelocity", "value": zero_u},
        (rotating(outer), rotating(inner)), {"type": "noSlip"}))


def mass_flows(case_dir: Path) -> dict[str, float]:
    """Mass flow [kg/s] at the last iteration through each patch (out of the domain
    positive) and each sealing line (seal<n>: from its faces' owners to neighbours),
    the sums of phi from the run's surfaceFieldValue tables."""
    return _last(case_dir, "flow_", "surfaceFieldValue")


def chamber_pressures(case_dir: Path) -> dict[str, float]:
    """Volume-averaged pressure [Pa] of each chamber (cellZone) at the last iteration."""
    return _last(case_dir, "pressure_", "volFieldValue")


def _last(case_dir: Path, prefix: str, kind: str) -> dict[str, float]:
    out = {}
    for path in sorted(Path(case_dir, "postProcessing").glob(f"{prefix}*/*/{kind}.dat")):
        rows = [r.split() for r in path.read_text().splitlines() if r and not r.startswith("#")]
        if not rows:
            raise CaseError(f"{path} holds no iteration")
        out[path.parent.parent.name.removeprefix(prefix)] = float(rows[-1][1])
    return out
