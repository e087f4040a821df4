"""The one wrapper around OpenFOAM applications.

Every OpenFOAM program rotorflow runs goes through :func:`run`: an argument list (never a
shell), the case folder as working directory, stdout and stderr into ``log.<application>``
inside the case, and a failure raised as :class:`~rotorflow.errors.ExternalRunError`
carrying the tail of that log.  A log is never taken as proof of success: callers check
the outputs they need (:func:`check_mesh`, :mod:`rotorflow.postprocess.foam_output`).

Dictionaries and fields are read and written with foamlib's ``FoamFile``
(:func:`write_dict`); post-processing tables are read by
:mod:`rotorflow.postprocess.foam_output`.

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
import math
import os
import re
import shutil
import subprocess
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

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


class MeshCheckError(CaseError):
    """checkMesh rejected a mesh rotorflow built; the message carries its complaints."""


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


def run(
    case_dir: Path,
    application: str,
    args: Sequence[str] = (),
    *,
    log_name: str | None = None,
    timeout_s: float | None = None,
    on_time: Callable[[float], None] | None = None,
    on_poll: Callable[[], None] | None = None,
) -> Path:
    """Run ``application args...`` in ``case_dir``; return the path of its log.

    Output goes to ``case_dir/log.<log_name or application>``.  A non-zero exit status,
    a ``FOAM FATAL`` message or a run past ``timeout_s`` raises ExternalRunError with the
    log tail.  ``on_time`` is called with the latest ``Time = ...`` the solver reported
    (the iteration of a steady solver), for progress bars; ``on_poll`` every
    :data:`POLL_INTERVAL_S` while it runs (a convergence monitor may call
    :func:`request_stop` from it).
    """
    inst = find_installation()
    case_dir = Path(case_dir)
    check_case_path(case_dir)
    if not (case_dir / "system" / "controlDict").is_file():
        raise CaseError(f"{case_dir} is not an OpenFOAM case (no system/controlDict)")
    exe = shutil.which(application, path=inst.environment()["PATH"])
    if exe is None:
        raise OpenFOAMNotFoundError(f"OpenFOAM application {application} not found")
    log_path = case_dir / f"log.{log_name or application}"
    cmd = [exe, *map(str, args)]
    log.debug("running %s in %s", " ".join(cmd), case_dir)
    start = time.monotonic()
    env = inst.environment()
    env["PWD"] = str(case_dir.resolve())  # OpenFOAM warns when PWD is not its cwd
    with log_path.open("wb") as out:
        proc = subprocess.Popen(
            cmd, cwd=case_dir, stdout=out, stderr=subprocess.STDOUT, env=env
        )
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


# --- dictionaries -------------------------------------------------------------------------


def write_dict(path: Path, entries: Mapping[str, Any]) -> Path:
    """Write an OpenFOAM dictionary (header included) with foamlib; returns ``path``.

    Multi-word entries are tuples (``("Gauss", "linear")``), lists are OpenFOAM lists,
    nested mappings sub-dictionaries.  An existing file is replaced, not merged.
    """
    from foamlib import FoamFile

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    with FoamFile(path) as f:
        for key, value in entries.items():
            f[key] = value
    return path


def write_field(
    path: Path,
    dimensions: Sequence[float],
    internal: Any,
    boundary: Mapping,
    *,
    vector: bool = False,
) -> Path:
    """Write a volume field file (``0/p``, ``0/U``, ...) with foamlib.

    ``internal`` and the boundary ``value``/``inletValue`` entries are plain numbers or
    arrays (foamlib adds ``uniform``/``nonuniform``); other field-valued entries such as
    ``p0`` must be given as ``("uniform", x)``.  The class is set explicitly because a
    list of three scalars is indistinguishable from one vector.
    """
    from foamlib import FoamFieldFile

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    with FoamFieldFile(path) as f:
        f["FoamFile"] = {
            "version": 2.0,
            "format": "ascii",
            "class": "volVectorField" if vector else "volScalarField",
            "location": f'"{path.parent.name}"',
            "object": path.name,
        }
        f["dimensions"] = FoamFieldFile.DimensionSet(*dimensions, *[0] * (7 - len(dimensions)))
        f["internalField"] = internal
        f["boundaryField"] = dict(boundary)
    return path


_MINIMAL_SYSTEM: dict[str, dict[str, Any]] = {
    "controlDict": {
        "application": "checkMesh",
        "startFrom": "latestTime",
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": 0,
        "deltaT": 1,
        "writeControl": "timeStep",
        "writeInterval": 1,
    },
    "fvSchemes": {
        key: {"default": "none"}
        for key in ("ddtSchemes", "gradSchemes", "divSchemes", "laplacianSchemes",
                    "interpolationSchemes", "snGradSchemes")
    },
    "fvSolution": {"solvers": {}},
}


def ensure_system_files(case_dir: Path) -> None:
    """Write stand-in ``system`` dictionaries where missing (mesh utilities read them)."""
    for name, entries in _MINIMAL_SYSTEM.items():
        path = Path(case_dir) / "system" / name
        if not path.is_file():
            write_dict(path, entries)


def set_patch_types(case_dir: Path, types: Mapping[str, str]) -> None:
    """Set the ``type`` of named patches in ``constant/polyMesh/boundary``.

    gmshToFoam makes every patch a plain ``patch``; walls and the empty front and back of
    a 2D mesh are set here.  A name missing from the mesh is a CaseError (boundary names
    must survive gmsh -> OpenFOAM), and so is a patch left without a type.
    """
    from foamlib import FoamFile

    path = Path(case_dir) / "constant" / "polyMesh" / "boundary"
    boundary = FoamFile(path)
    entries = list(boundary[None])
    names = [name for name, _ in entries]
    missing = sorted(set(types) - set(names))
    if missing:
        raise CaseError(
            f"mesh in {case_dir} lacks patch(es) {', '.join(missing)}; it has {', '.join(names)}"
        )
    untyped = sorted(set(names) - set(types))
    if untyped:
        raise CaseError(f"no patch type given for {', '.join(untyped)} in {case_dir}")
    new = []
    for name, entry in entries:
        entry = dict(entry)
        entry["type"] = types[name]
        entry.pop("physicalType", None)
        if types[name] == "wall":
            entry["inGroups"] = ["wall", "walls"]
        else:
            entry.pop("inGroups", None)
        new.append((name, entry))
    boundary[None] = new


def patch_face_counts(case_dir: Path) -> dict[str, int]:
    """``{patch: nFaces}`` from ``constant/polyMesh/boundary``."""
    from foamlib import FoamFile

    entries = FoamFile(Path(case_dir) / "constant" / "polyMesh" / "boundary")[None]
    return {name: int(entry["nFaces"]) for name, entry in entries}


# --- meshes --------------------------------------------------------------------


@dataclass(frozen=True)
class MeshQuality:
    """What checkMesh says about a mesh."""

    cells: int
    faces: int
    points: int
    max_aspect_ratio: float
    max_non_orthogonality_deg: float
    mean_non_orthogonality_deg: float
    max_skewness: float
    failed_checks: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.failed_checks


def parse_check_mesh(text: str) -> MeshQuality:
    """Parse checkMesh's report (the log of ``checkMesh``)."""

    def number(pattern: str) -> float:
        m = re.search(pattern, text)
        return float(m.group(1)) if m else math.nan

    def count(pattern: str) -> int:  # -1 where checkMesh did not get as far as saying
        m = re.search(pattern, text)
        return int(m.group(1)) if m else -1

    failed = tuple(line.strip() for line in text.splitlines() if line.strip().startswith("***"))
    if "Mesh OK." not in text and not failed:
        failed = ("checkMesh did not report 'Mesh OK.'",)
    return MeshQuality(
        cells=count(r"\n\s*cells:\s+(\d+)"),
        faces=count(r"\n\s*faces:\s+(\d+)"),
        points=count(r"\n\s*points:\s+(\d+)"),
        max_aspect_ratio=number(r"Max aspect ratio = ([-+0-9.eE]+)"),
        max_non_orthogonality_deg=number(r"non-orthogonality Max: ([-+0-9.eE]+)"),
        mean_non_orthogonality_deg=number(
            r"non-orthogonality Max: [-+0-9.eE]+ average: ([-+0-9.eE]+)"
        ),
        max_skewness=number(r"Max skewness = ([-+0-9.eE]+)"),
        failed_checks=failed,
    )


def check_mesh(case_dir: Path) -> MeshQuality:
    """Run checkMesh; a failed check raises MeshCheckError quoting checkMesh's complaints."""
    log_path = run(case_dir, "checkMesh")
    quality = parse_check_mesh(log_path.read_text(errors="replace"))
    if not quality.ok:
        raise MeshCheckError(
            f"checkMesh rejects the mesh in {case_dir}: " + "; ".join(quality.failed_checks)
        )
    return quality


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
