"""Section tables: one working chamber in a transverse section, over its life.

Every family tabulates its chamber on a uniform grid of the reference rotor's angle
``psi`` (aligned with the lobe period, so chambers one period apart share nodes and their
loads cancel exactly at uniform pressure), from birth ``phi_i`` to death ``phi_f``, one
node past the death, where the chamber is gone.  Per unit length and unit pressure:

* ``area``: A(psi);
* ``force[:, r]``: the force *of the fluid* on rotor r, fixed frame;
* ``torque[:, r]``: the torque of the fluid on rotor r about its own axis;
* ``perimeter[:, r]``: rotor r's edge length bounding the chamber (end-face lines);
* ``trail``, ``lead``: the trailing (toward the younger chamber) and leading contact;
* ``lead_offset``, ``trail_offset``: which chamber lies beyond each, in lobe periods of
  age (+1: the next, older one), ``lead_kind``, ``trail_kind``: the kind of sealing line
  it traces (interlobe, ...), ``lead_id``, ``trail_id``: which contact it is, so that
  contact rates never difference across a change of identity.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Track:
    """A sealing point of the section chamber other than its leading and trailing
    interlobe contacts (a family's tips, its second contacts, ...), on the same grid.

    ``name`` names the line (table columns and leakage paths use it), ``kind`` is its
    leakage kind; ``present`` says where the chamber has that point at all (a tip that
    has left its bore seals nothing); ``offset`` and ``ids`` as for the lead and trail.
    """

    name: str
    kind: str
    points: np.ndarray  # (n, 2)
    present: np.ndarray  # (n,) bool
    offset: np.ndarray  # (n,) int
    ids: np.ndarray  # (n,) int
    #: d point / d psi where the family knows it exactly (None: differences of points)
    rates: np.ndarray | None = None
    #: (n,) per node i, the angle between node i and i + 1 at which whatever changes
    #: there (the point appears or leaves, its chamber beyond or its identity changes)
    #: changes, where the family knows it; NaN (or None): halfway, each node's point
    #: standing for its half step.
    cuts: np.ndarray | None = None
    #: Where a point present at node 0 begins, before it (NaN: half a step before).
    start: float = float("nan")
    #: (psi, length, offset) of lines across the section: where the point jumps along
    #: a band of contact (the rotors touch along an arc at that instant), the line the
    #: swept point misses.
    bridges: tuple = ()

@dataclass(frozen=True)
class Opening:
    """An opening of the section chamber to the chamber ``offset`` periods away across a
    cut of the section (a segment, not a point), present over the angle ``intervals``
    (k, 2) with the width ``width(psi)`` there.  Swept along the rotors it is an
    orifice area, the width integrated over the length (the twin screw's blow-hole in
    the cusp plane).  The width is a function, not node values: the family knows it at
    any angle, and interpolating across the jumps of an opening cut short by a passing
    lobe would cost an order of convergence.  It is piecewise linear, and
    ``width.breakpoints(a, b)`` gives its pieces' ends in [a, b]."""

    name: str
    offset: int
    intervals: np.ndarray
    width: Callable[[np.ndarray], np.ndarray]

    def breakpoints(self, a: float, b: float) -> np.ndarray:
        """Angles in [a, b] between which the width is linear: the width's own
        (``width.breakpoints``) and the intervals' ends."""
        ends = self.intervals.ravel()
        pts = np.concatenate([[a, b], ends[(ends > a) & (ends < b)],
                              self.width.breakpoints(a, b)])
        return np.unique(pts)

    def at(self, psi) -> np.ndarray:
        psi = np.asarray(psi, dtype=float)
        inside = np.zeros(psi.shape, bool)
        for a, b in self.intervals:
            inside |= (psi >= a) & (psi < b)
        out = np.zeros(psi.shape)
        out[inside] = self.width(psi[inside])
        return out


#: Default angle samples per lobe period of the section tables.
POINTS_PER_PERIOD = 96


@dataclass(frozen=True)
class SectionChamber:
    """Section tables of one chamber on a uniform grid of reference angle ``psi``."""

    psi: np.ndarray
    area: np.ndarray
    force: np.ndarray  # (n, rotors, 2)
    torque: np.ndarray  # (n, rotors)
    perimeter: np.ndarray  # (n, rotors)
    trail: np.ndarray  # (n, 2)
    lead: np.ndarray  # (n, 2)
    phi_i: float
    phi_f: float
    speed_ratio: tuple[float, ...]  # of each rotor over the reference rotor
    lead_offset: np.ndarray
    trail_offset: np.ndarray
    lead_id: np.ndarray
    trail_id: np.ndarray
    lead_kind: np.ndarray
    trail_kind: np.ndarray
    #: Further sealing points (:class:`Track`); the lead and trail contacts are always
    #: followed, these where ``present``.
    tracks: tuple = ()
    #: Openings across cuts of the section (:class:`Opening`).
    openings: tuple = ()
    #: Where the loads jump (:class:`.load_sweep.LoadEvents`): given, the loads are swept
    #: at fourth order between them; None, as their linear interpolant.
    load_events: object = None

    def contact_rate(self, which: str | Track) -> np.ndarray:
        """d(contact point)/d(psi) of the leading or trailing contact, on the grid.

        Where the contact changes identity (a contact hands over to another, or a
        sub-region closes) the point jumps across the chamber; that jump is no sealing
        line, so differences never cross it.
        """
        if isinstance(which, Track):
            if which.rates is not None:
                return which.rates
            pts, ids = which.points, which.ids
        else:
            pts = self.lead if which == "lead" else self.trail
            ids = self.lead_id if which == "lead" else self.trail_id
        h = self.psi[1] - self.psi[0]
        d = np.diff(pts, axis=0) / h
        same = (ids[1:] == ids[:-1])[:, None]
        fwd = np.vstack([d * same, np.zeros((1, 2))])
        back = np.vstack([np.zeros((1, 2)), d * same])
        nf = np.append(same[:, 0], False).astype(float)[:, None]
        nb = np.insert(same[:, 0], 0, False).astype(float)[:, None]
        return (fwd + back) / np.maximum(nf + nb, 1.0)

    @property
    def area_max(self) -> float:
        return float(self.area.max())
