"""Where a twin-screw chamber's section loads jump, for sweeping them at high order.

A section's loads are the pressure on the wetted arcs between the chamber's sealing
points (:mod:`.boundaries`), so they change other than smoothly where the sealing
changes hands (:mod:`..load_sweep` integrates them piecewise between these events):

* a band, where the contact jumps along an arc (:func:`.track_ends.contact_breaks`);
* a lobe's last point on its bore reaching a cusp: the tip point, or a land's corners
  (the pin-cycloid female's tip is an arc on its bore 0.44 rad wide), in closed form as
  the rotor turns at a constant rate; and the end of a tip's band (:mod:`.tip_bands`)
  crossing the cusp line, where a cut there stops ending at the tip;
* an interlobe contact crossing the cusp line, which splits the section into male and
  female groove parts (the root of x(psi) - x_c along the contact).

The section cuts polygons of the rotors grown into each other (:mod:`.regions`), so it
resolves a sliver beyond a sealing point, or a pocket between two contacts, only once it
is thicker than their overlap (2 GROW C, 0.3 um at C = 80 mm): near an event its walls go
to a neighbour for a while, and the loads jump, or rise steeply, up to ~0.01 rad off the
event.  Nodes within a shadow of the event are therefore not trusted: each side of it is
the continuation of its own trusted nodes (as the tracks' ends are the exact ones, not
where a node saw them: :mod:`.track_ends`).  A tip's shadow lies on the mesh side only
(where its pockets are: before the tip reaches the top cusp, after the bottom one); on
the other side the loads are resolved and carry power (the chambers' areas follow the
same walls, and the shaft power must stay their rate of change, seed 000 Eq. 18).
Where two events leave fewer than MIN_DATA trusted nodes between them, the section is
cut there too.
"""

from __future__ import annotations

import math

import numpy as np

from ..load_sweep import LoadEvents
from .lands import find_land
from .regions import FEMALE, GROW, MALE
from .tip_bands import TIP_BAND
from .track_ends import _cusp_line_cut

#: Angle (rad) about an event over which the section's nodes are not trusted.  The
#: sliver a sealing point leaves as it moves (between the two rotors, tangent there, or
#: a rotor and the cusp line) reaches the grown rotors' overlap after ~0.2 mm of travel,
#: ~0.005 rad: measured on seed 004's 4/6 pairs, the circular pair's walls beyond a
#: contact crossing the cusp line come to their chamber 0.004 to 0.0075 rad after it.
LENS_SHADOW = 0.01
#: The same on the mesh side of a tip reaching a cusp.  Between the pin-cycloid's male
#: tip and its mate lies a pocket bounded by two contacts; the cusp line cuts it in two,
#: and each half goes to the dying or the newborn chamber by its own area's rate (a
#: pocket changes hands at its smallest: :mod:`.ages`): from 0.0142 to 0.0099 rad before
#: the tip reaches the top cusp the female half's walls go to the newborn chamber alone;
#: 0.0081 rad before it the pocket is thinner than the overlap and closes.  Without the
#: shadows the jumps lie between nodes, unlocated: Pi_max erred by 2.4e-4 at 24 points
#: per period on either of seed 004's pairs (against 9e-4 as the linear interpolant).
#: It also hid a cutter fault (the female's land across the lens taken for the bore,
#: 0.0052 rad before the passage: :meth:`.boundaries.Boundaries._labels`).  With that
#: fixed the pin-cycloid's chamber loads are smooth through the shadow (steps of 1.7e-5
#: per unit pressure every 2.5e-4 rad) but for the pocket's closing 0.0083 rad before
#: the passage (4e-4 moves between the chamber and its male groove's previous life),
#: which is still the resolution's: so the shadow stays.
TIP_SHADOW = 0.015
#: The same about a tip band's end crossing the cusp line (:func:`_bore_ends`).  The
#: closed form puts the grown rotor's band end on the line; the cut's polygon lies
#: inside the grown curve by up to its chord error (1e-6 C), which moves the crossing by
#: ~2e-6 rad (the pin-cycloid male: the jump found 1.0e-6 rad before the closed form);
#: 1e-5 keeps any node out of that window.
BAND_SHADOW = 1e-5
#: The pieces' data lie at least this far apart (:class:`..load_sweep.LoadEvents`): a
#: node spacing on the finest grids that matter at all (192 points per period, twice
#: for the sections), so that these and finer grids carry a piece across a shadow from
#: spans alike (768 and 1536 points per period gave Pi_max 5e-5 apart with the nearest
#: nodes, the cubic from 0.002 rad carried 0.015 rad).
SPREAD = TIP_SHADOW / 4.0
#: Events nearer than this (rad) are one (the pin-cycloid's male tip and the female land's
#: corner reach the top cusp 3e-4 rad apart: they are the same meeting of the rotors).
SAME_EVENT = 2e-3
#: A piece between two events needs this many data points (nodes it trusts and cuts)
#: for its polynomial to carry its slope; the missing ones are cut.
MIN_DATA = 2
#: A contact found at a crossing of the cusp line is the one followed if it lies within
#: this fraction of a step's travel of the followed contact moved on by its rate (else
#: the law of gearing found another contact, and there is no crossing).
SAME_CONTACT = 0.25


def load_events(pair, psi: np.ndarray, tracks, loads_at) -> LoadEvents:
    """The :class:`..load_sweep.LoadEvents` of a chamber tabulated at ``psi`` with sealing
    tracks ``tracks``; ``loads_at(phase)`` cuts the section at that phase for the
    samples (:func:`_samples`)."""
    period = pair.period
    h = psi[1] - psi[0]
    phases = _phases(pair, psi, tracks)
    at, before, after = [], [], []
    k0 = math.floor((psi[0] - period - phases[0][0]) / period) if phases else 0
    k1 = math.ceil((psi[-1] + period - phases[0][0]) / period) if phases else 0
    for k in range(k0, k1 + 1):
        for phase, lo, hi in phases:
            x = phase + k * period
            if psi[0] - period <= x <= psi[-1] + period:
                at.append(x)
                before.append(lo)
                after.append(hi)
    order = np.argsort(at)
    at, before, after = (np.asarray(v, dtype=float)[order] for v in (at, before, after))
    sample_phases = _sample_phases(phases, psi[0], h, period)
    sample_psi, force, torque = _samples(pair, psi, sample_phases, loads_at)
    return LoadEvents(at, before, after, sample_psi, force, torque, spread=SPREAD)


def _phases(pair, psi, tracks) -> list[tuple[float, float, float]]:
    """(phase in [0, period), shadow before, shadow after) of every event, merged."""
    period = pair.period
    found = []
    for phase, length, _, shadow in pair.contact_breaks:
        if length > 0.0:  # a band (a joint only turns the contact's rate: a kink)
            found.append((phase % period, shadow, shadow))
    for phase, before, after in _bore_ends(pair):
        found.append((phase % period, before, after))
    # A crossing's shadow spans both sides: its walls beyond the cusp line carry power
    # (their chamber's area grows by the sliver) but are not resolved for the lens's
    # length either way; taking them to arrive at the crossing leaves the circular
    # pair's power balance (against the volumes, which keep the sections' areas) at
    # 9e-5, against 2e-5 with the lens (make the family contract test: 1e-4).
    for phase in _crossings(pair, psi, tracks):
        found.append((phase % period, LENS_SHADOW, LENS_SHADOW))
    found.sort()
    merged: list[list[float]] = []
    for phase, lo, hi in found:
        if merged and (phase - merged[-1][0]) < SAME_EVENT:
            merged[-1][1] = max(merged[-1][1], lo)
            merged[-1][2] = max(merged[-1][2], hi)
        else:
            merged.append([phase, lo, hi])
    if len(merged) > 1 and merged[0][0] + period - merged[-1][0] < SAME_EVENT:
        last = merged.pop()
        merged[0][1] = max(merged[0][1], last[1])
        merged[0][2] = max(merged[0][2], last[2])
    return [tuple(m) for m in merged]


def _bore_ends(pair) -> list[tuple[float, float, float]]:
    """(male angle, shadow before, shadow after) at which a lobe's last point on its bore
    reaches a cusp: its tip point, or either corner of a land (whichever trails seals
    until it passes); and at which the end of a tip's band crosses the cusp line."""
    g = pair.gearing
    xc, yc = pair.cusp
    out = []
    for rotor, profile in ((MALE, pair.male), (FEMALE, pair.female)):
        axis = np.zeros(2) if rotor == MALE else g.female_axis
        speed = 1.0 if rotor == MALE else -g.lobes_male / g.lobes_female
        land = find_land(profile, g.centre_distance)
        if land is None:
            points = pair.tip_points(profile)[:1]
        else:
            points = profile.point(np.array(land[2]))
        for p in points:
            alpha = math.atan2(p[1], p[0])  # own frame, about the rotor's axis
            for y in (yc, -yc):
                gamma = math.atan2(y - axis[1], xc - axis[0])
                # the mesh side: a tip comes out of the mesh at the top cusp, goes in
                # at the bottom
                shadow = (TIP_SHADOW, 0.0) if y > 0.0 else (0.0, TIP_SHADOW)
                out.append(((gamma - alpha) / speed, *shadow))
        if land is None:  # (a land's band ends are its corners, found above)
            out.extend(_band_ends(pair, rotor, axis, speed))
    return out


def _band_ends(pair, rotor, axis, speed) -> list[tuple[float, float, float]]:
    """A cut at the cusp line that ends on a tip's band ends at the tip (:meth:`.tip_bands
    .TipBands._in_tip_band`); once the band's end has crossed the line, at the cut
    point.  The rotor's arc between the two changes parts there: 1.6e-4 (per unit
    pressure and length) of the pin-cycloid male's, 0.0038 rad after its tip leaves
    the top cusp.  The band's end is where the profile comes within TIP_BAND of its bore
    (radius R - TIP_BAND C), the cut sees it grown by GROW C: at radius r about the
    axis O it is on the line x = x_c at polar angle +-acos((x_c - O_x) / r).  Ends within
    SAME_EVENT of the tip are the tip's own event."""
    cutter = pair.cutter
    c = pair.gearing.centre_distance
    tip = pair.tip_points(pair.male if rotor == MALE else pair.female)[0]
    radius = cutter.R[rotor] - (TIP_BAND - GROW) * c
    gamma = math.acos((pair.cusp[0] - axis[0]) / radius)
    out = []
    for off in cutter.tip_band(rotor):
        if abs(off) < SAME_EVENT:
            continue
        alpha = math.atan2(tip[1], tip[0]) + off
        for side in (1.0, -1.0):
            out.append(((side * gamma - alpha) / speed, BAND_SHADOW, BAND_SHADOW))
    return out


def _crossings(pair, psi, tracks) -> list[float]:
    """Angles at which an interlobe contact followed by ``tracks`` crosses the cusp line
    (found in the cells where the contact leaves the chamber or changes the chamber
    beyond it, once per phase: every period repeats them; kept where the contact at the
    root is the one followed)."""
    xc = pair.cusp[0]
    h = psi[1] - psi[0]
    per_period = int(round(pair.period / h))
    seen, out = set(), []
    for t in tracks:
        if t.kind != "interlobe":
            continue
        p = t.present
        change = (p[:-1] != p[1:]) | (p[:-1] & p[1:] & (t.offset[:-1] != t.offset[1:]))
        for i in np.nonzero(change)[0]:
            j, k = (i, i + 1) if p[i] else (i + 1, i)
            key = (int(i) % per_period, j > k)
            if key in seen:
                continue
            seen.add(key)
            root = _cusp_line_cut(pair, t.points[j], t.rates[j], psi[j], psi[k])
            if not np.isfinite(root):
                continue
            guess = t.points[j] + (root - psi[j]) * t.rates[j]
            c, _ = pair.contact_near(guess, root)
            travel = np.linalg.norm(t.rates[j]) * h
            if abs(c[0] - xc) < 1e-9 * pair.gearing.centre_distance and \
                    np.linalg.norm(c - guess) <= SAME_CONTACT * max(travel, 1e-300):
                out.append(float(root))
    return out


def _sample_phases(phases, psi0: float, h: float, period: float) -> list[float]:
    """Phases at which to cut: in each gap between consecutive events (round the
    period) with fewer than MIN_DATA trusted nodes, enough evenly spaced cuts."""
    out = []
    m = len(phases)
    for i in range(m):
        a, _, after = phases[i]
        b, before, _ = phases[(i + 1) % m]
        if i == m - 1:
            b += period
        lo, hi = a + after, b - before
        overlap = hi <= lo
        if overlap:  # the shadows overlap: cut between the events themselves (a short
            lo, hi = a, b  # piece: its middle stands for it)
        first = math.ceil((lo - psi0) / h - 1e-9)
        last = math.floor((hi - psi0) / h + 1e-9)
        trusted = 0 if overlap else max(last - first + 1, 0)
        if m == 1 or trusted >= MIN_DATA:
            continue
        need = 1 if overlap else MIN_DATA - trusted
        # evenly between the trusted nodes (or the window's ends)
        for q in range(need):
            out.append((lo + (q + 1) * (hi - lo) / (need + 1)) % period)
    return sorted(out)


def _samples(pair, psi, sample_phases, loads_at):
    """(angles, forces, torques) of chamber 0 at every occurrence of the sample phases
    over the table's span a period either side (zero where the chamber is not there).
    ``loads_at(phase)`` gives (residue, {q: (force, torque)}): the section cut at the
    residue holds chamber 0 of angle residue + q period as its chamber q."""
    period = pair.period
    xs, forces, torques = [], [], []
    for phase in sample_phases:
        residue, by_q = loads_at(phase)
        k0 = math.ceil((psi[0] - period - residue) / period)
        k1 = math.floor((psi[-1] + period - residue) / period)
        for k in range(k0, k1 + 1):
            force, torque = by_q.get(k, (np.zeros((2, 2)), np.zeros(2)))
            xs.append(residue + k * period)
            forces.append(force)
            torques.append(torque)
    order = np.argsort(xs)
    return (np.asarray(xs, dtype=float)[order],
            np.asarray(forces, dtype=float).reshape(len(xs), 2, 2)[order],
            np.asarray(torques, dtype=float).reshape(len(xs), 2)[order])
