"""The one wrapper around OpenFOAM applications, and the runner that drains planned commands.

A case plans its OpenFOAM commands as data: a sequence of :class:`Step` (an argument list
such as ``("gmshToFoam", "gap.msh")`` or ``("checkMesh",)``, and what to do with the
program's output once it succeeded).  :func:`drain` runs them in order and nothing else
decides what runs, so the sequence of a case is unit-tested without OpenFOAM.

Every program goes through :func:`run`: an argument list (never a shell), the case folder
as working directory, stdout and stderr into ``log.<application>`` inside the case, and a
failure raised as :class:`~rotorflow.errors.ExternalRunError` carrying the tail of that
log.  A log is never taken as proof of success: the steps check the outputs they need
(:mod:`rotorflow.cases.foam_mesh`, :mod:`rotorflow.postprocess.foam_output`).  The process
is started by a *launcher* (:data:`Launch`); the default one starts the OpenFOAM
application found by :func:`find_installation`, tests pass a fake one.

Dictionaries and fields are written by :mod:`rotorflow.cases.foam_files`; meshes are
converted and checked by :mod:`rotorflow.cases.foam_mesh`.

Finding OpenFOAM.  Debian's ``openfoam`` package (ESI v1912, what ``make openfoam``
installs) puts the applications in ``/usr/bin`` but leaves the environment unset, and its
``etc/bashrc`` cannot be sourced (it calls helper scripts the package does not ship).  The
applications only need ``WM_PROJECT_DIR`` pointing at the folder holding ``etc/controlDict``
(``/usr/share/openfoam``), so :func:`find_installation` looks the application up on
``PATH`` and takes ``WM_PROJECT_DIR`` from the environment when set (a sourced OpenFOAM)
or from the known Debian location otherwise.
"""

from __future__ import annotations

import functools
import logging
import os
import re
import shutil
import subprocess
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

from rotorflow.errors import CaseError, ExternalRunError

log = logging.getLogger(__name__)

#: The solver whose presence stands for "OpenFOAM is installed".
PROBE_APPLICATION = "rhoSimpleFoam"

#: Folders that may hold ``etc/controlDict`` when ``WM_PROJECT_DIR`` is not set; the first
#: is Debian's layout, the others the layouts of OpenCFD's own packages.
PROJECT_DIR_CANDIDATES = (
    "/usr/share/openfoam",
    "/usr/lib/openfoam/openfoam*",
    "/opt/openfoam*",
    "/opt/OpenFOAM-*",
)

#: Lines of a log quoted in an error message: enough to show OpenFOAM's complaint and the
#: iterations before it, short enough to read on a terminal.
LOG_TAIL_LINES = 40

#: How often a running application's log is read for progress (seconds).
POLL_INTERVAL_S = 0.2


class OpenFOAMNotFoundError(CaseError):
    """OpenFOAM is not installed here (or not where rotorflow can find it)."""


@dataclass(frozen=True)
class Installation:
    """Where OpenFOAM lives: the applications' folder and the project (``etc``) folder."""

    bin_dir: Path
    project_dir: Path
    api: str
    build: str

    def environment(self) -> dict[str, str]:
        """The process environment with OpenFOAM's applications and ``etc`` reachable."""
        env = dict(os.environ)
        env["WM_PROJECT_DIR"] = str(self.project_dir)
        env["PATH"] = os.pathsep.join([str(self.bin_dir), env.get("PATH", "")])
        return env

    @property
    def version(self) -> str:
        return f"OpenFOAM {self.api} (build {self.build})"


def _project_dir_candidates() -> list[Path]:
    found = []
    env_dir = os.environ.get("WM_PROJECT_DIR")
    if env_dir:
        found.append(Path(env_dir))
    for pattern in PROJECT_DIR_CANDIDATES:
        root = Path(pattern).parent
        if root.is_dir():
            found.extend(sorted(root.glob(Path(pattern).name), reverse=True))
    return [d for d in found if (d / "etc" / "controlDict").is_file()]


@functools.cache
def find_installation(application: str = PROBE_APPLICATION) -> Installation:
    """Locate OpenFOAM and ask ``application -help`` for its version.

    Raises :class:`OpenFOAMNotFoundError` with what to do when it is missing.  The result
    is cached for the process; tests that change the environment call
    ``find_installation.cache_clear()``.
    """
    exe = shutil.which(application)
    if exe is None:
        raise OpenFOAMNotFoundError(
            f"OpenFOAM not found: no {application} on PATH; run `make openfoam` "
            "(installs Debian's openfoam package) or source your OpenFOAM etc/bashrc"
        )
    projects = _project_dir_candidates()
    if not projects:
        raise OpenFOAMNotFoundError(
            f"OpenFOAM found ({exe}) but not its etc/controlDict; set WM_PROJECT_DIR"
        )
    inst = Installation(Path(exe).parent, projects[0], api="?", build="?")
    try:
        out = subprocess.run(
            [exe, "-help"],
            capture_output=True,
            text=True,
            env=inst.environment(),
            timeout=60,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise OpenFOAMNotFoundError(f"OpenFOAM found ({exe}) but it does not start: {exc}") from exc
    text = out.stdout + out.stderr
    api = re.search(r"Using:\s*OpenFOAM-\S*\s*\((\d+)\)", text)
    build = re.search(r"Build:.*?\(patch=(\w+)\)", text) or re.search(r"Build:\s*(\S+)", text)
    if out.returncode != 0 or api is None:
        raise OpenFOAMNotFoundError(
            f"OpenFOAM found ({exe}) but `{application} -help` fails:\n{_tail(text)}"
        )
    return Installation(
        inst.bin_dir, inst.project_dir, api=api.group(1), build=build.group(1) if build else "?"
    )


def is_available() -> bool:
    """True when :func:`find_installation` succeeds."""
    try:
        find_installation()
    except OpenFOAMNotFoundError:
        return False
    return True


def _tail(text: str, lines: int = LOG_TAIL_LINES) -> str:
    return "\n".join(text.rstrip().splitlines()[-lines:])


def log_tail(path: Path, lines: int = LOG_TAIL_LINES) -> str:
    """The last ``lines`` lines of a log file ('' when it does not exist)."""
    path = Path(path)
    if not path.is_file():
        return ""
    with path.open("rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - 200 * lines))
        return _tail(fh.read().decode(errors="replace"), lines)


_TIME_LINE = re.compile(rb"^Time = ([-+0-9.eE]+)\s*$", re.MULTILINE)

#: Starts a program: ``(argv, case folder, open log file) -> process``.  The process is a
#: :class:`subprocess.Popen` or anything with its ``args``, ``returncode``, ``wait(timeout)``
#: and ``kill()``; its output must go to the log file.
Launch = Callable[[Sequence[str], Path, BinaryIO], Any]


def openfoam_launcher(application: str) -> Launch:
    """The launcher of an OpenFOAM application: found where :func:`find_installation`
    found OpenFOAM, run with its environment in the case folder."""
    inst = find_installation()
    env = inst.environment()
    exe = shutil.which(application, path=env["PATH"])
    if exe is None:
        raise OpenFOAMNotFoundError(f"OpenFOAM application {application} not found")

    def launch(argv: Sequence[str], case_dir: Path, out: BinaryIO) -> subprocess.Popen:
        cmd = [exe, *argv[1:]]
        log.debug("running %s in %s", " ".join(cmd), case_dir)
        env["PWD"] = str(case_dir.resolve())  # OpenFOAM warns when PWD is not its cwd
        return subprocess.Popen(cmd, cwd=case_dir, stdout=out, stderr=subprocess.STDOUT,
                                env=env)

    return launch


def run(
    case_dir: Path,
    application: str,
    args: Sequence[str] = (),
    *,
    log_name: str | None = None,
    timeout_s: float | None = None,
    on_time: Callable[[float], None] | None = None,
    on_poll: Callable[[], None] | None = None,
    launch: Launch | None = None,
) -> Path:
    """Run ``application args...`` in ``case_dir``; return the path of its log.

    Output goes to ``case_dir/log.<log_name or application>``.  A non-zero exit status,
    a ``FOAM FATAL`` message or a run past ``timeout_s`` raises ExternalRunError with the
    log tail.  ``on_time`` is called with the latest ``Time = ...`` the solver reported
    (the iteration of a steady solver), for progress bars; ``on_poll`` every
    :data:`POLL_INTERVAL_S` while it runs (a convergence monitor may call
    :func:`request_stop` from it).  ``launch`` starts the process (default: the OpenFOAM
    application, :func:`openfoam_launcher`).
    """
    launch = launch or openfoam_launcher(application)
    case_dir = Path(case_dir)
    check_case_path(case_dir)
    if not (case_dir / "system" / "controlDict").is_file():
        raise CaseError(f"{case_dir} is not an OpenFOAM case (no system/controlDict)")
    log_path = case_dir / f"log.{log_name or application}"
    start = time.monotonic()
    with log_path.open("wb") as out:
        proc = launch([application, *map(str, args)], case_dir, out)
        try:
            _wait(proc, log_path, start, timeout_s, on_time, on_poll)
        except BaseException:
            proc.kill()
            proc.wait()
            raise
    text_tail = log_tail(log_path)
    if proc.returncode != 0:
        raise ExternalRunError(
            f"{application} failed (exit status {proc.returncode}) in {case_dir}; "
            f"last lines of {log_path.name}:\n{text_tail}"
        )
    if "FOAM FATAL" in text_tail or _log_has(log_path, b"FOAM FATAL"):
        raise ExternalRunError(
            f"{application} reported a fatal error in {case_dir}; "
            f"last lines of {log_path.name}:\n{text_tail}"
        )
    log.info("%s finished in %.1f s (%s)", application, time.monotonic() - start, case_dir)
    return log_path


# --- planned commands ---------------------------------------------------------------------


@dataclass(frozen=True)
class Step:
    """One planned OpenFOAM command: its argument list and what to do around it.

    ``then(case_dir, log_path)`` runs once the program succeeded: it reads or edits what
    the program wrote (sets the patch types gmshToFoam left untyped, judges checkMesh's
    report) and raises if that is wrong; what it returns is the step's value.
    ``timeout_s``, ``on_time`` and ``on_poll`` are :func:`run`'s; ``log_name`` names the
    log (``log.<log_name>``) and the step's value where the program is a launcher (mpirun
    runs the solver: its log is still the solver's).
    """

    argv: tuple[str, ...]
    then: Callable[[Path, Path], Any] | None = field(default=None, compare=False)
    timeout_s: float | None = None
    on_time: Callable[[float], None] | None = field(default=None, compare=False)
    on_poll: Callable[[], None] | None = field(default=None, compare=False)
    log_name: str | None = None

    def __post_init__(self) -> None:
        if not self.argv or not all(isinstance(a, str) for a in self.argv):
            raise ValueError(f"a step's argv is a non-empty tuple of strings, not {self.argv!r}")

    @property
    def program(self) -> str:
        return self.argv[0]

    @property
    def name(self) -> str:
        """What the step's log and value are named by: ``log_name``, else the program."""
        return self.log_name or self.program


def drain(steps: Iterable[Step], case_dir: Path, *, launch: Launch | None = None
          ) -> dict[str, Any]:
    """Run ``steps`` in order in ``case_dir``, each with its log ``log.<name>``.

    The first program that fails (or whose ``then`` raises) stops the drain: its error,
    with the tail of its log, is raised and no later step runs.  Returns each step's
    value (what its ``then`` returned, else its log path) by :attr:`Step.name`.
    """
    values: dict[str, Any] = {}
    for step in steps:
        log_path = run(case_dir, step.program, step.argv[1:], log_name=step.log_name,
                       timeout_s=step.timeout_s, on_time=step.on_time, on_poll=step.on_poll,
                       launch=launch)
        values[step.name] = log_path if step.then is None else step.then(case_dir, log_path)
    return values


#: Characters OpenFOAM's fileName rejects (it strips them and then fails).
_INVALID_PATH = re.compile(r"[\s\"'\\;$]")


def check_case_path(case_dir: Path) -> None:
    """OpenFOAM refuses case paths with whitespace, quotes, ``\\``, ``;`` or ``$``."""
    path = str(Path(case_dir).resolve())
    bad = _INVALID_PATH.search(path)
    if bad:
        raise CaseError(f"OpenFOAM cannot run a case in {path!r}: the path contains "
                        f"{bad.group(0)!r}; choose a folder name without spaces or quotes")


def _wait(
    proc: subprocess.Popen,
    log_path: Path,
    start: float,
    timeout_s: float | None,
    on_time: Callable[[float], None] | None,
    on_poll: Callable[[], None] | None,
) -> None:
    offset = 0
    while True:
        try:
            proc.wait(timeout=POLL_INTERVAL_S)
            done = True
        except subprocess.TimeoutExpired:
            done = False
        if on_time is not None:
            with log_path.open("rb") as fh:
                fh.seek(offset)
                chunk = fh.read()
            cut = chunk.rfind(b"\n") + 1
            offset += cut
            times = _TIME_LINE.findall(chunk[:cut])
            if times:
                on_time(float(times[-1]))
        if done:
            return
        if on_poll is not None:
            on_poll()
        if timeout_s is not None and time.monotonic() - start > timeout_s:
            raise ExternalRunError(
                f"{proc.args[0]} ran past its limit of {timeout_s:.0f} s in {log_path.parent}; "
                f"last lines of {log_path.name}:\n{log_tail(log_path)}"
            )


def request_stop(case_dir: Path) -> None:
    """Ask a running solver to write its fields and stop (``stopAt writeNow``).

    The solver must run with ``runTimeModifiable`` on; the controlDict is replaced
    atomically so the solver never reads half a file.
    """
    from foamlib import FoamFile

    path = Path(case_dir) / "system" / "controlDict"
    tmp = path.with_name(".controlDict.stop")
    shutil.copyfile(path, tmp)
    FoamFile(tmp)["stopAt"] = "writeNow"
    os.replace(tmp, path)


def _log_has(path: Path, needle: bytes) -> bool:
    with path.open("rb") as fh:
        return any(needle in line for line in fh)


def _main() -> None:
    """``python -m rotorflow.cases.foam``: report the OpenFOAM found (used by make)."""
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    try:
        inst = find_installation()
    except OpenFOAMNotFoundError as exc:
        log.error("%s", exc)
        raise SystemExit(2) from None
    log.info("%s: %s in %s, etc in %s", PROBE_APPLICATION, inst.version, inst.bin_dir,
             inst.project_dir)


if __name__ == "__main__":
    _main()
