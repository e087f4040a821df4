"""Shared fixtures; the report header names the versions a failing run depends on."""

from __future__ import annotations

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
