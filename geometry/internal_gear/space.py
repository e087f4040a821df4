"""Transverse chamber regions of a pin-generated internal gear pair.

A *tooth space* of the outer rotor lies between two neighbouring pins.  Each pin always
touches the inner rotor (the inner profile is the pins' envelope), so the space between
pin -1 and pin 0 is closed at both ends by those pin contacts; while it passes the
deep-mesh position the inner tip also touches the conjugate fillet, at one to three
points, which split the space into sub-regions.

Areas come from Green's theorem, ``A = 1/2 \\oint x \\times dx``, split into the pieces
of the two profiles between contact points: closed forms on the pin arcs, a Fourier
antiderivative on the (periodic, analytic) inner profile, and a Chebyshev antiderivative
on the fillet.  Nothing is polygonised, so areas are exact to the fits' precision
(about 1e-13 of D^2 with the default orders), independent of any sampling of angles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.polynomial import chebyshev as C

from ..planar import TWO_PI, cross, rotate
from ..spline import CubicSpline
from .pair import PinGerotor

#: Starting samples per inner lobe for the Fourier antiderivative, the cap, and the
#: relative size of the Fourier tail accepted as converged (analytic integrand: the
#: coefficients fall geometrically, so a 1e-13 tail means ~1e-13 relative area error).
INNER_SAMPLES = 1024
INNER_SAMPLES_MAX = 1 << 17
INNER_TAIL = 1e-13
#: Chebyshev degree of the fillet fits; the fillet is analytic on its closed range.
FILLET_DEGREE = 96
#: Dense grid used only to bracket the roots of the fillet contact-time function.
FILLET_BRACKET = 2049


@dataclass(frozen=True)
class Contact:
    """A contact point bounding a region: where it is and its parameters on both rotors."""

    kind: str  # "pin" or "fillet"
    point: np.ndarray  # fixed frame
    psi1: float  # pin angle theta (pin) or generation angle g (fillet)
    g2: float  # generation parameter of the inner-rotor point


class PinSpace:
    """Region geometry of the tooth space between pin -1 and pin 0 (fillet -1)."""

    def __init__(self, pair: PinGerotor):
        self.pair = pair

    # ------------------------------------------------------------ inner profile integral
    @cached_property
    def _inner_table(self):
        """Periodic part of G2 on a fine grid, from a converged Fourier antiderivative.

        The integrand is analytic in g but, for lambda close to 1, sharply peaked where
        the pin passes the pitch point; the sample count doubles until the Fourier tail
        is below INNER_TAIL of the largest coefficient.
        """
        p = self.pair
        n = INNER_SAMPLES
        while True:
            g = np.arange(n) * TWO_PI / n
            f = 0.5 * cross(p.inner_point(g), p.inner_derivative(g))
            coef = np.fft.rfft(f) / n
            tail = np.abs(coef[-max(n // 16, 4) :]).max()
            if tail <= INNER_TAIL * np.abs(coef).max() or n >= INNER_SAMPLES_MAX:
                break
            n *= 2
        k = np.arange(1, len(coef))
        anti = np.zeros_like(coef)
        anti[1:] = coef[1:] / (1j * k)
        # Periodic part of the antiderivative, sampled on the grid and closed periodically.
        periodic = np.fft.irfft(anti * n, n)
        periodic -= periodic[0]
        gp = np.append(g, TWO_PI)
        spline = CubicSpline(gp, np.append(periodic, periodic[0]), bc_type="periodic")
        return coef[0].real, spline

    @cached_property
    def inner_lobe_integral(self) -> float:
        """1/2 \\int y x dy over one inner lobe (g from 0 to 2 pi); negative: clockwise."""
        return float(self._inner_table[0] * TWO_PI)

    def inner_integral(self, g):
        """G2(g) = 1/2 \\int_0^g y x dy/dg dg for any g."""
        g = np.asarray(g, dtype=float)
        mean, spline = self._inner_table
        return mean * g + spline(np.mod(g, TWO_PI))

    # ------------------------------------------------------------------ fillet fits
    @cached_property
    def _fillet_fit(self):
        p = self.pair
        g_lo, g_hi = p.fillet_range
        x = np.cos(np.pi * (np.arange(FILLET_DEGREE + 1) + 0.5) / (FILLET_DEGREE + 1))
        g = 0.5 * (g_lo + g_hi) + 0.5 * (g_hi - g_lo) * x
        t, pt = p.fillet(g)
        t_mid, _ = p.fillet(0.5 * (g_lo + g_hi))
        t = t_mid + np.angle(np.exp(1j * (t - t_mid)))  # unwrap around the tip instant

        def fit(v):
            return C.chebfit(x, v, FILLET_DEGREE)

        fx, fy, ft = fit(pt[:, 0]), fit(pt[:, 1]), fit(t)
        scale = 2.0 / (g_hi - g_lo)  # dx/dg
        dfx, dfy = C.chebder(fx) * scale, C.chebder(fy) * scale
        integrand = 0.5 * (
            C.chebmul(fx, dfy)[: FILLET_DEGREE + 1] - C.chebmul(fy, dfx)[: FILLET_DEGREE + 1]
        )
        # Antiderivative in x, rescaled to g, zero at g_hi (the pin-0 end).
        anti = C.chebint(integrand, lbnd=1.0) / scale
        return {"fx": fx, "fy": fy, "ft": ft, "anti": anti, "g_lo": g_lo, "g_hi": g_hi}

    def _x(self, g):
        f = self._fillet_fit
        return (2.0 * np.asarray(g) - f["g_lo"] - f["g_hi"]) / (f["g_hi"] - f["g_lo"])

    def fillet_point(self, g):
        """Fillet 0 point (S1) at generation angle g, from the fit."""
        f = self._fillet_fit
        x = self._x(g)
        return np.stack([C.chebval(x, f["fx"]), C.chebval(x, f["fy"])], -1)

    def fillet_time(self, g):
        """Outer angle (unwrapped around the deep mesh) at which fillet 0 touches psi2(g)."""
        return C.chebval(self._x(g), self._fillet_fit["ft"])

    def fillet_integral(self, g):
        """H(g) = 1/2 \\int_{g_hi}^{g} F x dF; F turns counter-clockwise as g decreases."""
        return C.chebval(self._x(g), self._fillet_fit["anti"])

    @cached_property
    def fillet_full_integral(self) -> float:
        """1/2 \\int x x dx along the whole fillet 0, counter-clockwise (S1)."""
        if self.pair.fillet_kind == "arc":
            c, r, a0, a1 = self.pair.arc_fillet
            e0 = np.array([math.cos(a0), math.sin(a0)])
            e1 = np.array([math.cos(a1), math.sin(a1)])
            return float(0.5 * (r * r * (a1 - a0) + r * cross(c, e1 - e0)))
        return float(self.fillet_integral(self._fillet_fit["g_lo"]))

    @cached_property
    def fillet_length(self) -> float:
        if self.pair.fillet_kind == "arc":
            _, r, a0, a1 = self.pair.arc_fillet
            return float(r * abs(a1 - a0))
        return float(self._fillet_arc_table[1][-1])

    @cached_property
    def _bracket(self):
        f = self._fillet_fit
        g = np.linspace(f["g_lo"], f["g_hi"], FILLET_BRACKET)
        return g, self.fillet_time(g)

    @cached_property
    def fillet_time_range(self) -> tuple[float, float]:
        """First and last outer angle at which fillet 0 carries a contact."""
        _, t = self._bracket
        return float(t.min()), float(t.max())

    def fillet_contacts(self, t):
        """Generation angles g (descending: counter-clockwise order) touching at time t.

        ``t`` is an outer angle for fillet 0 (unwrapped like :meth:`fillet_time`).
        """
        g, tt = self._bracket
        d = tt - t
        idx = np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) <= 0.0)[0]
        roots = []
        for i in idx:
            if d[i] == 0.0 and i > 0 and roots and abs(roots[-1] - g[i]) < 1e-12:
                continue
            g0 = g[i] - d[i] * (g[i + 1] - g[i]) / (d[i + 1] - d[i]) if d[i + 1] != d[i] else g[i]
            for _ in range(3):  # Newton polish on the fit
                x = self._x(g0)
                dt = C.chebval(x, C.chebder(self._fillet_fit["ft"])) * 2.0 / (
                    self._fillet_fit["g_hi"] - self._fillet_fit["g_lo"]
                )
                if dt == 0.0:
                    break
                step = (self.fillet_time(g0) - t) / dt
                g_new = float(np.clip(g0 - step, g[i], g[i + 1]))
                if abs(g_new - g0) < 1e-15:
                    break
                g0 = g_new
            roots.append(float(g0))
        return sorted(set(np.round(roots, 14)), reverse=True)

    # ------------------------------------------------------------------ pin contacts
    def pin_theta(self, k: int, phi1):
        """Contact angle on pin k at outer angle phi1 (0 faces O1, ccw positive)."""
        p = self.pair
        phi1 = np.asarray(phi1, dtype=float)
        c = p.pin_centre(k)
        pp = rotate(np.broadcast_to(p.P, phi1.shape + (2,)), -phi1)  # pitch point in S1
        d = pp - c
        inward = -c / p.a
        return np.arctan2(cross(inward, d), np.sum(inward * d, axis=-1))

    def pin_arc_integral(self, k: int, th_a, th_b):
        """1/2 \\int x x dx along pin k from th_a to th_b (S1)."""
        p = self.pair
        c = p.pin_centre(k)
        inward = -c / p.a
        ea, eb = rotate(inward, th_a), rotate(inward, th_b)
        return 0.5 * (p.rho**2 * (th_b - th_a) + p.rho * cross(c, eb - ea))

    # ------------------------------------------------------------------ regions
    def fillet_instant(self, phi1: float) -> float:
        """Fillet-0 time equivalent to fillet -1 at phi1, unwrapped like fillet_time."""
        t_lo, t_hi = self.fillet_time_range
        t = phi1 - TWO_PI / self.pair.lobes_outer
        half = 0.5 * (t_hi - t_lo)
        return t_lo + half + math.remainder(t - t_lo - half, TWO_PI)

    def contacts(self, phi1: float) -> list[Contact]:
        """Contacts bounding the space between pin -1 and pin 0, counter-clockwise."""
        p = self.pair
        n1 = p.lobes_outer
        out = []
        th_m = float(self.pin_theta(-1, phi1))
        g_m = phi1 - TWO_PI / n1 + TWO_PI
        out.append(Contact("pin", self._to_fixed(p.pin_point(-1, th_m), phi1), th_m, g_m))
        conjugate = p.fillet_kind == "conjugate"
        t_lo, t_hi = self.fillet_time_range if conjugate else (0.0, -1.0)
        t = self.fillet_instant(phi1) if conjugate else 0.0
        if conjugate and t_lo - 1e-12 <= t <= t_hi + 1e-12:
            g0 = phi1  # inner parameter touching pin 0
            for gc in self.fillet_contacts(t):
                j = math.ceil((g0 - gc) / TWO_PI - 1e-12)
                g2 = gc + TWO_PI * j
                pt = rotate(self.fillet_point(gc), -TWO_PI / n1)
                out.append(Contact("fillet", self._to_fixed(pt, phi1), gc, g2))
        th_0 = float(self.pin_theta(0, phi1))
        out.append(Contact("pin", self._to_fixed(p.pin_point(0, th_0), phi1), th_0, phi1))
        return out

    def _to_fixed(self, s1_point, phi1):
        return rotate(np.asarray(s1_point, dtype=float), phi1)

    def _outer_piece(self, a: Contact, b: Contact) -> float:
        """1/2 \\int x x dx along the outer profile from contact a to b (ccw), S1 frame."""
        p = self.pair
        e = p.pin_edge
        g_hi = self._fillet_fit["g_hi"]
        g_lo = self._fillet_fit["g_lo"]
        total = 0.0
        if a.kind == "pin":  # leave pin -1 toward its edge facing pin 0
            total += self.pin_arc_integral(-1, a.psi1, -e)
            g_start = g_hi
        else:
            g_start = a.psi1
        g_end = b.psi1 if b.kind == "fillet" else g_lo
        if p.fillet_kind == "arc":  # never touched, so always crossed whole
            total += self.fillet_full_integral
        else:
            total += self.fillet_integral(g_end) - self.fillet_integral(g_start)
        if b.kind == "pin":
            total += self.pin_arc_integral(0, e, b.psi1)
        return float(total)

    def _inner_piece(self, b: Contact, a: Contact, phi1: float) -> float:
        """1/2 \\int x x dx along the inner profile from contact b back to a, S1 frame."""
        p = self.pair
        ya, yb = p.inner_point(a.g2), p.inner_point(b.g2)
        o2 = rotate(p.O2, -p.m21 * phi1)
        return float(
            self.inner_integral(a.g2) - self.inner_integral(b.g2) + 0.5 * cross(o2, ya - yb)
        )

    def region_areas(self, phi1: float) -> tuple[list[Contact], np.ndarray, np.ndarray]:
        """Contacts, sub-region areas and which sub-regions are already *touched*.

        A sub-region is touched when the fillet points on its boundary have met the
        inner rotor already (their contact time is past): it belongs to the chamber
        born in this passage of the deep mesh; an untouched one belongs to the chamber
        that dies in it.  Contact time minus now changes sign at every contact, so the
        two kinds alternate, whatever the number of contacts.
        """
        cs = self.contacts(phi1)
        t = self.fillet_instant(phi1)
        g_hi, g_lo = self._fillet_fit["g_hi"], self._fillet_fit["g_lo"]
        areas, touched = [], []
        for a, b in zip(cs[:-1], cs[1:], strict=True):
            areas.append(self._outer_piece(a, b) + self._inner_piece(b, a, phi1))
            g_a = g_hi if a.kind == "pin" else a.psi1
            g_b = g_lo if b.kind == "pin" else b.psi1
            touched.append(bool(self.fillet_time(0.5 * (g_a + g_b)) < t))
        return cs, np.array(areas), np.array(touched)

    # ------------------------------------------------------------------ vectorised space
    def whole_space(self, phi1):
        """Area, contacts (trailing on pin -1, leading on pin 0) of the undivided space.

        Valid whenever no fillet contact splits the space; vectorised over phi1.
        Returns (area, trailing point, leading point), points in the fixed frame.
        """
        p = self.pair
        n1 = p.lobes_outer
        phi1 = np.asarray(phi1, dtype=float)
        e = p.pin_edge
        th_m, th_0 = self.pin_theta(-1, phi1), self.pin_theta(0, phi1)
        g_0 = phi1
        g_m = phi1 + TWO_PI * (n1 - 1) / n1
        o2 = rotate(np.broadcast_to(p.O2, phi1.shape + (2,)), -p.m21 * phi1)
        outer = (
            self.pin_arc_integral(-1, th_m, -e)
            + self.fillet_full_integral
            + self.pin_arc_integral(0, e, th_0)
        )
        inner = (
            self.inner_integral(g_m)
            - self.inner_integral(g_0)
            + 0.5 * cross(o2, p.inner_point(g_m) - p.inner_point(g_0))
        )
        trail = rotate(p.pin_point(-1, th_m[..., None]).reshape(phi1.shape + (2,)), phi1)
        lead = rotate(p.pin_point(0, th_0[..., None]).reshape(phi1.shape + (2,)), phi1)
        return outer + inner, trail, lead

    # ------------------------------------------------------------------ arc lengths
    @cached_property
    def _inner_arc_table(self):
        # |dpsi2/dg| has a kink where it vanishes at the undercut limit, so a dense
        # trapezoid table (relative error ~1e-7) is used instead of the Fourier series.
        g = np.linspace(0.0, TWO_PI, 8193)
        speed = np.linalg.norm(self.pair.inner_derivative(g), axis=-1)
        s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(g))])
        return g, s

    def inner_arc(self, g):
        """Arc length of psi2 from g = 0 to g (any g, lobes repeat)."""
        gt, st = self._inner_arc_table
        g = np.asarray(g, dtype=float)
        k = np.floor(g / TWO_PI)
        return k * st[-1] + np.interp(g - k * TWO_PI, gt, st)

    @cached_property
    def _fillet_arc_table(self):
        f = self._fillet_fit
        g = np.linspace(f["g_lo"], f["g_hi"], 4097)
        pt = self.fillet_point(g)
        seg = np.linalg.norm(np.diff(pt, axis=0), axis=-1)
        return g, np.concatenate([[0.0], np.cumsum(seg)])

    def fillet_arc(self, g):
        """Fillet arc length from g_lo to g."""
        gt, st = self._fillet_arc_table
        return np.interp(g, gt, st)

    def whole_space_perimeters(self, phi1):
        """Outer and inner arc lengths of the undivided space (vectorised)."""
        p = self.pair
        phi1 = np.asarray(phi1, dtype=float)
        e = p.pin_edge
        th_m, th_0 = self.pin_theta(-1, phi1), self.pin_theta(0, phi1)
        outer = p.rho * (np.abs(th_m + e) + np.abs(e - th_0)) + self.fillet_length
        g_m = phi1 + TWO_PI * (p.lobes_outer - 1) / p.lobes_outer
        inner = np.abs(self.inner_arc(g_m) - self.inner_arc(phi1))
        return outer, inner
