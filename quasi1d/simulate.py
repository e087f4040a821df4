"""The entry of the chamber model: a chamber table and an operating point in, figures out."""

from __future__ import annotations

from dataclasses import replace

from rotorflow.errors import CaseError

from . import cycle, delivered_plenum
from .chamber import prepare
from .fluids import make_fluid
from .mechanical import Mechanical
from .model import ChamberModel, build
from .result import SimulationResult, make_result
from .settings import Leakage, Numerics, Operating, Ports
from .shaft import shaft_figures


def case_settings(raw: dict, where: str) -> tuple:
    """(operating, leakage, ports, numerics, mechanical) of a parsed case file: the
    arguments of :func:`simulate` after the table (absent sections: their defaults)."""
    op, ports = (Operating.from_section(raw["operating"], where),
                 Ports.from_section(raw.get("ports", {}), where))
    delivered_plenum.check(op, ports)
    return (op, Leakage.from_section(raw.get("leakage", {}), where), ports,
            Numerics.from_section(raw.get("numerics", {}), where),
            Mechanical.from_section(raw.get("mechanical", {}), where))


def chamber_of(table, operating: Operating, numerics: Numerics):
    """The chamber of ``table`` timed for ``operating`` (:func:`.chamber.prepare`): where
    the port timing is refused against the chamber's life."""
    operating.check_ideal_gas()
    return prepare(table, operating.volume_ratio, operating.suction_close_rad,
                   operating.discharge_open_rad, operating.speed_rpm, numerics.vanish_fraction,
                   operating.discharge_early_opening_rad)


def build_model(table, operating: Operating, leakage: Leakage | None = None,
                ports: Ports | None = None, numerics: Numerics | None = None,
                fluid=None) -> ChamberModel:
    """The chamber equations of ``table`` at ``operating`` (what :func:`simulate` and
    :func:`~rotorflow.quasi1d.transient.simulate_transient` integrate); the defaults are
    :func:`simulate`'s. ``fluid``: a fluid whose table spans this point's states (a
    performance map shares one over its points), else the point's own."""
    if table is None:
        raise CaseError("no chamber table: the quasi-1D model needs the geometry's chamber table")
    leakage = leakage or Leakage(model="none")
    ports = ports or Ports()
    numerics = numerics or Numerics()
    if ports.reads_areas and not getattr(table, "port_areas", True):
        raise CaseError(f"{ports.model} ports need the chamber table's port areas, and this "
                        "table was made without them (for ideal ports)")
    geo = chamber_of(table, operating, numerics)
    fluid = fluid or make_fluid(operating, geo.v_max / geo.v_discharge)
    return build(geo, fluid, operating, leakage, ports)


def simulate(table, operating: Operating, leakage: Leakage | None = None,
             ports: Ports | None = None, numerics: Numerics | None = None,
             mechanical: Mechanical | None = None, fluid=None) -> SimulationResult:
    """Cycle-converged simulation of the machine whose chamber is ``table``.

    ``table`` is a :class:`rotorflow.geometry.table.ChamberTable`; the speed in
    ``operating`` is that of the driven rotor (converted with the table's
    ``speed_ratio_outer_per_driven``).  A cycle that does not converge within
    ``numerics.max_cycles`` is returned with ``converged`` False and a ``message`` in its
    figures; bad input raises CaseError, an integration that cannot proceed
    IntegrationError.  Without ``leakage`` the chambers are sealed; without ``ports`` the
    ports are ideal; without ``numerics`` the defaults of :class:`Numerics` apply.
    The gas loads, mechanical loss and shaft power (:mod:`.shaft`) use ``mechanical``
    (default: the published coefficients of :class:`Mechanical`).
    """
    ports = ports or Ports()
    delivered_plenum.check(operating, ports)
    model = build_model(table, operating, leakage, ports, numerics, fluid)
    num = numerics or Numerics()
    sol = cycle.solve(model, num)
    if ports.discharge_plenum == "delivered":
        model, sol = delivered_plenum.settle(
            lambda T: build_model(table, operating, leakage,
                                  delivered_plenum.plenum_ports(ports, T), numerics,
                                  model.fluid),
            lambda m: cycle.solve(m, num), model, sol)
    result = make_result(sol)
    extra, loads = shaft_figures(result, table, mechanical or Mechanical())
    if model.ports.discharge_plenum_K is not None:
        extra["discharge_plenum_K"] = model.ports.discharge_plenum_K
    return replace(result, figures={**result.figures, **extra}, loads=loads)
