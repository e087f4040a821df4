"""The compiled right-hand side: :func:`.kernel.rhs_fused` and the physics it calls,
compiled by numba, loaded only where it pays; and whole segments of the explicit
Runge-Kutta methods in one compiled call (:mod:`.stepping` around
:func:`.kernel.rhs_segment`, which evaluates the geometry too), so that Python is left
once per segment instead of once per right-hand side.

Numba is imported lazily and its machine code cached on disk (``cache=True``).  Even
from its cache, loading costs a process ~0.5 s CPU (numba's import, its typing
registries, scipy.linalg for the matrix products), five times what one ideal-port
operating point of the default case takes in numpy; compiling into an empty cache costs
~80 s CPU (the explicit and the Rosenbrock segment loops).  So in "auto" (the default) a
process starts in numpy and loads the compiled function once its cycle solutions have
taken COMPILE_AFTER_S (a performance map, a sweep, an optimisation, a benchmark) and only if
the cache holds it; each operating point is solved wholly by one of the two, which
agree to round-off.  The cache is filled by ``python -m rotorflow.quasi1d.compiled``
(or by any run with ``ROTORFLOW_COMPILED=1``, which compiles from the first point);
``=0`` never compiles (the numpy reference).  Without numba the model stays in numpy.

The cache sits in numba's cache directory (NUMBA_CACHE_DIR, else ~/.cache) under a
hash of the sources compiled and of this module: numba checks only the compiled
function's own file, not the helpers it inlines from the fluid and flow modules.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np

# CPU seconds of cycle solutions after which a process loads the compiled function (see
# the docstring): about numba's loading cost, so that no process spends more than twice
# what it needs.
COMPILE_AFTER_S = 0.5
MODES = ("auto", "0", "1")

_state = {"kernel": None, "work_s": 0.0, "failed": False}


def mode() -> str:
    m = os.environ.get("ROTORFLOW_COMPILED", "auto")
    return m if m in MODES else "auto"


def note_work(seconds: float) -> None:
    """Count CPU seconds spent solving cycles (towards COMPILE_AFTER_S)."""
    _state["work_s"] += seconds


def kernel_for_point():
    """The compiled right-hand side for the next operating point, or None (numpy)."""
    m = mode()
    if m == "0" or _state["failed"]:
        return None
    if _state["kernel"] is None and (m == "1" or (_state["work_s"] >= COMPILE_AFTER_S
                                                   and _cached())):
        _state["kernel"] = _compile()
    return _state["kernel"]


@functools.lru_cache(maxsize=1)
def _cache_dir() -> Path:

    digest = hashlib.sha256()
    # this module's own source too: it decides what is inlined and how select compiles
    for fn in (*_helpers(), *_entries(), sys.modules[__name__]):
        digest.update(inspect.getsource(fn).encode())
    base = os.environ.get("NUMBA_CACHE_DIR") or str(Path.home() / ".cache")
    return Path(base) / "rotorflow-numba" / digest.hexdigest()[:16]


def _cached() -> bool:
    """numba's cache holds the compiled function for this checkout (without importing
    numba).  numba files a function's cache under ``<dir name>_<sha1 of the dir's
    path>`` of its source: another checkout of the same sources has the same
    :func:`_cache_dir` but not its entries, and taking them for its own made a point
    compile for ~80 s inside its time budget."""
    from . import kernel

    src = os.path.dirname(os.path.abspath(kernel.__file__))
    where = _cache_dir() / f"{os.path.basename(src)}_{hashlib.sha1(src.encode()).hexdigest()}"
    return all(any(where.glob(f"*{fn.__name__}*.nbi")) for fn in _entries())


def _entries():
    from . import kernel

    return (kernel.rhs_fused, kernel.rhs_segment, kernel.segment_fused,
            kernel.segment_ros23)


def _helpers():
    from . import (
        chamber,
        coolprop_bubble,
        coolprop_fluid,
        dry_air,
        flows,
        kernel,
        liquid,
        oil,
        rarefied,
        stepping,
    )

    return (oil.homogeneous_split, oil.heat_to_gas, liquid.critical_ratio, liquid.omega_flux,
            liquid.mixture_factor, rarefied._rarefaction, rarefied.flow_flux,
            flows._x_eff, flows.nozzle_critical_ratio,
            flows._psi, flows.nozzle_constants,
            flows.nozzle_f_c, flows.fanno_f, dry_air.table_interp, dry_air._lerp,
            coolprop_fluid.table_cell, coolprop_fluid.table_row, coolprop_fluid.table_state,
            coolprop_fluid._or_liquid, coolprop_bubble.liquid_state, kernel.fluid_state,
            kernel.ideal_flow, kernel._add, kernel._node, kernel._slots, kernel._flux_at,
            kernel._port_gas, kernel._oil_leak,
            kernel._oil_heat, kernel._oil_exit, chamber.spline_at,
            stepping.err_norm, stepping.rk_step, stepping._grow, stepping.segment,
            stepping.ros23_step, stepping.jacobian, stepping._w_solve, kernel.rhs_segment,
            kernel.rk_step_fused, kernel.ros23_step_fused, kernel.rhs_fused)


def _inlined():
    from . import coolprop_bubble, coolprop_fluid, dry_air, kernel, oil

    return (kernel._add, kernel._node, kernel._slots, kernel._flux_at, kernel._port_gas,
            kernel._oil_leak, oil.homogeneous_split,
            oil.heat_to_gas, kernel.fluid_state,
            dry_air.table_interp, dry_air._lerp, coolprop_fluid.table_row,
            coolprop_fluid.table_state,
            coolprop_fluid._or_liquid, coolprop_bubble.liquid_state)


def _select(cond, a, b):
    """numba's :func:`.flows.select`: the conditional on scalars, np.where on arrays."""
    from numba.core import types

    if isinstance(cond, types.Boolean):
        return lambda cond, a, b: a if cond else b
    return lambda cond, a, b: np.where(cond, a, b)


def _batch_mv(A, x):
    """numba's :func:`.stepping.batch_mv` (no einsum): loops."""
    def impl(A, x):
        out = np.zeros(A.shape[:2])
        for b in range(A.shape[0]):
            for i in range(A.shape[1]):
                for j in range(A.shape[2]):
                    out[b, i] += A[b, i, j] * x[b, j]
        return out
    return impl


def _w_inverse(Jc, cols, hd):
    """numba's :func:`.stepping.w_inverse` (np.linalg.inv of one matrix at a time)."""
    def impl(Jc, cols, hd):
        nc = cols.size
        out = np.empty((Jc.shape[0], nc, nc))
        M = np.empty((nc, nc))
        for b in range(Jc.shape[0]):
            for i in range(nc):
                for j in range(nc):
                    M[i, j] = (1.0 if i == j else 0.0) - hd * Jc[b, cols[i], j]
            try:
                out[b] = np.linalg.inv(M)
            except Exception:  # singular (np.linalg.LinAlgError)
                out[b] = np.nan
        return out
    return impl


class Compiled(NamedTuple):
    """The compiled entry points: the fused right-hand side (one call per evaluation) and
    a whole segment's integration by an explicit Runge-Kutta method or by ros23 (one call
    per segment)."""

    rhs: object
    rhs_segment: object  # the first right-hand side of a segment, from its step's args
    rk_step: object  # the steps' identities: integrate dispatches segments by them
    segment: object
    ros23_step: object
    segment_ros23: object


def _compile():
    try:
        import numba
        from numba.extending import overload, register_jitable
    except ImportError:
        _state["failed"] = True
        return None
    from . import flows, kernel, stepping

    numba.config.CACHE_DIR = str(_cache_dir())
    inline = _inlined()
    for fn in _helpers():
        # the small helpers that take arrays, inlined: a call of a compiled function
        # counts references to its array arguments (atomic operations), which cost the
        # loops of the right-hand side more than the work inside them
        register_jitable(inline="always" if fn in inline else "never")(fn)
    if not _state.get("overloads"):  # (once a process: a second would be ambiguous)
        overload(flows.select)(_select)
        overload(stepping.batch_mv)(_batch_mv)
        overload(stepping.w_inverse)(_w_inverse)
        _state["overloads"] = True
    # error_model "numpy": a trial state's division by zero gives inf/nan (rejected by
    # the step control) as in numpy, not an exception
    jit = numba.njit(cache=True, error_model="numpy")
    return Compiled(jit(kernel.rhs_fused), jit(kernel.rhs_segment), kernel.rk_step_fused,
                    jit(kernel.segment_fused),
                    kernel.ros23_step_fused, jit(kernel.segment_ros23))


def warm_up() -> None:
    """Fill numba's cache: solve one small cycle of each fluid kind with the compiled
    right-hand side (``python -m rotorflow.quasi1d.compiled``, ~80 s CPU once), and
    evaluate the fused right-hand side on its own once (the cycles call it only inside
    the compiled segments; :func:`_cached` asks for every entry, and without this one
    the cache filled by ``make venv`` was never taken as filled: every process of a
    fresh checkout ran in numpy until the tests had called it)."""
    from .settings import Leakage, Numerics, Operating, Ports
    from .simulate import simulate
    from .synthetic import sin2_table

    os.environ["ROTORFLOW_COMPILED"] = "1"
    fn = kernel_for_point()
    if fn is None:
        raise SystemExit("numba is not installed: the model runs in numpy")
    table = sin2_table(rows=241)
    base = {"p_suction_bar": 1.0, "p_discharge_bar": 4.0, "T_suction_K": 300.0,
            "speed_rpm": 3000.0, "volume_ratio": 3.0}
    leak = Leakage(gap_m=10e-6, model="nozzle")
    # The compilation runs inside the first solve's clock: on a slow machine it took
    # more than the default 60-s budget (2026-12-01), which stopped `make venv`.
    num = Numerics(max_seconds=3600.0)
    for extra, ports in (({}, Ports()), ({"heat_capacity": "constant"}, Ports(model="nozzle")),
                         ({"oil_mass_ratio": 2.0}, Ports())):
        op = Operating.from_section({**base, **extra}, "warm-up")
        sol = simulate(table, op, leak, ports, num).solution  # (its model holds the kernel)
        model = sol.model
        seg = next(s for s in model.segments if model._fused_args(s) is not None)
        model.rhs(seg.start, sol.y_start[None], seg)


if __name__ == "__main__":
    warm_up()
