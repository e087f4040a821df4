"""Stage artifacts, their keys, and the record of each run.

Layout (``ROOT`` is the build folder, ``build/`` by default)::

    ROOT/<case>/<stage>/             one folder per stage, complete or absent
    ROOT/<case>/<stage>/.stage.json  the stamp: key, files and their hashes
    ROOT/<case>/run.json             what the last run planned, executed and skipped
    ROOT/<case>/.lock                held while a run works on the case

A stage's **key** is the hash of the case parts it reads, the artifact hashes of its
upstream stages, its own version, the rotorflow version and the source of the code it
runs (:func:`code_hash` of the stage's ``code`` modules).  An artifact is reused only
when its stamp carries the same key and every file it lists is there with its size.

A stage writes into ``ROOT/<case>/.tmp-<stage>-<token>/``; the stamp is written last,
and the folder is renamed into place only after the stage function returned.  A run
killed at any moment leaves either the old complete folder (whose stamp carries the
old key), or no folder, and temporary folders that the next run of the case removes
(it holds the case's lock, so no other run can be writing them).
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import importlib.util
import json
import logging
import os
import shutil
import socket
import sys
import time
import uuid
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from rotorflow import __version__

log = logging.getLogger(__name__)

STAMP = ".stage.json"
RECORD = "run.json"
LOCK = ".lock"
TMP_PREFIX = ".tmp-"
OLD_PREFIX = ".old-"
#: Bytes read at a time when hashing files.
CHUNK = 1 << 20


def digest(obj) -> str:
    """SHA-256 of a JSON-ready object, independent of dict order."""
    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def file_hash(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(CHUNK):
            h.update(chunk)
    return h.hexdigest()


@functools.cache
def code_hash(modules: tuple[str, ...]) -> str:
    """Hash of the source of modules and packages (a package: every .py file in it).

    Part of a stage's key, so that a stage reruns when the code it runs changes, not
    only when the rotorflow version does.  Hashed once per process (a few ms).
    """
    h = hashlib.sha256()
    for mod in sorted(set(modules)):
        try:
            spec = importlib.util.find_spec(mod)
        except ValueError:  # a script's __main__ has no spec
            spec = None
        if spec is None or spec.origin is None and not spec.submodule_search_locations:
            origin = getattr(sys.modules.get(mod), "__file__", None)
            if origin is None:
                raise ValueError(f"no source for module {mod}")
            files = [Path(origin)]
        elif spec.submodule_search_locations:
            files = sorted(f for d in spec.submodule_search_locations
                           for f in Path(d).rglob("*.py"))
        else:
            files = [Path(spec.origin)]
        for f in files:
            h.update(f.name.encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def stage_key(name: str, version: int, inputs: dict, upstream: dict[str, str],
              code: str = "") -> str:
    """The key of a stage run: case parts read, upstream artifact hashes, versions, code."""
    return digest({"stage": name, "stage_version": version, "rotorflow": __version__,
                   "code": code, "inputs": inputs, "upstream": upstream})


def write_json_atomic(path: Path, obj) -> None:
    """Write JSON beside ``path`` and rename it over, so readers never see half a file."""
    path = Path(path)
    tmp = path.with_name(f"{TMP_PREFIX}{path.name}-{uuid.uuid4().hex[:8]}")
    tmp.write_text(json.dumps(obj, indent=2, sort_keys=False, default=str) + "\n")
    os.replace(tmp, path)


def swap_in(tmp: Path, final: Path) -> None:
    """Put the finished folder ``tmp`` in place of ``final``: the old one is renamed
    aside first and removed after, so ``final`` is always a whole folder or absent."""
    old = None
    if final.exists():
        old = final.with_name(f"{OLD_PREFIX}{final.name}-{uuid.uuid4().hex[:8]}")
        os.rename(final, old)
    os.rename(tmp, final)
    if old:
        shutil.rmtree(old, ignore_errors=True)


def read_stamp(folder: Path) -> dict | None:
    """The stamp of a complete artifact folder, or None (absent, unreadable, incomplete)."""
    try:
        stamp = json.loads((Path(folder) / STAMP).read_text())
    except (OSError, ValueError):
        return None
    files = stamp.get("files")
    if not isinstance(files, dict) or "key" not in stamp or "artifact_hash" not in stamp:
        return None
    for rel, (size, _sha) in files.items():
        try:
            if (Path(folder) / rel).stat().st_size != size:
                return None
        except OSError:
            return None
    return stamp


def seal(folder: Path, stage: str, key: str, extra: dict) -> dict:
    """Hash every file of a finished stage folder and write its stamp (last)."""
    folder = Path(folder)
    files = {}
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        rel = path.relative_to(folder).as_posix()
        if rel == STAMP:
            continue
        files[rel] = [path.stat().st_size, file_hash(path)]
    stamp = {"stage": stage, "key": key, "rotorflow": __version__,
             "artifact_hash": digest(files), "files": files,
             "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), **extra}
    (folder / STAMP).write_text(json.dumps(stamp, indent=2, default=str) + "\n")
    return stamp


@dataclass
class CaseBuild:
    """The build folder of one case."""

    root: Path
    name: str

    @property
    def folder(self) -> Path:
        return Path(self.root) / self.name

    def artifact(self, stage: str) -> Path:
        return self.folder / stage

    def stamp(self, stage: str) -> dict | None:
        return read_stamp(self.artifact(stage))

    def new_tmp(self, stage: str) -> Path:
        self.folder.mkdir(parents=True, exist_ok=True)
        token = f"{socket.gethostname()}-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        tmp = self.folder / f"{TMP_PREFIX}{stage}-{token}"
        tmp.mkdir()
        return tmp

    def commit(self, tmp: Path, stage: str) -> Path:
        """Move a sealed temporary folder into place, replacing the old artifact."""
        final = self.artifact(stage)
        swap_in(tmp, final)
        return final

    def clean_stale(self) -> list[Path]:
        """Remove what killed runs left behind (call only while holding the lock)."""
        gone = []
        if not self.folder.is_dir():
            return gone
        for p in self.folder.iterdir():
            if p.name.startswith((TMP_PREFIX, OLD_PREFIX)):
                if p.is_dir():
                    shutil.rmtree(p, ignore_errors=True)
                else:
                    p.unlink(missing_ok=True)
                gone.append(p)
        if gone:
            log.info("removed %d unfinished folder(s) of an interrupted run in %s",
                     len(gone), self.folder)
        return gone

    @contextlib.contextmanager
    def lock(self):
        """Exclusive lock on the case's build folder (waits for another run)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        with open(self.folder / LOCK, "w") as fh:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                log.warning("waiting for another run of %s to finish", self.folder)
                fcntl.flock(fh, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(fh, fcntl.LOCK_UN)

    def write_record(self, record: dict) -> None:
        write_json_atomic(self.folder / RECORD, record)


@dataclass
class StageContext:
    """What a stage function gets: the case, its folder to write, upstream folders."""

    stage: str
    case_path: Path
    raw: dict
    out: Path
    inputs: dict[str, Path]
    _case: object = None

    @cached_property
    def case(self):
        if self._case is not None:
            return self._case
        from rotorflow.workflow.case import load_case

        return load_case(self.case_path)

    def input(self, stage: str) -> Path:
        try:
            return self.inputs[stage]
        except KeyError:
            raise KeyError(f"stage '{self.stage}' did not declare '{stage}' upstream") from None
