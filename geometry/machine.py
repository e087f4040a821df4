"""A swept rotor pair of any family: chamber curves, loads and sealing lines along z.

Volumes, forces and torques of a 3D chamber are integrals along z of the section
chamber (seed 000 Eq. 7 and Eqs. 13-15, generalised by the scale and twist laws of
:mod:`.sweep`): the section at height z of the chamber whose low-pressure-end section is
at angle ``phi`` is the planar chamber at ``phi - twist(z)``, scaled by ``scale(z)``.

Volumes come from a spline of the (smooth) area table and Gauss nodes along z.  Loads
do not: the section forces and torques have square-root kinks where fillet contacts
appear and vanish in pairs (:mod:`.split_space`), which Gauss nodes along z resolve
slowly (48 panels left Pi_max 1.2 % off).  They are tabulated ``section_refinement``
times finer than the chamber curves and integrated along z exactly for their linear
interpolant (:meth:`.Sweep.hat_kernel`), a convolution on the section grid; or, where
the family says at which angles they jump (:class:`.load_sweep.LoadEvents`: the twin
screw's, where its sealing changes hands between nodes), at fourth order between those
angles (:mod:`.load_sweep`: Pi_max of seed 004's 4/6 pairs within 3e-5 at 24 points per
period, against 9e-4 as the linear interpolant).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .family import RotorPair
from .lines import line_lengths, stretches
from .load_sweep import sweep_loads
from .scalar import minimum
from .section import POINTS_PER_PERIOD, SectionChamber
from .spline import CubicSpline
from .sweep import Sweep

#: Section-table samples per step of the chamber curves.  The load error is the section
#: table's, O(h^1.5) at its kinks: 32 (3072 per period at the default 96) puts Pi_max of
#: the default case within 1e-4 of its converged value (make bench: geometry.csv).
SECTION_REFINEMENT = 32

#: Gauss panels along z for the sealing lines.  A fillet contact races along the fillet
#: where contacts appear and vanish in pairs (its speed has a square-root singularity),
#: and a coarse set of nodes samples that unevenly: 48 panels left the axial lines
#: ragged by +-100 %, 192 by about +-20 %.
SEAL_PANELS = 192


@dataclass(frozen=True)
class ChamberLoads:
    """Volume and loads of one 3D chamber per unit pressure on the fine section grid."""

    phi: np.ndarray
    volume: np.ndarray
    force: np.ndarray  # (n, rotors, 2) force of the fluid on each rotor per unit pressure
    torque: np.ndarray  # (n, rotors) torque of the fluid on each rotor about its axis
    step: float


@dataclass(frozen=True)
class ChamberCurves:
    """One 3D chamber against its low-pressure-end angle ``phi`` (uniform grid)."""

    phi: np.ndarray
    volume: np.ndarray
    dvolume: np.ndarray
    area_lp: np.ndarray
    area_hp: np.ndarray
    force: np.ndarray  # (n, rotors, 2) force of the fluid on each rotor per unit pressure
    torque: np.ndarray  # (n, rotors) torque of the fluid on each rotor about its axis
    perimeter_lp: np.ndarray  # rotor edge length of the chamber on the lp end plate
    perimeter_hp: np.ndarray
    step: float


def _extend(section: SectionChamber, values: np.ndarray) -> CubicSpline:
    """Spline of a section quantity, zero outside the chamber's life."""
    return CubicSpline(section.psi, values, bc_type="not-a-knot", extrapolate=False)


def _eval(spline: CubicSpline, x, nu: int = 0):
    out = spline(x, nu)
    return np.nan_to_num(out, nan=0.0)


def _linear(section: SectionChamber, values: np.ndarray, x):
    """Linear interpolation on the period-aligned grid, zero outside the life.

    Used for loads: it is local and linear in the node values, so chambers one period
    apart, sampled at the same fraction of a cell, sum exactly as their nodes do (a
    spline's end conditions would break that cancellation).
    """
    psi = section.psi
    h = psi[1] - psi[0]
    t = (np.asarray(x) - psi[0]) / h
    i = np.floor(t).astype(int)
    f = t - i
    # One virtual zero node either side: the chamber does not exist there.
    padded = np.concatenate([[0.0], values, [0.0]])
    ok = (i >= -1) & (i < len(psi))
    j = np.clip(i + 1, 0, len(padded) - 2)
    out = padded[j] * (1.0 - f) + padded[j + 1] * f
    return np.where(ok, out, 0.0)


def _swept_width_constant_lead(opening, sweep, phi: np.ndarray) -> np.ndarray:
    """:func:`_swept_width` at every angle at once where g = L / wrap is constant: the
    difference of one antiderivative of the width at phi and at phi - wrap (both among
    the pieces' ends, so the pieces' Gauss sums stay exact)."""
    lo, hi = float(phi.min()) - sweep.wrap, float(phi.max())
    bp = np.unique(np.concatenate([opening.breakpoints(lo, hi), phi, phi - sweep.wrap]))
    x, w = np.polynomial.legendre.leggauss(2)
    mid, half = 0.5 * (bp[1:] + bp[:-1]), 0.5 * np.diff(bp)
    pieces = (opening.at(mid[:, None] + half[:, None] * x[None, :]) @ w) * half
    integral = np.concatenate([[0.0], np.cumsum(pieces)])
    upper = integral[np.searchsorted(bp, phi)]
    lower = integral[np.searchsorted(bp, phi - sweep.wrap)]
    return (upper - lower) * sweep.length / sweep.wrap


def _swept_width(opening, sweep, phi: float) -> float:
    """``int_0^wrap w(phi - theta) g(theta) d theta`` (:attr:`SweptMachine.opening_areas`)."""
    bp = opening.breakpoints(phi - sweep.wrap, phi)
    if len(bp) < 2:
        return 0.0
    x, w = np.polynomial.legendre.leggauss(2)
    mid, half = 0.5 * (bp[1:] + bp[:-1]), 0.5 * np.diff(bp)
    psi = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    z = sweep.z_of_twist(phi - psi)
    g = sweep.scale(z) / sweep.dtwist(z)
    return float(np.sum(opening.at(psi) * g * (half[:, None] * w[None, :]).ravel()))


def _symmetric(lines: dict[int, np.ndarray], per_period: int) -> dict[int, np.ndarray]:
    """Make the line to the chamber d periods older, at angle phi, equal to that
    chamber's line to this one, at phi + d periods (the same line): the larger view."""
    out = {d: v.copy() for d, v in lines.items()}
    n = len(next(iter(lines.values())))
    for d in sorted(k for k in set(lines) | {-k for k in lines} if k > 0):
        fwd = out.get(d, np.zeros(n))
        back = out.get(-d, np.zeros(n))
        k = d * per_period
        if k >= n:
            continue
        both = np.maximum(fwd[: n - k], back[k:])
        fwd = fwd.copy()
        back = back.copy()
        fwd[: n - k] = both
        back[k:] = both
        out[d], out[-d] = fwd, back
    return out


@dataclass(frozen=True)
class SweptMachine:
    """A family's pair swept along z: the 3D chamber against its low-pressure-end angle."""

    pair: RotorPair
    sweep: Sweep
    points_per_period: int = POINTS_PER_PERIOD
    #: None: the pair's own ``section_refinement`` if it has one (a family whose loads
    #: have no kinks needs none), else SECTION_REFINEMENT.
    section_refinement: int | None = None

    def __post_init__(self):
        if self.section_refinement is None:
            own = getattr(self.pair, "section_refinement", None)
            object.__setattr__(self, "section_refinement", own or SECTION_REFINEMENT)

    @cached_property
    def section(self) -> SectionChamber:
        return self.pair.section(self.points_per_period * self.section_refinement)

    @cached_property
    def loads(self) -> ChamberLoads:
        """Volume and loads on the section grid, integrated along z by convolution:
        the loads at fourth order between the events where they jump where the family
        gives them (:mod:`.load_sweep`), else as their linear interpolant."""
        sec = self.section
        step = sec.psi[1] - sec.psi[0]
        k2 = self.sweep.hat_kernel(step, 2)
        volume = np.maximum(_convolve(sec.area, k2), 0.0)
        n = len(volume)
        ev = sec.load_events
        if ev is not None:
            # forces weigh scale(z) (a section's edge), torques scale(z)^2 (its moment)
            nf, nt = sec.force[0].size, sec.torque.shape[1]
            both = np.concatenate([sec.force.reshape(len(sec.psi), nf), sec.torque], 1)
            extra = np.concatenate([ev.sample_force.reshape(len(ev.sample_psi), nf),
                                    ev.sample_torque], 1)
            out = sweep_loads(sec.psi, both, self.sweep, [1] * nf + [2] * nt, n, ev, extra)
            force = out[:, :nf].reshape((n,) + sec.force.shape[1:])
            torque = out[:, nf:]
        else:
            k1 = self.sweep.hat_kernel(step, 1)
            rotors = range(sec.torque.shape[1])
            force = np.stack([np.stack([_convolve(sec.force[:, r, c], k1) for c in (0, 1)],
                                       -1) for r in rotors], 1)
            torque = np.stack([_convolve(sec.torque[:, r], k2) for r in rotors], 1)
        return ChamberLoads(phi=sec.psi[0] + step * np.arange(n), volume=volume,
                            force=force, torque=torque, step=step)

    @cached_property
    def planar_life(self) -> tuple[float, float]:
        """(birth, death): the reference-rotor angles at which the chamber's planar
        section first and last holds fluid (:func:`.ports.planar_life`)."""
        from .ports import planar_life

        return planar_life(self)

    @property
    def birth_age(self) -> float:
        """The chamber's birth as an age of its curves.  They start at a section-table
        node at or before it, which moves with the resolution (by up to a step: 3.75 deg
        at 24 points per period on a 4/6 pair); every angle a user gives or reads (port
        timing, figures, the chamber table's) is counted from the birth itself."""
        return self.planar_life[0] - float(self.curves.phi[0])

    @property
    def period(self) -> float:
        return self.pair.period

    @property
    def life_2d(self) -> float:
        return self.section.phi_f - self.section.phi_i

    @property
    def wrap_bar(self) -> float:
        """Normalised wrap angle, seed 000 Eq. 8."""
        birth, death = self.planar_life
        return self.sweep.wrap / (death - birth)

    @property
    def pitch_length(self) -> float | None:
        """Axial advance of the rotor per lobe period, seed 000 Eq. 23 (constant lead
        only); None for straight rotors."""
        if self.sweep.wrap == 0.0 or self.sweep.lead_ratio != 1.0:
            return None  # (a variable lead has no one pitch)
        return self.period * self.sweep.length / self.sweep.wrap

    @cached_property
    def curves(self) -> ChamberCurves:
        sec = self.section
        sw = self.sweep
        step = self.period / self.points_per_period
        n = int(math.ceil((self.life_2d + sw.wrap) / step)) + 1
        phi = sec.phi_i + step * np.arange(n)
        z, wz = sw.nodes()
        s = sw.scale(z)
        psi = phi[:, None] - sw.twist(z)[None, :]
        a_spl = _extend(sec, sec.area)
        w2 = wz * s * s
        if sec.area[0] == 0.0:  # conjugate: the area is smooth and vanishes at birth
            volume = _eval(a_spl, psi) @ w2
            dvolume = _eval(a_spl, psi, 1) @ w2
        else:
            # A non-conjugate chamber is handed over with a finite area (clearance
            # volume), a jump that a spline would ring on; interpolate linearly.
            volume = _linear(sec, sec.area, psi) @ w2
            alive = sec.psi < sec.phi_f
            d_area = np.zeros_like(sec.area)
            d_area[alive] = np.gradient(sec.area[alive], sec.psi[alive])
            dvolume = _linear(sec, d_area, psi) @ w2
        # The loads of the curve grid are every r-th sample of the fine ones.
        r = self.section_refinement
        fine = self.loads

        def coarse(x):
            x = x[::r][:n]
            return np.concatenate([x, np.zeros((n - len(x),) + x.shape[1:])])

        area_lp = _eval(a_spl, phi) * float(sw.scale(0.0)) ** 2
        area_hp = _eval(a_spl, phi - sw.wrap) * float(sw.scale(sw.length)) ** 2
        # The spline may undershoot by ~1e-10 of the maximum where the area rises from
        # zero like the fourth power of the angle; areas and volumes cannot be negative.
        volume, area_lp, area_hp = (np.maximum(x, 0.0) for x in (volume, area_lp, area_hp))
        per = _extend(sec, sec.perimeter.sum(1))
        return ChamberCurves(
            phi=phi,
            volume=volume,
            dvolume=dvolume,
            area_lp=area_lp,
            area_hp=area_hp,
            force=coarse(fine.force),
            torque=coarse(fine.torque),
            perimeter_lp=np.maximum(_eval(per, phi), 0.0),
            perimeter_hp=np.maximum(_eval(per, phi - sw.wrap), 0.0) * float(sw.scale(sw.length)),
            step=step,
        )

    @cached_property
    def seal_lines(self) -> dict[int, np.ndarray]:
        """Length of the 3D contact lines between the chamber and each other chamber.

        Keyed by the other chamber's age offset in lobe periods (+1 the next, older one;
        see :class:`.section.SectionChamber`).  A contact point c(psi) of the section
        sweeps the space curve (scale(z) c(phi - twist(z)), z); its length element is
        sqrt(1 + |scale' c - scale twist' c'|^2) dz, counted where the chamber exists
        and booked to the chamber beyond that contact at that height.  An offset of 0
        (no chamber beyond: the family follows that contact as a track) is no line.

        A line seen from both sides must have one length: where a chamber's section
        has sub-regions, only its outermost contacts are followed, so its neighbour may
        see more of their common line; both take the larger view.
        """
        sec = self.section
        lines: dict[int, np.ndarray] = {}
        for which, offsets in (("lead", sec.lead_offset), ("trail", sec.trail_offset)):
            if not np.any(offsets):
                continue  # no chamber beyond (the family follows its contacts as tracks)
            pts = sec.lead if which == "lead" else sec.trail
            for d, v in self._line_lengths(pts, sec.contact_rate(which), offsets).items():
                if d != 0:
                    lines[d] = lines.get(d, 0.0) + v
        return _symmetric(lines, self.points_per_period) if lines else {}

    @cached_property
    def track_lines(self) -> dict[tuple[str, int], np.ndarray]:
        """Lengths of the section's further sealing lines (:class:`.section.Track`),
        keyed by (track name, offset of the chamber beyond), like :attr:`seal_lines`."""
        return self.track_lines_at(self.curves.phi)

    def track_lines_at(self, phi) -> dict[tuple[str, int], np.ndarray]:
        """:attr:`track_lines` at any angles ``phi`` (:mod:`.lines`: exact between the
        ends the family gives)."""
        sec = self.section
        phi = np.asarray(phi, dtype=float)
        out: dict[tuple[str, int], np.ndarray] = {}
        for track in sec.tracks:
            st = stretches(sec.psi, track.points, sec.contact_rate(track), track.present,
                           track.offset, track.ids, track.cuts, track.bridges, track.start)
            for d, v in line_lengths(st, self.sweep, phi).items():
                out[(track.name, d)] = out.get((track.name, d), 0.0) + v
        return out

    @cached_property
    def opening_areas(self) -> dict[tuple[str, int], np.ndarray]:
        """Areas of the section's openings (:class:`.section.Opening`) over the chamber
        curves' angles, keyed (name, offset): the width swept along the rotors,
        ``A(phi) = int w(phi - twist(z)) s(z) dz``.

        With theta = twist(z) this is ``int_0^wrap w(phi - theta) g(theta) d theta``,
        g = s dz/d theta; the width is linear between its breakpoints, so two Gauss
        nodes per piece integrate it exactly where g is constant (a constant lead) and
        to the pieces' second order elsewhere (a constant lead takes every angle at once,
        from one antiderivative).  A straight sweep has every section alike.
        """
        sw, phi = self.sweep, self.curves.phi
        out: dict[tuple[str, int], np.ndarray] = {}
        for o in self.section.openings:
            key = (o.name, int(o.offset))
            if sw.wrap == 0.0:
                z, wz = sw.nodes()
                area = o.at(phi) * float(wz @ sw.scale(z))
            elif sw.lead_ratio == 1.0 and sw.scale_end == 1.0:
                area = _swept_width_constant_lead(o, sw, phi)
            else:
                area = np.array([_swept_width(o, sw, p) for p in phi])
            out[key] = out.get(key, 0.0) + area
        return out

    def _line_lengths(self, pts, rate, offsets) -> dict[int, np.ndarray]:
        """Per offset beyond, the length of the line point ``pts`` sweeps (seal_lines).

        Gauss nodes along z, each booked by the nearest table node: a line's ends are
        known to half a step.  The tracks' lines (:mod:`.lines`) are exact between the
        ends the family gives; the lead and trail contacts stay here for now, as the
        exact integration of a table refined 32 times (the internal gear's) costs
        seconds on a conical rotor."""
        sec = self.section
        sw = self.sweep
        phi = self.curves.phi
        z, wz = sw.nodes(SEAL_PANELS)
        s = sw.scale(z)
        psi = phi[:, None] - sw.twist(z)[None, :]
        alive = (psi >= sec.phi_i) & (psi <= sec.phi_f)
        ds, dt = sw.dscale(z)[None, :], sw.dtwist(z)[None, :]
        h = sec.psi[1] - sec.psi[0]
        node = np.clip(np.rint((psi - sec.psi[0]) / h).astype(int), 0, len(sec.psi) - 1)
        c = np.stack([_linear(sec, pts[:, i], psi) for i in (0, 1)], -1)
        dc = np.stack([_linear(sec, rate[:, i], psi) for i in (0, 1)], -1)
        tang = ds[..., None] * c - (s[None, :] * dt)[..., None] * dc
        elem = np.sqrt(1.0 + np.sum(tang * tang, -1)) * alive
        label = offsets[node]
        return {int(d): (elem * (label == d)) @ wz for d in np.unique(label[alive])}

    # ----------------------------------------------------------------- summary figures
    def volume_at(self, phi) -> np.ndarray:
        """Chamber volume at any low-pressure-end angle(s), by the same quadrature."""
        z, wz = self.sweep.nodes()
        s = self.sweep.scale(z)
        psi = np.atleast_1d(phi)[:, None] - self.sweep.twist(z)[None, :]
        return _eval(_extend(self.section, self.section.area), psi) @ (wz * s * s)

    @cached_property
    def volume_max(self) -> float:
        """Largest chamber volume, polished between grid points (not the sampled maximum)."""
        c = self.curves
        k = int(np.argmax(c.volume))
        lo, hi = c.phi[max(k - 1, 0)], c.phi[min(k + 1, len(c.phi) - 1)]
        _, least = minimum(lambda x: -float(self.volume_at(x)[0]), lo, hi, xtol=1e-10)
        return max(-least, float(c.volume[k]))

    @property
    def swept_volume(self) -> float:
        """Volume drawn in per reference-rotor revolution: N1 V_max (seed 000, 3.1.1)."""
        return self.pair.rotors[0].lobes * self.volume_max

    @property
    def cylinder_volume(self) -> float:
        return math.pi * self.pair.diameter**2 / 4.0 * self.sweep.length


def _convolve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Full linear convolution by FFT (numpy's own: scipy.signal's import alone costs
    half a second of every command)."""
    n = a.size + b.size - 1
    size = 1 << (n - 1).bit_length()
    return np.fft.irfft(np.fft.rfft(a, size) * np.fft.rfft(b, size), size)[:n]
