"""The seam between machine families and everything else.

A family (internal gear, twin screw, ...) turns its case-file ``[machine]`` section into
a :class:`RotorPair`; the sweep machinery, the chamber table, ports, solids, the
quasi-1D model and the CFD cases read only that object.  What a pair offers:

* ``rotors``: each rotor's closed planar profile (a :class:`~.curves.PieceCurve` in the
  rotor's own frame), its axis in the fixed frame, lobe count and signed speed ratio.
  Rotor 0 is the reference: every angle of the tables is its angle.
* ``period``: the reference rotor's lobe period; chambers one period apart are the same
  chamber at different ages.
* ``section(points_per_period)``: the section tables of one chamber over its life
  (:class:`~.section.SectionChamber`: area, contacts labelled with their neighbouring
  chamber and their kind, forces and torques on each rotor per unit pressure).
* ``chamber_polygons(phi)``: that chamber's transverse section as polygons (ports).
* ``working_area``: the area enclosed by the working space's outer boundary (the chamber
  areas plus the material areas of the rotors inside it).
* ``casing_bores(bore_factor)``: the casing's bores for the solids.
* ``gap_walls(angle, gap)`` and ``wall_speeds(angle, omega)``: the clearance-gap section
  at a contact, for the CFD gap cases.
* ``figures()``, ``contact_table(step_deg)``, ``digest()``: the family's own figures, its
  contact points against angle, a short identity for run folders.
* ``leakage_paths(far_lines, track_lines, opening_areas)``: the named leakage paths its
  chamber table declares (kind, neighbour or plenum, column, own clearance), which the
  quasi-1D model builds its flow network from.
* Optional, with defaults: ``swept_figures(machine)`` and ``face_columns(machine)`` (the
  family's own figures and end-face columns of the swept pair), ``radial_ports`` and
  ``radial_port(machine, timing)`` (a discharge port cut in the casing), ``oil_films(paths)``
  (the rotor surfaces that shear oil against the casing, :mod:`.films`).

A registry maps ``[machine] type`` to a :class:`Family`; :func:`family_for` fails with
one line that lists the known types.
"""

from __future__ import annotations

import importlib
import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError


@dataclass(frozen=True)
class Rotor:
    """One rotor of a pair, in the transverse plane at z = 0 (scale 1)."""

    name: str  # "outer", "inner", "male", "female", ...
    profile: object  # PieceCurve in the rotor's own frame (origin on its axis)
    axis: tuple[float, float]  # the axis in the fixed frame
    lobes: int
    speed_ratio: float  # angular speed over the reference rotor's, signed (+: same sense)
    pitch_radius: float

    @property
    def material_inside(self) -> bool:
        return bool(self.profile.material_inside)


class RotorPair(ABC):
    """What every family's pair offers (see the module docstring)."""

    #: The case file's [machine] type of the family.
    family: str = ""
    #: The size the family's dimensionless figures are normalised by [m] (an attribute
    #: or field of every pair).
    diameter: float
    #: Whether the casing can have a radial discharge port ([operating] discharge_port,
    #: :meth:`radial_port`).
    radial_ports = False
    #: Whether the section table's ``phi_i`` and ``phi_f`` are the chamber's planar birth
    #: and death exactly (else they are its zero nodes either side, and the life is
    #: located between them: :func:`.ports.planar_life`).
    life_on_nodes = True
    #: Whether the pair can be swept conically (the internal gear's CRC.60 rotors).
    conical_sweep = True

    @property
    @abstractmethod
    def rotors(self) -> tuple[Rotor, ...]: ...

    @property
    def period(self) -> float:
        return 2.0 * math.pi / self.rotors[0].lobes

    @property
    def film_deficit(self) -> float:
        """How much thinner (per centre distance) a film between the two rotors is in
        :meth:`chamber_polygons` than between the true surfaces: 0 where the sections'
        polygons lie on the surfaces within their chord error."""
        return 0.0

    @property
    def split_phase(self) -> float:
        """Reference-rotor angle after birth (and before death) over which the chamber's
        section is split into sub-regions that move fast; 0 when it never is."""
        return 0.0

    @abstractmethod
    def section(self, points_per_period: int): ...

    @abstractmethod
    def chamber_polygons(self, phi: float, contacts: list | None = None) -> list[np.ndarray]: ...

    @property
    @abstractmethod
    def working_area(self) -> float: ...

    @abstractmethod
    def casing_bores(self, bore_radius: float | None = None
                     ) -> tuple[tuple[tuple[float, float], float], ...]: ...

    @abstractmethod
    def gap_walls(self, angle: float, gap: float, **options): ...

    @abstractmethod
    def wall_speeds(self, angle: float, omega_reference: float) -> tuple[float, float]: ...

    @abstractmethod
    def figures(self) -> dict: ...

    @abstractmethod
    def contact_table(self, step_deg: float = 1.0, span_deg: float | None = None): ...

    @abstractmethod
    def digest(self) -> str: ...

    @abstractmethod
    def leakage_paths(self, far_lines: dict[int, np.ndarray],
                      track_lines: dict | None = None,
                      opening_areas: dict | None = None) -> tuple:
        """The chamber table's leakage paths (:class:`~.table.LeakagePath`), given the
        sealing lines to chambers two or more periods away that the sweep found, the
        lines of the section's further tracks and the areas of its openings, both keyed
        (name, offset)."""

    def swept_figures(self, machine) -> dict:
        """The family's own figures of the swept pair (none by default)."""
        return {}

    def radial_port(self, machine, timing):
        """The radial discharge port of the swept pair for a port timing: an object with
        ``open_area(ages)`` (m2 against the chamber's age) and ``figures()``."""
        raise CaseError(f"a {self.family} machine has no radial discharge port")

    def face_columns(self, machine) -> dict[str, np.ndarray]:
        """Table columns of the family's own end-face paths (none by default: the
        end faces leak to the plena along the chamber's rotor edges)."""
        return {}

    def oil_films(self, paths) -> tuple:
        """The surfaces that shear an oil film against the casing (:mod:`.films`), given
        the table's leakage paths (whose clearances they have); none by default."""
        return ()

    def rotor(self, name: str) -> Rotor:
        for r in self.rotors:
            if r.name == name:
                return r
        raise CaseError(f"no rotor '{name}' in a {self.family} pair "
                        f"({', '.join(r.name for r in self.rotors)})")


@dataclass(frozen=True)
class Family:
    """A registered machine family: its [machine] keys and how it reads them."""

    type: str
    keys: frozenset[str]
    #: (section, where) -> RotorPair; ``where`` names the section and file for errors.
    from_section: Callable[[dict, str], RotorPair]
    #: Pairs the family contract tests run on (straight/helical/conical are sweeps of them).
    examples: Callable[[], dict[str, RotorPair]]


_REGISTRY: dict[str, Family] = {}


def register(family: Family) -> Family:
    _REGISTRY[family.type] = family
    return family


#: The built-in families by type, each imported (and so registered) only when a case
#: asks for it: the twin-screw package alone pulls in scipy.spatial/optimize, 0.3 s that
#: an internal-gear case should not pay.
BUILTIN = {"internal-gear": "internal_gear", "twin-screw": "twin_screw"}


def families() -> dict[str, Family]:
    for type_ in BUILTIN:
        _load_builtin(type_)
    return dict(_REGISTRY)


def family_for(type_: object, where: str) -> Family:
    if isinstance(type_, str):
        _load_builtin(type_)
    if not isinstance(type_, str) or type_ not in _REGISTRY:
        known = sorted(set(_REGISTRY) | set(BUILTIN))
        raise CaseError(f"unknown machine type {type_!r} in {where} "
                        f"(known: {', '.join(known)})")
    return _REGISTRY[type_]


def _load_builtin(type_: str) -> None:
    # A built-in family registers itself on import.
    if type_ in BUILTIN and type_ not in _REGISTRY:
        importlib.import_module(f"{__package__}.{BUILTIN[type_]}")


def number(section: dict, key: str, where: str, *, integer: bool = False):
    """A finite number (an integer with ``integer``) from a case-file section, or a
    CaseError naming the key and ``where``."""
    value = section[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CaseError(f"'{key}' in {where} must be a number, got {value!r}")
    if integer and not float(value).is_integer():
        raise CaseError(f"'{key}' in {where} must be an integer, got {value!r}")
    if not math.isfinite(value):
        raise CaseError(f"'{key}' in {where} must be finite, got {value!r}")
    return int(value) if integer else float(value)
