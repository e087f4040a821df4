"""Run time against error, pressure traces included, on the problem run beside PDSim.

The problem (issue 19): one chamber of the default case (examples/default.toml), air,
ports as isentropic nozzles of coefficient 1 through the chamber table's end-face areas
(suction to the volume maximum, discharge from the built-in volume ratio), no leakage.
Each integrator and tolerance is timed warm (the table and fluid built, the compiled
right-hand side loaded; median of REPEATS runs of :func:`rotorflow.quasi1d.simulate`,
shaft figures included; CPU seconds, the machine being shared, with the wall seconds
beside) and compared with Radau at rtol 1e-9: mass flow, indicated power, and the
chamber's pressure trace (its largest difference over the cycle, the method's points
against the reference interpolated linearly, as a share of the discharge pressure).
Every row names its right-hand side (``kernel``): "compiled" (numba, :mod:`.compiled`)
over the whole sweep, "numpy" (ROTORFLOW_COMPILED=0) on the fast integrators.  A second
row set times the default case as it is (ideal ports, nozzle leakage).

Targets: 0.1 % in flow, power and trace in 0.1 s warm (PDSim: 1.99 s on this machine);
the ideal-port default point in 20 ms. Outputs: pdsim.csv in results_dir.
"""

from __future__ import annotations

import csv
import os
import statistics
import time
from pathlib import Path

import numpy as np

from rotorflow.geometry.summary import chamber_table
from rotorflow.quasi1d import Leakage, Numerics, Ports, case_settings, simulate
from rotorflow.workflow.case import load_case

REPO = Path(__file__).resolve().parents[1]
SWEEP = {
    "auto": (2e-3, 1e-3, 5e-4, 1e-4),
    "ros23": (3e-3, 2e-3, 1e-3, 5e-4, 1e-4, 1e-5),
    "dopri5": (1e-3, 1e-4, 1e-5),
    "bs3": (1e-3, 1e-4),
    "bdf": (1e-4, 1e-6),
}
# the numpy right-hand side on the integrators that come near the target
NUMPY_SWEEP = {"auto": (1e-3, 1e-4), "ros23": (2e-3, 1e-3, 1e-4)}
KERNELS = {"compiled": "1", "numpy": "0"}  # ROTORFLOW_COMPILED
REFERENCE = Numerics(integrator="radau", rtol=1e-9, atol=1e-11)
REPEATS = 3
TARGET_ERROR, TARGET_TIME_S, TARGET_IDEAL_S = 1e-3, 0.1, 0.02


def _timed(table, op, leak, ports, num):
    cpu, wall, res = [], [], None
    for _ in range(REPEATS):
        t0, c0 = time.perf_counter(), time.process_time()
        res = simulate(table, op, leak, ports, num)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - t0)
    return statistics.median(cpu), statistics.median(wall), res


def _errors(res, ref, p_discharge):
    th, p = np.asarray(res.chamber["angle_rad"]), np.asarray(res.chamber["p_Pa"])
    th_r, p_r = np.asarray(ref.chamber["angle_rad"]), np.asarray(ref.chamber["p_Pa"])
    f, fr = res.figures, ref.figures
    return {"flow_error": abs(f["mass_flow_kg_s"] / fr["mass_flow_kg_s"] - 1.0),
            "power_error": abs(f["indicated_power_W"] / fr["indicated_power_W"] - 1.0),
            "trace_error": float(np.max(np.abs(p - np.interp(th, th_r, p_r)))) / p_discharge}


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    case = load_case(REPO / "examples" / "default.toml")
    table = chamber_table(case)
    op, leak_case, ports_case, _, _ = case_settings(case.raw, "default.toml")
    rows = []
    problems = {"pdsim": (Leakage(model="none"), Ports(model="nozzle", coefficient=1.0)),
                "default": (leak_case, ports_case)}
    given = os.environ.get("ROTORFLOW_COMPILED")
    for name, (leak, ports) in problems.items():
        ref = simulate(table, op, leak, ports, REFERENCE)
        for kernel, flag in KERNELS.items():
            os.environ["ROTORFLOW_COMPILED"] = flag
            simulate(table, op, leak, ports)  # warm: numba's cache loaded (or compiled)
            sweep = SWEEP if kernel == "compiled" else NUMPY_SWEEP
            if name == "default":
                sweep = {"auto": sweep["auto"]}
            for integrator, tols in sweep.items():
                for rtol in tols:
                    rows.append(_row(name, kernel, integrator, rtol, ref, op,
                                     *_timed(table, op, leak, ports,
                                             Numerics(integrator=integrator, rtol=rtol))))
    if given is None:
        os.environ.pop("ROTORFLOW_COMPILED")
    else:
        os.environ["ROTORFLOW_COMPILED"] = given
    with (results_dir / "pdsim.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows


def _row(name, kernel, integrator, rtol, ref, op, cpu, wall, res):
    err = _errors(res, ref, op.p_discharge_Pa)
    if name == "default":  # ideal ports jump: the trace is compared elsewhere
        err["trace_error"] = None
    worst = max(v for v in err.values() if v is not None)
    target = TARGET_TIME_S if name == "pdsim" else TARGET_IDEAL_S
    return {"problem": name, "kernel": kernel, "integrator": integrator, "rtol": rtol,
            "cpu_s_warm": cpu, "wall_s_warm": wall, **err,
            "met": worst < TARGET_ERROR and cpu < target,
            "default_rtol": rtol == Numerics().rtol, "cycles": res.solution.cycles,
            "load_1min": os.getloadavg()[0]}


if __name__ == "__main__":
    for row in run(REPO / "bench" / "results"):
        print(row)
