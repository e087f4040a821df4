"""The frozen state of a case file's machine at one angle, for the 3D CFD and the quasi-1D
model alike (issue 16).

:func:`frozen_models` puts the product's quasi-1D model (:mod:`rotorflow.quasi1d.frozen`)
into the frozen state of each leakage model asked for, from the case file's own
[operating] and [leakage] settings; :func:`frozen_machine` builds the 3D case of
:mod:`.machine_case` at the same angle, its ports cut by the case's port timing, its
chambers started at the pressures of the case's own leakage model.

The CFD grid has no end-face clearance (the end plates touch the rotors' faces), so the
model's end-face paths are closed for the comparison (``[leakage.end-face] model =
"none"``, the product's own per-kind override): both then leak through the same lines.
"""

from __future__ import annotations

import copy
import math
from dataclasses import astuple, dataclass, replace
from pathlib import Path

from rotorflow.errors import CaseError

from .machine_case import FrozenMachine
from .ogrid import OGridSpec


@dataclass(frozen=True)
class Grid:
    """One grid of the stack: columns around, cells across every gap, equal layers along
    the rotors, and the thin end layer (m; None: none)."""

    columns: int
    cells_across_gap: int
    layers: int
    end_layer_m: float | None = None

    def spec(self, base: OGridSpec | None = None) -> OGridSpec:
        return replace(base or OGridSpec(), columns=self.columns,
                       cells_across_gap=self.cells_across_gap)

    def refined(self, ratio: float) -> Grid:
        """Every direction refined by ``ratio`` (counts rounded; the end layer thinner)."""
        def n(v: int) -> int:
            return max(1, int(round(v * ratio)))

        return Grid(n(self.columns), n(self.cells_across_gap), n(self.layers),
                    None if self.end_layer_m is None else self.end_layer_m / ratio)

    @property
    def label(self) -> str:
        end = "" if self.end_layer_m is None else f"-e{self.end_layer_m * 1e6:.0f}um"
        return f"c{self.columns}-x{self.cells_across_gap}-l{self.layers}{end}"


def comparison_raw(raw: dict, model: str | None = None, correlation: Path | None = None
                   ) -> dict:
    """The case file's sections with the end faces sealed and, where given, every other
    path on ``model`` (``correlation``: the fit of "cfd-calibrated")."""
    out = copy.deepcopy(raw)
    leak = out.setdefault("leakage", {})
    if model is not None:
        leak["model"] = model
        leak.pop("correlation", None)
        if model == "cfd-calibrated":
            if correlation is None:
                raise CaseError('leakage model "cfd-calibrated" needs a fitted flow '
                                "coefficient (flow_coefficient.json)")
            leak["correlation"] = str(Path(correlation).resolve())
    leak["end-face"] = {**leak.get("end-face", {}), "model": "none"}
    return out


def case_table(case):
    """The case's chamber table (the quasi-1D model's input)."""
    from rotorflow.geometry.summary import build_machine, chamber_table

    return chamber_table(case, build_machine(case))


def quasi1d_model(table, raw: dict, where: str):
    """The product's chamber model of ``table`` under the case sections ``raw``."""
    from rotorflow.quasi1d.simulate import build_model, case_settings

    op, leak, ports, num, _ = case_settings(raw, where)
    return build_model(table, op, leak, ports, num)


def table_origin(case) -> float:
    """The machine angle at which the chamber table's angle is zero (the chamber's
    planar birth, where the table's curves start): a chamber of table age ``a`` has
    machine age ``a + table_origin``."""
    from rotorflow.geometry.summary import build_machine

    return float(build_machine(case).planar_life[0])


def frozen_models(case, table, phi: float, models, correlation: Path | None = None,
                  where: str = "the case") -> dict:
    """{model name: FrozenState} at machine angle ``phi`` (the model's angle is the
    table's, ``phi - table_origin``; :func:`slot_of` maps its chambers to the CFD's
    slots)."""
    from rotorflow.quasi1d.frozen import solve_frozen

    theta = phi - table_origin(case)
    return {name: solve_frozen(quasi1d_model(table, comparison_raw(case.raw, name, correlation),
                                             where), theta)
            for name in models}


def slot_of(state, phi: float, period: float, origin: float) -> list[int]:
    """The CFD slot of each of a frozen state's chambers: slot s holds the chamber of
    machine age ``phi + s * period``, the state's chambers have table ages."""
    return [int(round((a + origin - phi) / period)) for a in state.ages]


def frozen_machine(case, table, phi: float, gap: float, grid: Grid, iterations: int = 1500,
                   where: str = "the case", spec: OGridSpec | None = None) -> FrozenMachine:
    """The 3D case of the machine at ``phi`` on ``grid``: ports by the case's timing,
    plenums and speed from its [operating], cells started at its own leakage model's
    frozen pressures (end faces sealed, as in the comparison)."""
    from rotorflow.geometry.ports import ports
    from rotorflow.geometry.summary import build_machine, case_port_timing
    from rotorflow.quasi1d.frozen import solve_frozen

    if case.pair.family != "internal-gear":
        raise CaseError(f"the 3D O-grid case is for the internal gear, not {case.pair.family}")
    if not gap > 0.0:
        raise CaseError(f"the clearance must be positive, got {gap * 1e6:g} um")
    machine = build_machine(case)
    origin = table_origin(case)
    model = quasi1d_model(table, comparison_raw(case.raw), where)
    state = solve_frozen(model, phi - origin)
    period = float(case.pair.period)
    initial = dict(zip(slot_of(state, phi, period, origin), map(float, state.p), strict=True))
    timing = case_port_timing(case, machine)
    suction, discharge = ports(machine, timing)
    return FrozenMachine(
        case.pair, machine.sweep, phi, gap, grid.layers, grid.spec(spec),
        (suction.to_polygons(), discharge.to_polygons()),
        float(model.suc.p), float(model.dis.p), float(model.suc.T), float(model.dis.T),
        float(model.geo.omega_outer), iterations=iterations, initial_p=initial,
        end_layer=grid.end_layer_m,
        port_cut=(machine.points_per_period, *map(float, astuple(timing))))


def angle_name(phi: float) -> str:
    return f"a{math.degrees(phi):.6g}deg"


def model_flows(state, phi: float, period: float, origin: float, paths) -> tuple[dict, float]:
    """A frozen state's flows as the CFD measures them: ({(a, b): kg/s from slot a into
    slot b, a < b}, the total leakage into the suction side).  ``paths``: the table's
    LeakagePath declarations by name.  A flow with a plenum at one end joins the chamber
    at the other end with the one its path targets, which the model holds as that plenum
    (not yet born: suction; discharged: discharge).  The suction side is the plenum and
    the chambers open to it (held at its state), as the CFD's suction port takes what
    leaks into those chambers."""
    slots = slot_of(state, phi, period, origin)
    n = len(slots)
    p_suction = min(float(p) for p in state.p)
    suction_side = {0} | {k + 1 for k in range(n)
                          if not state.closed[k] and float(state.p[k]) == p_suction}
    pairs: dict = {}
    total = 0.0
    for name, ia, ib, f in zip(state.names, state.ia, state.ib, state.flows, strict=True):
        ia, ib, f = int(ia), int(ib), float(f)
        total += f * ((ib in suction_side) - (ia in suction_side))
        a = b = None
        if 1 <= ia <= n and 1 <= ib <= n:
            a, b = slots[ia - 1], slots[ib - 1]
        elif (1 <= ia <= n) != (1 <= ib <= n) and paths[name].to_chamber:
            s = slots[ia - 1] if 1 <= ia <= n else slots[ib - 1]
            plenum = ib if 1 <= ia <= n else ia
            other = s - abs(paths[name].target) if plenum == 0 else s + abs(paths[name].target)
            a, b = (s, other) if 1 <= ia <= n else (other, s)
        if a is None:
            continue
        if a > b:
            a, b, f = b, a, -f
        pairs[(a, b)] = pairs.get((a, b), 0.0) + f
    return pairs, total
