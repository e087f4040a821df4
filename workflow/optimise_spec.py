"""The [optimise] section of a case file: design variables, objectives, constraints.

A case file that `rotorflow optimise` reads is an ordinary case (the base design) with::

    [optimise]
    seed = 1                       # the same seed gives the same front
    population = 40
    generations = 30
    # hypervolume_reference = [0.0, 1.0]   # per objective, in its units (default: the
    #                                      # worst feasible value seen, plus a tenth)

    [optimise.variables]           # "section.key" of the case file, as in a sweep file
    "machine.lobes_outer" = [3, 6]           # integer bounds: an integer variable
    "machine.lambda" = [1.01, 2.0]           # real bounds
    "operating.driven" = { choices = ["inner", "outer"] }

    [optimise.objectives]          # figures of the geometry or quasi-1D stage
    "geometry.V_dr_bar" = "max"
    "geometry.Pi_max" = "min"

    [optimise.constraints]
    "geometry.pressure_angle_deg" = { max = 30 }
    "quasi1d.volumetric_efficiency" = { min = 0.8 }

    [optimise.cluster]             # as a sweep file's [cluster] (default: local Dask)
    workers = 2

Figures are named ``stage.key`` as the columns of a sweep's summary (``geometry.*``:
`rotorflow geometry --json`; ``quasi1d.*``: `rotorflow simulate --json`).  Variables
are addressed and checked by the sweep's own key addressing
(:func:`.sweep_file._check_param`).  Everything wrong is a CaseError of one line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from rotorflow.errors import CaseError

OPTIMISE_KEYS = ("seed", "population", "generations", "hypervolume_reference", "variables",
                 "objectives", "constraints", "cluster", "polish", "separate")
#: Stages an optimisation evaluates in process, and the figure names they give.
EVALUABLE_STAGES = ("geometry", "quasi1d")
SENSES = ("min", "max")
#: Defaults: enough for a 3-4 variable geometric problem to settle (seed 000 Fig. 14).
DEFAULT_POPULATION = 40
DEFAULT_GENERATIONS = 30


@dataclass(frozen=True)
class Variable:
    name: str  # "section.key" of the case file
    kind: str  # "int" | "real" | "choice"
    low: float | int | None = None
    high: float | int | None = None
    choices: tuple = ()

    def middle(self):
        """A value inside the bounds (the probe point of :func:`load_optimise`)."""
        if self.kind == "choice":
            return self.choices[0]
        if self.kind == "int":
            return (self.low + self.high) // 2
        return 0.5 * (self.low + self.high)

    def ends(self) -> tuple:
        return self.choices if self.kind == "choice" else (self.low, self.high)


@dataclass(frozen=True)
class Objective:
    name: str  # "stage.key"
    sense: str  # "min" | "max"

    @property
    def sign(self) -> float:
        """Factor turning the figure into a value to minimise."""
        return 1.0 if self.sense == "min" else -1.0


@dataclass(frozen=True)
class Constraint:
    name: str
    low: float | None = None
    high: float | None = None

    def violations(self, value: float) -> list[float]:
        """pymoo's g <= 0 form, one per bound given."""
        out = []
        if self.low is not None:
            out.append(self.low - value)
        if self.high is not None:
            out.append(value - self.high)
        return out


@dataclass(frozen=True)
class OptimiseSpec:
    path: Path
    name: str
    base_raw: dict  # the case file without its [optimise] section
    variables: tuple[Variable, ...]
    objectives: tuple[Objective, ...]
    constraints: tuple[Constraint, ...]
    population: int
    generations: int
    seed: int
    reference: tuple[float, ...] | None
    cluster: object = field(repr=False, default=None)  # sweep_file.ClusterSpec
    #: Evaluations of each local search that polishes a front's end (0: none; see
    #: :mod:`.optimise_polish`).
    polish: int = 0
    #: Integer or choice variables searched one value (combination) at a time: one
    #: population per value, evaluated together each generation, fronts merged.
    separate: tuple[str, ...] = ()

    def niches(self) -> list[dict]:
        """The fixed values of each separate search ([{}]: one search of everything)."""
        import itertools

        fixed = [v for v in self.variables if v.name in self.separate]
        values = [v.choices if v.kind == "choice" else range(v.low, v.high + 1)
                  for v in fixed]
        return [dict(zip((v.name for v in fixed), combo, strict=True))
                for combo in itertools.product(*values)]

    @property
    def figures(self) -> list[str]:
        return [o.name for o in self.objectives] + [c.name for c in self.constraints]

    @property
    def stages(self) -> tuple[str, ...]:
        """The stages the objectives and constraints need (nothing else runs)."""
        asked = {f.partition(".")[0] for f in self.figures}
        return tuple(s for s in EVALUABLE_STAGES if s in asked)


def _err(path, msg) -> CaseError:
    return CaseError(f"{msg} in [optimise] of {path}")


def _positive_int(path, section, key, default):
    v = section.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise _err(path, f"'{key}' must be a positive integer")
    return v


def _number(v) -> bool:
    """A finite number a float can hold (a TOML integer such as 10**400 cannot)."""
    if not isinstance(v, int | float) or isinstance(v, bool):
        return False
    try:
        return math.isfinite(float(v))
    except OverflowError:
        return False


def check_section(section, path) -> None:
    """The section's own structure (keys, types, bounds, senses); the case loader calls
    this so that `rotorflow run` on an optimisation's case rejects a bad section too."""
    _parse(section, path)


def _parse(section, path):
    if not isinstance(section, dict):
        raise CaseError(f"[optimise] in {path} must be a table")
    for k in section:
        if k not in OPTIMISE_KEYS:
            raise _err(path, f"unknown key '{k}'")
    population = _positive_int(path, section, "population", DEFAULT_POPULATION)
    generations = _positive_int(path, section, "generations", DEFAULT_GENERATIONS)
    seed = section.get("seed", 1)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _err(path, "'seed' must be a non-negative integer")
    variables = _variables(path, section.get("variables"))
    objectives = _objectives(path, section.get("objectives"))
    constraints = _constraints(path, section.get("constraints", {}))
    ref = section.get("hypervolume_reference")
    if ref is not None and not (isinstance(ref, list) and len(ref) == len(objectives)
                                and all(map(_number, ref))):
        raise _err(path, f"'hypervolume_reference' must be a list of {len(objectives)} "
                         "numbers, one per objective")
    polish = section.get("polish", 0)
    if isinstance(polish, bool) or not isinstance(polish, int) or polish < 0:
        raise _err(path, "'polish' must be a non-negative integer (evaluations per start)")
    separate = section.get("separate", [])
    kinds = {v.name: v.kind for v in variables}
    if not isinstance(separate, list) or any(kinds.get(n) not in ("int", "choice")
                                             for n in separate):
        raise _err(path, "'separate' must list integer or choice variables (one search per "
                         "value)")
    return (variables, objectives, constraints, population, generations, seed,
            None if ref is None else tuple(float(r) for r in ref), polish, tuple(separate))


def _variables(path, table) -> tuple[Variable, ...]:
    if not isinstance(table, dict) or not table:
        raise _err(path, "[optimise.variables] must give at least one \"section.key\" = "
                         "[min, max]")
    out = []
    for name, r in table.items():
        if isinstance(r, dict):
            choices = r.get("choices")
            if set(r) != {"choices"} or not isinstance(choices, list) or len(choices) < 2 \
                    or not all(isinstance(c, str | int | float) for c in choices):
                raise _err(path, f"variable '{name}' must be [min, max] or {{ choices = "
                                 "[two or more values] }")
            out.append(Variable(name, "choice", choices=tuple(choices)))
            continue
        if not (isinstance(r, list) and len(r) == 2 and all(map(_number, r))):
            raise _err(path, f"variable '{name}' must be [min, max] (numbers) or "
                             "{ choices = [...] }")
        if not r[0] < r[1]:
            raise _err(path, f"variable '{name}' has empty bounds [{r[0]}, {r[1]}] "
                             "(min must be below max)")
        kind = "int" if all(isinstance(x, int) for x in r) else "real"
        out.append(Variable(name, kind, r[0] if kind == "int" else float(r[0]),
                            r[1] if kind == "int" else float(r[1])))
    return tuple(out)


def _figure_name(path, what, name) -> str:
    stage, dot, key = name.partition(".")
    if not dot or not key or stage not in EVALUABLE_STAGES:
        raise _err(path, f"{what} '{name}' must be \"stage.figure\" with a stage among "
                         f"{', '.join(EVALUABLE_STAGES)}")
    return name


def _objectives(path, table) -> tuple[Objective, ...]:
    if not isinstance(table, dict) or not table:
        raise _err(path, "[optimise.objectives] must give at least one \"stage.figure\" = "
                         "\"min\" or \"max\"")
    out = []
    for name, sense in table.items():
        _figure_name(path, "objective", name)
        if sense not in SENSES:
            raise _err(path, f"objective '{name}' must be \"min\" or \"max\", got {sense!r}")
        out.append(Objective(name, sense))
    return tuple(out)


def _constraints(path, table) -> tuple[Constraint, ...]:
    if not isinstance(table, dict):
        raise _err(path, "[optimise.constraints] must be a table")
    out = []
    for name, bound in table.items():
        _figure_name(path, "constraint", name)
        ok = (isinstance(bound, dict) and bound and set(bound) <= {"min", "max"}
              and all(map(_number, bound.values())))
        if not ok:
            raise _err(path, f"constraint '{name}' must be {{ min = x }}, {{ max = x }} or both")
        if "min" in bound and "max" in bound and not bound["min"] < bound["max"]:
            raise _err(path, f"constraint '{name}' has empty bounds")
        out.append(Constraint(name, bound.get("min"), bound.get("max")))
    return tuple(out)


def load_optimise(path: Path, cluster_overrides: dict | None = None) -> OptimiseSpec:
    """Read and check an optimisation's case file; CaseError (one line) on anything
    wrong, found before anything is written: the section, the base case, every
    variable's key and both its bounds (the case loader must accept each), and every
    figure's name (the stages must compute it, at the middle of the bounds)."""
    from .case import case_from_raw, load_toml
    from .sweep_file import cluster_spec

    path = Path(path)
    data = load_toml(path)
    if "optimise" not in data:
        raise CaseError(f"{path} has no [optimise] section")
    (variables, objectives, constraints, population, generations, seed,
     ref, polish, separate) = _parse(data["optimise"], path)
    cluster = data["optimise"].get("cluster", {})
    base_raw = {k: v for k, v in data.items() if k != "optimise"}
    case_from_raw(base_raw, path)
    spec = OptimiseSpec(path=path, name=path.stem, base_raw=base_raw, variables=variables,
                        objectives=objectives, constraints=constraints,
                        population=population, generations=generations, seed=seed,
                        reference=ref, cluster=cluster_spec(path, cluster, cluster_overrides or {}),
                        polish=polish, separate=separate)
    _check_variables(spec)
    _check_figures(spec)
    return spec


def _check_variables(spec: OptimiseSpec) -> None:
    """Each variable names a case key, and the case loader accepts both its ends (the
    other variables at the middle of their bounds)."""
    from .case import case_from_raw
    from .optimise_eval import with_values
    from .sweep_file import _check_param

    for v in spec.variables:
        try:
            _check_param(spec.path, v.name, spec.base_raw)
        except CaseError as exc:
            raise CaseError(str(exc).replace("sweep key", "optimise variable", 1)) from None
    middle = {v.name: v.middle() for v in spec.variables}
    for v in spec.variables:
        for end in v.ends():
            try:
                case_from_raw(with_values(spec.base_raw, {**middle, v.name: end}), spec.path)
            except CaseError as exc:
                raise CaseError(f"optimise variable '{v.name}' = {end!r}, an end of its "
                                f"bounds, is outside what the case allows: {exc}") from None


def _check_figures(spec: OptimiseSpec) -> None:
    """Every objective and constraint is a number that its stage computes: one
    evaluation at the middle of the bounds, in process, not stored."""
    from . import stages as st
    from .optimise_eval import evaluate, with_values

    raw = with_values(spec.base_raw, {v.name: v.middle() for v in spec.variables})
    for stage in spec.stages:
        reason = st.REGISTRY[stage].missing(raw)
        if reason:
            first = next(f for f in spec.figures if f.startswith(stage + "."))
            raise CaseError(f"'{first}' in [optimise] of {spec.path} needs the {stage} "
                            f"stage, but {reason}")
    result = evaluate(raw, str(spec.path), spec.stages)
    if result["error"]:
        raise CaseError(f"[optimise] of {spec.path}: the design at the middle of the bounds "
                        f"cannot be evaluated: {result['error']}")
    for name in spec.figures:
        value = result["figures"].get(name, "")
        # None: not defined at this design (no pitch-point contact, say), yet a figure.
        if value is None or _number(value):
            continue
        known = sorted(k for k, v in result["figures"].items()
                       if k.startswith(name.partition(".")[0]) and _number(v))
        what = "no stage computes it" if name not in result["figures"] else \
            f"it is not a number ({value!r})"
        raise CaseError(f"'{name}' in [optimise] of {spec.path}: {what} (numeric "
                        f"figures of that stage: {', '.join(known)})")
