"""The interlobe contact line of a rack-generated pair, straight from the rack.

Every rack point t meshes where the rack has shifted by s(t) (seed 003 Eq. 5), at the
fixed point X(t) = (r1 + a(t), b(t) + s(t)) (:mod:`.meshing`): the path of contact is the
curve X(t), reached at male angles s(t) / r1 modulo the lobe period.  In a helical pair
the section at height z is the planar pair at male angle theta - twist(z), so at male
angle theta the rotors touch along the space curves (X(t), z_k(t)) with
twist(z_k) = theta - s(t) / r1 + k period, wherever z_k lies on the rotors and X(t) in
both bores.  Seed 004's Fig. 2 plots that line's length against the male angle.

This is independent of the sections (:mod:`.regions`): it needs only the rack and the
law of gearing, which is what makes it a check of the sealing lines the chamber table
carries.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .meshing import rack_shift

#: Samples per rack arc on which the branches on the rotors are found (their ends are
#: then placed where z crosses the rotor's ends).
SAMPLES = 4000
#: Gauss-Legendre nodes and panels per branch (a smooth curve: 1e-10).
GAUSS_NODES = 8
GAUSS_PANELS = 16
#: Parameter tolerance of a branch's end where it leaves the rotors (an arc's parameter
#: runs over [0, 1]; 1e-14 is rounding).
EDGE_XTOL = 1e-14


def contact_line_length(pair, arcs, sweep, theta: float) -> float:
    """Length of the whole interlobe contact line at male angle ``theta`` (straight or
    helical sweep, constant or variable lead; ``arcs``: the rack that generated
    ``pair``)."""
    return float(contact_line_lengths(pair, arcs, sweep, [theta])[0])


def contact_line_lengths(pair, arcs, sweep, thetas) -> np.ndarray:
    """:func:`contact_line_length` at every male angle of ``thetas`` (the rack's samples
    and their meshing points, which do not depend on the angle, found once)."""
    g = pair.gearing
    period = 2.0 * math.pi / g.lobes_male
    r1, c = g.r1, g.centre_distance
    t = np.linspace(0.0, 1.0, SAMPLES)
    samples = []
    for arc in arcs:
        q = arc.eval(t, 0)
        s, _ = rack_shift(arc, t)
        x = np.stack([r1 + q[:, 0], q[:, 1] + s], -1)
        inside = ((np.linalg.norm(x, axis=-1) <= pair.male_radius)
                  & (np.linalg.norm(x - [c, 0.0], axis=-1) <= pair.female_radius))
        samples.append((arc, s / r1, inside))
    out = np.zeros(len(thetas))
    for i, theta in enumerate(thetas):
        for arc, psi, inside in samples:
            out[i] += _arc_length(pair, arc, sweep, float(theta), t, psi, inside, period)
    return out


def _arc_length(pair, arc, sweep, theta, t, psi, inside, period) -> float:
    """The contact line's length on the rotors from one rack arc (sampled at ``t``,
    meshing at male angles ``psi``, inside both bores where ``inside``)."""
    r1 = pair.gearing.r1
    if sweep.wrap == 0.0:
        # Straight: every contact of the section runs the whole length.
        return _count_contacts(psi, inside, theta, period) * sweep.length
    total = 0.0
    k_lo = math.floor((psi.min() - theta) / period) - 1
    k_hi = math.ceil((psi.max() - theta + sweep.wrap) / period) + 1
    for k in range(k_lo, k_hi + 1):
        # twist(z) = theta - s / r1 + k period, inverted by the sweep's own law (a
        # constant or a variable lead)
        z = sweep.z_of_twist(theta - psi + k * period)

        def z_at(u, k=k):
            twist = theta - rack_shift(arc, np.array([u]))[0][0] / r1 + k * period
            return float(sweep.z_of_twist(twist))

        ok = inside & (z >= 0.0) & (z <= sweep.length)
        for lo, hi in _runs(t, ok, z, z_at, sweep.length):
            total += _branch_length(pair, arc, lo, hi, sweep, theta + k * period)
    return total


def _runs(t, ok, z, z_at, length):
    """Parameter intervals where a branch lies on the rotors, their ends placed where z
    crosses 0 or L (a root of ``z_at``: near the end of an arc whose contact is nearly
    still, the line runs along z and a chord between samples misplaces that end by
    ~1e-6 of the line; a bore's edge stays at its sample)."""
    out = []
    idx = np.nonzero(ok)[0]
    if not len(idx):
        return out
    breaks = np.nonzero(np.diff(idx) > 1)[0]
    for a, b in zip(np.r_[0, breaks + 1], np.r_[breaks, len(idx) - 1], strict=True):
        i, j = idx[a], idx[b]
        lo, hi = t[i], t[j]
        if i > 0:
            lo = _edge(t[i - 1], t[i], z[i - 1], z[i], z_at, length, lo)
        if j < len(t) - 1:
            hi = _edge(t[j], t[j + 1], z[j], z[j + 1], z_at, length, hi)
        out.append((lo, hi))
    return out


def _edge(ta, tb, za, zb, z_at, length, fallback):
    for level in (0.0, length):
        if (za - level) * (zb - level) < 0.0:
            return brentq(lambda u, level=level: z_at(u) - level, ta, tb, xtol=EDGE_XTOL)
    return fallback


def _branch_length(pair, arc, lo, hi, sweep, shift) -> float:
    """Length of the space curve (X(t), z(t)) for t in [lo, hi] (Gauss-Legendre), where
    twist(z(t)) = shift - s(t) / r1."""
    x, w = np.polynomial.legendre.leggauss(GAUSS_NODES)
    edges = np.linspace(lo, hi, GAUSS_PANELS + 1)
    t = (0.5 * (edges[:-1, None] + edges[1:, None])
         + 0.5 * np.diff(edges)[:, None] * x[None, :]).ravel()
    wt = (0.5 * np.diff(edges)[:, None] * w[None, :]).ravel()
    r1 = pair.gearing.r1
    q1 = arc.eval(t, 1)
    s, ds = rack_shift(arc, t)
    dx = np.stack([q1[:, 0], q1[:, 1] + ds], -1)
    dz = (ds / r1) / sweep.dtwist(sweep.z_of_twist(shift - s / r1))
    return float(np.sum(np.sqrt(np.sum(dx * dx, -1) + dz * dz) * wt))


def _count_contacts(psi, inside, theta, period) -> int:
    """Contacts in the section at male angle theta: rack samples whose meshing angle
    passes theta (modulo the period) inside both bores."""
    phase = np.mod(psi - theta, period)
    cross = np.nonzero((np.abs(np.diff(phase)) > 0.5 * period) & inside[1:] & inside[:-1])[0]
    return len(cross)
