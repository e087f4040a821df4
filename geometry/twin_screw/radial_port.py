"""The radial discharge port of a twin-screw casing, and the area through which the
working chamber sees it.

The window (seed 004).  Xing, Deng & Shu size the discharge port as the sum of the axial
port (on the end plate, :mod:`..ports`) and the radial port, whose "unfold graph ...
consists of two triangles": one window in each bore at the discharge end, on the side
of the mesh where the lobes go in (the bottom cusp, y < 0, where the chambers die).  On
the unrolled bore of rotor r the window is bounded by

* the discharge end plane z = L;
* the cusp line, where the two bores meet;
* a helical edge parallel to the rotor's lobe tips: the line that the chamber's leading
  tip on that bore occupies at the discharge opening (the axial port's PortTiming: the
  built-in volume ratio less the early opening).

So a whole tip uncovers the edge at once, at the opening.  With a constant lead the edge
is straight on the unrolled bore and the window is seed 004's triangle; with a variable
lead it follows the tips' curve.

Coordinates.  On bore r, ``u`` is the angle about the rotor's axis counted the way the
rotor turns (the male counter-clockwise, the female clockwise), unwrapped over a groove's
life.  The casing is the arc [top, bottom] between the cusps (beyond it lies the other
bore); a groove's opening on it is [lead - pitch, lead] cut to that arc, whatever the
mesh does inside the lens, because only the groove's own tips touch the casing arc.  The
leading tip moves by ``rate`` = |speed ratio| per radian of male angle, and at height z
the chamber whose low-pressure-end section is at phi has its section at
psi = phi - twist(z) (:mod:`..sweep`).  The edge at height z is the leading tip at
phi_open - twist(z), so it trails the chamber's leading tip by rate (age - opening), and
the chamber's open arc at z is exactly

    |[lead(psi) - w, lead(psi)] cut to [top, bottom]|,   w = clip(rate (age - opening), 0, pitch),

piecewise linear in the twist; it is integrated along z between its kinks by
Gauss-Legendre (exact for a constant lead, to rounding for a variable one).

Why it never opens early, and how far it may reach.  A point (u, z) of the casing first
belongs to the chamber when the chamber's leading tip passes it there, at an age that
grows with u and with z.  The window is the set of points not yet reached at the
opening: everything between the edge and the cusp belongs to chambers at or past their
opening, everything behind the edge to younger ones.  It is the largest window that never
opens early, so its extent away from the cusp is the edge itself; it is further cut to
the casing arc and to the rotor length.

The limit.  The latest point to be reached is the cusp at z = L, where the chamber's
section is youngest.  A discharge that opens after the chamber's leading tip has crossed
the cusp at the discharge end leaves that bore no window at all; when neither bore has
one, asking for a radial port is an error that says the latest opening possible.  (Seed
004's 4/6 at 325 deg wrap: 751 deg male, 775 deg female, against 781.5 deg for its
built-in ratio 8.3 less 7 deg: that machine discharges axially only.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from ..planar import TWO_PI
from ..sweep import Sweep

#: A section vertex this close to a bore circle (per centre distance) lies on it: a few of
#: the sections' chord errors (1e-6 C), as the sections' own edge labels take it.
ON_BORE = 5e-6
#: The fullest sections searched for one where the chamber opens on a bore (to find which
#: tips bound its groove): the fullest hold both grooves whole.
ANCHOR_SCAN = 16
#: Gauss-Legendre nodes per piece of the z integral: between kinks the open arc is linear
#: in the twist and dz/dtwist smooth (constant for a constant lead); 8 nodes integrate
#: an exponential lead law over a piece to rounding.
GAUSS_NODES = 8


@dataclass(frozen=True)
class BoreWindow:
    """One bore: the casing arc, and the chamber's groove on it (``u``: module docstring)."""

    rotor: str
    radius: float
    rate: float  # du of the rotor's tips per radian of male angle (|speed ratio|)
    pitch: float  # the rotor's lobe pitch (its own angle)
    top: float  # u of the cusp where grooves leave the mesh (suction side, y > 0)
    bottom: float  # u of the cusp where they go into it (discharge side, y < 0)
    lead0: float  # u of the chamber's leading tip on this bore at male angle 0

    def lead(self, psi):
        """u of the chamber's leading tip at section angle(s) ``psi``."""
        return self.lead0 + self.rate * np.asarray(psi, dtype=float)


@dataclass(frozen=True)
class RadialPort:
    """The windows of both bores for one port timing."""

    bores: tuple[BoreWindow, ...]
    sweep: Sweep
    phi_birth: float  # section angle of the table's first node (SectionChamber.phi_i)
    opening: float  # age at the discharge opening (PortTiming.discharge_open)
    #: the chamber's birth as an age (SweptMachine.birth_age): the figures and messages
    #: count from the birth, as every angle a user reads
    birth_age: float = 0.0

    def edge(self, bore: BoreWindow, z):
        """u of the window's edge on ``bore`` at height(s) z (the window: edge to bottom)."""
        return bore.lead(self.phi_birth + self.opening - self.sweep.twist(z))

    def latest_opening(self, bore: BoreWindow) -> float:
        """The latest opening age at which ``bore`` can have a window: the chamber's
        leading tip reaches the bottom cusp at z = L."""
        return (bore.bottom - bore.lead0) / bore.rate - self.phi_birth + self.sweep.wrap

    def has_window(self, bore: BoreWindow) -> bool:
        return self.opening < self.latest_opening(bore)

    def open_area(self, ages) -> np.ndarray:
        return open_area(self, ages)

    def figures(self) -> dict:
        return port_figures(self)


def radial_port(machine, timing) -> RadialPort:
    """The radial port of ``machine`` (a swept twin-screw pair) for ``timing``.

    Raises CaseError if the sweep tapers (the windows are cut in cylindrical bores) or if
    neither bore can have a window that opens no earlier than the timing says.
    """
    pair, sweep, sec = machine.pair, machine.sweep, machine.section
    if sweep.scale_end != 1.0:
        raise CaseError("a radial discharge port is cut in cylindrical bores; this sweep "
                        "tapers (use discharge_port = \"axial\")")
    bores = tuple(_bore(pair, sec, r) for r in range(len(pair.rotors)))
    b0 = machine.birth_age
    port = RadialPort(bores, sweep, float(sec.phi_i), float(timing.discharge_open), b0)
    if not any(port.has_window(b) for b in bores):
        latest = [port.latest_opening(b) for b in bores]
        ratio = machine.volume_max / float(machine.volume_at(sec.phi_i + max(latest))[0])
        at = ", ".join(f"{math.degrees(a - b0):.1f} deg ({b.rotor})"
                       for a, b in zip(latest, bores, strict=True))
        raise CaseError(
            f"no radial discharge port can open at {math.degrees(port.opening - b0):.1f} deg: at "
            f"the discharge end the chamber's grooves reach the discharge-side cusp at {at}"
            f" (V_max / V = {ratio:.2f}), and no part of the bores is ahead of them after "
            "that; open the discharge earlier (lower volume_ratio or raise "
            "discharge_early_opening_deg) or set discharge_port = \"axial\" in [operating]")
    return port


def _bore(pair, sec, r: int) -> BoreWindow:
    """Rotor r's casing arc and the tip leading the chamber's groove on it."""
    rotor = pair.rotors[r]
    (axis, radius), other = pair.casing_bores()[r], pair.casing_bores()[1 - r]
    sense = 1.0 if rotor.speed_ratio > 0.0 else -1.0
    away = math.atan2(axis[1] - other[0][1], axis[0] - other[0][0])

    def u_of(points):
        """u of fixed-frame points (or angles about the axis) on this bore: unwrapped
        about the direction away from the other rotor, the middle of a groove's life."""
        theta = np.asarray(points, dtype=float)
        if theta.ndim:
            theta = np.arctan2(theta[..., 1] - axis[1], theta[..., 0] - axis[0])
        mid = sense * away
        return mid + np.remainder(sense * theta - mid + math.pi, TWO_PI) - math.pi

    xc, yc = pair.cusp
    top, bottom = float(u_of(np.array([xc, yc]))), float(u_of(np.array([xc, -yc])))
    if not top < bottom:
        # Grooves are born at the top cusp and die at the bottom (pair.py's turning
        # sense); a pair turning the other way needs the window on the other side.
        raise CaseError(f"the {rotor.name}'s grooves do not run from the top cusp to the "
                        "bottom one: no radial port is placed for this pair")
    pitch = TWO_PI / rotor.lobes
    rate = abs(rotor.speed_ratio)
    for psi in sec.psi[np.argsort(sec.area)[::-1][:ANCHOR_SCAN]]:
        opening = _casing_points(pair, pair.chamber_polygons(float(psi)), r)
        if len(opening) >= 3:
            break
    else:
        raise CaseError(f"the chamber never opens on the {rotor.name} bore in its fullest "
                        "sections: no radial port is placed")
    u = u_of(opening)
    mid = 0.5 * (u.min() + u.max())
    tips = rotor.speed_ratio * psi + pair.tip_angle(r) + pitch * np.arange(rotor.lobes)
    # The leading tip is the first one ahead of the opening's middle, the way it turns.
    ahead = float(np.remainder(sense * tips - mid, TWO_PI).min())
    return BoreWindow(rotor.name, radius, rate, pitch, top, bottom,
                      float(mid + ahead - rate * psi))


def _casing_points(pair, polygons, r: int) -> np.ndarray:
    """The vertices of a section's polygons on rotor r's casing arc (on its bore, off the
    other bore)."""
    (axis, radius), (other, other_radius) = pair.casing_bores()[r], pair.casing_bores()[1 - r]
    tol = ON_BORE * math.dist(axis, other)
    out = []
    for q in polygons:
        on = np.abs(np.linalg.norm(q - np.asarray(axis), axis=-1) - radius) < tol
        off = np.linalg.norm(q - np.asarray(other), axis=-1) > other_radius + tol
        out.append(q[on & off])
    return np.concatenate(out) if out else np.zeros((0, 2))


# ------------------------------------------------------------------ areas against age
def open_area(port: RadialPort, ages, bore: BoreWindow | None = None) -> np.ndarray:
    """The area of the chamber's opening on the bores inside the windows (m2) at every
    age of ``ages`` (male angle from the table's first node, as the port timing's); one
    bore's, or both summed."""
    ages = np.atleast_1d(np.asarray(ages, dtype=float))
    total = np.zeros(len(ages))
    for b in (port.bores if bore is None else (bore,)):
        if not port.has_window(b):
            continue
        w = np.clip(b.rate * (ages - port.opening), 0.0, b.pitch)[:, None, None]
        total += _along(port, b, ages, lambda v, w=w, b=b: _arc(v, w, b),
                        [b.top, b.top + w[:, 0, 0], b.bottom, b.bottom + w[:, 0, 0]])
    return total


def footprint(port: RadialPort, ages, bore: BoreWindow | None = None) -> np.ndarray:
    """The whole of the chamber's openings on the bores (m2): what a window over all of
    the casing would give."""
    ages = np.atleast_1d(np.asarray(ages, dtype=float))
    total = np.zeros(len(ages))
    for b in (port.bores if bore is None else (bore,)):
        total += _along(port, b, ages, lambda v, b=b: _arc(v, b.pitch, b),
                        [b.top, b.top + b.pitch, b.bottom, b.bottom + b.pitch])
    return total


def window_area(port: RadialPort, bore: BoreWindow) -> float:
    """The window's area on ``bore`` (m2): the leading tip's u at the opening is the edge,
    so the window is the arc from it to the bottom cusp, along z."""
    if not port.has_window(bore):
        return 0.0
    ages = np.array([port.opening])
    return float(_along(port, bore, ages,
                        lambda v: np.clip(bore.bottom - np.maximum(v, bore.top), 0.0, None),
                        [bore.top, bore.bottom])[0])


def _arc(v, w, b: BoreWindow):
    """Length in u of [v - w, v] cut to the casing arc."""
    return np.clip(np.minimum(v, b.bottom) - np.maximum(v - w, b.top), 0.0, None)


def _along(port: RadialPort, b: BoreWindow, ages, f, breaks) -> np.ndarray:
    """radius * integral over z of f(u of the chamber's leading tip at z), per age.

    The leading tip at height z is at v = lead(phi) - rate twist(z): linear in the twist,
    so f, piecewise linear in v with kinks at ``breaks`` (values or per-age arrays), is
    integrated in the twist between them with the weight dz/dtwist.
    """
    sw = port.sweep
    v0 = b.lead(port.phi_birth + ages)  # at z = 0
    if sw.wrap == 0.0:
        return b.radius * sw.length * f(v0[:, None, None])[:, 0, 0]
    kinks = np.stack([np.broadcast_to(k, v0.shape) for k in breaks], -1)
    theta = np.clip((v0[:, None] - kinks) / b.rate, 0.0, sw.wrap)
    ends = np.sort(np.concatenate([np.zeros((len(v0), 1)), theta,
                                   np.full((len(v0), 1), sw.wrap)], -1), -1)
    x, wt = np.polynomial.legendre.leggauss(GAUSS_NODES)
    lo, half = ends[:, :-1, None], 0.5 * np.diff(ends, axis=-1)[..., None]
    t = lo + half * (1.0 + x)
    dz = 1.0 / sw.dtwist(sw.z_of_twist(t))
    return b.radius * np.sum(f(v0[:, None, None] - b.rate * t) * dz * half * wt, (1, 2))


def port_figures(port: RadialPort) -> dict:
    """Per bore: the window's area, its axial length and its span at the end plane
    (rotor angle), and the latest opening a window there allows."""
    out = {}
    sw = port.sweep
    for b in port.bores:
        edge = float(port.edge(b, sw.length))
        span = max(0.0, b.bottom - max(edge, b.top))
        if sw.wrap == 0.0:
            length = sw.length if span > 0.0 else 0.0
        else:
            # The edge meets the cusp where the twist is this much short of the wrap.
            short = float(np.clip((b.bottom - edge) / b.rate, 0.0, sw.wrap))
            length = sw.length - float(sw.z_of_twist(sw.wrap - short))
        out[f"radial_window_area_{b.rotor}_mm2"] = window_area(port, b) * 1e6
        out[f"radial_window_length_{b.rotor}_mm"] = length * 1e3
        out[f"radial_window_span_{b.rotor}_deg"] = math.degrees(span)
        out[f"radial_latest_open_{b.rotor}_deg"] = math.degrees(port.latest_opening(b)
                                                                 - port.birth_age)
    return out
