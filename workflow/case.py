"""The case file: TOML in, validated frozen settings out.

Keys carry their unit in their name; everything returned is SI.  Unknown sections and
keys are errors naming the key and the file, never ignored.  Sections owned by later
stages ([leakage], [ports], ...) are validated by those stages' own settings classes.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from rotorflow.errors import CaseError
from rotorflow.geometry.family import RotorPair, family_for, number
from rotorflow.geometry.ports import DISCHARGE_PORTS
from rotorflow.geometry.section import POINTS_PER_PERIOD
from rotorflow.geometry.sweep import Sweep

from .plausible import check_plausible

#: [machine] keys of every family; each family adds its own (geometry.family.Family.keys).
MACHINE_KEYS = {"type", "length_mm", "points_per_period"}
#: Bounds of [machine] points_per_period, the chamber tables' angle samples per lobe
#: period: below 12 a twin screw's port events crowd one cell (at 20 its discharge area
#: errs by 2.5e-4 to 8.8e-4, bench/bench_twin_screw.py); above 1536 a table costs
#: minutes (the benches' references stop at 768).
POINTS_PER_PERIOD_RANGE = (12, 1536)
SWEEP_KEYS = {"kind", "wrap_outer_deg", "wrap_bar", "diameter_end_mm", "lead_ratio"}
#: A family's rotors may give the wrap by name (wrap_male_deg, wrap_female_deg, ...): any
#: rotor's wrap fixes the others' through the lobe ratio (a rotor's twist is its speed
#: ratio times the reference rotor's).
WRAP_KEY = "wrap_{}_deg"
#: [operating] keys the geometry reads; the quasi-1D stage owns the others.
OPERATING_GEOMETRY_KEYS = {"volume_ratio", "driven", "discharge_port"}
SECTIONS = {
    "machine", "sweep", "operating", "leakage", "ports", "numerics", "mechanical", "export",
    "outputs", "cfd", "cfd_chamber", "cfd_machine", "optimise", "plausibility", "map",
}


@dataclass(frozen=True)
class Case:
    name: str
    path: Path
    pair: RotorPair
    sweep_kind: str
    length: float
    wrap: float | None  # outer wrap [rad], or None when given as wrap_bar
    wrap_bar: float | None
    scale_end: float
    lead_ratio: float
    volume_ratio: float
    driven: str
    raw: dict = field(repr=False, compare=False)
    #: [operating] discharge_port: which discharge ports the chamber table opens
    #: (geometry.ports.DISCHARGE_PORTS); "axial", the end-plate port alone, by default.
    discharge_port: str = "axial"
    #: [machine] points_per_period: angle samples per lobe period of the machine's chamber
    #: curves and tables (its figures, loads and port timing, the table's rows).
    points_per_period: int = POINTS_PER_PERIOD

    def sweep(self, life_2d: float) -> Sweep:
        """The sweep law; a wrap given as wrap_bar needs the profile's chamber life."""
        wrap = self.wrap if self.wrap is not None else self.wrap_bar * life_2d
        return Sweep(self.sweep_kind, self.length, wrap, self.scale_end, self.lead_ratio)


def _check_keys(section: dict, allowed: set[str], name: str, path: Path):
    if not isinstance(section, dict):
        raise CaseError(f"[{name}] in {path} must be a table")
    for key in section:
        if key not in allowed:
            raise CaseError(f"unknown key '{key}' in [{name}] of {path}")


def load_toml(path: Path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise CaseError(f"case file not found: {path}")
    try:
        return tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise CaseError(f"malformed case file {path}: {exc}") from None


def load_case(path: Path) -> Case:
    path = Path(path)
    return case_from_raw(load_toml(path), path)


def case_from_raw(data: dict, path: Path) -> Case:
    """The case of a parsed case file (``path``: its name and where errors point), so
    that an optimisation evaluates its points in process, without a file per point."""
    path = Path(path)
    for name in data:
        if name not in SECTIONS:
            raise CaseError(f"unknown section [{name}] in {path}")
    check_plausible(data, path)
    pair, length, points = _machine(data, path)
    kind, wrap, wrap_bar, scale_end, lead_ratio = _sweep_law(data, path, pair)
    volume_ratio, driven, discharge_port = _operating(data, path, pair)
    validate_stage_sections(data, path, pair)
    return Case(
        name=path.stem,
        path=path,
        pair=pair,
        sweep_kind=kind,
        length=length,
        wrap=wrap,
        wrap_bar=wrap_bar,
        scale_end=scale_end,
        lead_ratio=lead_ratio,
        volume_ratio=volume_ratio,
        driven=driven,
        raw=data,
        discharge_port=discharge_port,
        points_per_period=points,
    )


def _machine(data: dict, path: Path) -> tuple[RotorPair, float, int]:
    """[machine]: the family's pair, the rotor length [m] and the chamber tables' points
    per period."""
    if "machine" not in data:
        raise CaseError(f"missing section [machine] in {path}")
    m = data["machine"]
    if not isinstance(m, dict):
        raise CaseError(f"[machine] in {path} must be a table")
    where = f"[machine] of {path}"
    if "type" not in m:
        raise CaseError(f"missing key 'type' in {where}")
    family = family_for(m["type"], where)
    _check_keys(m, MACHINE_KEYS | family.keys, "machine", path)
    if "length_mm" not in m:
        raise CaseError(f"missing key 'length_mm' in {where}")
    length = number(m, "length_mm", where) * 1e-3
    if not length > 0.0:
        raise CaseError(f"length_mm must be positive in {where}")
    points = (number(m, "points_per_period", where, integer=True)
              if "points_per_period" in m else POINTS_PER_PERIOD)
    lo, hi = POINTS_PER_PERIOD_RANGE
    if not lo <= points <= hi:
        raise CaseError(f"points_per_period must lie from {lo} to {hi} in {where}, "
                        f"got {points}")
    pair = family.from_section({k: v for k, v in m.items() if k in family.keys}, where)
    return pair, length, points


def _wrap_keys(pair: RotorPair) -> dict[str, float]:
    """The wrap keys a case may use, each with the factor that turns that rotor's wrap
    into the reference rotor's."""
    keys = {"wrap_outer_deg": 1.0}
    keys.update({WRAP_KEY.format(r.name): 1.0 / abs(r.speed_ratio) for r in pair.rotors})
    return keys


def _sweep_law(data: dict, path: Path, pair: RotorPair):
    """[sweep]: kind, reference-rotor wrap [rad] or wrap_bar (the other None), end scale
    and lead ratio (both 1 but for a conical sweep)."""
    diameter = pair.diameter
    s = data.get("sweep", {"kind": "straight"})
    wraps = _wrap_keys(pair)
    _check_keys(s, SWEEP_KEYS | set(wraps), "sweep", path)
    where = f"[sweep] of {path}"
    kind = s.get("kind", "straight")
    if kind not in ("straight", "helical", "conical"):
        raise CaseError(f"unknown sweep kind '{kind}' in {where} (straight, helical, conical)")
    wrap = wrap_bar = None
    given = [k for k in (*wraps, "wrap_bar") if k in s]
    if kind == "straight":
        if given:
            raise CaseError(f"a straight sweep takes no wrap in {where}")
        wrap = 0.0
    else:
        if len(given) != 1:
            raise CaseError(f"give exactly one of {', '.join(repr(k) for k in wraps)} or "
                            f"'wrap_bar' in {where}")
        key = given[0]
        if key != "wrap_bar":
            wrap = math.radians(number(s, key, where)) * wraps[key]
            if wrap < 0.0:
                raise CaseError(f"{key} must not be negative in {where}")
        else:
            wrap_bar = number(s, "wrap_bar", where)
            if wrap_bar < 0.0:
                raise CaseError(f"wrap_bar must not be negative in {where}")
    scale_end, lead_ratio = 1.0, 1.0
    if kind == "conical" and not pair.conical_sweep:
        raise CaseError(f"a {pair.family} pair cannot be swept conically in {where} "
                        f"(kind: straight or helical)")
    if kind == "conical":
        if "diameter_end_mm" not in s:
            raise CaseError(f"missing key 'diameter_end_mm' in {where} (conical sweep)")
        scale_end = number(s, "diameter_end_mm", where) * 1e-3 / diameter
        if not 0.0 < scale_end <= 1.0:
            raise CaseError(f"diameter_end_mm must lie in (0, diameter_mm] in {where}")
    elif "diameter_end_mm" in s:
        raise CaseError(f"diameter_end_mm belongs to a conical sweep in {where}")
    # The variable-lead law (lead linear along z, geometry.sweep) serves helical rotors
    # of any family too: the mating rotor's twist is its speed ratio times the
    # reference rotor's, so the pair meshes in every section whatever the law.
    if "lead_ratio" in s:
        if kind == "straight":
            raise CaseError(f"a straight sweep has no lead (lead_ratio) in {where}")
        lead_ratio = number(s, "lead_ratio", where)
        if not lead_ratio > 0.0:
            raise CaseError(f"lead_ratio must be positive in {where}")
    return kind, wrap, wrap_bar, scale_end, lead_ratio


def _operating(data: dict, path: Path, pair: RotorPair) -> tuple[float, str, str]:
    """The [operating] keys the geometry reads: volume ratio, driven rotor and the
    discharge ports."""
    op = data.get("operating", {})
    if not isinstance(op, dict):
        raise CaseError(f"[operating] in {path} must be a table")
    where = f"[operating] of {path}"
    volume_ratio = number(op, "volume_ratio", where) if "volume_ratio" in op else 2.0
    if not volume_ratio >= 1.0:
        raise CaseError(f"volume_ratio must be at least 1 in {where} (1: no internal "
                        f"compression), got {volume_ratio}")
    driven = op.get("driven", "auto")
    names = [r.name for r in pair.rotors]
    if driven not in (*names, "auto"):
        raise CaseError(f"driven must be one of {', '.join(repr(n) for n in names)} or "
                        f"'auto' in {where}, got {driven!r}")
    port = op.get("discharge_port", "axial")
    if not isinstance(port, str) or port not in DISCHARGE_PORTS:
        raise CaseError(f"discharge_port must be one of "
                        f"{', '.join(repr(k) for k in DISCHARGE_PORTS)} in {where}, got {port!r}")
    if port != "axial" and not pair.radial_ports:
        raise CaseError(f"discharge_port = {port!r} in {where}: a {pair.family} machine has no "
                        "radial discharge port; it discharges through its axial port only")
    return volume_ratio, driven, port


def validate_stage_sections(data: dict, path: Path, pair: RotorPair | None = None) -> None:
    """Hand the sections of later stages to their owners' validators (``pair``: the
    case's rotors, for the sections cut from them).

    [operating] keys other than the geometry's go to the quasi-1D settings; until a
    stage that owns a section exists, any key in it is reported as unknown.
    """
    op_extra = {k: v for k, v in data.get("operating", {}).items()}
    owned = {"operating": op_extra}
    for name in ("leakage", "ports", "numerics"):
        if name in data:
            owned[name] = data[name]
    try:
        from rotorflow.quasi1d import settings as q1d
    except ImportError:
        q1d = None
    for name, section in owned.items():
        if not isinstance(section, dict):
            raise CaseError(f"[{name}] in {path} must be a table")
        if name == "operating" and set(section) <= OPERATING_GEOMETRY_KEYS:
            continue  # a geometry-only case: the quasi-1D keys are not needed
        validator = getattr(q1d, name.capitalize(), None) if q1d else None
        if validator is not None and hasattr(validator, "from_section"):
            validator.from_section(section, str(path))
            continue
        allowed = OPERATING_GEOMETRY_KEYS if name == "operating" else set()
        _check_keys(section, allowed, name, path)
    if "mechanical" in data:  # owned by the quasi-1D stage (shaft power)
        from rotorflow.quasi1d.mechanical import Mechanical

        Mechanical.from_section(data["mechanical"], str(path))
    if "export" in data:  # owned by the solids stage
        from rotorflow.geometry.export.settings import Export

        Export.from_section(data["export"], str(path))
    if "cfd" in data:  # owned by the CFD leakage stage
        from rotorflow.cases.leakage_stage import validate_section

        validate_section(data, str(path), pair)
    if "cfd_chamber" in data:  # owned by the CFD chamber stage
        from rotorflow.cases.chamber_case import ChamberSettings

        if not isinstance(data["cfd_chamber"], dict):
            raise CaseError(f"[cfd_chamber] in {path} must be a table")
        ChamberSettings.from_section(data["cfd_chamber"], str(path))
    if "cfd_machine" in data:  # owned by the CFD machine stage
        from rotorflow.cases.machine_study import validate_section as validate_machine

        validate_machine(data, str(path), pair)
    if "optimise" in data:  # owned by `rotorflow optimise` (its section's own keys)
        from rotorflow.workflow.optimise_spec import check_section

        check_section(data["optimise"], path)
    if "map" in data:  # owned by `rotorflow map`
        from rotorflow.workflow.perf_map import map_spec

        map_spec(data, str(path))
    if "outputs" in data:  # the stages a case asks for (rotorflow run)
        from rotorflow.workflow.stages import plan, validate_outputs

        # Every stage asked for has its input: geometry, simulate and run accept the
        # same files.
        plan(data, validate_outputs(data["outputs"], path), path)
