"""Errors the command line turns into one line on stderr: exit status 2 for input the
user must fix (:class:`CaseError`), 1 for a computation that ran and failed
(:class:`RunFailure`)."""


class RotorflowError(Exception):
    """Base of the errors a user can cause and fix."""


class CaseError(RotorflowError, ValueError):
    """A case, sweep or table file is malformed or asks for something impossible."""


class RunFailure(RotorflowError, RuntimeError):
    """Accepted input whose computation failed: an external program, or the solver.
    Not bad input as far as the checks can tell, so not its exit status."""


class ExternalRunError(RunFailure):
    """An external program (gmsh, OpenFOAM) failed; the message carries its log tail."""
