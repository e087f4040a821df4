"""The clearance gap at a sealing line, as a 2D section for a CFD gap case.

At outer-rotor angle ``phi1`` the leading pin (pin 0) of the chamber space touches the
inner rotor.  In a real machine one rotor is relieved by a clearance ``gap``: its profile
is offset along its own normal (a true normal offset, :func:`..offsets.offset_profile`,
not a shift), into the outer rotor by default, as for the solids (``clearance_on``).  The
section is written in the gap's own frame: origin at the contact point of the conjugate
(unrelieved) pair, y along the contact normal (from the inner rotor into the pin), x along
the common tangent, pointing from the older (leading, higher-pressure) chamber into the
younger one, so the flow of a compressor's leakage runs toward +x.  Both walls are the
true rotor profiles: the lower one the inner rotor, the upper one the outer rotor (pin 0
and, past the pin's edges, its fillets), as polylines y(x) over the same x range, cut
where the gap has opened to ``inlet_ratio`` and ``outlet_ratio`` times its minimum,
ready for :class:`rotorflow.cases.gap_walls.GapWalls`.  This module supplies the frame
and the walls; the cut is every family's (:mod:`..gap_section`).

Where no such section exists the functions raise a CaseError naming the angle and the
reason.  At sigma_bar = 1 the inner profile has a point of zero arc-length speed and
infinite curvature (the undercut limit, seed 000 Eq. 4; g = 70 and 290 deg for the
default pair): a normal offset *into the inner rotor* folds into a swallowtail there (the
relieved rotor does not exist), which is why the inner-rotor clearance of the first
version of this module failed at phi1 = 300 deg.  With the clearance on the outer rotor
the sections near that point are sharp-edged seals, and they exist.

:func:`sealing_wall_speeds` gives the tangential speeds of both walls in the same frame,
relative to the moving contact point: the speeds that drag gas through a gap that moves
with its sealing line (what the neighbouring chambers exchange).
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError

from ..gap_section import SEARCH_SAMPLES, Wall, check_arguments, cut_section, surface_speeds
from ..offsets import Clearance, offset_profile
from ..planar import TWO_PI, rotate
from .pair import PinGerotor
from .profiles import inner_profile, outer_profile

#: Parameter span searched on each side of the contact on the inner profile, in lobes
#: (u of :func:`.profiles.inner_profile`): half a lobe, so both ways reach past
#: the tip and past the zero-speed point of sigma_bar = 1, where little arc length
#: is spread over a wide range of parameter.
INNER_SPAN = 0.5
#: Step of the central difference of the contact point's path [rad of phi1]; the path is
#: analytic, so the relative error is ~1e-12.
PATH_STEP = 1e-6


def _contact_frame(pair: PinGerotor, phi1: float):
    """Contact point of pin 0 (fixed frame), unit normal n (inner rotor into the pin) and
    tangent t (older chamber into the younger)."""
    x0 = _contact_point(pair, phi1)
    centre = rotate(pair.pin_centre(0), phi1)
    n = (centre - x0) / pair.rho
    t = np.array([n[1], -n[0]])
    e_theta = np.array([-x0[1], x0[0]])
    if t @ e_theta > 0.0:  # point from the older (ccw-ahead) chamber to the younger
        t = -t
    return x0, n, t


def _contact_point(pair: PinGerotor, phi1):
    """Contact of pin 0 with the inner rotor at outer angle(s) phi1, fixed frame."""
    theta = pair.space.pin_theta(0, phi1)
    return rotate(pair.pin_point(0, theta), phi1)


def sealing_wall_speeds(pair: PinGerotor, phi1: float, omega_outer: float) -> tuple[float, float]:
    """(lower, upper) wall speeds along +x of the gap frame [m/s], relative to the contact.

    Both rotors turn counter-clockwise, the outer one at ``omega_outer`` [rad/s] about O1,
    the inner one at ``m21 * omega_outer`` about O2.  The contact point X(phi1) moves; in
    a frame travelling with it the gap keeps its shape and both surfaces slide along it
    at ``(v_rotor - dX/dt) . t`` (:func:`..gap_section.surface_speeds`).  Their difference
    is the sliding speed |omega_inner - omega_outer| |X - P|, zero where the contact
    passes the pitch point P.
    """
    x0, _, t = _contact_frame(pair, phi1)
    h = PATH_STEP
    moving = omega_outer * (_contact_point(pair, phi1 + h) - _contact_point(pair, phi1 - h)) / (
        2.0 * h)
    lower, upper = surface_speeds(x0, t, moving, omega_outer,
                                  ((pair.O2, pair.m21), (np.zeros(2), 1.0)))
    return lower, upper


def _check_arguments(gap: float, inlet_ratio: float, outlet_ratio: float, clearance_on: str):
    check_arguments(gap, inlet_ratio, outlet_ratio)
    if clearance_on not in ("outer", "inner"):
        raise CaseError(f"clearance_on must be 'outer' or 'inner', not {clearance_on!r}")


def _with_clearance(pair: PinGerotor, gap: float, clearance_on: str, where: str):
    """(outer, inner) profiles, the one named by ``clearance_on`` relieved by ``gap``."""
    outer, inner = outer_profile(pair), inner_profile(pair)
    try:
        if clearance_on == "outer":
            outer = offset_profile(outer, Clearance((gap,)), +1)
        else:
            inner = offset_profile(inner, Clearance((gap,)), -1)
    except CaseError as exc:
        raise CaseError(f"{where}: {exc}") from None
    return outer, inner


def sealing_gap_walls(
    pair: PinGerotor,
    phi1: float,
    gap: float,
    inlet_ratio: float = 20.0,
    outlet_ratio: float = 3.0,
    points: int = 201,
    clearance_on: str = "outer",
) -> tuple[np.ndarray, np.ndarray]:
    """Lower (inner rotor) and upper (outer rotor) walls in the gap frame, with the
    clearance ``gap`` on the rotor ``clearance_on`` ("outer" or "inner"), cut by
    :func:`..gap_section.cut_section`."""
    where = f"no gap section at phi1 = {math.degrees(phi1):.6g} deg"
    _check_arguments(gap, inlet_ratio, outlet_ratio, clearance_on)
    space = pair.space
    lead = space.contacts(phi1)[-1]
    if lead.kind != "pin":
        raise CaseError(f"{where}: no pin contact leads the chamber")
    x0, n, t = _contact_frame(pair, phi1)
    outer, inner = _with_clearance(pair, gap, clearance_on, where)
    phi2 = pair.m21 * phi1

    def upper_xy(u):  # the outer rotor, S1 turned by phi1
        d = rotate(outer.point(u), phi1) - x0
        return d @ t, d @ n

    def lower_xy(u):  # the inner rotor, S2 turned by phi2 about O2
        d = rotate(inner.point(u), phi2) + pair.O2 - x0
        return d @ t, d @ n

    # Pin 0 is piece 0 of the outer profile (pin angle from +edge to -edge), between
    # fillet -1 (piece 2 N1 - 1) and fillet 0 (piece 1).  The inner point touching pin 0
    # is psi2(g = phi1), at u = -g / (2 pi) on the inner profile.
    u_lo = -phi1 / TWO_PI
    y_up, y_lo = (gap, 0.0) if clearance_on == "outer" else (0.0, -gap)
    upper = Wall("outer", upper_xy, np.linspace(-1.0, 2.0, SEARCH_SAMPLES), y_up)
    lower = Wall("inner", lower_xy,
                 u_lo + np.linspace(-INNER_SPAN, INNER_SPAN, SEARCH_SAMPLES), y_lo)
    return cut_section(lower, upper, gap, inlet_ratio, outlet_ratio, points, where,
                       pair.diameter)
