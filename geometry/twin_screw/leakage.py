"""The leakage paths a twin-screw chamber table declares (seed 003's sealing lines).

Seed 003 names four sealing lines: the leading and trailing tip lines of both rotors on
the casing, the interlobe line between the rotors, and the front (end-face) line at the
discharge end; the blow-hole goes with the tip lines.  Each tip and interlobe line is a
track of the section (:class:`..section.Track`) swept along the rotors; a line between
two chambers is seen from both (a male groove's leading tip is its older neighbour's
trailing tip), so one path carries both columns.  The end faces leak to the suction
(low-pressure plate) and the discharge (high-pressure plate).
"""

from __future__ import annotations

from ..table import LeakagePath, track_column

#: The same line seen from the chamber beyond it.
PARTNER = {"tip-male-lead": "tip-male-trail", "tip-female-lead": "tip-female-trail",
           "interlobe-lead": "interlobe-trail"}


def _partner(name: str) -> str | None:
    base, _, rest = name.partition("#")
    other = PARTNER.get(base) or {v: k for k, v in PARTNER.items()}.get(base)
    if other is None:
        return None
    return other + (f"#{rest}" if rest else "")


def twin_screw_paths(track_lines: dict) -> tuple[LeakagePath, ...]:
    """Paths for the tracks' lines (keys (track name, offset)) and the end faces."""
    paths = [
        LeakagePath("lp-face", "end-face", "suction", "seal_lp_face_m", report="lp_face"),
        LeakagePath("hp-face", "end-face", "discharge", "seal_hp_face_m", report="hp_face"),
    ]
    kinds = {"tip": "tip", "interlobe": "interlobe"}
    done = set()
    for (name, d) in sorted(track_lines, key=lambda k: (k[0], k[1])):
        if (name, d) in done:
            continue
        other = _partner(name)
        mirror = (other, -d) if other is not None and (other, -d) in track_lines else None
        done.add((name, d))
        if mirror is not None:
            done.add(mirror)
        kind = kinds[name.split("-")[0]]
        paths.append(LeakagePath(
            f"{name}{d:+d}", kind, d, track_column(name, d),
            mirror=None if mirror is None else track_column(*mirror), report=kind))
    return tuple(paths)
