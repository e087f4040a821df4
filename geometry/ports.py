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
Sections are sampled at
``STEP_PER_PERIOD`` angles per lobe period (``SPLIT_REFINE`` times more in the split
phases, where thin sub-regions move fast), the strip a chamber's tip sweeps between two
samples is added as the hull of both tips, and the pieces are joined exactly
(Clipper, through manifold3d's CrossSection); slivers and holes below
``HOLE_FRACTION`` of a port are sampling artefacts and dropped.

Caveat: in the split phases newborn and dying sub-regions interleave near the deep
mesh, so where the open and sealed footprints overlap there the sealed one wins: the
port there opens a little late (it never opens early).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from .machine import SweptMachine

#: The discharge ports a case may ask for ([operating] discharge_port): the axial port on
#: the high-pressure end plate, the radial port in the casing bores (the twin screw's,
#: :mod:`.twin_screw.radial_port`), or both, whose areas add.
DISCHARGE_PORTS = ("axial", "radial", "axial+radial")

#: Angles per lobe period at which the chamber section is added to a port, and how many
#: times more during the split phases near the deep mesh.  A port is a union of sampled
#: footprints, so its areas carry the sampling's strips: on the 4/6 twin screws, against
#: ports sampled 384 times, 1e-3 (suction) and 3-4e-2 (discharge) at 24, converging at
#: about first order (bench/bench_twin_screw.py).
STEP_PER_PERIOD = 24
SPLIT_REFINE = 8
#: Holes of a port smaller than this fraction of its area are sampling strips, filled.
HOLE_FRACTION = 0.01
#: Scale of the tip hulls' reach [m]: about the boundary spacing of the families' chamber
#: polygons (0.1 mm).
SECTION_SPACING = 1e-4
#: Ages (rad) this close are one sample: the grid's angles carry rounding of ~1e-15.
EPS_AGE = 1e-9


@dataclass(frozen=True)
class PortTiming:
    """Outer-rotor angles since the chamber's birth (radians)."""

    suction_close: float
    discharge_open: float
    death: float


def port_timing(machine: SweptMachine, volume_ratio: float,
                suction_close: float | None = None,
                discharge_open: float | None = None,
                early_opening: float = 0.0) -> PortTiming:
    cur = machine.curves
    age = cur.phi - cur.phi[0]
    v = cur.volume
    imax = int(np.argmax(v))
    alive = np.nonzero(v > 0.0)[0]
    death = float(age[alive[-1] + 1]) if alive[-1] + 1 < len(age) else float(age[-1])
    # The transport plateau: from the section's death (it leaves the suction plate) to
    # its birth reaching the discharge plate, ages on the table's nodes.
    plateau = (machine.life_2d, machine.sweep.wrap)
    transport = plateau[0] < plateau[1]
    if suction_close is not None:
        sc = float(suction_close)
    else:
        sc = plateau[0] if transport else float(age[imax])
    if discharge_open is None and volume_ratio == 1.0:
        do = (plateau[1] if transport else sc) - early_opening
    elif discharge_open is None:
        target = v[imax] / volume_ratio
        after = np.nonzero(v[imax:] <= target)[0]
        if not len(after):
            raise CaseError(f"the chamber never falls to V_max / {volume_ratio:g}: no discharge "
                            "port can be placed")
        k = imax + int(after[0])
        f = (v[k - 1] - target) / (v[k - 1] - v[k])
        do = float(age[k - 1] + f * (age[k] - age[k - 1])) - early_opening
    else:
        do = float(discharge_open)
    # Without internal compression and without a transport phase the suction closes and
    # the discharge opens at one angle, the volume maximum.
    if not (0.0 < sc < do < death or (0.0 < sc == do < death and volume_ratio == 1.0)):
        raise CaseError(f"port timing out of order: suction closes at {math.degrees(sc):.1f} deg,"
                        f" discharge opens at {math.degrees(do):.1f} deg, the chamber dies at "
                        f"{math.degrees(death):.1f} deg")
    return PortTiming(sc, do, death)


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
               cut_discharge: bool = True, steps: int = STEP_PER_PERIOD):
    """(suction, discharge): the area through which the chamber is open to each port at
    every age of ``ages`` (its face section inside the port), m2.

    The chamber's face section is what an end face would offer if the whole plate were
    open; the port is only part of it, so a chamber opening to the discharge port sees
    an area that grows from nothing (seed 004's point: the early-opened port is small at
    first and throttles the gas).  Without ``cut_discharge`` (no axial discharge port)
    the discharge areas are zero and that port is not cut.

    The areas are cut at the ports' own sample ages (:func:`_ages`; a port edge sweeps
    the chamber's footprint smoothly, and ``steps`` samples per lobe period resolve its
    opening),
    linear between.  A sample while the chamber is sealed from a port, and the one
    where the port closes or opens, is one of the footprints taken out of that port
    (:func:`ports`): its area there is zero by construction, and not cut; the port's
    own angle is a node, so the area is zero up to it, not a ramp across a step.
    """
    from manifold3d import CrossSection, FillRule

    suction, discharge = ports(machine, timing, cut_discharge, steps)
    sec = machine.section
    sw = machine.sweep
    step = machine.pair.period / steps
    life = float(ages[-1])
    out = []
    for port, shift, face, open_ in ((suction, 0.0, 0.0, (0.0, timing.suction_close)),
                                     (discharge, sw.wrap, sw.length,
                                      (timing.discharge_open, timing.death))):
        # The ports' regular samples (_ages) over [0, life].
        grid = shift + step * np.arange(math.floor(-shift / step),
                                        math.ceil((life - shift) / step) + 1)
        edge = open_[1] if face == 0.0 else open_[0]
        grid = np.unique(np.concatenate([grid[np.abs(grid - edge) > EPS_AGE], [edge]]))
        scale = float(sw.scale(face))
        vals = np.zeros(len(grid))
        inside = (grid > open_[0] + EPS_AGE) & (grid < open_[1] - EPS_AGE)
        if port is not None and inside.any():
            chambers = []
            for age in grid[inside]:
                polys = [q for q in _section(machine, sec.phi_i + age - shift) if len(q) >= 3]
                chambers.append(CrossSection([np.ascontiguousarray(q * scale) for q in polys],
                                             FillRule.Positive))
            vals[inside] = _areas_inside(port, chambers)
        out.append(np.interp(ages, grid, vals))
    return out[0], out[1]


#: Consecutive chamber sections whose port areas are cut from one crop of the port.
CROP_WINDOW = 8


def _areas_inside(port, chambers) -> np.ndarray:
    """Area of each CrossSection of ``chambers`` inside ``port``.

    A Boolean costs as many port vertices as chamber ones, and a port has ten times
    a section's; a few consecutive sections lie in a small part of it, so each run of
    CROP_WINDOW is cut from the port cropped to their bounding box (the same areas up
    to Clipper's rounding: 6e-10 of the largest on the 4/6 suction port, 40 % faster)."""
    from manifold3d import CrossSection

    out = np.zeros(len(chambers))
    for i in range(0, len(chambers), CROP_WINDOW):
        window = [c for c in chambers[i:i + CROP_WINDOW] if not c.is_empty()]
        if not window:
            continue
        box = np.array([c.bounds() for c in window]).reshape(-1, 2, 2)
        lo, hi = box[:, 0].min(0), box[:, 1].max(0)
        pad = 1e-3 * float(np.max(hi - lo))  # off the sections' own edges
        lo, hi = lo - pad, hi + pad
        crop = port ^ CrossSection([np.array([lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]])])
        for j, c in enumerate(chambers[i:i + CROP_WINDOW]):
            out[i + j] = 0.0 if c.is_empty() else (c ^ crop).area()
    return out
