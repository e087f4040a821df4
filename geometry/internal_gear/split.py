"""The tooth space while fillet contacts split it, for many angles at once.

:meth:`PinSpace.region_areas` follows one angle in Python; the section tables need the
split phase at hundreds of angles, so this module does the same work on arrays.  The
fillet contact-time function ``t(g)`` is cut at its turning points into monotone
branches; a contact at time ``t`` lies on every branch whose range holds ``t``, found by
inverse interpolation on the bracket table and polished by Newton steps clipped to the
branch.  The contacts of each angle, in counter-clockwise order (pin -1, fillet contacts
by falling g, pin 0), are packed to the front of a padded array; the sub-regions between
consecutive contacts then carry areas, chords, torques and arc lengths as arrays too.

The turning points are where contacts are born and die in pairs (double roots); there
the section loads have square-root kinks, which is why the split phase needs a finer
angle grid than the rest of the chamber's life (see :mod:`.section`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.polynomial import chebyshev as C

from ..planar import TWO_PI, cross, rotate
from .space import PinSpace

#: Newton steps after inverse interpolation on the bracket table (quadratic convergence
#: from a start ~1e-7 off: two reach machine precision, the third is a margin).
NEWTON_STEPS = 3

#: Identity of the two pin contacts in :attr:`SplitRegions.branch` (fillet contacts are
#: numbered 1.. by branch), the same whatever the number of branches.
PIN_TRAILING = 0
PIN_LEADING = -1


@dataclass(frozen=True)
class SplitRegions:
    """Contacts and sub-regions of the space at ``n`` angles, padded to ``k`` contacts.

    Contacts of angle i are ``points[i, :count[i]]``; sub-region r of angle i lies
    between contacts r and r + 1 and exists when ``r < count[i] - 1``.
    """

    count: np.ndarray  # (n,) number of contacts
    points: np.ndarray  # (n, k, 2) fixed frame
    branch: np.ndarray  # (n, k) which contact: PIN_TRAILING, 1.. fillet branch, PIN_LEADING
    area: np.ndarray  # (n, k - 1)
    touched: np.ndarray  # (n, k - 1) bool
    perimeter_outer: np.ndarray  # (n, k - 1)
    perimeter_inner: np.ndarray  # (n, k - 1)

    @property
    def valid(self) -> np.ndarray:
        r = np.arange(self.area.shape[1])
        return r[None, :] < self.count[:, None] - 1


class SplitSpace:
    """Vectorised split-phase regions of a conjugate pair's tooth space."""

    def __init__(self, space: PinSpace):
        self.space = space
        self.pair = space.pair

    @cached_property
    def _branches(self):
        """Monotone pieces of t(g), each as (g_a > g_b, sorted bracket t, matching g)."""
        sp = self.space
        g, t = sp._bracket
        dt = np.diff(t)
        turn = np.nonzero(np.sign(dt[:-1]) * np.sign(dt[1:]) < 0.0)[0] + 1
        fit = sp._fillet_fit
        der = C.chebder(fit["ft"])
        der2 = C.chebder(der)
        edges = [g[0]]
        for i in turn:  # polish each turning point on the fit: t'(g) = 0
            x = sp._x(g[i])
            for _ in range(8):
                step = C.chebval(x, der) / C.chebval(x, der2)
                x = float(np.clip(x - step, sp._x(g[i - 1]), sp._x(g[i + 1])))
            edges.append(fit["g_lo"] + 0.5 * (x + 1.0) * (fit["g_hi"] - fit["g_lo"]))
        edges.append(g[-1])
        out = []
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            inside = (g > lo) & (g < hi)
            gb = np.concatenate([[lo], g[inside], [hi]])
            tb = sp.fillet_time(gb)
            order = np.argsort(tb)
            out.append((hi, lo, tb[order], gb[order]))
        return out[::-1]  # falling g: counter-clockwise contact order

    def fillet_contacts(self, t: np.ndarray) -> np.ndarray:
        """(n, branches) generation angles touching at times t (nan: none on a branch)."""
        sp = self.space
        fit = sp._fillet_fit
        der = C.chebder(fit["ft"])
        dxdg = 2.0 / (fit["g_hi"] - fit["g_lo"])
        cols = []
        for g_a, g_b, tb, gb in self._branches:
            on = (t >= tb[0] - 1e-12) & (t <= tb[-1] + 1e-12)
            g0 = np.interp(t, tb, gb)
            for _ in range(NEWTON_STEPS):
                slope = C.chebval(sp._x(g0), der) * dxdg
                safe = np.where(slope == 0.0, 1.0, slope)
                step = np.where(slope == 0.0, 0.0, (sp.fillet_time(g0) - t) / safe)
                g0 = np.clip(g0 - step, g_b, g_a)
            cols.append(np.where(on, g0, np.nan))
        g = np.stack(cols, -1)
        # Neighbouring branches share their turning point: one contact there, not two.
        same = np.abs(np.diff(g, axis=1)) < 1e-12
        g[:, 1:][same] = np.nan
        return g

    def regions(self, phi1) -> SplitRegions:
        sp, p = self.space, self.pair
        phi1 = np.atleast_1d(np.asarray(phi1, dtype=float))
        n1, e = p.lobes_outer, p.pin_edge
        t_lo, t_hi = sp.fillet_time_range
        half = 0.5 * (t_hi - t_lo)
        x = phi1 - TWO_PI / n1 - t_lo - half
        t = t_lo + half + (x - TWO_PI * np.round(x / TWO_PI))  # PinSpace.fillet_instant

        gf = self.fillet_contacts(t)
        n, nb = gf.shape
        k = nb + 2
        th_m, th_0 = sp.pin_theta(-1, phi1), sp.pin_theta(0, phi1)
        g2_f = gf + TWO_PI * np.ceil((phi1[:, None] - gf) / TWO_PI - 1e-12)
        g2 = np.column_stack([phi1 - TWO_PI / n1 + TWO_PI, g2_f, phi1])
        gfil = np.column_stack([np.full(n, p.fillet_range[1]), gf,
                                np.full(n, p.fillet_range[0])])
        pts = np.empty((n, k, 2))
        pts[:, 0] = rotate(p.pin_point(-1, th_m[:, None]).reshape(n, 2), phi1)
        pts[:, -1] = rotate(p.pin_point(0, th_0[:, None]).reshape(n, 2), phi1)
        fp = rotate(sp.fillet_point(np.nan_to_num(gf)), -TWO_PI / n1)
        pts[:, 1:-1] = rotate(fp, phi1[:, None])

        present = np.isfinite(g2)
        order = np.argsort(~present, axis=1, kind="stable")
        count = present.sum(1)

        def pack(a):
            idx = order if a.ndim == 2 else order[..., None]
            return np.take_along_axis(a, idx, axis=1)

        g2, gfil, pts = pack(g2), pack(gfil), pack(pts)
        branch = pack(np.broadcast_to(np.arange(k)[None, :], (n, k)).copy())
        branch[branch == k - 1] = PIN_LEADING
        r = np.arange(k - 1)[None, :]
        valid = r < count[:, None] - 1
        a_pin = np.broadcast_to(r == 0, valid.shape)
        b_pin = r == count[:, None] - 2
        g2a, g2b = g2[:, :-1], np.where(valid, g2[:, 1:], g2[:, :-1])
        ga = gfil[:, :-1]
        gb = np.where(valid, gfil[:, 1:], ga)
        g2a, g2b = np.nan_to_num(g2a), np.nan_to_num(g2b)
        ga, gb = np.nan_to_num(ga), np.nan_to_num(gb)

        outer = sp.fillet_integral(gb) - sp.fillet_integral(ga)
        outer = outer + np.where(a_pin, sp.pin_arc_integral(-1, th_m, -e)[:, None], 0.0)
        outer = outer + np.where(b_pin, sp.pin_arc_integral(0, e, th_0)[:, None], 0.0)
        o2 = rotate(p.O2, -p.m21 * phi1)[:, None, :]
        inner = (sp.inner_integral(g2a) - sp.inner_integral(g2b)
                 + 0.5 * cross(o2, p.inner_point(g2a) - p.inner_point(g2b)))
        touched = sp.fillet_time(0.5 * (ga + gb)) < t[:, None]

        per_o = np.abs(sp.fillet_arc(ga) - sp.fillet_arc(gb))
        per_o = per_o + np.where(a_pin, p.rho * np.abs(th_m + e)[:, None], 0.0)
        per_o = per_o + np.where(b_pin, p.rho * np.abs(e - th_0)[:, None], 0.0)
        per_i = np.abs(sp.inner_arc(g2a) - sp.inner_arc(g2b))
        zero = ~valid
        return SplitRegions(
            count=count,
            points=pts,
            branch=branch,
            area=np.where(zero, 0.0, outer + inner),
            touched=touched & valid,
            perimeter_outer=np.where(zero, 0.0, per_o),
            perimeter_inner=np.where(zero, 0.0, per_i),
        )
