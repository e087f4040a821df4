"""One twin-screw working chamber in a transverse section, followed over its life.

A working chamber is one male groove and one female groove: the pair that meet at the
bottom cusp, where the lobes go into mesh and the chamber dies (:mod:`.regions` says
which life of a groove a part of the section belongs to).  The female groove is born
first (a female groove lives N2 / N1 male turns, a male groove one), so the chamber's
section holds the female part alone at first, then both, until the two are squeezed
out together at the bottom.

Chambers one lobe period apart are the same chamber at different ages, and a section
at male angle psi holds every chamber of the machine at once; so one lobe period of
sections, each part booked to its chamber's age, gives the whole life.  Chamber 0 is
the one whose male groove is groove 0, born at psi = -beta_0 (its mid-line then facing
the female axis); a part of age ``a`` at angle psi belongs to the chamber
``(a - psi - beta_0) / period`` periods older (the female parts' ages shifted by the
pairing at the bottom cusp).

Sealing points per chamber (tracks): both tips of the male groove and of the female
groove while they seal on their bores (beyond a leading tip the chamber one period
older, beyond a trailing one the one a period younger, or a revolution off where that
groove has begun its next life; a land's corners: :func:`.lands.corner_seals`), and the
interlobe contacts: in the newborn part the
chamber beyond is older ("interlobe-lead"), in the dying part younger ("-trail").
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from rotorflow.errors import CaseError

from ..planar import TWO_PI
from ..section import POINTS_PER_PERIOD, SectionChamber, Track
from .blowhole import build_openings, openings_of
from .boundaries import turning_rate
from .lands import corner_seals
from .load_events import load_events
from .regions import FEMALE, MALE
from .track_ends import refine

#: A contact seen from the parts on both its sides is one point: within this (per C).
SAME_POINT = 1e-6
#: Sections over one period scanned for the male and female grooves that die together
#: (any section where they share the bottom cusp will do).
FEMALE_SHIFT_SCAN = 8
#: Angles within this (rad) are one section; the memo of cut sections keeps this many
#: (a table of 192 points per period and its ports' few dozen more).
RESIDUE_TOL = 1e-9
CUT_MEMO = 512
#: A track point that moves more than this many times its median step between two
#: nodes has jumped to another contact (a new identity, no rate across it).
JUMP_FACTOR = 8.0
#: Absent nodes inside a track filled by its cubic (:func:`_holes`): one or two were
#: seen near the cusps on the pin-cycloid.
HOLE_NODES = 3


def _beta0(pair) -> float:
    period = TWO_PI / pair.gearing.lobes_male
    return pair.tip_angle(MALE) + 0.5 * period


def _female_shift(pair, parts_by_section, psis) -> float:
    """The female parts' age shift: the male groove and the female groove that die
    together at the bottom cusp belong to one chamber."""
    period = TWO_PI / pair.gearing.lobes_male
    b0 = _beta0(pair)
    frac = None
    for psi, parts in zip(psis, parts_by_section, strict=True):
        for p in parts:
            if p.rotor == FEMALE:
                x = (p.age - psi - b0) / period
                frac = x - round(x)
                break
        if frac is not None:
            break
    for psi, parts in zip(psis, parts_by_section, strict=True):
        bottom = defaultdict(dict)
        for p in parts:
            if p.side == "bottom":
                bottom[p.piece][p.rotor] = p
        for both in bottom.values():
            if MALE in both and FEMALE in both:
                qm = (both[MALE].age - psi - b0) / period
                qf = (both[FEMALE].age - psi - b0) / period - frac
                return -(frac + round(qf - qm)) * period
    # Lands (the screw pumps' trochoidal profile): one rotor's land covers each cusp at
    # every angle, so no piece reaches a cusp; the male and female grooves of a chamber
    # meet in the mesh instead, through the space between their flanks, which straddles
    # the cusp line (its two halves are one fluid in that section).
    if pair.has_lands:
        for psi, parts in zip(psis, parts_by_section, strict=True):
            by_piece = defaultdict(dict)
            for p in parts:
                by_piece[p.piece].setdefault(p.rotor, p)
            for both in by_piece.values():
                if MALE in both and FEMALE in both:
                    qm = (both[MALE].age - psi - b0) / period
                    qf = (both[FEMALE].age - psi - b0) / period - frac
                    return -(frac + round(qf - qm)) * period
    raise CaseError("no section shows a male and a female groove meeting at the "
                    "discharge-side cusp: the profiles do not form working chambers")


def female_shift(pair) -> float:
    """The female parts' age shift, from a coarse scan of one period."""
    psis, scans = _scan(pair, FEMALE_SHIFT_SCAN)
    return _female_shift(pair, scans, psis)


def _scan(pair, points_per_period):
    period = TWO_PI / pair.gearing.lobes_male
    h = period / points_per_period
    psis = -_beta0(pair) + h * np.arange(points_per_period)
    return psis, [_cut(pair, float(p)) for p in psis]


class _PolygonsOnly(list):
    """The parts of a polygons-only cut (:meth:`.regions.SectionCutter.cut`)."""


def _cut(pair, residue: float, polygons_only: bool = False):
    """The section at ``residue`` (an angle in the period from -beta_0), cut once per
    pair: the table, the female parts' shift and the ports' chamber polygons ask for
    many of the same angles.  A polygons-only cut serves polygons-only requests alone
    (a whole one replaces it)."""
    key = round(residue / RESIDUE_TOL)
    cuts = pair.cut_memo
    held = cuts.get(key)
    if held is not None and (polygons_only or not isinstance(held, _PolygonsOnly)):
        return held
    if held is None and len(cuts) >= CUT_MEMO:
        cuts.pop(next(iter(cuts)))
    parts = pair.cutter.cut(residue, polygons_only)
    cuts[key] = _PolygonsOnly(parts) if polygons_only else parts
    return cuts[key]


def chamber_index(pair, part, psi, shift) -> int:
    period = TWO_PI / pair.gearing.lobes_male
    age = part.age + (shift if part.rotor == FEMALE else 0.0)
    return int(round((age - psi - _beta0(pair)) / period))


def section_chamber(pair, points_per_period: int = POINTS_PER_PERIOD) -> SectionChamber:
    """Tabulate chamber 0 of ``pair`` from birth to death."""
    psis, scans = _scan(pair, points_per_period)
    shift = pair.female_shift
    nodes = defaultdict(lambda: {"area": 0.0, "force": np.zeros((2, 2)),
                                 "torque": np.zeros(2), "perimeter": np.zeros(2),
                                 "seals": [], "openings": []})
    for m, (psi, parts) in enumerate(zip(psis, scans, strict=True)):
        qs = [chamber_index(pair, p, psi, shift) for p in parts]
        for p, q in zip(parts, qs, strict=True):
            node = nodes[m + q * points_per_period]
            node["area"] += p.area
            node["force"] += p.force
            node["torque"] += p.torque
            node["perimeter"] += p.perimeter
        for q, name, offset, width in openings_of(parts, qs):
            nodes[m + q * points_per_period]["openings"].append((name, offset, width))
        for q, name, kind, point, other, rate in _seals(pair, parts, qs):
            nodes[m + q * points_per_period]["seals"].append((name, kind, point, other - q,
                                                              rate))
    return _assemble(pair, psis[0], points_per_period, nodes)


def _seals(pair, parts, qs):
    """(chamber, track name, kind, point, chamber beyond) of every sealing point."""
    out = []
    tips = defaultdict(list)
    for p, q in zip(parts, qs, strict=True):
        for rotor, k, pt in p.tips:
            tips[(rotor, k)].append((p, q, pt))
    for (rotor, k), seen in tips.items():
        if len(seen) != 2:
            continue
        for (p, q, pt), (_, q2, _) in (seen, seen[::-1]):
            # Male grooves lie between tip k (clockwise end) and k + 1; the male turns
            # counter-clockwise, so its groove leads with tip k + 1.  The female turns
            # clockwise: its groove j leads with tip j.
            # A 1-lobe rotor's one tip bounds its groove at both ends, the newborn life
            # (whose leading tip it is: beyond it the older, dying life) and the dying one.
            n = pair.gearing.lobes_male if rotor == MALE else pair.gearing.lobes_female
            if n == 1:
                leading = q2 > q
            else:
                leading = (k == (p.groove + 1) % n) if rotor == MALE else (k == p.groove)
            name = f"tip-{'male' if rotor == MALE else 'female'}-{'lead' if leading else 'trail'}"
            out.append((q, name, "tip", pt, q2, turning_rate(pair.gearing, rotor, pt)))
    out.extend(corner_seals(pair, parts, qs))
    tol = SAME_POINT * pair.gearing.centre_distance
    contacts = [(q, p.rotor, c, r) for p, q in zip(parts, qs, strict=True)
                for c, r in zip(p.contacts, p.contact_rates, strict=True)]
    booked = set()
    for i, (q, rotor, c, r) in enumerate(contacts):
        for j, (q2, rotor2, c2, _) in enumerate(contacts):
            if j != i and q2 != q and np.linalg.norm(c - c2) < tol:
                if rotor != rotor2:
                    q, q2 = _lives(pair, c, q, rotor, q2)
                # A chamber whose parts meet the contact more than once (its male and
                # female part both end there) has one sealing point there, not two.
                key = (q, q2, round(c[0] / tol), round(c[1] / tol))
                if key not in booked:
                    booked.add(key)
                    out.append((q, "interlobe-lead" if q2 > q else "interlobe-trail",
                                "interlobe", c, q2, r))
                break
    return out


def _lives(pair, c, q, rotor, q2):
    """(chamber, chamber beyond) of a contact between a male part (chamber q or q2)
    and a female part: one within a lens's length of the cusp line.

    The two sides of an interlobe contact are two lives of one groove, the groove on
    the contact's side of the cusp line: N1 lobe periods apart for a male groove, N2
    for a female one (a revolution of that rotor).  Near the cusp line the section
    cannot tell which groove's fluid touches the contact: the grown rotors overlap over
    a lens ~0.2 mm long either side of it, and the dying groove's sliver (1e-11 m^2 and
    shrinking like the cube of its distance) vanishes up to a lens early, the next one
    appears up to a lens late.  So the part on the contact's side is trusted, and the
    other side is its other life: the chambers then change exactly where the contact
    crosses the cusp line (:mod:`.track_ends`)."""
    g = pair.gearing
    side = MALE if c[0] < pair.cusp[0] else FEMALE
    n = g.lobes_male if side == MALE else g.lobes_female
    if rotor == side:
        return q, q + n if q2 > q else q - n
    return (q2 + n if q > q2 else q2 - n), q2


def _assemble(pair, psi0, ppp, nodes) -> SectionChamber:
    period = TWO_PI / pair.gearing.lobes_male
    h = period / ppp
    # The chamber lives where it has fluid, and where a sealing point next to that
    # keeps it: near the cusp line a newborn or dying sliver is below the polygons'
    # resolution while its contact, booked to it (_lives), already or still seals.
    # Only next to it: a contact on a film Clipper broke into specks was booked to a
    # life four periods beyond the chamber's death (the 4/6 pin-cycloid at 384 section
    # points per period), and the chamber's table ran on 1,003 nodes past its death.
    sealed = {k for k, v in nodes.items() if v["seals"]}
    live = sorted(k for k, v in nodes.items() if v["area"] > 0.0) or sorted(sealed)
    first, last = live[0], live[-1]
    while first - 1 in sealed:
        first -= 1
    while last + 1 in sealed:
        last += 1
    first, last = first - 1, last + 1  # a zero node either side
    idx = np.arange(first, last + 1)
    n = len(idx)
    area = np.array([nodes[k]["area"] if k in nodes else 0.0 for k in idx])
    force = np.array([nodes[k]["force"] if k in nodes else np.zeros((2, 2)) for k in idx])
    torque = np.array([nodes[k]["torque"] if k in nodes else np.zeros(2) for k in idx])
    perim = np.array([nodes[k]["perimeter"] if k in nodes else np.zeros(2) for k in idx])
    psi = psi0 + h * idx
    tracks = [refine(pair, psi, t) for t in
              _tracks([nodes[k]["seals"] if k in nodes else [] for k in idx], n, h)]
    tracks = tuple(t for t in tracks if t.present.any())
    openings = build_openings(pair, psi, [nodes[k]["openings"] if k in nodes else []
                                          for k in idx], tracks)
    events = load_events(pair, psi, tracks, lambda phase: _loads_at(pair, phase))
    zero2 = np.zeros((n, 2))
    zeros = np.zeros(n, dtype=int)
    return SectionChamber(
        psi=psi, area=area, force=force, torque=torque, perimeter=perim,
        trail=zero2, lead=zero2, phi_i=float(psi[0]), phi_f=float(psi[-1]),
        speed_ratio=tuple(r.speed_ratio for r in pair.rotors),
        lead_offset=zeros, trail_offset=zeros, lead_id=zeros, trail_id=zeros,
        lead_kind=np.full(n, "interlobe"), trail_kind=np.full(n, "interlobe"),
        tracks=tracks, openings=openings, load_events=events,
    )


def _loads_at(pair, phase: float):
    """(residue, {q: (force, torque)}): the section cut at ``phase``'s residue in the
    period from -beta_0, its parts' loads summed per chamber q (chamber 0 at residue +
    q period: :func:`section_chamber`'s booking)."""
    period = TWO_PI / pair.gearing.lobes_male
    base = -_beta0(pair)
    residue = base + ((phase - base) % period)
    shift = pair.female_shift
    out = {}
    for p in _cut(pair, residue):
        q = chamber_index(pair, p, residue, shift)
        force, torque = out.get(q, (np.zeros((2, 2)), np.zeros(2)))
        out[q] = (force + p.force, torque + p.torque)
    return residue, out


def _tracks(seals_per_node, n, h) -> tuple[Track, ...]:
    """One Track per sealing-point name; where one chamber has two points of one name at
    once (a second interlobe contact), the second gets a name of its own, ``name#2``.

    Which point continues which track goes by continuity, not by position: each point
    takes the track whose point at the node before, moved on by its rate over the step
    ``h``, lies nearest (the points of one name may swap their order across the
    section as they move).  A point that changed tracks would end one line and begin
    another half a step off, an error of the first order in the step."""
    by_name = defaultdict(lambda: (np.zeros((n, 2)), np.zeros(n, bool), np.zeros(n, int),
                                   np.zeros((n, 2))))
    kinds = {}
    slots = defaultdict(list)  # name -> its tracks' keys, in order of creation
    for i, seals in enumerate(seals_per_node):
        groups = defaultdict(list)
        for seal in sorted(seals, key=lambda s: (s[0], s[2][1])):
            groups[seal[0]].append(seal)
        for name, items in groups.items():
            keys = slots[name]
            # Tracks present at the node before, with where their point would be now.
            live = [(k, by_name[k][0][i - 1] + h * by_name[k][3][i - 1]) for k in keys
                    if i > 0 and by_name[k][1][i - 1]]
            pairs = sorted((float(np.linalg.norm(seal[2] - guess)), a, k)
                           for a, seal in enumerate(items) for k, guess in live)
            chosen, used = {}, set()
            for _, a, k in pairs:
                if a not in chosen and k not in used:
                    chosen[a] = k
                    used.add(k)
            for a in range(len(items)):
                if a in chosen:
                    continue
                free = [k for k in keys if k not in used and k not in dict(live)]
                if not free:
                    free = [name if not keys else f"{name}#{len(keys) + 1}"]
                    keys.append(free[0])
                chosen[a] = free[0]
                used.add(free[0])
            for a, (_, kind, point, offset, rate) in enumerate(items):
                pts, present, off, rates = by_name[chosen[a]]
                pts[i], present[i], off[i], rates[i] = point, True, offset, rate
                kinds[chosen[a]] = kind
    out = []
    for name in sorted(by_name):
        pts, present, off, rates = _holes(*by_name[name], h)
        out.append(Track(name, kinds[name], *_fill(pts, present), off, _ids(pts, present),
                         rates=rates))
    return tuple(out)


def _holes(pts, present, off, rates, h):
    """Fill a run of at most HOLE_NODES absent nodes between two present ones of the
    same chamber beyond whose points the cubic through both (their rates) joins within
    JUMP_FACTOR steps: the section lost the point there (the sliver beyond a contact
    near a cusp is below the polygons' resolution), the line did not stop."""
    pts, present, off, rates = pts.copy(), present.copy(), off.copy(), rates.copy()
    idx = np.nonzero(present)[0]
    if len(idx) < 2:
        return pts, present, off, rates
    steps = np.linalg.norm(np.diff(pts[idx], axis=0), axis=-1)[np.diff(idx) == 1]
    typical = np.median(steps) if len(steps) else 0.0
    for i, j in zip(idx[:-1], idx[1:], strict=True):
        if not 1 < j - i <= HOLE_NODES + 1 or off[i] != off[j]:
            continue
        span = (j - i) * h
        if np.linalg.norm(pts[j] - pts[i]) > JUMP_FACTOR * (j - i) * max(typical, 1e-300):
            continue
        s = (np.arange(i + 1, j) - i)[:, None] / (j - i)
        s2, s3 = s * s, s * s * s
        pts[i + 1:j] = ((2 * s3 - 3 * s2 + 1) * pts[i] + (s3 - 2 * s2 + s) * span * rates[i]
                        + (3 * s2 - 2 * s3) * pts[j] + (s3 - s2) * span * rates[j])
        rates[i + 1:j] = ((6 * s2 - 6 * s) * (pts[i] - pts[j]) / span
                          + (3 * s2 - 4 * s + 1) * rates[i] + (3 * s2 - 2 * s) * rates[j])
        present[i + 1:j] = True
        off[i + 1:j] = off[i]
    return pts, present, off, rates


def _fill(pts, present):
    """Absent points take the nearest present one (rates stay finite)."""
    idx = np.nonzero(present)[0]
    j = idx[np.clip(np.searchsorted(idx, np.arange(len(pts))), 0, len(idx) - 1)]
    out = pts.copy()
    out[~present] = pts[j[~present]]
    return out, present


def _ids(pts, present):
    step = np.linalg.norm(np.diff(pts, axis=0), axis=-1)
    both = present[1:] & present[:-1]
    typical = np.median(step[both]) if both.any() else 0.0
    jump = ~both | (step > JUMP_FACTOR * max(typical, 1e-300))
    return np.concatenate([[0], np.cumsum(jump)])


def chamber_polygons(pair, phi: float, contacts: list | None = None) -> list[np.ndarray]:
    """Chamber 0's section at male angle ``phi`` (fixed frame, metres).

    The section one period on is the same section with every chamber one period older:
    chamber 0 at ``phi`` is chamber q at ``phi - q period``.  So every angle is cut at
    its residue in one period (ports ask for hundreds of ages, a few dozen residues).
    """
    period = TWO_PI / pair.gearing.lobes_male
    base = -_beta0(pair)
    q = int(np.floor((phi - base) / period + RESIDUE_TOL))
    residue = float(phi - q * period)
    shift = pair.female_shift
    out = []
    for p in _cut(pair, residue, polygons_only=contacts is None):
        if chamber_index(pair, p, residue, shift) == q:
            out.extend(p.polygons)
            if contacts is not None:
                contacts.extend(p.contacts)
    return out


def contact_table(pair, step_deg: float = 1.0, span_deg: float | None = None):
    """Every interlobe contact of the pair every ``step_deg`` of male angle over
    ``span_deg`` (default: one lobe period, after which the pattern repeats), as a
    :class:`..contacts.ContactTable` (kind "interlobe"; ``space`` the male groove whose
    part it bounds; radii from the male and the female axis)."""
    from ..contacts import ContactTable

    period = 360.0 / pair.gearing.lobes_male
    span = period if span_deg is None else span_deg
    if not step_deg > 0.0 or not span > 0.0:
        raise CaseError("contact table step and span must be positive")
    angles = np.arange(0.0, span + 0.5 * step_deg, step_deg)
    if span_deg is None:
        angles = angles[angles < span - 1e-9]
    rows = []
    tol = SAME_POINT * pair.gearing.centre_distance
    for a in angles:
        seen = []
        for p in pair.cutter.cut(float(np.radians(a))):
            for c in p.contacts:
                if any(np.linalg.norm(c - d) < tol for d in seen):
                    continue
                seen.append(c)
                rows.append((a, "interlobe", p.groove if p.rotor == MALE else -1 - p.groove,
                             c[0], c[1], float(np.linalg.norm(c)),
                             float(np.linalg.norm(c - pair.gearing.female_axis))))
    cols = list(zip(*rows, strict=True)) if rows else [[]] * 7
    return ContactTable(*(np.array(c) for c in cols))
