"""Shared fixtures; the report header names the versions a failing run depends on."""

from __future__ import annotations

import contextlib
import io
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy

REPO = Path(__file__).resolve().parents[1]
CASES = REPO / "examples"
REFERENCE = REPO / "tests" / "data" / "reference"


def pytest_report_header(config):
    return [f"numpy {np.__version__}, scipy {scipy.__version__}"]


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


def run_cli(*args) -> subprocess.CompletedProcess:
    """``rotorflow *args`` in this process (the command line's own ``main``), as
    subprocess.run would report it: its exit status, stdout and stderr, Python's
    warnings included in stderr as a separate process would print them.  A separate
    process pays ~5 s of CPU a real-fluid command on a slow machine for importing
    CoolProp 8, which loads its whole fluid library; the entry point itself is run as a
    process by tests/test_cli_simulate.py."""
    from rotorflow.workflow.cli import main

    out, err = io.StringIO(), io.StringIO()
    argv = [str(a) for a in args]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's refusals
            code = exc.code if isinstance(exc.code, int) else 1
    for w in caught:
        err.write(warnings.formatwarning(w.message, w.category, w.filename, w.lineno))
    return subprocess.CompletedProcess(["rotorflow", *argv], code, out.getvalue(),
                                       err.getvalue())
