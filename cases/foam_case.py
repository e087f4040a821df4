"""The one routine by which every CFD case is built, run, judged and stored.

:func:`run_case` does, for any kind of case (the steady gap of
:mod:`~rotorflow.cases.gap_case`, the moving chamber of
:mod:`~rotorflow.cases.chamber_case`):

1. **key -> folder.**  The case's key is a digest of everything that determines its
   result (:func:`digest`).  A folder holding ``case.key`` with that key and a
   ``result.json`` is finished: its result is returned without running anything, a
   failed one included (failed runs are kept with their log tail and never retried
   silently; their status keeps them out of every comparison).
2. **Build in a temporary folder.**  ``<folder>.tmp`` is emptied and the case's
   ``build`` writes into it everything Python writes (dictionaries, fields, the gmsh
   mesh, ``case.json``) and returns its :class:`Plan`: the OpenFOAM commands as data.
3. **Drain the plan** with :func:`rotorflow.cases.foam.drain`.  A failing setup step
   (mesh conversion, checkMesh, topoSet ...) raises: the case cannot be built, and no
   folder that looks finished is left.  A failing solver is a result: its message and
   log tail go into the result.
4. **Judge** the run from its outputs (never from its log alone), write ``result.json``
   and ``case.key`` and rename the folder into place: an interrupted run never leaves a
   folder that looks finished.
"""

from __future__ import annotations

import hashlib
import json
import logging
import re
import shutil
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from rotorflow.errors import ExternalRunError

from . import foam
from .foam import Launch, Step

log = logging.getLogger(__name__)

#: Log lines kept in a failed result.
RESULT_LOG_LINES = 30

#: Log lines searched for signs of divergence when a solver failed.
DIVERGENCE_LOG_LINES = 60

R = TypeVar("R")


@dataclass(frozen=True)
class Plan:
    """The OpenFOAM commands of a case, in order.

    ``setup``: mesh conversion and checks (a failure stops the case with an error);
    ``solve``: the solver (a failure is the run's result, kept with its log tail);
    ``post``: what turns the solver's output into the case's (reconstructPar after a
    parallel run); run only after the solver finished, a failure is the run's too.
    """

    setup: tuple[Step, ...]
    solve: Step
    post: tuple[Step, ...] = ()

    @property
    def steps(self) -> tuple[Step, ...]:
        return (*self.setup, self.solve, *self.post)

    def commands(self) -> list[list[str]]:
        """The argument lists, in the order they run."""
        return [list(step.argv) for step in self.steps]


#: ``build(folder) -> (plan, context)``: writes the case into ``folder``; ``context`` is
#: whatever the judge needs of the build (the mesh's depth, its gap cells, ...).
Build = Callable[[Path], tuple[Plan, Any]]

#: ``judge(folder, context, values, elapsed_s, failure) -> result``: ``values`` are the
#: setup steps' values by program (checkMesh's MeshQuality ...), ``failure`` the solver's
#: error message ("" when it finished).
Judge = Callable[[Path, Any, Mapping[str, Any], float, str], R]


def digest(payload: Mapping[str, Any]) -> str:
    """The key of a case: SHA-256 of its JSON (sorted keys), 20 hex digits."""
    text = json.dumps(payload, sort_keys=True, allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def stored_result(case_dir: Path, key: str, load: Callable[[str], R]) -> R | None:
    """The result of a finished folder whose key is ``key`` (None: not finished, or
    another case)."""
    key_path, result_path = Path(case_dir) / "case.key", Path(case_dir) / "result.json"
    if key_path.is_file() and result_path.is_file() and key_path.read_text().strip() == key:
        return load(result_path.read_text())
    return None


def run_case(
    case_dir: Path,
    key: str,
    build: Build,
    judge: Judge,
    load: Callable[[str], R],
    *,
    reuse: bool = True,
    label: str = "case",
    summary: Callable[[R], str] | None = None,
    launch: Launch | None = None,
) -> R:
    """Build, run and judge one case in ``case_dir``; return (and store) its result.

    See the module docstring.  ``load`` reads a result from ``result.json``'s text (the
    result has ``to_json()``); with ``reuse`` a finished folder of the same ``key`` is
    returned as it is.  ``summary`` describes a new result for the log; ``launch`` starts
    the programs (default: OpenFOAM's).
    """
    case_dir = Path(case_dir)
    foam.check_case_path(case_dir)
    if reuse:
        stored = stored_result(case_dir, key, load)
        if stored is not None:
            log.info("%s %s: reusing the stored result", label, case_dir.name)
            return stored
    tmp = case_dir.with_name(case_dir.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    plan, context = build(tmp)
    values = foam.drain(plan.setup, tmp, launch=launch)
    start = time.monotonic()
    failure = ""
    try:
        foam.drain([plan.solve, *plan.post], tmp, launch=launch)
    except ExternalRunError as exc:
        failure = str(exc)
    result = judge(tmp, context, values, time.monotonic() - start, failure)
    (tmp / "result.json").write_text(result.to_json())
    (tmp / "case.key").write_text(key + "\n")
    if case_dir.exists():
        shutil.rmtree(case_dir)
    tmp.rename(case_dir)
    if summary is not None:
        log.info("%s %s: %s", label, case_dir.name, summary(result))
    return result


# --- judging ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Verdict:
    """Status, first line of the message and (unless the status is the good one) the
    solver log's tail."""

    status: str
    message: str
    log_tail: str


def verdict(case_dir: Path, solver: str, failure: str,
            outcome: tuple[str, str] | ExternalRunError, ok: str) -> Verdict:
    """The verdict on a run: its solver's failure first; else ``outcome``, what its
    outputs say (status and message, or the error raised reading them: "crashed").  A
    crash whose log shows the solution blowing up is "diverged".  ``ok``: the status of
    a good run, which carries no log tail.
    """
    if failure:
        status, message = "crashed", failure
    elif isinstance(outcome, ExternalRunError):
        status, message = "crashed", str(outcome)
    else:
        status, message = outcome
    log_path = Path(case_dir) / f"log.{solver}"
    if status == "crashed" and looks_diverged(foam.log_tail(log_path, DIVERGENCE_LOG_LINES)):
        status = "diverged"
    return Verdict(status, message.splitlines()[0] if message else "",
                   "" if status == ok else foam.log_tail(log_path, RESULT_LOG_LINES))


#: What a log tail shows when the solution blew up rather than the program failing.
_DIVERGENCE = re.compile(
    r"sigFpe|Floating point exception|Maximum number of iterations exceeded"
    r"|Negative initial temperature|\bnan\b|\binf\b",
    re.IGNORECASE,
)


def looks_diverged(log_text: str) -> bool:
    """True when a solver log shows the solution blowing up (FPE trap, nan, runaway T).

    The banner line ``trapFpe: Floating point exception trapping enabled`` that starts
    every log is left out: a run that fails in its first lines has not diverged.
    """
    text = "\n".join(ln for ln in log_text.splitlines() if not ln.startswith("trapFpe"))
    return _DIVERGENCE.search(text) is not None


def count_time_steps(log_path: Path) -> int:
    """Time steps a solver log reports (its ``Time = ...`` lines; 0 without a log)."""
    log_path = Path(log_path)
    if not log_path.is_file():
        return 0
    with log_path.open("rb") as fh:
        return sum(1 for line in fh if line.startswith(b"Time = "))
