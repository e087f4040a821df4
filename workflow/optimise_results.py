"""What an optimisation leaves in ``<build>/<case>/optimise/`` (built beside it and
swapped in whole): ``points.csv`` (every evaluated design), ``pareto.csv`` (the
non-dominated feasible designs of all generations), ``hypervolume.csv`` (the front's
hypervolume after each generation), ``front.png`` (the front with the variables of each
of its designs, as seed 000 Fig. 14), ``front_by_<variable>.png`` (one front per value
of each integer or choice variable, as seed 000 Fig. 15), ``index.html`` (the report
section) and the record ``optimise.json``.
"""

from __future__ import annotations

import csv
import shutil
import uuid
from pathlib import Path

import numpy as np

from .cache import swap_in, write_json_atomic
from .optimise_plots import plot_all, write_page
from .optimise_spec import OptimiseSpec

#: The default hypervolume reference point lies this fraction of the front's range
#: beyond the worst feasible value of each objective (so the front's ends count).
REFERENCE_MARGIN = 0.1


def feasible_F(spec: OptimiseSpec, rows: list[dict]) -> tuple[np.ndarray, list[int]]:
    """Objectives to minimise of the feasible rows, and their row numbers."""
    from .optimise import objective_arrays

    F, G = objective_arrays(spec, rows)
    ok = [i for i in range(len(rows)) if np.all(G[i] <= 0.0)]
    return F[ok], ok


def pareto_rows(spec: OptimiseSpec, rows: list[dict]) -> list[dict]:
    """The non-dominated feasible designs (each design once), best first objective first."""
    from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

    F, ok = feasible_F(spec, rows)
    if not ok:
        return []
    front = NonDominatedSorting().do(F, only_non_dominated_front=True)
    seen, out = set(), []
    for j in sorted(front, key=lambda j: tuple(F[j])):
        design = tuple(rows[ok[j]][v.name] for v in spec.variables)
        if design not in seen:
            seen.add(design)
            out.append(rows[ok[j]])
    return out


def reference_point(spec: OptimiseSpec, rows: list[dict]) -> np.ndarray | None:
    """The hypervolume reference in minimisation form: the spec's, or the worst feasible
    value of each objective plus a margin of the range."""
    if spec.reference is not None:
        return np.array([o.sign * r for o, r in zip(spec.objectives, spec.reference,
                                                     strict=True)])
    F, ok = feasible_F(spec, rows)
    if not ok:
        return None
    lo, hi = F.min(axis=0), F.max(axis=0)
    return hi + REFERENCE_MARGIN * np.where(hi > lo, hi - lo, np.maximum(abs(hi), 1.0))


def hypervolumes(spec: OptimiseSpec, rows: list[dict], ends: list[tuple]) -> list[dict]:
    """The hypervolume of the feasible designs found up to each generation, with the
    seconds the search had taken by then (``ends``: rows and seconds per generation)."""
    from pymoo.indicators.hv import HV

    ref = reference_point(spec, rows)
    out = []
    for g, (end, elapsed) in enumerate(ends):
        F, ok = feasible_F(spec, rows[:end])
        F = F[np.all(F < ref, axis=1)] if ref is not None and ok else F[:0]
        hv = float(HV(ref_point=ref)(F)) if len(F) else 0.0
        out.append({"generation": g, "evaluations": end, "feasible": len(ok),
                    "hypervolume": hv, "elapsed_s": elapsed})
    return out


def _write_csv(path: Path, rows: list[dict], head: list[str]) -> None:
    cols = head + sorted({k for r in rows for k in r} - set(head))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})


def write_results(folder: Path, spec: OptimiseSpec, rows: list[dict], ends: list[tuple],
                  seconds: float, where: str | None) -> dict:
    """Write ``folder/optimise/`` whole and return the run's record."""
    front = pareto_rows(spec, rows)
    hv = hypervolumes(spec, rows, ends)
    head = ["generation", "index", *[v.name for v in spec.variables], "status", *spec.figures,
            "seconds", "error"]
    final = folder / "optimise"
    tmp = folder / f".tmp-optimise-{uuid.uuid4().hex[:8]}"
    tmp.mkdir(parents=True)
    try:
        _write_csv(tmp / "points.csv", rows, head)
        _write_csv(tmp / "pareto.csv", front, head)
        _write_csv(tmp / "hypervolume.csv", hv, ["generation", "evaluations", "feasible",
                                                 "hypervolume", "elapsed_s"])
        pictures = plot_all(tmp, spec, rows, front, hv)
        record = _record(spec, rows, front, hv, seconds, where, final)
        write_page(tmp, spec, front, hv, record, pictures)
        write_json_atomic(tmp / "optimise.json", record)
        swap_in(tmp, final)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return record


def _record(spec, rows, front, hv, seconds, where, final: Path) -> dict:
    ref = reference_point(spec, rows)
    return {
        "case": str(spec.path), "seed": spec.seed, "population": spec.population,
        "generations": min(len(hv), spec.generations), "stages": list(spec.stages),
        "polish_evaluations": sum(r["generation"] >= spec.generations for r in rows),
        "variables": [v.name for v in spec.variables],
        "objectives": {o.name: o.sense for o in spec.objectives},
        "evaluations": len(rows),
        "computed": sum(r["status"] == "ok" for r in rows),
        "cached": sum(r["status"] == "cached" for r in rows),
        "failed": sum(r["status"] == "failed" for r in rows),
        "pareto_size": len(front), "hypervolume": hv[-1]["hypervolume"] if hv else 0.0,
        "hypervolume_reference": None if ref is None else [
            o.sign * float(r) for o, r in zip(spec.objectives, ref, strict=True)],
        "seconds": round(seconds, 2), "where": where or "nothing to compute",
        "folder": str(final), "points": str(final / "points.csv"),
        "pareto": str(final / "pareto.csv"), "report": str(final / "index.html"),
        "pareto_set": [{k: r.get(k) for k in [v.name for v in spec.variables] + spec.figures}
                       for r in front],
    }
