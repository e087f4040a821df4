"""The chamber table's port areas: the face section inside the port, at any age.

:mod:`.ports` says what a port is.  The areas do not go through its shapes.  A point
that the chamber covers in one interval of angles lies in a section after suction
closes exactly when it lies in the section at closing; outside the region both rotors'
surfaces pass (:func:`.footprint.crop_region`) every point is covered so (tested), and
there a section's part in the suction port is the section less the section at
closing, exactly.  Inside it (the twin screw's lens between the bores, where a groove
pair passes a point as it is born and again as it dies) the sections after closing are
swept between the section table's samples (:mod:`.footprint`).  The discharge likewise,
with the sections before the opening.

The suction face's sections lie on the table's nodes, which are section-grid nodes.
The discharge face's are shifted by the wrap, off that grid: their areas are computed
on the section grid and interpolated by cubic Hermites, except where the grid shows a
kink near a node: there the node's own section is cut (:data:`KINK_TOL`).  The open
discharge area turns sharply where a corner of the moving section passes a corner of
the sealed region's edge, several times per section step near its largest value; the
interpolation alone erred by up to 5.8e-4 (pin-cycloid) and 1.1e-3 (circular) of the
largest area at 24 points per period.

How far these areas are from the exact ones, at each angle resolution, is measured by
bench/bench_twin_screw.py against sections with polygons 16 times finer swept 3072
times per period; its figures, and what each change did to them, are in
docs/twin_screw.md.
"""

from __future__ import annotations

import math

import numpy as np

from .machine import SweptMachine
from .ports import EPS_AGE, PortTiming, _section

#: Consecutive sections whose open areas are cut from one crop of the sealed region.
CROP_WINDOW = 8
#: A table node whose cell's neighbourhood on the section grid has a third difference
#: above this fraction of the largest open area gets its own section.  The Hermite
#: interpolant with three-point slopes errs by about a twentieth of the third
#: difference where the area is smooth (its slopes err by h^2 f'''/6, weighted by at
#: most 4/27 h), but by up to 0.37 of it across a kink (a slope jump anywhere in a
#: cell, tested: the discharge area's peak).  2.5e-4 keeps both below 1e-4.  With 1e-3
#: (until 2026-11-30; measured on the 4/6 pin-cycloid at 24 points per period, the
#: nodes below it erred by at most 2.1e-5, the ones above by up to 5.8e-4) the
#: pin-cycloid's peak node at 96 erred by 1.05e-4 (5.8e-5 with its own section).  At
#: 24 points per period the own sections went from 17 to 20 of 35 on the pin-cycloid,
#: from 16 to 24 of 29 on the circular.
KINK_TOL = 2.5e-4


def open_areas(machine: SweptMachine, timing: PortTiming, ages: np.ndarray,
               cut_discharge: bool = True, steps: int | None = None):
    """(suction, discharge): the area through which the chamber is open to each port at
    every age of ``ages`` (its face section inside the port), m2.

    The chamber's face section is what an end face would offer if the whole plate were
    open; the port is only part of it, so a chamber opening to the discharge port sees
    an area that grows from nothing (seed 004's point: the early-opened port is small at
    first and throttles the gas).  Without ``cut_discharge`` (no axial discharge port)
    the discharge areas are zero.

    The suction areas are F(a) less the section at closing and, inside the crop region,
    less the sections after closing swept on the section table's grid (or ``steps`` per
    lobe period); the discharge likewise (the module docstring).  Zero where the port
    is closed, up to and from the timing's own angles.
    """
    from .footprint import Surfaces, Sweeper, crop_region

    sec, sw = machine.section, machine.sweep
    life = sec.phi_f - sec.phi_i
    h = float(sec.psi[1] - sec.psi[0]) if steps is None else machine.period / steps
    memo = {}

    def section_at(psi, contacts=None):
        # Each planar section serves both faces; the sweeps' samples need the contacts
        # (a whole cut), the open sections only the polygons.
        key = round(psi / EPS_AGE)
        if key not in memo or (contacts is not None and memo[key][1] is None):
            found = None if contacts is None else []
            memo[key] = ([q for q in _section(machine, psi, found) if len(q) >= 3], found)
        if contacts is not None:
            contacts.extend(memo[key][1])
        return memo[key][0]

    sweeper = Sweeper(Surfaces(machine.pair), section_at, *crop_region(machine.pair))
    ages = np.asarray(ages, dtype=float)
    sc, do = timing.suction_close, timing.discharge_open
    lp = np.zeros(len(ages))
    open_ = _inside(ages, (0.0, min(sc, life)))
    if open_.any():
        sealed = _sealed_region(section_at, sec, sweeper, sc, (sc, min(life, timing.death)), h)
        lp[open_] = _areas_outside(section_at, sec, sealed, ages[open_],
                                   float(sw.scale(0.0)))
    hp = np.zeros_like(ages)
    if not cut_discharge:
        return lp, hp
    b_open, b_death = do - sw.wrap, timing.death - sw.wrap
    planar = ages - sw.wrap
    lo, hi = max(b_open, 0.0), min(b_death, life)
    inside = (planar > lo) & (planar < hi)
    if not inside.any():
        return lp, hp
    grid = h * np.arange(math.floor(lo / h) + 1, math.ceil(hi / h))
    grid = np.unique(np.concatenate([[lo], grid[(grid > lo + EPS_AGE) & (grid < hi - EPS_AGE)],
                                     [hi]]))
    scale = float(sw.scale(sw.length))
    sealed = _sealed_region(section_at, sec, sweeper, b_open, (0.0, b_open), h)
    vals = np.zeros(len(grid))
    on = _inside(grid, (lo, hi))
    vals[on] = _areas_outside(section_at, sec, sealed, grid[on], scale)
    nodes = planar[inside]
    out = np.maximum(_hermite(grid, vals, nodes), 0.0)
    own = _kinked(grid, vals, nodes, h)
    if own.any():
        out[own] = _areas_outside(section_at, sec, sealed, nodes[own], scale)
    hp[inside] = out
    return lp, hp


def _inside(ages, window):
    return (ages > window[0] + EPS_AGE) & (ages < window[1] - EPS_AGE)


def _sealed_region(section_at, sec, sweeper, edge, sealed, h):
    """What the face sections cover over planar ages ``sealed`` (swept, ``h`` apart)
    and at ``edge``, the port's own angle (the sealed window's end on the open side):
    a CrossSection, or None."""
    from manifold3d import CrossSection, FillRule

    s0, s1 = sealed
    parts = []
    if s1 > s0:
        window = h * np.arange(math.ceil(s0 / h), math.floor(s1 / h) + 1)
        window = np.unique(np.concatenate([[s0], window[(window > s0 + EPS_AGE)
                                                         & (window < s1 - EPS_AGE)], [s1]]))
        parts.append(sweeper.sweep(sec.phi_i + window))
    rings = [np.ascontiguousarray(q) for q in section_at(sec.phi_i + edge)]
    if rings:
        parts.append(CrossSection(rings, FillRule.Positive))
    return parts[0] if len(parts) == 1 else (parts[0] + parts[1] if parts else None)


def _areas_outside(section_at, sec, sealed_region, ages, scale):
    """Areas of the face sections at planar ``ages`` outside ``sealed_region``, times
    ``scale`` squared (the face's)."""
    from manifold3d import CrossSection, FillRule

    out = np.zeros(len(ages))
    for j in range(0, len(ages), CROP_WINDOW):
        # A few consecutive sections lie in a small part of the sealed region: each is
        # cut from that part (a Boolean costs as many of its vertices as theirs).
        window = []
        for i in range(j, min(j + CROP_WINDOW, len(ages))):
            rings = [np.ascontiguousarray(q) for q in section_at(sec.phi_i + ages[i])]
            if rings:
                window.append((i, CrossSection(rings, FillRule.Positive),
                               np.min([q.min(0) for q in rings], axis=0),
                               np.max([q.max(0) for q in rings], axis=0)))
        if not window:
            continue
        crop = sealed_region
        if crop is not None:
            lo = np.min([w[2] for w in window], axis=0)
            hi = np.max([w[3] for w in window], axis=0)
            pad = 1e-3 * float(np.max(hi - lo))  # off the sections' own edges
            lo, hi = lo - pad, hi + pad
            crop = crop ^ CrossSection([np.array([lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]])])
        for i, f, _, _ in window:
            out[i] = f.area() if crop is None or crop.is_empty() else (f - crop).area()
    return out * scale * scale


def _kinked(x, y, xq, h):
    """Per query point of ``xq``: whether the third divided differences of (x, y) over
    the stencils that reach its cell (the Hermite's, and one either side), times 6 h^3
    (the third difference of a grid of step h), exceed KINK_TOL of the largest |y|."""
    n = len(x)
    top = float(np.max(np.abs(y))) if n else 0.0
    if n < 4 or top == 0.0:
        return np.zeros(len(xq), dtype=bool)
    d = np.asarray(y, dtype=float)
    for order in (1, 2, 3):
        d = np.diff(d) / (x[order:] - x[:-order])
    big = 6.0 * h ** 3 * np.abs(d) > KINK_TOL * top  # per stencil k .. k + 3
    k = np.clip(np.searchsorted(x, xq) - 1, 0, n - 2)  # xq's cell [x_k, x_k+1]
    out = np.zeros(len(xq), dtype=bool)
    for s in (-2, -1, 0):  # stencils k - 2 .. k + 1, k - 1 .. k + 2, k .. k + 3
        j = k + s
        ok = (j >= 0) & (j < len(big))
        out[ok] |= big[j[ok]]
    return out


def _hermite(x, y, xq):
    """Piecewise cubic Hermite through (x, y) with three-point slopes (exact for
    quadratics), at xq in [x0, x_end].  (Exact slopes, the flux of the rotors' motion
    through the open region's boundary, were tried: 5.8e-4 became 3.5e-4 on the 4/6
    pin-cycloid at 24 points per period, for 0.3 s of classifying those boundaries, and
    Clipper's zigzags where a section runs along the sealed region spoilt some.)"""
    x, y, xq = (np.asarray(v, dtype=float) for v in (x, y, xq))
    if len(x) < 3:
        return np.interp(xq, x, y)
    hx = np.diff(x)
    d = np.diff(y) / hx
    m = np.empty_like(y)
    m[1:-1] = (hx[1:] * d[:-1] + hx[:-1] * d[1:]) / (hx[:-1] + hx[1:])
    m[0] = d[0] - hx[0] * (d[1] - d[0]) / (hx[0] + hx[1])
    m[-1] = d[-1] + hx[-1] * (d[-1] - d[-2]) / (hx[-1] + hx[-2])
    k = np.clip(np.searchsorted(x, xq) - 1, 0, len(x) - 2)
    t = (xq - x[k]) / hx[k]
    h00, h10 = (1 + 2 * t) * (1 - t) ** 2, t * (1 - t) ** 2
    h01, h11 = t * t * (3 - 2 * t), t * t * (t - 1)
    out = h00 * y[k] + h10 * hx[k] * m[k] + h01 * y[k + 1] + h11 * hx[k] * m[k + 1]
    return out
