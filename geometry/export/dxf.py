"""Transverse profiles as ASCII DXF (R12): one closed POLYLINE (layer PROFILE), and the
outer rotor's outside circle (layer BORE) when given."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def write(path: Path, poly: np.ndarray, scale: float, units: str,
                      circle_radius: float | None = None) -> None:
    """ASCII DXF (R12): one closed 2D POLYLINE, optionally a CIRCLE centred at 0."""
    insunits = 4 if units == "mm" else 6  # AutoCAD unit codes: 4 mm, 6 m
    out = ["0", "SECTION", "2", "HEADER", "9", "$ACADVER", "1", "AC1009",
           "9", "$INSUNITS", "70", str(insunits), "0", "ENDSEC",
           "0", "SECTION", "2", "ENTITIES",
           "0", "POLYLINE", "8", "PROFILE", "66", "1", "70", "1",
           "10", "0.0", "20", "0.0", "30", "0.0"]
    for x, y in poly * scale:
        out += ["0", "VERTEX", "8", "PROFILE", "10", f"{x:.9f}", "20", f"{y:.9f}", "30", "0.0"]
    out += ["0", "SEQEND", "8", "PROFILE"]
    if circle_radius is not None:
        out += ["0", "CIRCLE", "8", "BORE", "10", "0.0", "20", "0.0", "30", "0.0",
                "40", f"{circle_radius * scale:.9f}"]
    out += ["0", "ENDSEC", "0", "EOF"]
    Path(path).write_text("\n".join(out) + "\n")


def read(path: Path) -> tuple[np.ndarray, bool]:
    """Vertices of the first POLYLINE of an R12 DXF and whether it is flagged closed."""
    lines = [s.strip() for s in Path(path).read_text().splitlines()]
    pairs = list(zip(lines[0::2], lines[1::2], strict=False))
    pts, closed, inside, vert = [], False, False, None
    for code, value in pairs:
        if code == "0":
            if vert is not None:
                pts.append(vert)
                vert = None
            if value == "POLYLINE":
                inside = True
            elif value == "SEQEND" and inside:
                break
            elif value == "VERTEX" and inside:
                vert = [0.0, 0.0]
        elif inside and vert is None and code == "70":
            closed = bool(int(value) & 1)
        elif vert is not None and code == "10":
            vert[0] = float(value)
        elif vert is not None and code == "20":
            vert[1] = float(value)
    return np.array(pts), closed
