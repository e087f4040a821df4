"""Polishing the ends of a front: a local descent from each objective's best designs.

NSGA-II spreads its designs along the front, but a front's ends, each objective's own
optimum, can lie in valleys too narrow for its operators to descend: seed 000's
minimum Pi_max is a kink where two peaks of the idle rotor's power ratio trade places,
a few thousandths of lambda wide, and NSGA-II at population 40 stops 20-60 % above its
bottom.  From the best feasible design of each objective within each combination of
integer and choice values (seed 000 Fig. 15 has one front per lobe count), scipy's
bounded Nelder-Mead descends on the real variables with the others held.  Nelder-Mead
needs no gradient, which a max over the cycle does not have at its kink.

Its designs are evaluated through the search's own dispatch (store, cache, cluster), and
the descent is deterministic, so a rerun replays it from the store.
"""

from __future__ import annotations

import numpy as np

from .optimise_spec import OptimiseSpec

#: Starts per objective: the best combinations of integer and choice values.
MAX_STARTS = 6
#: The first simplex spans this share of each real variable's range.
SIMPLEX_SHARE = 0.05
#: Stop when the simplex is this share of each range (far below any tolerance a
#: designer reads from a front) or the objective changes less than this share.
XTOL_SHARE, FTOL_SHARE = 1e-4, 1e-5
#: Added to an objective per unit of constraint violation (a feasible design wins).
PENALTY = 1.0e6


def starts(spec: OptimiseSpec, rows: list[dict], k: int) -> list[dict]:
    """The best feasible design of objective ``k`` in each combination of integer and
    choice values, best first (at most :data:`MAX_STARTS`)."""
    from .optimise_results import feasible_F

    F, ok = feasible_F(spec, rows)
    held = [v.name for v in spec.variables if v.kind != "real"]
    best: dict[tuple, tuple[float, dict]] = {}
    for f, i in zip(F[:, k], ok, strict=True):
        combo = tuple(rows[i][n] for n in held)
        if combo not in best or f < best[combo][0]:
            best[combo] = (float(f), rows[i])
    return [r for _, r in sorted(best.values(), key=lambda t: t[0])[:MAX_STARTS]]


def polish(spec: OptimiseSpec, dispatch, rows: list[dict], generation: int) -> list[dict]:
    """The rows of every design the descents evaluated (tagged with ``generation``)."""
    from scipy.optimize import minimize

    from .optimise import design_values, objective_arrays

    reals = [v for v in spec.variables if v.kind == "real"]
    if not reals or spec.polish <= 0:
        return []
    low = np.array([v.low for v in reals], float)
    span = np.array([v.high - v.low for v in reals], float)
    seen: dict[tuple, dict] = {}
    out: list[dict] = []

    def evaluate(start: dict, x: np.ndarray) -> dict:
        values = design_values(spec, {**start, **{v.name: float(xi) for v, xi
                                                  in zip(reals, x, strict=True)}})
        key = tuple(values[v.name] for v in spec.variables)
        if key not in seen:
            seen[key] = dispatch.run([values], generation)[0]
            out.append(seen[key])
        return seen[key]

    for k in range(len(spec.objectives)):
        for start in starts(spec, rows, k):
            x0 = np.array([start[v.name] for v in reals], float)

            def f(x, start=start, k=k):
                F, G = objective_arrays(spec, [evaluate(start, x)])
                return float(F[0, k] + PENALTY * np.clip(G[0], 0.0, None).sum())

            f0 = abs(f(x0)) or 1.0
            minimize(f, x0, method="Nelder-Mead", bounds=list(zip(low, low + span,
                                                                  strict=True)),
                     options={"initial_simplex": _simplex(x0, low, span),
                              "maxfev": spec.polish, "xatol": XTOL_SHARE * span.min(),
                              "fatol": FTOL_SHARE * f0})
    return out


def _simplex(x0: np.ndarray, low: np.ndarray, span: np.ndarray) -> np.ndarray:
    """x0 and one step along each variable, inward where x0 sits at its upper bound."""
    pts = [x0]
    for j in range(len(x0)):
        x = x0.copy()
        step = SIMPLEX_SHARE * span[j]
        x[j] = x0[j] + step if x0[j] + step <= low[j] + span[j] else x0[j] - step
        pts.append(x)
    return np.array(pts)
