"""Leakage paths as the chamber model uses them: the table's declarations, each with the
case's settings resolved for it.

The chamber table declares the paths (:class:`rotorflow.geometry.table.LeakagePath`:
name, kind, the chamber or plenum it joins, the column it reads, and where the family
knows them its own gap and flow model).  The case file's [leakage] section gives the
settings of every path, and may override them per kind and per named path:

    [leakage]                   # every path
    gap_um = 20
    model = "nozzle"
    [leakage.end-face]          # every path of kind "end-face"
    gap_um = 40
    [leakage.paths."interlobe+2"]   # one path, by the name the table gives it
    model = "none"

Per setting the most specific wins: [leakage.paths.<name>], then [leakage.<kind>], then
the table's own declaration (gap_m, model), then [leakage].  ``model = "none"`` in
[leakage] seals every path that the case file does not open itself (the table's own
model does not open it).  An override naming a path or a kind the table does not
declare is an error, as is an unknown key.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rotorflow.errors import CaseError
from rotorflow.geometry.table import LEAKAGE_KINDS

from .settings import LEAKAGE_MODELS, _check_keys, _choice, _load_correlation, _number

PATHS_SECTION = "paths"
OVERRIDE_SECTIONS = (*LEAKAGE_KINDS, PATHS_SECTION)


@dataclass(frozen=True)
class PathSettings:
    """Settings of [leakage.<kind>] or [leakage.paths.<name>]; None: not set there."""

    gap_m: float | None = None
    model: str | None = None
    coefficient: float | None = None
    zeta: float | None = None
    land_m: float | None = None
    correlation: object = None
    section: str = "leakage"  # where it was read, for messages
    where: str = field(default="the case", compare=False)

    KEYS = ("gap_um", "model", "coefficient", "zeta", "land_mm", "correlation")

    @classmethod
    def from_section(cls, d: dict, section: str, where: str, parent_model: str,
                     parent_fit) -> PathSettings:
        _check_keys(d, cls.KEYS, section, where)
        model = None
        if "model" in d:
            model = _choice(d, "model", section, where, LEAKAGE_MODELS, None)
        fit = None
        if "correlation" in d:
            if (model or parent_model) != "cfd-calibrated":
                raise CaseError(f"key 'correlation' in [{section}] of {where} needs model "
                                '"cfd-calibrated"')
            fit = _load_correlation(d, section, where)
        elif model == "cfd-calibrated" and parent_fit is None:
            raise CaseError(f"model \"cfd-calibrated\" in [{section}] of {where} needs a "
                            "'correlation' (there or in [leakage])")

        def num(key, scale=1.0):
            return None if key not in d else _number(d, key, section, where,
                                                     positive=True) * scale

        return cls(num("gap_um", 1e-6), model, num("coefficient"), num("zeta"),
                   num("land_mm", 1e-3), fit, section, where)


def read_overrides(d: dict, where: str, model: str, fit):
    """The per-kind and per-path settings of a [leakage] section: two dicts, kind ->
    PathSettings and path name -> PathSettings."""
    by_kind = {k: PathSettings.from_section(d[k], f"leakage.{k}", where, model, fit)
               for k in LEAKAGE_KINDS if k in d}
    by_path = {}
    if PATHS_SECTION in d:
        named = d[PATHS_SECTION]
        if not isinstance(named, dict):
            raise CaseError(f"[leakage.{PATHS_SECTION}] of {where} must be a table")
        # a named path may take its model and correlation from its kind's section
        kinds = list(by_kind.values())
        if any(s.model == "cfd-calibrated" for s in kinds):
            model = "cfd-calibrated"
        fit = fit or next((s.correlation for s in kinds if s.correlation is not None), None)
        for name, sub in named.items():
            section = f"leakage.{PATHS_SECTION}.{name}"
            if not isinstance(sub, dict):
                raise CaseError(f"[{section}] of {where} must be a table")
            by_path[name] = PathSettings.from_section(sub, section, where, model, fit)
    return by_kind, by_path


@dataclass(frozen=True)
class PathLaw:
    """A declared path with the settings it flows by (SI)."""

    path: object  # the table's LeakagePath
    model: str
    gap_m: float
    coefficient: float
    zeta: float
    land_m: float
    correlation: object
    viscosity_Pa_s: float
    couette: bool  # the walls drag gas along it: a separate Couette flow
    drag_in_fit: bool  # the walls drag gas along it: the CFD fit's own wall term
    accommodation: float = 1.0  # "rarefied": the walls' momentum accommodation

    @property
    def area_factor(self) -> float:
        """Flow area per unit of the path's column: gap x coefficient for a sealing line,
        the coefficient for an orifice (its column is an area)."""
        if self.path.measure == "length":
            return self.gap_m * self.coefficient
        return self.coefficient

    @property
    def k_factor(self) -> float:
        """24 L mu / h^2 of the fit's viscous group K = 24 L mu / (h^2 sqrt(p rho))."""
        return 24.0 * self.land_m * self.viscosity_Pa_s / self.gap_m**2


def resolve(paths, leak) -> tuple[PathLaw, ...]:
    """The flow law of every declared path under the case's Leakage settings."""
    names = [p.name for p in paths]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise CaseError(f"the chamber table declares leakage path '{twice[0]}' twice")
    by_path, by_kind = dict(leak.by_path), dict(leak.by_kind)
    _check_addressed(by_path, set(names), "path", "paths")
    _check_addressed(by_kind, {p.kind for p in paths}, "kind", "kinds")
    return tuple(_law(p, leak, by_path.get(p.name), by_kind.get(p.kind)) for p in paths)


def _check_addressed(overrides: dict, declared: set, what: str, whats: str) -> None:
    for key, s in overrides.items():
        if key not in declared:
            raise CaseError(f"[{s.section}] of {s.where} names no leakage {what} of the "
                            f"chamber table (its {whats}: {', '.join(sorted(declared))})")


def _law(path, leak, named, kind) -> PathLaw:
    layers = [s for s in (named, kind) if s is not None]

    def pick(attr, declared, default):
        for s in layers:
            if getattr(s, attr) is not None:
                return getattr(s, attr)
        return default if declared is None else declared

    if path.model is not None and path.model not in LEAKAGE_MODELS:
        raise CaseError(f"the chamber table's leakage path '{path.name}' declares model "
                        f"{path.model!r}, not one of {', '.join(LEAKAGE_MODELS)}")
    # "none" in [leakage] seals what the case does not open itself, the table's own
    # model included
    model = pick("model", None if leak.model == "none" else path.model, leak.model)
    gap = pick("gap_m", path.gap_m, leak.gap_m)
    fit = pick("correlation", None, leak.correlation)
    where = f"leakage path '{path.name}' ({path.kind})"
    if model == "cfd-calibrated":
        if fit is None:
            raise CaseError(f"{where} flows by model \"cfd-calibrated\" but the case gives "
                            "no 'correlation'")
        if path.measure != "length":
            raise CaseError(f"{where} is an orifice (its column is an area): the "
                            "\"cfd-calibrated\" fit is per length of a sealing line")
    if path.measure != "length" and model != "rarefied":
        for s in layers:
            if s.gap_m is not None:
                # (an orifice's area is the table's: only the rarefied law reads a gap,
                # as the hole's size that sets its Knudsen number)
                raise CaseError(f"[{s.section}] of {s.where} gives gap_um, but {where} is an "
                                f"orifice (its column is an area) and model {model!r} reads "
                                "no gap there: its flow is coefficient x area")
    moving = bool(leak.wall_motion and path.moving_wall and model != "none")
    in_fit = moving and model == "cfd-calibrated" and fit.wall != 0.0
    return PathLaw(path, model, gap, pick("coefficient", None, leak.coefficient),
                   pick("zeta", None, leak.zeta), pick("land_m", None, leak.land_m), fit,
                   leak.viscosity_Pa_s, moving and not in_fit, in_fit, leak.accommodation)
