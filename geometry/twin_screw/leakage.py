"""The leakage paths a twin-screw chamber table declares (seed 003's sealing lines).

Seed 003 names four sealing lines: the leading and trailing tip lines of both rotors on
the casing, the interlobe line between the rotors, and the front (end-face) line at the
discharge end; "the tip leakage areas are accompanied by the blow-hole areas".  Each tip
and interlobe line is a track of the section (:class:`..section.Track`) swept along the
rotors; a line between two chambers is seen from both (a male groove's leading tip is
its older neighbour's trailing tip), so one path carries both columns.  The blow-holes
at both cusps (:mod:`.blowhole`) are orifices: their columns are areas, the gap does
not enter.

End faces (seed 003's front sealing line): a groove's section on an end plate is
separated from the next groove's by the lobe between them, and gas crosses the lobe's
end face through the end clearance from the older chamber into the younger.  The line
is the lobes' radial extent (each rotor's lobe depth), present while both chambers have
a section on that plate.  (The internal gear's end faces leak to the plena along the
chamber's whole rotor edge; a twin-screw groove reaches the discharge plate long before
it opens to the port, so that would blow discharge gas into chambers still filling.)
"""

from __future__ import annotations

import numpy as np

from ..table import LeakagePath, opening_column, track_column

#: The same line seen from the chamber beyond it.
PARTNER = {"tip-male-lead": "tip-male-trail", "tip-female-lead": "tip-female-trail",
           "interlobe-lead": "interlobe-trail"}


def _partner(name: str) -> str | None:
    base, _, rest = name.partition("#")
    other = PARTNER.get(base) or {v: k for k, v in PARTNER.items()}.get(base)
    if other is None:
        return None
    return other + (f"#{rest}" if rest else "")


def _mirror(name: str, d: int, track_lines: dict, done: set):
    """The same line seen from the chamber beyond: its partner's track at offset -d,
    first under the partner's own name (``interlobe-trail#2`` for
    ``interlobe-lead#2``), else under any of the partner's names not yet paired (which
    of a chamber's two points of one name is ``#2`` goes by the order they appear in,
    :func:`.section._tracks`, not by the line)."""
    other = _partner(name)
    if other is None:
        return None
    if (other, -d) in track_lines and (other, -d) not in done:
        return other, -d
    base = other.partition("#")[0]
    for key in sorted(track_lines):
        if key[1] == -d and key[0].partition("#")[0] == base and key not in done:
            return key
    return None


def twin_screw_paths(track_lines: dict, opening_areas: dict | None = None
                     ) -> tuple[LeakagePath, ...]:
    """Paths for the tracks' lines and the openings' areas (both keyed (name, offset))
    and the end faces."""
    paths = [
        LeakagePath("lp-front+1", "end-face", 1, "seal_front_lp_m", report="lp_face"),
        LeakagePath("hp-front+1", "end-face", 1, "seal_front_hp_m", report="hp_face"),
    ]
    kinds = {"tip": "tip", "interlobe": "interlobe"}
    done = set()
    for (name, d) in sorted(track_lines, key=lambda k: (k[0], k[1])):
        if (name, d) in done:
            continue
        mirror = _mirror(name, d, track_lines, done)
        done.add((name, d))
        if mirror is not None:
            done.add(mirror)
        kind = kinds[name.split("-")[0]]
        paths.append(LeakagePath(
            f"{name}{d:+d}", kind, d, track_column(name, d),
            mirror=None if mirror is None else track_column(*mirror), report=kind))
    for (name, d) in sorted(opening_areas or {}):
        # an opening is seen from both chambers under one name, offsets opposite
        if d < 0 and (name, -d) in opening_areas:
            continue
        mirror = opening_column(name, -d) if (name, -d) in opening_areas else None
        paths.append(LeakagePath(f"{name}{d:+d}", "blow-hole", d, opening_column(name, d),
                                 mirror=mirror, measure="area", report=name))
    return tuple(paths)


def front_lines(pair, machine) -> dict:
    """The end-face lines to the next (older) chamber on each plate (module docstring)."""
    cur = machine.curves
    k = machine.points_per_period
    depth = sum(pair.lobe_depths)
    out = {}
    for face, area in (("lp", cur.area_lp), ("hp", cur.area_hp)):
        here = area > 0.0
        older = np.zeros_like(here)
        older[:-k] = here[k:]
        out[f"seal_front_{face}_m"] = depth * (here & older)
    return out
