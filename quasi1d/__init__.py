"""Quasi-1D chamber model: mass and energy of every working chamber, coupled by leakage
and ports, integrated to the machine's periodic state.

    from rotorflow.quasi1d import simulate, Operating, Leakage, Ports, Numerics
    result = simulate(table, Operating.from_section(case["operating"], "case.toml"),
                      Leakage.from_section(case.get("leakage", {}), "case.toml"),
                      Ports.from_section(case.get("ports", {}), "case.toml"),
                      mechanical=Mechanical.from_section(case.get("mechanical", {}), "case.toml"))
    result.summary()               # figures as a JSON-ready dict
    result.write_traces(folder)    # chamber_cycle.csv, chambers.csv
    result.plot(folder)            # p-angle and p-V PNGs

``simulate_transient`` integrates the same model once over one lobe period from a given
state, without cycle convergence (a single chamber's transient, see :mod:`.transient`).
"""

from .integrate import IntegrationError
from .mechanical import Mechanical
from .result import SimulationResult, plot_cycle
from .settings import Leakage, Numerics, Operating, Ports
from .simulate import case_settings, simulate
from .transient import TransientResult, simulate_transient

__all__ = ["IntegrationError", "Leakage", "Mechanical", "Numerics", "Operating", "Ports",
           "SimulationResult", "TransientResult", "case_settings", "plot_cycle", "simulate",
           "simulate_transient"]
