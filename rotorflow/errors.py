"""Errors that the command line turns into one line on stderr and exit status 2."""


class RotorflowError(Exception):
    """Base of the errors a user can cause and fix."""


class CaseError(RotorflowError, ValueError):
    """A case, sweep or table file is malformed or asks for something impossible."""


class ExternalRunError(RotorflowError, RuntimeError):
    """An external program (gmsh, OpenFOAM) failed; the message carries its log tail."""
