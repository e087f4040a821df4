"""Chamber pressures of the section in motion from the grid's topology at every written
time, and their comparison with the closed-section quasi-1D model (issue 17).

The cellZones of :mod:`.moving_case` are cut at the start angle and stay with their
cells; the O-grid's cells follow the rotors only roughly (the contact points, where the
chambers part, move along both walls), so over more than a few degrees a zone's average
is no longer its chamber's.  Here the fields written at key-frame times (where the moved
mesh *is* the key-frame grid, to round-off: ``test_cfd_moving_run``) are cut into
chambers by the grid's own topology at that angle (:func:`.moving_case.chamber_cells`):
each chamber's pressure is the area-weighted mean over its cells, its gap columns left
out as in the zones.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .moving_case import chamber_cells
from .moving_section import MovingSection, _areas
from .ogrid import make_ogrid


def written_times(case_dir: Path) -> list[tuple[float, Path]]:
    """(time, folder) of every time folder holding a pressure field, in order."""
    out = []
    for d in Path(case_dir).iterdir():
        try:
            t = float(d.name)
        except ValueError:
            continue
        if (d / "p").is_file():
            out.append((t, d))
    return sorted(out)


def read_scalar_field(path: Path, cells: int) -> np.ndarray:
    """A volScalarField's internal values (uniform or an ASCII list)."""
    text = Path(path).read_text()
    head = text.index("internalField")
    rest = text[head + len("internalField"):].lstrip()
    if rest.startswith("uniform"):
        return np.full(cells, float(rest.split()[1].rstrip(";")))
    body = rest[rest.index("(") + 1:]
    return np.array(body[:body.index(")")].split(), float)[:cells]


def topology_pressures(s: MovingSection, case_dir: Path) -> dict:
    """{"angles_deg": [...], "p": {slot: [Pa at each]}} from every written time: slot s
    (1..N, N the outer rotor's lobes) is the chamber of machine age phi + s period."""
    period = float(s.pair.period)
    n = int(round(2.0 * math.pi / period))
    angles, table = [], {c: [] for c in range(1, n + 1)}
    for t, folder in written_times(case_dir):
        phi = s.start + s.omega_outer * t
        grid = make_ogrid(s.pair, phi, s.gap, s.spec)[0]
        area = _areas(grid.points)[0].ravel()  # cell (i, j) is i * rows + j
        p = read_scalar_field(folder / "p", area.size)
        cells, _ = chamber_cells(s, grid, phi)
        got = {((slot - 1) % n) + 1: float(np.sum(p[c] * area[c]) / np.sum(area[c]))
               for slot, c in cells.items()}
        angles.append(math.degrees(phi))
        for c in table:
            table[c].append(got.get(c, math.nan))
    return {"angles_deg": angles, "p": {str(c): v for c, v in table.items()}}


def compare(cfd: dict, model_p: np.ndarray) -> dict:
    """Per chamber, the largest and the RMS difference between the model's pressures
    (``model_p``, (angles, N), at ``cfd["angles_deg"]``) and the CFD's, as a share of
    the CFD's pressure swing over the angles; angles where the CFD has no cells of the
    chamber are left out (and counted)."""
    out = {}
    for c, values in cfd["p"].items():
        p = np.asarray(values, float)
        q = np.asarray(model_p)[:, int(c) - 1]
        ok = np.isfinite(p) & np.isfinite(q)
        if ok.sum() < 2:
            continue
        swing = float(p[ok].max() - p[ok].min())
        d = q[ok] - p[ok]
        out[c] = {"max": float(np.abs(d).max()) / swing,
                  "rms": float(np.sqrt(np.mean(d * d))) / swing,
                  "swing_Pa": swing, "left_out": int((~ok).sum())}
    return out


def comparison_record(s: MovingSection, run, case_dir: Path, raw: dict, where: Path,
                      models, case_of, correlation: Path | None = None) -> dict:
    """A completed run's chamber pressures (:func:`topology_pressures`) against the
    closed-section quasi-1D model under each leakage model (:mod:`.moving_quasi1d`, the
    case file ``raw``'s machine at the run's depth, clearance and gas, made by
    ``case_of``, the workflow's case_from_raw), as recorded in
    ``tests/data``: small, and re-checkable offline with :func:`compare`."""
    import time

    from rotorflow.errors import CaseError

    from .moving_quasi1d import section_models, simulate_closed

    if not run.ok:
        raise CaseError(f"the run is {run.status} ({run.message}): not compared")
    cfd = topology_pressures(s, case_dir)
    angles = np.radians(cfd["angles_deg"])
    rec = {"cfd": {"status": run.status, "cells": run.cells, "time_steps": run.time_steps,
                   "run_time_s": run.run_time_s, "mass_drift": run.mass_drift,
                   "max_courant": run.max_courant, "wall_velocity": run.wall_velocity,
                   "gap_m": s.gap, "depth_m": s.depth, "start_deg": math.degrees(s.start),
                   "span_deg": math.degrees(s.span), "chambers": cfd}, "models": {}}
    for name, sm in section_models(raw, where, s.depth, s.gap, s.gas, models, case_of,
                                   correlation).items():
        if not math.isclose(sm.model.geo.omega_outer, s.omega_outer, rel_tol=1e-9):
            raise CaseError(f"the case's outer-rotor speed {sm.model.geo.omega_outer:.6g} "
                            f"rad/s is not the run's {s.omega_outer:.6g}")
        t0 = time.perf_counter()
        got = simulate_closed(sm, s.start, s.span, s.omega_outer, s.p0, s.T0, angles)
        rec["models"][name] = {"p": got["p"].tolist(), "mass_drift": got["mass_drift"],
                               "seconds": time.perf_counter() - t0,
                               "errors": compare(cfd, got["p"])}
    return rec
