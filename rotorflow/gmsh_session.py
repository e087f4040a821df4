"""The one way rotorflow uses gmsh: a session that is always finalized.

gmsh keeps global state.  :func:`gmsh_session` opens it for exactly one model, refuses to
nest (two meshes never mix in one session), collects gmsh's messages, turns a gmsh error
into :class:`~rotorflow.errors.ExternalRunError` carrying the last messages, optionally
writes them to ``log.gmsh``, and finalizes on every exit path.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rotorflow.errors import ExternalRunError

log = logging.getLogger(__name__)

#: gmsh messages quoted in an error.
MESSAGE_TAIL = 30


@contextmanager
def gmsh_session(model: str, *, log_dir: Path | None = None, threads: int = 1) -> Iterator:
    """Open gmsh with one empty model named ``model``; yield the ``gmsh`` module.

    ``log_dir``: where to write ``log.gmsh`` (gmsh's messages), if anywhere.
    """
    import gmsh

    if gmsh.isInitialized():
        raise RuntimeError("a gmsh session is already open; rotorflow never nests two")
    # interruptible=False: gmsh must not replace Python's SIGINT handler.
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", threads)
        gmsh.logger.start()
        gmsh.model.add(model)
        try:
            yield gmsh
        except Exception as exc:
            if type(exc) is Exception:  # the gmsh API raises bare Exception
                messages = "\n".join(gmsh.logger.get()[-MESSAGE_TAIL:])
                raise ExternalRunError(f"gmsh failed on {model}: {exc}\n{messages}") from exc
            raise
        finally:
            if log_dir is not None:
                Path(log_dir).mkdir(parents=True, exist_ok=True)
                (Path(log_dir) / "log.gmsh").write_text("\n".join(gmsh.logger.get()) + "\n")
            gmsh.logger.stop()
    finally:
        gmsh.finalize()
