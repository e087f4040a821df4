"""Pin-generated internal gear pair (seed 000, section 2; Vecchiato et al. 2001).

The outer rotor 1 carries ``N1`` circular pins of radius ``rho`` on the radius ``a``;
its conjugate mate, the inner rotor 2 with ``N2 = N1 - 1`` lobes, is the envelope of
the pin circle in the inner rotor's frame (an inner offset of an extended epicycloid).
Between the pins the outer profile is closed by a fillet: by default the conjugate one
(the envelope of the inner rotor in the outer frame), which makes the smallest chamber
area zero.

Frames (all lengths in metres, angles in radians):

* fixed frame: outer axis ``O1 = (0, 0)``, inner axis ``O2 = (0, E)``, pitch point
  ``P = (0, r1)`` with ``r1 = N1 E``; both rotors turn counter-clockwise,
  ``phi2 = m21 phi1`` with ``m21 = N1 / N2``;
* S1 (outer rotor) and S2 (inner rotor, origin ``O2``) turn with their rotors and
  coincide with the fixed frame at ``phi1 = 0``; pin 0 sits on +y.

Everything is parametrised by the *generation angle* ``g``: the outer-rotor angle at
which pin 0 touches the inner profile point ``psi2(g)``.  The inner profile is analytic
in ``g`` (smooth even at the undercut limit, where its arc-length speed vanishes), and
so are its normals, which is what makes the chamber areas converge fast.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rotorflow.errors import CaseError

from ..family import Rotor, RotorPair
from ..planar import TWO_PI, cross, rotate
from ..scalar import root
from .limits import pressure_angle_at_pitch, sigma_limit

#: A pin above its undercut limit by this share is the limit written with fewer digits
#: (sigma_bar = 1.0000001, a sigma copied from a table), not an undercut: sigma_bar = 1
#: is the paper's optimum and must survive a round trip through decimal input.
ROUNDING = 1e-6
#: An arc fillet may touch the conjugate one at the pin edges, where both start: the
#: depth there is round-off, and anything deeper (relative to D) is interference.
ARC_TOLERANCE = 1e-9

#: Default radius of the casing bore (the outer rotor's outside) per outer diameter D / 2.
BORE_FACTOR = 1.25


@dataclass(frozen=True)
class PinGerotor(RotorPair):
    """A conjugate pin-generated internal gear pair of maximum outer diameter ``diameter``.

    The internal-gear family's :class:`~..family.RotorPair`: rotor 0 (the reference) is
    the outer rotor, rotor 1 the inner; the interface methods are at the end.
    """

    family = "internal-gear"

    lobes_outer: int
    lam: float
    sigma: float
    diameter: float
    #: "conjugate" (zero smallest chamber) or "arc": a circular arc between the pin
    #: edges through an apex on the fillet's mid-line at ``fillet_apex_diameter / 2``.
    fillet_kind: str = "conjugate"
    fillet_apex_diameter: float | None = None

    def __post_init__(self):
        if self.lobes_outer < 2:
            raise CaseError(f"lobes_outer must be at least 2, got {self.lobes_outer}")
        if not self.lam > 1.0:
            raise CaseError(f"lambda must be greater than 1, got {self.lam}")
        if not self.diameter > 0.0:
            raise CaseError(f"diameter must be positive, got {self.diameter}")
        if not self.sigma > 0.0:
            raise CaseError(f"sigma must be positive, got {self.sigma}")
        lim = self.sigma_lim
        if self.sigma > lim * (1.0 + ROUNDING):
            raise CaseError(
                f"sigma = {self.sigma:.6g} is above the undercut limit sigma_lim = {lim:.6g} "
                f"for N1={self.lobes_outer}, lambda={self.lam:g} (seed 000 Eq. 4)"
            )
        if self.fillet_kind not in ("conjugate", "arc"):
            raise CaseError(f"unknown fillet '{self.fillet_kind}' (conjugate or arc)")
        if self.fillet_kind == "arc":
            self._check_arc_fillet()

    # ---------------------------------------------------------------- dimensions (Eq. 1)
    @cached_property
    def sigma_lim(self) -> float:
        return sigma_limit(self.lobes_outer, self.lam)

    @property
    def lobes_inner(self) -> int:
        return self.lobes_outer - 1

    @property
    def m21(self) -> float:
        return self.lobes_outer / self.lobes_inner

    @cached_property
    def E(self) -> float:
        """Centre distance, Eq. 1."""
        n1 = self.lobes_outer
        return self.diameter / (2.0 * n1 * (self.lam - self.sigma + 2.0 / n1))

    @property
    def r1(self) -> float:
        return self.lobes_outer * self.E

    @property
    def a(self) -> float:
        return self.lam * self.r1

    @property
    def rho(self) -> float:
        return self.sigma * self.r1

    @property
    def O2(self) -> np.ndarray:
        return np.array([0.0, self.E])

    @property
    def P(self) -> np.ndarray:
        return np.array([0.0, self.r1])

    @property
    def pressure_angle(self) -> float | None:
        return pressure_angle_at_pitch(self.lam, self.sigma)

    @property
    def pin_edge(self) -> float:
        """Half-angle of the pin arc that ever carries contact: asin(1/lambda).

        The contact normal of a pin passes through the pitch point, which runs on the
        pitch circle of radius r1 < a; the normals from the pin centre to that circle
        fill a cone of half-angle asin(r1/a).
        """
        return math.asin(1.0 / self.lam)

    def pin_centre(self, k):
        """Centre of pin k in S1 (pin 0 on +y, counter-clockwise numbering)."""
        ang = math.pi / 2.0 + TWO_PI * np.asarray(k, dtype=float) / self.lobes_outer
        return self.a * np.stack([np.cos(ang), np.sin(ang)], -1)

    def pin_point(self, k, theta):
        """Point of pin k at pin angle theta (0 faces O1, counter-clockwise positive), S1."""
        c = self.pin_centre(k)
        inward = -c / self.a
        return c + self.rho * rotate(inward, theta)

    # ---------------------------------------------------------------- inner profile psi2
    def _generation(self, g):
        """Contact point X(g) and unit normal u(g) of pin 0 at outer angle g, fixed frame."""
        g = np.asarray(g, dtype=float)
        c = self.a * np.stack([-np.sin(g), np.cos(g)], -1)
        d = self.P - c
        u = d / np.linalg.norm(d, axis=-1)[..., None]
        return c + self.rho * u, u

    def inner_point(self, g):
        """psi2(g) in S2 (origin O2); g spans [0, 2 pi N2) for the closed profile."""
        x, _ = self._generation(g)
        return rotate(x - self.O2, -self.m21 * np.asarray(g, dtype=float))

    def inner_normal(self, g):
        """Unit normal of psi2 at g in S2, pointing out of the inner rotor."""
        _, u = self._generation(g)
        return -rotate(u, -self.m21 * np.asarray(g, dtype=float))

    # ---------------------------------------------------------------- conjugate fillet
    def _fillet_raw(self, g):
        """Second solution of the equation of meshing for psi2(g).

        Returns (phi1 mod 2 pi, S1 point) of the fillet between pin 0 and pin 1 that
        psi2(g) generates.  The normal line of psi2(g) at inner angle p must pass through
        the pitch point: r2 cos(p + beta) = -(y x n), two roots per g; one is the
        generating instant m21 g (the pin contact), the other is the fillet contact.
        """
        g = np.asarray(g, dtype=float)
        y = self.inner_point(g)
        n = self.inner_normal(g)
        r2 = self.lobes_inner * self.E
        beta = np.arctan2(n[..., 1], n[..., 0])
        c = np.clip(-cross(y, n) / r2, -1.0, 1.0)
        acos = np.arccos(c)
        p_gen = self.m21 * g
        p1, p2 = acos - beta, -acos - beta
        d1 = np.abs(np.angle(np.exp(1j * (p1 - p_gen))))
        d2 = np.abs(np.angle(np.exp(1j * (p2 - p_gen))))
        p = np.where(d1 > d2, p1, p2)
        phi1 = p / self.m21
        x = rotate(y, p) + self.O2
        pt = rotate(x, -phi1)
        # Move the point into the sector of fillet 0 (between pins 0 and 1) by adding
        # whole inner turns: each adds 2 pi / m21 to phi1 and turns the point by 2 pi / N1.
        n1 = self.lobes_outer
        ang = np.arctan2(pt[..., 1], pt[..., 0]) - math.pi / 2.0
        k = np.mod(-np.floor(ang / (TWO_PI / n1)), n1)
        phi1 = np.mod(phi1 + k * TWO_PI / self.m21, TWO_PI)
        pt = rotate(pt, k * TWO_PI / n1)
        return phi1, pt

    @cached_property
    def fillet_range(self) -> tuple[float, float]:
        """Generation angles (g_lo, g_hi) where the conjugate fillet meets the pin arcs.

        The fillet is generated by the inner tip (g = pi); it ends where it reaches the
        edge of the pin cone, at polar angle ``edge`` on either side of the fillet middle.
        """
        edge_pt = self.pin_point(0, -self.pin_edge)  # edge of pin 0 toward pin 1
        edge_ang = math.atan2(edge_pt[1], edge_pt[0])
        mid = math.pi / 2.0 + math.pi / self.lobes_outer

        def off(g):
            _, pt = self._fillet_raw(g)
            return np.abs(np.arctan2(pt[..., 1], pt[..., 0]) - mid) - (mid - edge_ang)

        # off < 0 inside the fillet sector: bracket the end by a scan from the tip.
        gs = math.pi + np.linspace(0.0, math.pi, 4001)
        vals = off(gs)
        k = int(np.argmax(vals > 0.0))
        if k == 0:
            raise CaseError("degenerate pin profile: no conjugate fillet between pins")
        g_hi = root(lambda g: float(off(g)), gs[k - 1], gs[k], xtol=0.0)
        return 2.0 * math.pi - g_hi, g_hi

    def fillet(self, g):
        """Fillet between pin 0 and pin 1: (phi1 of contact, S1 point) for g in fillet_range."""
        return self._fillet_raw(g)

    # ---------------------------------------------------------------- derivatives
    def inner_derivative(self, g):
        """d psi2 / dg in S2 (analytic)."""
        g = np.asarray(g, dtype=float)
        c = self.a * np.stack([-np.sin(g), np.cos(g)], -1)
        dc = self.a * np.stack([-np.cos(g), -np.sin(g)], -1)
        d = self.P - c
        nd = np.linalg.norm(d, axis=-1)[..., None]
        u = d / nd
        du = (-dc - u * np.sum(u * -dc, axis=-1)[..., None]) / nd
        x = c + self.rho * u - self.O2
        dx = dc + self.rho * du
        jx = np.stack([-x[..., 1], x[..., 0]], -1)
        return rotate(dx - self.m21 * jx, -self.m21 * g)

    # ---------------------------------------------------------------- arc fillet
    @cached_property
    def arc_fillet(self) -> tuple[np.ndarray, float, float, float]:
        """Circle (centre, radius) and end angles about it of the arc fillet 0, ccw."""
        return self._arc_circle(self.apex_diameter)

    def _arc_circle(self, apex_d: float) -> tuple[np.ndarray, float, float, float]:
        j0 = self.pin_point(0, -self.pin_edge)
        j1 = self.pin_point(1, self.pin_edge)
        mid = math.pi / 2.0 + math.pi / self.lobes_outer
        apex = 0.5 * apex_d * np.array([math.cos(mid), math.sin(mid)])
        # Circle through three points: the centre is on the mid-line (symmetry).
        u = np.array([math.cos(mid), math.sin(mid)])
        # |c - apex| = |c - j0| with c = t u: solve for t.
        t = (apex @ apex - j0 @ j0) / (2.0 * (apex - j0) @ u)
        centre = t * u
        radius = float(np.linalg.norm(apex - centre))
        a0 = math.atan2(*(j0 - centre)[::-1])
        a1 = math.atan2(*(j1 - centre)[::-1])
        a_apex = math.atan2(*(apex - centre)[::-1])
        # Go from j0 to j1 the way that passes through the apex.
        span = (a1 - a0) % TWO_PI
        if (a_apex - a0) % TWO_PI > span:
            span -= TWO_PI
        return centre, radius, a0, a0 + span

    def _infringement(self, apex_d: float) -> float:
        """How far [m] the arc through an apex at ``apex_d / 2`` cuts into the conjugate
        fillet (negative: it clears it)."""
        centre, radius, _, _ = self._arc_circle(apex_d)
        conj = PinGerotor(self.lobes_outer, self.lam, self.sigma, self.diameter)
        g_lo, g_hi = conj.fillet_range
        _, pts = conj.fillet(np.linspace(g_lo, g_hi, 401))
        # The fluid side of the arc is inside its circle; a conjugate-fillet point
        # outside it would be cut by the arc: the rotors would interfere.
        return float((np.linalg.norm(pts - centre, axis=-1) - radius).max())

    @cached_property
    def apex_diameter(self) -> float:
        """The arc fillet's apex diameter: the one given, or else the smallest at or
        above D whose arc clears the conjugate fillet (at D itself a short pin's arc
        cuts into it, so D alone is no default for every pair)."""
        if self.fillet_apex_diameter is not None:
            return self.fillet_apex_diameter
        tol = ARC_TOLERANCE * self.diameter
        lo = hi = self.diameter
        while self._infringement(hi) > tol:
            lo, hi = hi, 1.5 * hi  # a deeper apex bulges the arc away from the fillet
        while hi - lo > 1e-7 * self.diameter:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self._infringement(mid) > tol else (lo, mid)
        return hi

    def _check_arc_fillet(self):
        apex_d = self.apex_diameter
        if apex_d < self.diameter * (1.0 - 1e-12):
            raise CaseError(
                f"fillet apex diameter {apex_d:.6g} m is inside the conjugate fillet "
                f"(smallest allowed: D = {self.diameter:.6g} m)"
            )
        worst = self._infringement(apex_d)
        if worst > ARC_TOLERANCE * self.diameter:
            raise CaseError(
                f"the arc fillet infringes the conjugate fillet by {worst * 1e6:.3g} um: "
                "raise fillet_apex_diameter_mm"
            )

    # ---------------------------------------------------------------- the family seam
    @cached_property
    def space(self):
        """The tooth space's region geometry (fits built once per pair)."""
        from .space import PinSpace

        return PinSpace(self)

    @cached_property
    def rotors(self) -> tuple[Rotor, Rotor]:
        from .profiles import inner_profile, outer_profile

        return (Rotor("outer", outer_profile(self), (0.0, 0.0), self.lobes_outer, 1.0, self.r1),
                Rotor("inner", inner_profile(self), (0.0, self.E), self.lobes_inner, self.m21,
                      self.lobes_inner * self.E))

    @property
    def split_phase(self) -> float:
        if self.fillet_kind != "conjugate":
            return 0.0
        t_lo, t_hi = self.space.fillet_time_range
        return t_hi - t_lo

    def section(self, points_per_period: int):
        from .section import section_chamber

        return section_chamber(self, points_per_period)

    def chamber_polygons(self, phi: float, contacts: list | None = None):
        from .chambers import chamber_polygons

        return chamber_polygons(self, phi, contacts)

    @property
    def working_area(self) -> float:
        """The fluid region inside the outer rotor: its chambers plus the inner rotor."""
        return self.rotors[0].profile.area

    def casing_bores(self, bore_radius: float | None = None):
        """The bore the outer rotor turns in (its outside), about O1."""
        r = 0.5 * BORE_FACTOR * self.diameter if bore_radius is None else bore_radius
        return (((0.0, 0.0), r),)

    def gap_walls(self, angle: float, gap: float, **options):
        from .sealing_gap import sealing_gap_walls

        return sealing_gap_walls(self, angle, gap, **options)

    def wall_speeds(self, angle: float, omega_reference: float) -> tuple[float, float]:
        from .sealing_gap import sealing_wall_speeds

        return sealing_wall_speeds(self, angle, omega_reference)

    def figures(self) -> dict:
        """Seed 000's design figures of the pair (Eqs. 1, 4, 5)."""
        alpha = self.pressure_angle
        d = self.diameter
        return {
            "lobes_outer": self.lobes_outer,
            "lobes_inner": self.lobes_inner,
            "m21": self.m21,
            "lambda": self.lam,
            "sigma": self.sigma,
            "sigma_lim": self.sigma_lim,
            "sigma_bar": self.sigma / self.sigma_lim,
            "E_over_D": self.E / d,
            "a_over_D": self.a / d,
            "rho_over_D": self.rho / d,
            "pressure_angle_deg": None if alpha is None else math.degrees(alpha),
            "pitch_point_contact": alpha is not None,
        }

    def contact_table(self, step_deg: float = 1.0, span_deg: float | None = None):
        from .contacts import contact_table

        return contact_table(self, step_deg, span_deg)

    def digest(self) -> str:
        """A short digest of the pair's defining numbers (CFD run folders)."""
        import hashlib

        text = repr((self.lobes_outer, self.lam, self.sigma, self.diameter, self.fillet_kind,
                     self.fillet_apex_diameter))
        return hashlib.sha256(text.encode()).hexdigest()[:8]

    def leakage_paths(self, far_lines, track_lines=None, opening_areas=None) -> tuple:
        """Interlobe lines to +-1 and every farther neighbour found, end faces to suction
        (low-pressure face) and discharge (high-pressure face)."""
        from ..table import internal_gear_paths

        return internal_gear_paths(far_lines)
