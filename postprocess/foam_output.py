"""Reading what OpenFOAM function objects write under ``postProcessing/``.

Plain text and numpy only, so that recorded outputs are read (and tested) without
OpenFOAM.  A table that is missing or empty raises
:class:`~rotorflow.errors.ExternalRunError`: the absence of an output is a failure of
the run that should have written it, never a zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import ExternalRunError


def read_table(path: Path) -> tuple[list[str], np.ndarray]:
    """Read one function-object table (``postProcessing/<name>/<time>/<file>.dat``).

    Returns the column names from the ``# Time ...`` header line and the numbers as a 2D
    array.  Only complete lines are read (a running solver may be half-way through one);
    non-finite values are kept for the caller to judge.
    """
    path = Path(path)
    if not path.is_file():
        raise ExternalRunError(f"expected OpenFOAM output {path} was not written")
    text = path.read_text()
    header: list[str] = []
    rows: list[list[float]] = []
    for line in text[: text.rfind("\n") + 1].splitlines():
        if line.startswith("#"):
            words = line[1:].split()
            if words and words[0] == "Time":
                header = words
            continue
        if line.strip():
            try:
                rows.append([float(w) for w in line.split()])
            except ValueError as exc:
                raise ExternalRunError(f"malformed line in {path}: {line!r}") from exc
    if not rows:
        raise ExternalRunError(f"OpenFOAM output {path} holds no data")
    width = max(len(r) for r in rows)
    data = np.full((len(rows), width), np.nan)
    for i, r in enumerate(rows):
        data[i, : len(r)] = r
    return header, data


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def function_object_table(
    case_dir: Path, name: str, file_name: str
) -> tuple[list[str], np.ndarray]:
    """The table of function object ``name``, joined over its restart-time folders.

    A restart writes a new ``<start time>/`` folder; where two folders cover the same
    iteration the later one wins.
    """
    root = Path(case_dir) / "postProcessing" / name
    if not root.is_dir():
        raise ExternalRunError(f"function object {name} wrote nothing in {case_dir}")
    starts = sorted((d for d in root.iterdir() if _is_number(d.name)), key=lambda d: float(d.name))
    parts = [read_table(d / file_name) for d in starts if (d / file_name).is_file()]
    if not parts:
        raise ExternalRunError(f"function object {name} wrote no {file_name} in {case_dir}")
    header = parts[-1][0]
    data = np.vstack([p[1] for p in parts]) if len(parts) > 1 else parts[0][1]
    _, last = np.unique(data[::-1, 0], return_index=True)
    keep = np.sort(len(data) - 1 - last)
    return header, data[keep]


@dataclass(frozen=True)
class PatchFlowHistory:
    """Mass flow through an inlet and an outlet patch per iteration, both positive when
    the flow goes from inlet to outlet (kg/s through the mesh's depth)."""

    iteration: np.ndarray
    inlet: np.ndarray
    outlet: np.ndarray

    @property
    def imbalance(self) -> np.ndarray:
        """|inlet - outlet| / inlet per iteration."""
        return np.abs(self.inlet - self.outlet) / np.abs(self.inlet)


def read_patch_flows(
    case_dir: Path,
    inlet: str = "massFlowInlet",
    outlet: str = "massFlowOutlet",
    file_name: str = "surfaceFieldValue.dat",
) -> PatchFlowHistory:
    """Join two ``surfaceFieldValue sum(phi)`` tables on their common iterations.

    OpenFOAM's face fluxes point out of the domain, so the inlet sum is negated.
    """
    _, t_in = function_object_table(case_dir, inlet, file_name)
    _, t_out = function_object_table(case_dir, outlet, file_name)
    common, i_in, i_out = np.intersect1d(t_in[:, 0], t_out[:, 0], return_indices=True)
    if len(common) == 0:
        raise ExternalRunError(f"inlet and outlet flow tables share no iteration in {case_dir}")
    return PatchFlowHistory(common, -t_in[i_in, 1], t_out[i_out, 1])
