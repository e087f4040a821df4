"""A steady 3D run of the whole internal-gear machine at a frozen rotor angle (issue 16).

The working domain is the stacked structured grid (:mod:`.ogrid`, :mod:`.polymesh`) of
the machine at outer-rotor angle ``phi``, with thin end layers where asked
(:func:`.polymesh.graded_heights`: they keep the end faces' skewness within checkMesh's
limit on a helix).  Its end faces inside the ports (:func:`..geometry.ports.ports`) are
the ``suction`` and ``discharge`` patches, named by the mesh writer itself
(:func:`.machine_zones.end_labels`): the plenums' total pressures (the plenum is at
rest, as the quasi-1D model's; the gas enters at the plenum's temperature).  The rest
of the end plates is the static wall ``endPlates``, and each rotor's wall turns about
its own axis at its own speed (stock ``rotatingWallVelocity``, which keeps the
tangential part of omega x r: the rotors are frozen, their surfaces slide).
rhoSimpleFoam, laminar: at the clearances of these machines (20-100 um) the gap
Reynolds number is far below transition (:mod:`.gap_setup`'s criterion), and the
chambers, closed or open to a large port, hold slow flow.

What it reports (``postProcessing``, read by :func:`read_outputs`): the net flow through
every patch (walls included: they must carry none), through each sealing faceZone
between two chambers (:mod:`.machine_zones`), and each chamber's volume-averaged
pressure, by slot (machine age ``phi + s * period``); the mass balance is the net flow
over all patches against the inflow.

The cells start at the pressure the product's quasi-1D model gives each chamber at the
same frozen angle (:mod:`rotorflow.quasi1d.frozen`) where the caller passes it, else
at the mean of the plenums.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.postprocess.foam_output import function_object_table
from rotorflow.quasi1d.perfect_gas import PerfectGas

from .foam import Step
from .foam_case import Plan
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
from .foam_mesh import judge_check_mesh
from .machine_zones import NONE, PORTS, chamber_zones, end_labels, seal_faces, write_zones
from .ogrid_quality import QualityLimits
from .polymesh import build_polymesh, helical_stack, write_mesh

SOLVER = "rhoSimpleFoam"
#: Function objects write every this many iterations (tables stay small on long runs).
OUTPUT_EVERY = 10
WALLS = ("innerRotor", "outerRotor", "endPlates")
#: Bound on |U| while the start settles (m/s): above the choked speed of air at the
#: temperatures reached (~400 m/s at 400 K), so a settled flow never meets it.
VELOCITY_LIMIT = 600.0


def slot_name(s: int) -> str:
    return f"chamber{s}" if s >= 0 else f"chamber_m{-s}"


def seal_name(a: int, b: int) -> str:
    return f"seal_{slot_name(a)}_{slot_name(b)}"


@dataclass(frozen=True)
class FrozenMachine:
    """The machine at one angle with its plenums (SI)."""

    pair: Any
    sweep: Any
    phi: float  # outer-rotor (machine) angle, rad
    gap: float  # clearance, m
    layers: int
    spec: Any  # cases.ogrid.OGridSpec
    ports: tuple  # (suction, discharge) regions: lists of polygons in the end planes
    p_suction: float
    p_discharge: float
    T_suction: float
    T_discharge: float
    omega_outer: float  # rad/s, counter-clockwise positive
    gas: PerfectGas = field(default_factory=PerfectGas)
    iterations: int = 1500
    initial_p: dict | None = None  # slot -> Pa (the frozen quasi-1D state)
    end_layer: float | None = None  # thin end layers, m (:func:`.polymesh.graded_heights`)
    moving_walls: bool = True  # the rotors' surfaces slide at their speeds (else at rest)
    #: How the ports were cut: the machine's points per period and the ages (rad) of its
    #: :class:`..geometry.ports.PortTiming`.  With the pair and sweep they determine the
    #: ports, and they key the run (its polygons' last vertices follow the CPU's SIMD
    #: paths, :func:`.machine_run.case_key`).
    port_cut: tuple = ()

    def rotor_speeds(self) -> list[tuple[str, tuple[float, float], float]]:
        """(patch, axis point, omega) per rotor: the outer rotor about O1, the inner
        about its own axis, each at its speed ratio."""
        out = []
        for patch, rotor in zip(("outerRotor", "innerRotor"), self.pair.rotors, strict=True):
            out.append((patch, tuple(float(c) for c in rotor.axis),
                        float(rotor.speed_ratio) * self.omega_outer))
        return out


@dataclass(frozen=True)
class Built:
    """What the judge needs of the written case."""

    cells: int
    slots: tuple
    ages: dict
    seals: tuple  # (a, b) slot pairs with a sealing zone
    patches: tuple  # every patch's name
    open_area: dict  # port -> {slot: end-face area of the slot's cells in the port, m2}


def write_case(m: FrozenMachine, case_dir: Path) -> tuple[Plan, Built]:
    """Write the case into ``case_dir``: mesh with its port patches and zones,
    dictionaries, fields; return its plan (checkMesh; the solver) and what the judge
    needs.  A grid without a face in a port is a CaseError naming the angle."""
    case_dir = Path(case_dir)
    sections, z = helical_stack(m.pair, m.phi, m.gap, m.sweep, m.layers, m.spec, m.end_layer)
    zones = chamber_zones(m.pair, sections, z, m.phi, m.sweep)
    mesh = build_polymesh(sections, z, end_labels(m.ports))
    pts, faces, owner, nei, patches = mesh
    names = [p[0] for p in patches]
    for port in PORTS:
        if port not in names:
            raise CaseError(f"no end face of the grid lies in the {port} port at "
                            f"phi = {math.degrees(m.phi):.6g} deg")
    write_mesh(case_dir, mesh)
    seals = seal_faces(zones, owner, nei)
    cell_zones = {slot_name(s): zones.cells_of(s) for s in zones.slots}
    face_zones = {seal_name(a, b): v for (a, b), v in seals.items()}
    write_zones(case_dir, cell_zones, face_zones)
    _write_dicts(m, case_dir, names, list(cell_zones), list(face_zones))
    _write_fields(m, case_dir, zones, names)
    open_area = {}
    for name, _, start, count in patches:
        if name in PORTS:
            q = pts[faces[start:start + count]]
            area = 0.5 * np.linalg.norm(np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]), axis=1)
            slot = zones.cell_slot[owner[start:start + count]]
            open_area[name] = {int(s): float(area[slot == s].sum()) for s in np.unique(slot)
                               if s != NONE}
    cells = zones.cell_slot.size
    plan = Plan(
        # thin gap cells are the grid's design: the O-grid's own aspect limit holds
        setup=(Step(("checkMesh",), then=functools.partial(
            judge_check_mesh, expected_cells=cells,
            max_aspect_ratio=QualityLimits().max_aspect_ratio)),),
        solve=Step((SOLVER,)),
    )
    return plan, Built(cells, zones.slots, dict(zones.ages), tuple(seals), tuple(names),
                       open_area)


def _write_dicts(m: FrozenMachine, case_dir: Path, patches: list, chambers: list,
                 seals: list) -> None:
    def fo(kind, region, op, fields, name):
        return field_value(kind, region, op, fields, write_control="timeStep",
                           write_interval=OUTPUT_EVERY, name=name)

    functions = {f"flow_{p}": fo("surfaceFieldValue", "patch", "sum", ["phi"], p)
                 for p in patches}
    functions |= {f"flow_{s}": fo("surfaceFieldValue", "faceZone", "sum", ["phi"], s)
                  for s in seals}
    functions |= {f"p_{c}": fo("volFieldValue", "cellZone", "volAverage", ["p"], c)
                  for c in chambers}
    system, constant = case_dir / "system", case_dir / "constant"
    write_dict(system / "controlDict", control_dict(
        SOLVER, start_from="latestTime", end_time=m.iterations, delta_t=1,
        write_control="timeStep", write_interval=m.iterations, purge_write=1,
        time_precision=8, run_time_modifiable=True, functions=functions))
    bounded = ("bounded", "Gauss", "linearUpwind", "limited")
    schemes = fv_schemes("steadyState", {
        "div(phi,U)": bounded, "div(phi,e)": bounded,
        "div(phi,K)": ("bounded", "Gauss", "linear"),
        "div(phi,Ekp)": ("bounded", "Gauss", "linear"),
        "div(phid,p)": ("Gauss", "upwind")})
    # the stacked helical grid is non-orthogonal (checkMesh up to ~80 deg near the
    # sealing lines): limit the correction there and correct twice per iteration
    schemes["laplacianSchemes"] = {"default": ("Gauss", "linear", "limited", 0.5)}
    schemes["snGradSchemes"] = {"default": ("limited", 0.5)}
    write_dict(system / "fvSchemes", schemes)
    write_dict(system / "fvSolution", {
        "solvers": {
            # At most 20 V-cycles a correction: on the 20 um grids (cells 600:1 in the
            # gaps, faces at 87 deg) GAMG stalls at the start and the first iterations
            # then took 100 cycles for each of three corrections (6 s each on 221,184
            # cells); capped, with the DIC smoother, 1.7 s, and from iteration 30 on it
            # converges in 2-6 cycles anyway.
            "p": {"solver": "GAMG", "smoother": "DICGaussSeidel", "tolerance": 1e-12,
                  "relTol": 0.01, "maxIter": 20},
            '"(U|e)"': {"solver": "smoothSolver", "smoother": "symGaussSeidel",
                        "tolerance": 1e-14, "relTol": 0.1, "maxIter": 100},
        },
        "SIMPLE": {"nNonOrthogonalCorrectors": 2, "consistent": False, "transonic": False,
                   "pMinFactor": 0.5, "pMaxFactor": 2.0},
        "relaxationFactors": {"fields": {"p": 0.3, "rho": 0.05},
                              "equations": {"U": 0.5, "e": 0.5}},
    })
    # The chambers start at different pressures across gaps a few cells wide: the first
    # iterations accelerate the gap cells violently.  Stock fvOptions bound T and |U|
    # there (inactive once the solution settles; the judge checks they no longer act).
    T_lo, T_hi = 0.5 * m.T_suction, 2.0 * m.T_discharge
    write_dict(system / "fvOptions", {
        "limitT": {"type": "limitTemperature", "active": True, "selectionMode": "all",
                   "min": T_lo, "max": T_hi},
        "limitU": {"type": "limitVelocity", "active": True, "selectionMode": "all",
                   "max": VELOCITY_LIMIT},
    })
    write_dict(constant / "thermophysicalProperties", thermophysical_properties(m.gas))
    write_dict(constant / "turbulenceProperties", turbulence_properties("laminar"))


def _write_fields(m: FrozenMachine, case_dir: Path, zones, patches: list) -> None:
    zero = case_dir / "0"
    p_mid = 0.5 * (m.p_suction + m.p_discharge)
    p = np.full(zones.cell_slot.size, p_mid)
    T = np.full(zones.cell_slot.size, 0.5 * (m.T_suction + m.T_discharge))
    known = dict(m.initial_p or {})
    for s in zones.slots:  # chambers the model does not hold: their nearest plenum's
        if s not in known and known:
            known[s] = m.p_suction if s < min(known) else m.p_discharge
    for s, ps in known.items():
        p[zones.cell_slot == s] = ps
        T[zones.cell_slot == s] = m.T_suction if ps <= m.p_suction else m.T_discharge
    walls = {name: {"type": "zeroGradient"} for name in WALLS if name in patches}
    # Each port at its plenum's total pressure: the gas enters from rest, and what
    # enters through a port face next to a sealing gap is bounded by the plenum's
    # state (with a fixed static pressure there the inflow grew without bound on the
    # default machine at 20 um: the 600 m/s velocity bound reached in the discharge end
    # layer, cells at 585 K, a chamber open to discharge at 4.2 bar).
    psi = {"psi": "thermo:psi", "gamma": m.gas.gamma}
    write_field(zero / "p", (1, -1, -2), p, {
        "suction": {"type": "totalPressure", "p0": uniform(m.p_suction), **psi,
                    "value": m.p_suction},
        "discharge": {"type": "totalPressure", "p0": uniform(m.p_discharge), **psi,
                      "value": m.p_discharge}, **walls})
    write_field(zero / "T", (0, 0, 0, 1), T, {
        "suction": inlet_outlet(m.T_suction), "discharge": inlet_outlet(m.T_discharge),
        **walls})
    zero_u = np.zeros(3)
    u_walls = {name: {"type": "rotatingWallVelocity", "origin": [*axis, 0.0],
                      "axis": [0.0, 0.0, 1.0], "omega": omega, "value": zero_u}
               for name, axis, omega in m.rotor_speeds() if m.moving_walls}
    write_field(zero / "U", (0, 1, -1), zero_u, vector=True, boundary={
        "suction": {"type": "pressureInletOutletVelocity", "value": zero_u},
        "discharge": {"type": "pressureInletOutletVelocity", "value": zero_u},
        **{w: {"type": "noSlip"} for w in walls if w not in u_walls}, **u_walls})


@dataclass(frozen=True)
class MachineOutputs:
    """Last values of the function objects: the net flow out of every patch (kg/s,
    positive out of the domain), sealing flows (kg/s from the younger slot a into b),
    chamber pressures (Pa)."""

    iterations: int
    patches: dict
    seals: dict
    chamber_p: dict
    imbalance: float  # |net flow out of all patches| / inflow
    drift: float  # largest change of a port flow over the drift window, over the flow

    @property
    def inflow(self) -> float:
        return -sum(min(f, 0.0) for f in self.patches.values())

    @property
    def leakage(self) -> float:
        """The machine's total leakage at the frozen angle: the mean of what enters and
        what leaves (the gas comes in by the discharge port and leaves by suction)."""
        return 0.5 * (self.inflow + sum(max(f, 0.0) for f in self.patches.values()))


def read_outputs(case_dir: Path, built: Built, window: int | None = None) -> MachineOutputs:
    """The run's last values (see :class:`MachineOutputs`); ``window``: iterations over
    which the ports' drift is taken (default: the last tenth of the run)."""
    def table(name, file_name):
        return function_object_table(case_dir, name, file_name)[1]

    flows = {p: table(f"flow_{p}", "surfaceFieldValue.dat") for p in built.patches}
    last_it = min(t[-1, 0] for t in flows.values())
    window = max(last_it // 10, 1) if window is None else window
    drift = 0.0
    for p in PORTS:
        t = flows[p]
        before = t[t[:, 0] <= last_it - window]
        drift = max(drift, abs(t[-1, 1] - before[-1, 1]) / max(abs(t[-1, 1]), 1e-300)
                    if len(before) else math.inf)
    net = {p: float(t[-1, 1]) for p, t in flows.items()}
    seals = {(a, b): float(table(f"flow_{seal_name(a, b)}", "surfaceFieldValue.dat")[-1, 1])
             for a, b in built.seals}
    chamber_p = {s: float(table(f"p_{slot_name(s)}", "volFieldValue.dat")[-1, 1])
                 for s in built.slots}
    inflow = -sum(min(f, 0.0) for f in net.values())
    return MachineOutputs(int(last_it), net, seals, chamber_p,
                          abs(sum(net.values())) / inflow if inflow > 0 else math.inf, drift)
