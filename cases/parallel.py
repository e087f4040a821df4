"""Running a case's solver on several processes: decomposePar, mpirun, reconstructPar.

A case plans its commands once (:class:`~rotorflow.cases.foam_case.Plan`);
:func:`parallel_plan` turns the serial plan into the parallel one: the domain is split
by ``decomposePar`` after the setup, the solver runs under ``mpirun -np N ... -parallel``
(its log is still ``log.<solver>``, so judging and divergence checks read the same file),
and ``reconstructPar`` gathers the last time into the case folder afterwards, so that
everything downstream reads the case as if it had run serially.  Function objects
(postProcessing/) are written by the master process and need no reconstruction.

Decomposition methods: Debian's OpenFOAM v1912 ships scotch, metis and kahip as stub
libraries that fail at run time, so only the geometric methods are offered:
"hierarchical" (split along x, then y, then z: ``split`` gives the parts per direction)
and "simple" (the same counts, no ordering).  The case files are the same on a cluster;
only ``processes`` and ``split`` change.

Open MPI refuses to start as root unless told; CI runs as root in a container, so
mpirun is given ``--allow-run-as-root`` there (and only there).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

from rotorflow.errors import CaseError

from .foam import Step
from .foam_files import write_dict

METHODS = ("hierarchical", "simple")


@dataclass(frozen=True)
class Decomposition:
    """How a case's domain is split: ``processes`` parts, ``split`` = (nx, ny, nz) whose
    product is ``processes`` (None: all along ``axis``)."""

    processes: int = 1
    method: str = "hierarchical"
    split: tuple[int, int, int] | None = None
    axis: int = 0  # direction split when ``split`` is None: 0 x, 1 y, 2 z

    def __post_init__(self) -> None:
        if not isinstance(self.processes, int) or self.processes < 1:
            raise CaseError(f"processes must be a whole number >= 1, not {self.processes!r}")
        if self.method not in METHODS:
            raise CaseError(f"decomposition method {self.method!r} is not available here "
                            f"(Debian's scotch/metis/kahip are stubs): use one of {METHODS}")
        if self.split is not None and math.prod(self.split) != self.processes:
            raise CaseError(f"decomposition split {self.split} does not make "
                            f"{self.processes} parts")
        if self.axis not in (0, 1, 2):
            raise CaseError(f"decomposition axis must be 0, 1 or 2, not {self.axis!r}")

    @property
    def counts(self) -> tuple[int, int, int]:
        if self.split is not None:
            return tuple(self.split)
        n = [1, 1, 1]
        n[self.axis] = self.processes
        return tuple(n)

    def entries(self) -> dict:
        """system/decomposeParDict's entries."""
        coeffs = {"n": list(self.counts)}
        if self.method == "hierarchical":
            coeffs["order"] = "xyz"
        return {"numberOfSubdomains": self.processes, "method": self.method,
                f"{self.method}Coeffs": coeffs}


#: One process: the plan as it is.
SERIAL = Decomposition()


def write_decompose_dict(case_dir: Path, dec: Decomposition) -> Path:
    return write_dict(Path(case_dir) / "system" / "decomposeParDict", dec.entries())


def mpirun_argv(dec: Decomposition, solver_argv: tuple[str, ...]) -> tuple[str, ...]:
    """``mpirun -np N <solver> <args> -parallel`` (allowed to run as root where it is)."""
    root = ("--allow-run-as-root",) if hasattr(os, "geteuid") and os.geteuid() == 0 else ()
    return ("mpirun", *root, "-np", str(dec.processes), *solver_argv, "-parallel")


def parallel_plan(plan, case_dir: Path, dec: Decomposition):
    """The plan ``plan`` run on ``dec.processes`` processes (itself for one process);
    writes system/decomposeParDict into ``case_dir``."""
    if dec.processes == 1:
        return plan
    write_decompose_dict(case_dir, dec)
    solve = replace(plan.solve, argv=mpirun_argv(dec, plan.solve.argv),
                    log_name=plan.solve.name)
    return replace(plan,
                   setup=(*plan.setup, Step(("decomposePar", "-force"))),
                   solve=solve,
                   post=(Step(("reconstructPar", "-latestTime")), *plan.post))
