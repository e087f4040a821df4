"""`rotorflow optimise CASE.toml`: a multi-objective search over a case's design.

The case's [optimise] section (:mod:`.optimise_spec`) names the variables, objectives
and constraints.  pymoo's NSGA-II does the search, with its mixed-variable operators
(SBX and polynomial mutation on reals, the same rounded on integers, uniform crossover
on choices) and NSGA-II's binary tournament; pymoo's constraint domination puts every
feasible design ahead of every infeasible one.  The search is driven by ask and tell:
each generation's designs are evaluated here (:mod:`.optimise_eval`), those already in
the store taken from it, the others in process or on the sweep's Dask cluster
(:mod:`.dask_cluster`), and told back to the algorithm.

Because the same seed asks for the same designs, and every result is stored as it
arrives, a rerun replays the search from the store without computing anything; a run
killed part way resumes where it stopped, and a run with more generations computes
only the new ones.  Results (:mod:`.optimise_results`) go to ``<build>/<case>/optimise/``.
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path

import numpy as np

from .cache import CaseBuild, digest
from .optimise_eval import STORE, EvaluationStore, evaluate_stages, stage_keys, with_values
from .optimise_polish import polish
from .optimise_spec import OptimiseSpec, load_optimise

log = logging.getLogger(__name__)

#: Objective value given to a design that could not be evaluated (it is infeasible
#: through its own constraint, so NSGA-II ranks it by that alone; finite so that
#: pymoo's sorting and normalisation never meet an infinity).
FAILED_F = 1.0e12
#: Characters of the key hash naming a design's task on the cluster.
TASK_ID_CHARS = 16


def run_optimise(path: Path, root: Path = Path("build"), *, cluster: dict | None = None,
                 serial: bool = False, progress: bool = True) -> dict:
    """Run the optimisation of ``path``; return its record (also ``optimise.json``)."""
    from .optimise_results import write_results

    t0 = time.perf_counter()
    spec = load_optimise(path, cluster)
    build = CaseBuild(Path(root).resolve(), spec.name)
    with build.lock():  # one run per case at a time: one writer of the store
        build.clean_stale()
        store = EvaluationStore(build.folder / STORE)
        with Dispatch(spec, store, serial, progress) as dispatch:
            rows, generations = search(spec, dispatch)
        return write_results(build.folder, spec, rows, generations,
                             time.perf_counter() - t0, dispatch.where)


def _problem(spec: OptimiseSpec, fixed: dict):
    from pymoo.core.problem import Problem
    from pymoo.core.variable import Choice, Integer, Real

    kinds = {"int": lambda v: Integer(bounds=(v.low, v.high)),
             "real": lambda v: Real(bounds=(v.low, v.high)),
             "choice": lambda v: Choice(options=list(v.choices))}
    variables = {v.name: kinds[v.kind](v) for v in spec.variables if v.name not in fixed}
    n_constr = sum((c.low is not None) + (c.high is not None) for c in spec.constraints)
    return Problem(vars=variables, n_obj=len(spec.objectives), n_ieq_constr=n_constr + 1)


def _algorithm(spec: OptimiseSpec):
    from pymoo.algorithms.moo.nsga2 import NSGA2, binary_tournament
    from pymoo.core.mixed import (
        MixedVariableDuplicateElimination,
        MixedVariableMating,
        MixedVariableSampling,
    )
    from pymoo.operators.selection.tournament import TournamentSelection

    dedup = MixedVariableDuplicateElimination()
    return NSGA2(pop_size=spec.population, sampling=MixedVariableSampling(),
                 mating=MixedVariableMating(
                     selection=TournamentSelection(func_comp=binary_tournament),
                     eliminate_duplicates=dedup),
                 eliminate_duplicates=dedup)


def search(spec: OptimiseSpec, dispatch: Dispatch) -> tuple[list[dict], list[tuple]]:
    """Every evaluated design (one row each, in the order asked), and after each
    generation (and after the polish of the front's ends, if asked) the number of rows
    and the seconds since the search began.

    With ``separate`` variables, one NSGA-II per value (combination) of them: each
    generation asks every one of them for its designs and evaluates them together
    (one batch for the cluster), so that a value whose front lies behind another's
    (seed 000 Fig. 15: N1 = 6 against N1 = 4) is still searched to its own front."""
    from pymoo.core.evaluator import Evaluator
    from pymoo.problems.static import StaticProblem

    searches = []
    for fixed in spec.niches():
        problem = _problem(spec, fixed)
        algorithm = _algorithm(spec)
        algorithm.setup(problem, termination=("n_gen", spec.generations), seed=spec.seed,
                        verbose=False)
        searches.append((fixed, problem, algorithm))
    rows: list[dict] = []
    ends: list[tuple[int, float]] = []
    t0 = time.perf_counter()
    while any(a.has_next() for _, _, a in searches):
        asked = [(f, p, a, a.ask()) for f, p, a in searches if a.has_next()]
        designs = [design_values(spec, {**x, **f}) for f, _, _, pop in asked
                   for x in pop.get("X")]
        batch = dispatch.run(designs, len(ends))
        F, G = objective_arrays(spec, batch)
        start = 0
        for _, problem, algorithm, pop in asked:
            end = start + len(pop)
            Evaluator().eval(StaticProblem(problem, F=F[start:end], G=G[start:end]), pop)
            algorithm.tell(infills=pop)
            start = end
        rows += batch
        ends.append((len(rows), round(time.perf_counter() - t0, 3)))
    polished = polish(spec, dispatch, rows, len(ends))
    if polished:  # one more "generation" in the hypervolume record: the polish
        rows += polished
        ends.append((len(rows), round(time.perf_counter() - t0, 3)))
    return rows, ends


def design_values(spec: OptimiseSpec, x: dict) -> dict:
    """A design's values as plain Python numbers (integers exact), in the spec's order."""
    out = {}
    for v in spec.variables:
        value = x[v.name]
        if v.kind == "int":
            out[v.name] = int(round(float(value)))
        elif v.kind == "real":
            out[v.name] = float(value)
        else:
            out[v.name] = value.item() if hasattr(value, "item") else value
    return out


def _finite(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def objective_arrays(spec: OptimiseSpec, rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """pymoo's F (every objective to minimise) and G (g <= 0 feasible; the last column
    is 1 where the design could not be evaluated or a figure is undefined)."""
    F, G = [], []
    for r in rows:
        ok = r["status"] != "failed" and all(_finite(r.get(f)) for f in spec.figures)
        if ok:
            F.append([o.sign * r[o.name] for o in spec.objectives])
            G.append([g for c in spec.constraints for g in c.violations(r[c.name])] + [0.0])
        else:
            F.append([FAILED_F] * len(spec.objectives))
            n = sum((c.low is not None) + (c.high is not None) for c in spec.constraints)
            G.append([0.0] * n + [1.0])
    return np.array(F, dtype=float), np.array(G, dtype=float)


class Dispatch:
    """Evaluates a generation's designs: from the store, or computed (in process, or on
    the Dask cluster) and stored as each arrives; shows progress."""

    def __init__(self, spec: OptimiseSpec, store: EvaluationStore, serial: bool,
                 progress: bool):
        self.spec, self.store, self.serial = spec, store, serial
        self.client = self._close = None
        self.where = "in this process" if serial else None
        self.computed = self.cached = 0
        from tqdm import tqdm

        self.bar = tqdm(total=spec.population * spec.generations * len(spec.niches()),
                        unit="design",
                        desc=f"optimise {spec.name}", disable=not progress,
                        dynamic_ncols=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.bar.close()
        if self._close:
            self._close()

    def _cluster(self):
        from .dask_cluster import local_workers, open_client

        if self.client is None:
            self.client, self._close = open_client(self.spec.cluster, self.spec.population)
            self.where = self.spec.cluster.describe(
                local_workers(self.spec.cluster, self.spec.population))
        return self.client

    def run(self, designs: list[dict], generation: int) -> list[dict]:
        """One row per design: its values, status (ok: computed now, cached, failed),
        error, seconds and every figure of its stages."""
        raws = [with_values(self.spec.base_raw, d) for d in designs]
        keys = [stage_keys(raw, self.spec.stages) for raw in raws]
        todo: dict[str, tuple] = {}
        for raw, k in zip(raws, keys, strict=True):
            missing = [s for s in self.spec.stages if k[s] not in self.store]
            if missing:
                todo.setdefault(digest(k)[:TASK_ID_CHARS], (raw, missing, k))
        lost = self._compute(todo, generation)
        rows = []
        for i, (d, k) in enumerate(zip(designs, keys, strict=True)):
            tid = digest(k)[:TASK_ID_CHARS]
            rows.append(self._row(generation, i, d, k, tid in todo, lost.get(tid)))
        self.cached += sum(r["status"] == "cached" for r in rows)
        self.bar.update(len(rows))
        self.bar.set_postfix(generation=generation + 1, computed=self.computed,
                             cached=self.cached, refresh=False)
        return rows

    def _compute(self, todo: dict[str, tuple], generation: int) -> dict[str, str]:
        """Compute and store the missing stages of ``todo``; the errors of tasks that
        never came back (a lost worker: not stored, so a rerun tries again)."""
        where = str(self.spec.path)
        lost: dict[str, str] = {}

        def keep(tid, res):
            raw, missing, k = todo[tid]
            for s in missing:
                self.store.put(k[s], s, res[s])
            self.computed += 1

        if todo and self.serial:
            for tid, (raw, missing, _k) in todo.items():
                keep(tid, evaluate_stages(raw, where, missing))
        elif todo:
            from .dask_cluster import as_completed_results

            jobs = [(tid, (raw, where, missing)) for tid, (raw, missing, _k) in todo.items()]
            for tid, res, exc in as_completed_results(
                    self._cluster(), evaluate_stages, jobs,
                    f"optimise-{self.spec.name}-g{generation}"):
                if exc is None:
                    keep(tid, res)
                else:
                    lost[tid] = " ".join(f"{type(exc).__name__}: {exc}".split())
        return lost

    def _row(self, generation, index, design, keys, computed, lost) -> dict:
        row = {"generation": generation, "index": index, **design, "status": "ok",
               "error": "", "seconds": 0.0}
        if lost:
            row.update(status="failed", error=lost)
            return row
        for s in self.spec.stages:
            rec = self.store.get(keys[s])
            row["seconds"] += rec.get("seconds") or 0.0
            row.update(rec["figures"])
            if rec["error"] and not row["error"]:
                row.update(status="failed", error=rec["error"])
        if row["status"] == "ok" and not computed:
            row["status"] = "cached"
        row["seconds"] = round(row["seconds"], 4)
        return row
