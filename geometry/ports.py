"""End-plate ports of a swept machine (any family), as planar regions in the machine frame.

Port model: a port is what the working chamber's end-face section covers while the
chamber is open to it, less what the section covers while the chamber must be sealed
from it.  The suction port on the low-pressure plate (z = 0): the union of the
chamber's lp-face section from its birth until suction closes, less the union of that
section from suction closing until the section vanishes.  The discharge port on the
high-pressure plate (z = L): the union of the hp-face section (the planar chamber at
``phi - wrap``, scaled by ``scale(L)``) from the discharge opening until the chamber
dies, less its union before the opening.  So a chamber between suction closing and
discharge opening overlaps neither port (up to the sampling, tested), and the ports
close progressively as the chamber's trailing footprint leaves them.  The timing
follows the quasi-1D model's rules: suction closes at the volume maximum and discharge
opens where the volume has fallen to ``V_max / volume_ratio``, unless [operating]
gives ``suction_close_deg`` / ``discharge_open_deg`` (angles since birth).

A chamber with a transport phase (a wrap longer than its section's life, seed 003's
screw pumps: the chamber leaves the suction plate before it reaches the discharge plate
and keeps its volume in between) closes to suction where its last section leaves the
suction plate, the start of that plateau (its volume maximum is anywhere on it).  With
``volume_ratio = 1`` (no internal compression: a vacuum or multiphase pump, where
seed 003's transport phase carries the gas to the discharge at constant volume) the
discharge opens where the chamber's leading section reaches the discharge plate, the
end of the plateau, where the volume starts to fall (screw-pump practice: the discharge
edge lies on the end plate, the pressure rises by backflow when the chamber opens);
without a plateau that is the volume maximum, where suction closes.

The chamber's section is the family's (:meth:`RotorPair.chamber_polygons`); where it is
split into sub-regions (the internal gear's deep mesh), only those that belong to it.

The port shapes (:func:`ports`, for solids and CFD cases) are unions of sections sampled
``STEP_PER_PERIOD`` times per lobe period (``SPLIT_REFINE`` times more in the split
phases, where thin sub-regions move fast), with the strip a chamber's tip sweeps between
two samples added as the hull of both tips, joined by Clipper (manifold3d's
CrossSection); slivers and holes below ``HOLE_FRACTION`` of a port are dropped.  So they
carry the sampling's strips (on the 4/6 twin screws, a section inside them is off its
open area by 7e-4 of the largest suction area, 5e-2 of the discharge's).  Caveat: in the
split phases newborn and dying sub-regions interleave near the deep mesh, so where the
open and sealed footprints overlap there the sealed one wins: the shapes open a little
late there (never early).

The table's open areas (:func:`open_areas`) do not go through the shapes: they are
the face sections less the sealed regions, swept (:mod:`.port_areas`, with their measured
errors).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from . import scalar
from .machine import SweptMachine

#: The discharge ports a case may ask for ([operating] discharge_port): the axial port on
#: the high-pressure end plate, the radial port in the casing bores (the twin screw's,
#: :mod:`.twin_screw.radial_port`), or both, whose areas add.
DISCHARGE_PORTS = ("axial", "radial", "axial+radial")

#: Angles per lobe period at which the chamber section is added to a port shape, and how
#: many times more during the split phases near the deep mesh (the module docstring).
STEP_PER_PERIOD = 24
SPLIT_REFINE = 8
#: Holes of a port smaller than this fraction of its area are sampling strips, filled.
HOLE_FRACTION = 0.01
#: Scale of the tip hulls' reach [m]: about the boundary spacing of the families' chamber
#: polygons (0.1 mm).
SECTION_SPACING = 1e-4
#: Ages (rad) this close are one sample: the grid's angles carry rounding of ~1e-15.
EPS_AGE = 1e-9
#: Halvings of a section step that locate the planar section's birth and death
#: (:func:`planar_life`): 1/4096 of a step, 3.2e-5 rad at 24 points per period on a 1-1
#: pump, for 24 polygons-only section cuts (0.13-0.2 s) on every twin-screw machine (the
#: origin of the angles a case gives and reads; a pump's transport plateau).
LIFE_BISECTIONS = 12
#: How far the section table's zero nodes and a seal's nodes next to the fluid may
#: carry the nodes' life past the fluid's, in curve steps (two section steps each): up
#: to 3 section steps at one end measured (the 4/6 pin-cycloid at 384), so a plateau
#: is looked for wherever the nodes' life is within this of the wrap.
LIFE_OVERSHOOT = 4


@dataclass(frozen=True)
class PortTiming:
    """Ages of the chamber's curves (radians of the reference rotor from their first
    node, :attr:`.machine.SweptMachine.birth_age` before the birth)."""

    suction_close: float
    discharge_open: float
    death: float


def port_timing(machine: SweptMachine, volume_ratio: float,
                suction_close: float | None = None,
                discharge_open: float | None = None,
                early_opening: float = 0.0) -> PortTiming:
    """The port timing as ages of the curves; ``suction_close`` and ``discharge_open``,
    where given, are angles since the chamber's birth (the case's)."""
    cur = machine.curves
    age = cur.phi - cur.phi[0]
    v = cur.volume
    imax = int(np.argmax(v))
    alive = np.nonzero(v > 0.0)[0]
    death = float(age[alive[-1] + 1]) if alive[-1] + 1 < len(age) else float(age[-1])
    # The transport plateau: from the section's death (it leaves the suction plate) to
    # its birth reaching the discharge plate, as ages of the table (from its first node).
    transport = machine.life_2d < machine.sweep.wrap + LIFE_OVERSHOOT * cur.step
    if transport:
        birth, death_2d = machine.planar_life
        plateau = (death_2d - float(cur.phi[0]), birth + machine.sweep.wrap - float(cur.phi[0]))
        transport = plateau[0] < plateau[1]
    b = machine.birth_age
    if suction_close is not None:
        sc = float(suction_close) + b
    else:
        sc = plateau[0] if transport else _volume_peak(machine, imax) - float(cur.phi[0])
    if discharge_open is None and volume_ratio == 1.0:
        do = (plateau[1] if transport else sc) - early_opening
    elif discharge_open is None:
        do = _volume_fall(machine, imax, volume_ratio) - float(cur.phi[0]) - early_opening
    else:
        do = float(discharge_open) + b
    # Without internal compression and without a transport phase the suction closes and
    # the discharge opens at one angle, the volume maximum.
    if not (b < sc < do < death or (b < sc == do < death and volume_ratio == 1.0)):
        life = machine.planar_life[1] - machine.planar_life[0] + machine.sweep.wrap
        raise CaseError(f"port timing out of order: suction closes at "
                        f"{math.degrees(sc - b):.1f} deg, discharge opens at "
                        f"{math.degrees(do - b):.1f} deg, the chamber dies at "
                        f"{math.degrees(life):.1f} deg (since its birth)")
    return PortTiming(sc, do, death)


def planar_life(machine: SweptMachine) -> tuple[float, float]:
    """(birth, death): where the chamber's planar section first and last holds fluid,
    between the section table's nodes, each bisected LIFE_BISECTIONS times on whether
    a section cut there holds any of it.  The zero nodes either side (``phi_i``,
    ``phi_f``) bound the life only to a step, and a 1-1 pump's suction closed at
    ``phi_f``, where its transport plateau began: with ideal ports a step late is a step
    more open to suction (the involute pump's eta_v moved by 3.3e-3 from 24 to 192
    points per period, and by 9e-5 once bisected)."""
    sec = machine.section
    live = np.nonzero(sec.area > 0.0)[0]
    if machine.pair.life_on_nodes or not len(live):  # (nothing to bisect)
        return float(sec.phi_i), float(sec.phi_f)

    def edge(inside: float, outside: float) -> float:
        return 0.5 * sum(scalar.edge(
            lambda psi: any(len(q) >= 3 for q in chamber_section(machine, psi)),
            inside, outside, LIFE_BISECTIONS))

    first, last = int(live[0]), int(live[-1])
    birth = edge(sec.psi[first], sec.psi[first - 1]) if first > 0 else float(sec.psi[0])
    death = (edge(sec.psi[last], sec.psi[last + 1]) if last + 1 < len(sec.psi)
             else float(sec.psi[-1]))
    return birth, death


def _volume_peak(machine: SweptMachine, imax: int) -> float:
    """The angle of the largest volume between the table's nodes, on the cubic Hermite
    through the table's volume and its derivative (the quasi-1D model's volume,
    :mod:`rotorflow.quasi1d.chamber`): the node's angle errs by up to half a step, a
    shift of the suction port's closing edge."""
    from .scalar import hermite_peak

    cur = machine.curves
    return hermite_peak(cur.phi, cur.volume, cur.dvolume)[0]


def _volume_fall(machine: SweptMachine, imax: int, volume_ratio: float) -> float:
    """The angle after the volume maximum where the volume has fallen to V_max /
    volume_ratio, both on the cubic Hermite of :func:`_volume_peak`."""
    from .scalar import hermite_fall, hermite_peak

    cur = machine.curves
    v_max = hermite_peak(cur.phi, cur.volume, cur.dvolume)[1]
    try:
        return hermite_fall(cur.phi, cur.volume, cur.dvolume, v_max / volume_ratio, imax)
    except ValueError:
        raise CaseError(f"the chamber never falls to V_max / {volume_ratio:g}: no discharge "
                        "port can be placed") from None


def chamber_section(machine: SweptMachine, phi: float, contacts: list | None = None):
    """Polygons (fixed frame, unit scale) of the working chamber's section at angle phi
    (the planar-chamber angle); empty outside the chamber's life.  The contact points
    bounding them are appended to ``contacts`` if given."""
    return machine.pair.chamber_polygons(phi, contacts)


def _section(machine: SweptMachine, psi: float, contacts: list | None = None):
    """:func:`chamber_section`, empty without asking the family outside the section
    table's span (a family that cuts its sections would cut one for nothing)."""
    psi_table = machine.section.psi
    if not psi_table[0] <= psi <= psi_table[-1]:
        return []
    return chamber_section(machine, psi, contacts)


def port_region(machine: SweptMachine, start: float, stop: float, face: str,
                hulls: bool = False, steps: int = STEP_PER_PERIOD):
    """The union of the chamber's ``face`` ("lp"/"hp") sections for ages in [start, stop]
    (with ``hulls``, also what the chamber's tips sweep between the samples).

    Returns a manifold3d CrossSection in the machine frame (metres, scaled for hp).
    """
    from manifold3d import CrossSection, FillRule

    sw = machine.sweep
    sec = machine.section
    shift = 0.0 if face == "lp" else sw.wrap
    scale = float(sw.scale(0.0 if face == "lp" else sw.length))
    ages = _ages(machine, start, stop, shift, steps)
    pieces = []
    prev = None
    for age in ages:
        psi = sec.phi_i + age - shift
        contacts = []
        polys = [q for q in _section(machine, psi, contacts) if len(q) >= 3]
        pieces.extend(CrossSection([np.ascontiguousarray(q * scale)], FillRule.Positive)
                      for q in polys)
        if hulls and prev is not None and polys:
            pieces.extend(_tip_hulls(prev, (polys, contacts), scale))
        prev = (polys, contacts) if polys else None
    if not pieces:
        return CrossSection()
    return _fill_small_holes(union(pieces))


#: Pieces joined per Clipper call in :func:`union`.
UNION_BATCH = 8


def union(pieces):
    """The union of CrossSections, joined a few at a time in a tree: consecutive
    sections overlap almost wholly, and Clipper's sweep over all of them at once keeps
    every one's edges active together (measured 0.32 s for the 4/6 suction port's 288
    pieces, 0.05 s in batches of 8; the same region up to Clipper's rounding, 1e-7)."""
    from manifold3d import CrossSection, OpType

    while len(pieces) > 1:
        pieces = [CrossSection.batch_boolean(pieces[i:i + UNION_BATCH], OpType.Add)
                  for i in range(0, len(pieces), UNION_BATCH)]
    return pieces[0]


def _ages(machine: SweptMachine, start: float, stop: float, shift: float,
          steps: int = STEP_PER_PERIOD) -> np.ndarray:
    """Sample ages: ``start``, ``stop`` and ``steps`` per lobe period between,
    SPLIT_REFINE times more while the section is split near the deep mesh (thin
    sub-regions that move fast).

    The regular samples lie where the face's section angle is on the grid of the
    machine's section table (``shift`` + whole steps from birth): a family that cuts
    its sections (the twin screw) has those cut already, and only the ends, the port
    timing's own angles, cost a cut of their own."""
    sec = machine.section
    step = machine.pair.period / steps
    split = machine.pair.split_phase
    life = sec.phi_f - sec.phi_i
    regular = shift + step * np.arange(math.ceil((start - shift) / step),
                                       math.floor((stop - shift) / step) + 1)
    # (a regular sample within rounding of an end is that end)
    ages = [[start, stop], regular[(regular > start + EPS_AGE) & (regular < stop - EPS_AGE)]]
    for a0 in (shift, shift + life - split):  # the split phases, in ages
        lo, hi = max(a0, start), min(a0 + split, stop)
        if hi > lo:
            ages.append(np.linspace(lo, hi, int(math.ceil((hi - lo) / step * SPLIT_REFINE)) + 1))
    return np.unique(np.clip(np.concatenate(ages), start, stop))


def _fill_small_holes(region):
    """Drop holes and islands smaller than HOLE_FRACTION of the region: the strips that
    sampled positions of a moving sub-region leave uncovered, and slivers cut off at a
    contact.  (A real hole, such as the inner rotor's root disc when the window is a
    whole turn, is far larger.)"""
    from manifold3d import CrossSection, FillRule

    polys = region.to_polygons()
    area = region.area()
    keep = []
    for q in polys:
        a = 0.5 * float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - q[:, 1] * np.roll(q[:, 0], -1)))
        if abs(a) > HOLE_FRACTION * area:
            keep.append(np.ascontiguousarray(q))
    return CrossSection(keep, FillRule.Positive)


def _tip_hulls(prev, cur, scale):
    """Hulls of the chamber's tips at two consecutive angles.

    Near a contact point the chamber is a thin wedge whose tip runs along the path of
    contact; two sampled positions leave the strip between them uncovered.  The convex
    hull of both tips (the polygon vertices within a few steps of each contact) is what
    the wedge sweeps in between, up to the path's curvature.
    """
    from manifold3d import CrossSection

    (pp, pc), (cp, cc) = prev, cur
    if not pc or not cc:
        return []
    pv, cv = np.concatenate(pp), np.concatenate(cp)
    pc, cc = np.asarray(pc), np.asarray(cc)
    out = []
    for t in cc:
        d = np.linalg.norm(pc - t, axis=-1)
        j = int(np.argmin(d))
        reach = max(3.0 * d[j], 5.0 * SECTION_SPACING)
        if d[j] > 0.25 * np.linalg.norm(t) or d[j] == 0.0:
            continue  # no counterpart: a contact born or gone between the samples
        pts = np.concatenate([pv[np.linalg.norm(pv - pc[j], axis=-1) < reach],
                              cv[np.linalg.norm(cv - t, axis=-1) < reach]])
        if len(pts) >= 3:
            out.append(CrossSection.hull_points(np.ascontiguousarray(pts * scale)))
    return out


def ports(machine: SweptMachine, timing: PortTiming, cut_discharge: bool = True,
          steps: int = STEP_PER_PERIOD):
    """(suction on the lp plate, discharge on the hp plate) as CrossSections.

    Each is what the chamber's face section covers while it is open to the port, less
    what it covers while it must be sealed from it: otherwise a chamber just past
    suction closing would still sit over its own earlier footprints.  Without
    ``cut_discharge`` (a machine that discharges through its casing only) the discharge
    is None.
    """
    sec = machine.section
    life = sec.phi_f - sec.phi_i
    wrap = machine.sweep.wrap
    suction = port_region(machine, 0.0, timing.suction_close, "lp", True, steps)
    sealed = port_region(machine, timing.suction_close, min(life, timing.death), "lp",
                         True, steps)
    if not cut_discharge:
        return _fill_small_holes(suction - sealed), None
    discharge = port_region(machine, timing.discharge_open, timing.death, "hp", True, steps)
    sealed_hp = port_region(machine, min(wrap, timing.discharge_open), timing.discharge_open,
                            "hp", True, steps)
    return (_fill_small_holes(suction - sealed), _fill_small_holes(discharge - sealed_hp))


def open_areas(machine: SweptMachine, timing: PortTiming, ages: np.ndarray,
               cut_discharge: bool = True, steps: int | None = None):
    """(suction, discharge) areas open to the ports at ``ages``: :func:`.port_areas
    .open_areas`."""
    from .port_areas import open_areas as areas

    return areas(machine, timing, ages, cut_discharge, steps)
