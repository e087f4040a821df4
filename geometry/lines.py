"""Sealing lines: a sealing point of the section swept along the rotors.

A point c(psi) of the section table (a contact, a tip) at the section of height z of
the chamber at angle phi sits at psi = phi - twist(z) and traces the space curve
(scale(z) c(psi), z); its length element is sqrt(1 + |scale' c - scale twist' c'|^2) dz
(c' = dc/dpsi, the rate).  Changing the variable to psi (dz = dpsi / twist') the line
at phi is an integral over the angles psi in [phi - wrap, phi] where the point seals.

The table knows the point and its rate at its nodes only, and where it begins, ends
or changes its chamber beyond between them where the family says so
(:attr:`.section.Track.cuts`; else halfway).  Each node stands for the angles from the
cut before it to the cut after it, and on each half of that the point is the cubic
Hermite interpolant of the cell on that side (between the node and its neighbour of
the same identity, else the other cell's, extrapolated): a *stretch*.  The integral is
split at every stretch end and integrated by Gauss-Legendre on each.  The cubic's
derivative errs by O(h^3), but over a whole cell that error integrates to the points'
own, zero at both nodes, so a line errs by O(h^4) (tests/test_twin_screw_lines.py),
not by the half step that a presence looked up at the nearest node leaves.

With scale 1 and a constant lead (straight and helical rotors) the integrand does not
depend on z, and the line at every phi is a difference of one cumulative integral;
otherwise each (phi, stretch) is integrated on its own.  Where the point jumps along a
band of contact the track carries the line across the section (a *bridge*), counted
at its height: scale(z) times its length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Gauss-Legendre nodes per stretch: the integrand is sqrt(1 + |a quadratic in psi|^2),
#: smooth on a stretch, and 4 nodes leave 5e-10 of it (3 left 4e-8 at 24 points per
#: period where the contact races round the male tip, tests/test_twin_screw_lines.py).
STRETCH_GAUSS = 4
#: Stretch-and-angle pairs integrated at once where the integrand depends on z (memory).
CHUNK = 400_000


@dataclass(frozen=True)
class Stretches:
    """Angles [a, b] on each of which a sealing point is the cubic Hermite interpolant
    of one table cell: from node u (angle ``psi_u``, point ``c_u``, rate ``r_u``) to
    node v, ``step`` further; and the chamber beyond them."""

    a: np.ndarray
    b: np.ndarray
    psi_u: np.ndarray
    step: np.ndarray
    c_u: np.ndarray  # (m, 2)
    c_v: np.ndarray
    r_u: np.ndarray
    r_v: np.ndarray
    offset: np.ndarray
    bridges: tuple = ()  # (psi, length, offset)

    def select(self, keep: np.ndarray) -> Stretches:
        return Stretches(*(getattr(self, f)[keep] for f in _FIELDS), ())

    def at(self, m, psi):
        """Point and rate of stretches ``m`` at angles ``psi`` (broadcast)."""
        step = self.step[m][..., None]
        s = (psi - self.psi_u[m])[..., None] / step
        s2, s3 = s * s, s * s * s
        c = ((2 * s3 - 3 * s2 + 1) * self.c_u[m] + (s3 - 2 * s2 + s) * step * self.r_u[m]
             + (3 * s2 - 2 * s3) * self.c_v[m] + (s3 - s2) * step * self.r_v[m])
        dc = ((6 * s2 - 6 * s) * (self.c_u[m] - self.c_v[m]) / step
              + (3 * s2 - 4 * s + 1) * self.r_u[m] + (3 * s2 - 2 * s) * self.r_v[m])
        return c, dc


_FIELDS = ("a", "b", "psi_u", "step", "c_u", "c_v", "r_u", "r_v", "offset")


def stretches(psi, points, rates, present, offset, ids, cuts=None, bridges=(),
              start=float("nan")) -> Stretches:
    """The stretches of a point tabulated on the uniform grid ``psi`` (module doc);
    ``start``: where a point present at the first node begins, before it."""
    n = len(psi)
    h = psi[1] - psi[0]
    cut = np.full(n, np.nan) if cuts is None else np.asarray(cuts, float)
    # A cut bounds the nodes either side; where they are not both there, it may lie
    # across the absent ones, up to the next node that is.
    k = np.arange(n)
    before = np.maximum.accumulate(np.where(present, k, -1))
    after = np.minimum.accumulate(np.where(present, k, n)[::-1])[::-1]
    # Beyond the first and last present nodes a cut is bounded by nothing: the family
    # may know the point's end a little past the table's ends.
    prev_node = np.concatenate([[-1], before[:-1]])
    next_node = np.concatenate([after[1:], [n]])
    floor = np.where(prev_node >= 0, psi[prev_node.clip(0)], -np.inf)
    ceil = np.where(next_node < n, psi[next_node.clip(max=n - 1)], np.inf)
    left = np.concatenate([[start], cut[:-1]])
    lo = np.where(np.isfinite(left), np.clip(left, floor, psi),
                  np.clip(psi - 0.5 * h, psi[0], psi[-1]))
    hi = np.where(np.isfinite(cut), np.clip(cut, psi, ceil),
                  np.clip(psi + 0.5 * h, psi[0], psi[-1]))
    link = present[:-1] & present[1:] & (ids[:-1] == ids[1:])
    nxt = np.append(link, False)
    prv = np.insert(link, 0, False)
    i = np.nonzero(present)[0]
    # Left half then right half of each node, in order of angle; each half takes the
    # cell on its side if the neighbour there is the same point, else the other cell.
    node = np.repeat(i, 2)
    left = np.tile([True, False], len(i))
    back = np.where(left, prv[node] | ~nxt[node], ~nxt[node] & prv[node])
    other = np.where(back, node - 1, node + 1)
    alone = ~(prv[node] | nxt[node])
    step = np.where(back, -h, h)
    # A point with no neighbour of its own moves at its rate: a linear Hermite cell.
    other = np.clip(other, 0, n - 1)
    c_v = np.where(alone[:, None], points[node] + step[:, None] * rates[node], points[other])
    r_v = np.where(alone[:, None], rates[node], rates[other])
    a = np.where(left, lo[node], psi[node])
    b = np.where(left, psi[node], hi[node])
    keep = b > a
    st = Stretches(a, b, psi[node], step, points[node], c_v, rates[node], r_v, offset[node])
    return Stretches(*(getattr(st, f)[keep] for f in _FIELDS), tuple(bridges))


def line_lengths(st: Stretches, sweep, phi: np.ndarray) -> dict[int, np.ndarray]:
    """Per offset of the chamber beyond (0: none, no line), the length at each ``phi``
    of the line the point sweeps."""
    out: dict[int, np.ndarray] = {}
    for d in np.unique(st.offset):
        if d != 0:
            out[int(d)] = _swept(st.select(st.offset == d), sweep, phi)
    if sweep.wrap == 0.0:
        return out  # a bridge lies in one section: no length along a straight rotor
    for psi_b, length, d in st.bridges:
        theta = phi - psi_b
        on = (theta >= 0.0) & (theta <= sweep.wrap)
        if d != 0 and on.any():
            z = sweep.z_of_twist(np.clip(theta, 0.0, sweep.wrap))
            out[int(d)] = out.get(int(d), np.zeros(len(phi))) + on * length * sweep.scale(z)
    return out


def _integrand(st, m, psi, z, sweep):
    """Line length per unit angle psi at height z (per unit z if the sweep has no
    twist)."""
    c, dc = st.at(m, psi)
    s, dt = sweep.scale(z), sweep.dtwist(z)
    tang = sweep.dscale(z)[..., None] * c - (s * dt)[..., None] * dc
    elem = np.sqrt(1.0 + np.sum(tang * tang, -1))
    return elem / dt if sweep.wrap > 0.0 else elem


def _swept(st: Stretches, sweep, phi):
    x, w = np.polynomial.legendre.leggauss(STRETCH_GAUSS)
    if sweep.wrap == 0.0:
        # Every section holds the chamber at phi itself: the point there, run along z.
        z, wz = sweep.nodes()
        m = np.searchsorted(st.b, phi, side="right")
        on = (m < len(st.a)) & (st.a[np.minimum(m, len(st.a) - 1)] <= phi)
        m = np.minimum(m, len(st.a) - 1)
        f = _integrand(st, m[:, None], phi[:, None], z[None, :], sweep)
        return np.where(on, f @ wz, 0.0)
    z, _ = sweep.nodes()
    if np.all(sweep.dscale(z) == 0.0) and np.ptp(sweep.dtwist(z)) == 0.0:
        return _cumulative(st, sweep, phi, x, w)
    out = np.zeros(len(phi))
    rows = max(1, CHUNK // max(len(st.a) * len(x), 1))
    m = np.arange(len(st.a))[None, :, None]
    for k in range(0, len(phi), rows):
        p = phi[k:k + rows, None]
        lo, hi = np.maximum(st.a[None, :], p - sweep.wrap), np.minimum(st.b[None, :], p)
        half = np.maximum(hi - lo, 0.0)[..., None] * 0.5
        psi = 0.5 * (lo + hi)[..., None] + half * x
        # Stretches outside the window have no weight; keep their z on the rotor.
        z = np.clip(sweep.z_of_twist(p[..., None] - psi), 0.0, sweep.length)
        out[k:k + rows] = np.sum(_integrand(st, m, psi, z, sweep) * half * w, (1, 2))
    return out


def _cumulative(st: Stretches, sweep, phi, x, w):
    """The line at phi as C(phi) - C(phi - wrap), C the integral from the first
    stretch up to an angle (the integrand does not depend on z)."""
    zero = np.zeros(1)
    m = np.arange(len(st.a))[:, None]
    half = 0.5 * (st.b - st.a)[:, None]
    f = _integrand(st, m, 0.5 * (st.a + st.b)[:, None] + half * x, zero, sweep)
    whole = np.concatenate([[0.0], np.cumsum(np.sum(f * half * w, 1))])

    def upto(u):
        k = np.searchsorted(st.b, u, side="right")  # stretches wholly below u
        j = np.minimum(k, len(st.a) - 1)
        part = np.clip(u - st.a[j], 0.0, None) * (k < len(st.a))
        g = _integrand(st, j[:, None], st.a[j][:, None] + 0.5 * part[:, None] * (x + 1.0),
                       zero, sweep)
        return whole[k] + np.sum(g * 0.5 * part[:, None] * w, 1)

    return upto(phi) - upto(phi - sweep.wrap)
