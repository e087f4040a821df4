"""The working chamber's transverse section as polygons (for the end-plate ports).

Each sub-region between two contacts is bounded by the outer profile (pin arcs and the
fillet between them) and the inner profile, sampled every ``SECTION_SPACING``.
"""

from __future__ import annotations

import math

import numpy as np

from ..planar import TWO_PI, rotate
from .pair import PinGerotor
from .section import chamber_life
from .space import Contact, PinSpace

#: Boundary sample spacing of one chamber section [m] (a port is a model: 0.1 mm keeps
#: the chord error of a 10 mm radius near 0.1 um).
SECTION_SPACING = 1e-4


def _arc(fn, a, b, length):
    n = max(int(math.ceil(length / SECTION_SPACING)), 2)
    return fn(np.linspace(a, b, n))


def _region_polygon(space: PinSpace, a: Contact, b: Contact, phi: float) -> np.ndarray:
    """Boundary (fixed frame, ccw) of the sub-region between contacts a and b at phi."""
    p = space.pair
    n1 = p.lobes_outer
    e = p.pin_edge
    g_lo, g_hi = p.fillet_range if p.fillet_kind == "conjugate" else (0.0, 0.0)
    parts = []
    if a.kind == "pin":
        parts.append(_arc(lambda t: p.pin_point(-1, t), a.psi1, -e, p.rho * abs(a.psi1 + e)))
        g_start = g_hi
    else:
        g_start = a.psi1
    if p.fillet_kind == "arc":
        c, r, a0, a1 = p.arc_fillet
        cc = rotate(np.asarray(c), -TWO_PI / n1)
        parts.append(_arc(lambda t: cc + r * np.stack([np.cos(t - TWO_PI / n1),
                                                       np.sin(t - TWO_PI / n1)], -1),
                          a0, a1, r * abs(a1 - a0)))
    else:
        g_end = b.psi1 if b.kind == "fillet" else g_lo
        length = abs(float(space.fillet_arc(g_start) - space.fillet_arc(g_end)))
        parts.append(_arc(lambda t: rotate(space.fillet_point(t), -TWO_PI / n1),
                          g_start, g_end, length))
    if b.kind == "pin":
        parts.append(_arc(lambda t: p.pin_point(0, t), e, b.psi1, p.rho * abs(e - b.psi1)))
    outer = np.concatenate(parts)  # S1
    length = abs(float(space.inner_arc(a.g2) - space.inner_arc(b.g2)))
    y = _arc(p.inner_point, b.g2, a.g2, length)  # S2
    inner = rotate(rotate(y, p.m21 * phi) + p.O2, -phi)  # S1
    poly = rotate(np.concatenate([outer, inner]), phi)
    # drop repeated points where the pieces meet
    keep = np.append(np.linalg.norm(np.diff(poly, axis=0), axis=-1) > 1e-12, True)
    return poly[keep]



def chamber_polygons(pair: PinGerotor, phi: float, contacts: list | None = None):
    """Polygons (fixed frame, unit scale) of the working chamber's section at angle phi.

    ``phi`` is the planar-chamber angle (section.py); empty outside the chamber's life.
    During the split phases only the sub-regions that belong to the chamber
    (:meth:`PinSpace.region_areas`).  The contact points bounding them are appended to
    ``contacts`` if given.
    """
    phi_i, phi_j, phi_f = chamber_life(pair)
    if not phi_i < phi < phi_f:
        return []
    space = pair.space
    cs, areas, touched = space.region_areas(phi)
    if pair.fillet_kind == "conjugate":
        birth = phi < phi_j + 1e-12
        split = phi < phi_j or phi > phi_f - (phi_j - phi_i)
    else:
        split, birth = False, False
    if len(cs) == 2 or not split:
        keep = list(range(len(areas)))
    else:
        keep = [k for k in range(len(areas)) if touched[k] == birth]
    keep = [k for k in keep if areas[k] > 0.0]
    if contacts is not None:
        for k in keep:
            contacts.extend([cs[k].point, cs[k + 1].point])
    return [_region_polygon(space, cs[k], cs[k + 1], phi) for k in keep]
