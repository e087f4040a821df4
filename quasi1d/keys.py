"""Reading one key of a case file's TOML table: numbers, choices, booleans, and the check
that a table has no unknown keys; each failure is one CaseError line naming the key, the
section and the file."""

from __future__ import annotations

import math

from rotorflow.errors import CaseError


def _number(d: dict, key: str, section: str, where: str, default=None, *, positive=False,
            nonnegative=False, integer=False):
    """Read one numeric key; a missing key gives ``default`` (None: required)."""
    if key not in d:
        if default is None:
            raise CaseError(f"missing key '{key}' in [{section}] of {where}")
        return default
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise CaseError(f"key '{key}' in [{section}] of {where} must be a number, got {v!r}")
    if not math.isfinite(v):
        raise CaseError(f"key '{key}' in [{section}] of {where} must be finite, got {v!r}")
    if integer and int(v) != v:
        raise CaseError(f"key '{key}' in [{section}] of {where} must be an integer, got {v!r}")
    if positive and v <= 0:
        raise CaseError(f"key '{key}' in [{section}] of {where} must be positive, got {v!r}")
    if nonnegative and v < 0:
        raise CaseError(f"key '{key}' in [{section}] of {where} must not be negative, got {v!r}")
    return int(v) if integer else float(v)


def _choice(d: dict, key: str, section: str, where: str, choices, default):
    v = d.get(key, default)
    if not isinstance(v, str) or v not in choices:
        allowed = ", ".join(f'"{c}"' for c in choices)
        raise CaseError(
            f"key '{key}' in [{section}] of {where} must be one of {allowed}, got {v!r}")
    return v


def _bool(d: dict, key: str, section: str, where: str, default: bool) -> bool:
    v = d.get(key, default)
    if not isinstance(v, bool):
        raise CaseError(f"key '{key}' in [{section}] of {where} must be true or false, got {v!r}")
    return v


def _check_keys(d: dict, allowed, section: str, where: str) -> None:
    if not isinstance(d, dict):
        raise CaseError(f"[{section}] of {where} must be a table")
    for k in d:
        if k not in allowed:
            raise CaseError(f"unknown key '{k}' in [{section}] of {where}")
