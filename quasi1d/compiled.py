"""The compiled right-hand side: :func:`.kernel.rhs_fused` and the physics it calls,
compiled by numba, loaded only where it pays.

Numba is imported lazily and its machine code cached on disk (``cache=True``), but even
from its cache loading it costs a process ~0.4 s CPU (numba's import, its typing
registries, scipy.linalg for the matrix products), four times what one ideal-port
operating point of the default case takes in numpy.  So a process starts in numpy and
compiles once its cycle solutions have taken COMPILE_AFTER_S (a performance map, a
sweep, an optimisation, a benchmark); each operating point is solved wholly by one of
the two, which agree to round-off.  ``ROTORFLOW_COMPILED=1`` compiles from the first
point, ``=0`` never (the numpy reference); without numba the model stays in numpy.

The cache sits in numba's cache directory (NUMBA_CACHE_DIR, else ~/.cache) under a
hash of the sources compiled: numba checks only the compiled function's own file, not
the helpers it inlines from the fluid and flow modules.
"""

from __future__ import annotations

import hashlib
import inspect
import os
from pathlib import Path

# CPU seconds of cycle solutions after which a process compiles (see the docstring):
# about numba's loading cost, so that no process spends more than twice what it needs.
COMPILE_AFTER_S = 0.4
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
    if _state["kernel"] is None and (m == "1" or _state["work_s"] >= COMPILE_AFTER_S):
        _state["kernel"] = _compile()
    return _state["kernel"]


def _helpers():
    from . import coolprop_fluid, dry_air, flows, kernel

    return (flows._x_eff, flows.nozzle_critical_ratio, flows._psi, flows._psi_k,
            flows.nozzle_constants, flows.nozzle_f_c, flows.fanno_f, dry_air.table_interp,
            coolprop_fluid.table_interp, kernel.fluid_state, kernel.nodes, kernel.upstream,
            kernel.mass_flows, kernel.enthalpy_flows, kernel.balances, kernel.ideal_ports)


def _compile():
    try:
        import numba
        from numba.extending import register_jitable
    except ImportError:
        _state["failed"] = True
        return None
    from . import kernel

    helpers = _helpers()
    digest = hashlib.sha256()
    for fn in (*helpers, kernel.rhs_fused):
        digest.update(inspect.getsource(fn).encode())
    base = numba.config.CACHE_DIR or str(Path.home() / ".cache")
    numba.config.CACHE_DIR = str(Path(base) / "rotorflow-numba" / digest.hexdigest()[:16])
    for fn in helpers:
        register_jitable(fn)
    # error_model "numpy": a trial state's division by zero gives inf/nan (rejected by
    # the step control) as in numpy, not an exception
    return numba.njit(cache=True, error_model="numpy")(kernel.rhs_fused)
