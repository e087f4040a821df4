"""The clearance gap at a sealing line, as a 2D section for a CFD gap case.

At outer-rotor angle ``phi1`` the leading pin (pin 0) of the chamber space touches the
inner rotor.  In a real machine one rotor is relieved by a clearance ``gap``: its profile
is offset along its own normal (a true normal offset, :func:`..curves.offset_profile`,
not a shift), into the outer rotor by default, as for the solids (``clearance_on``).  The
section is written in the gap's own frame: origin at the contact point of the conjugate
(unrelieved) pair, y along the contact normal (from the inner rotor into the pin), x along
the common tangent, pointing from the older (leading, higher-pressure) chamber into the
younger one, so the flow of a compressor's leakage runs toward +x.  Both walls are the
true rotor profiles: the lower one the inner rotor, the upper one the outer rotor (pin 0
and, past the pin's edges, its fillets), as polylines y(x) over the same x range, cut
where the gap has opened to ``inlet_ratio`` and ``outlet_ratio`` times its minimum,
ready for :class:`rotorflow.cases.gap_walls.GapWalls`.

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

from ..curves import Clearance, offset_profile
from ..planar import TWO_PI, rotate
from .pair import PinGerotor
from .profiles import inner_profile, outer_profile

#: Parameter span searched on each side of the contact on the inner profile, in lobes
#: (u of :func:`.profiles.inner_profile`): half a lobe, so both ways reach past
#: the tip and past the zero-speed point of sigma_bar = 1, where little arc length
#: is spread over a wide range of parameter.
INNER_SPAN = 0.5
#: Samples per wall over its searched span: brackets for the exact points (the walls are
#: evaluated exactly at the output abscissae, these only locate them).
SEARCH_SAMPLES = 60001
#: Output points crowd toward the contact as (k/n)^CLUSTER: at a sharp-edged contact (near
#: the zero-speed point) the walls curve most there, and the throat lands on a point.
CLUSTER = 2.0
#: Bisection steps that put an output point on the wall: 2^-60 of a sample interval.
BISECTIONS = 60
#: Relative agreement of the sampled walls' narrowest gap with the clearance: linear
#: interpolation between samples only locates the throat; a larger miss is interference.
SAMPLED_GAP_TOL = 0.05
#: Relative agreement of the section's narrowest local gap with the clearance: a normal
#: offset leaves exactly the clearance at the contact; more means the walls interfere.
GAP_TOL = 1e-3
#: A second narrow point (another contact) ends the section: a local gap below this
#: multiple of the minimum, after the gap had opened beyond twice that.
SECOND_CONTACT_RATIO = 1.5
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
    at ``(v_rotor - dX/dt) . t`` (their normal components vanish: the contact stays on
    both).  Their difference is the sliding speed |omega_inner - omega_outer| |X - P|,
    zero where the contact passes the pitch point P.
    """
    x0, _, t = _contact_frame(pair, phi1)
    h = PATH_STEP
    moving = omega_outer * (_contact_point(pair, phi1 + h) - _contact_point(pair, phi1 - h)) / (
        2.0 * h)
    v_outer = omega_outer * np.array([-x0[1], x0[0]])
    r2 = x0 - pair.O2
    v_inner = pair.m21 * omega_outer * np.array([-r2[1], r2[0]])
    return float((v_inner - moving) @ t), float((v_outer - moving) @ t)


def _check_arguments(gap: float, inlet_ratio: float, outlet_ratio: float, clearance_on: str):
    if not gap > 0.0:
        raise CaseError(f"the gap must be positive, got {gap}")
    if inlet_ratio <= 1.0 or outlet_ratio <= 1.0:
        raise CaseError("inlet and outlet gap ratios must exceed 1")
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
    clearance ``gap`` on the rotor ``clearance_on`` ("outer" or "inner")."""
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
    e = pair.pin_edge
    theta = float(space.pin_theta(0, phi1))
    u_up = (e - theta) / (2.0 * e)
    u_lo = -phi1 / TWO_PI
    y_up, y_lo = (gap, 0.0) if clearance_on == "outer" else (0.0, -gap)
    branches = {
        "outer": _branch(upper_xy, np.linspace(-1.0, 2.0, SEARCH_SAMPLES), u_up, y_up),
        "inner": _branch(lower_xy, u_lo + np.linspace(-INNER_SPAN, INNER_SPAN, SEARCH_SAMPLES),
                         u_lo, y_lo),
    }
    lo_b, up_b = branches["inner"], branches["outer"]
    x_a = max(lo_b.x[0], up_b.x[0])
    x_b = min(lo_b.x[-1], up_b.x[-1])
    xs = np.linspace(x_a, x_b, SEARCH_SAMPLES)
    local = np.interp(xs, up_b.x, up_b.y) - np.interp(xs, lo_b.x, lo_b.y)
    k = int(np.argmin(local))
    g_min = float(local[k])
    if g_min <= 0.0 or abs(g_min - gap) > SAMPLED_GAP_TOL * gap:
        raise CaseError(f"{where}: the walls leave {g_min * 1e6:.4g} um near the contact, not "
                        f"the clearance {gap * 1e6:.4g} um (the rotors interfere)")

    def ends(side: int) -> str:  # why the section stops on that side
        reasons = []
        for name, b in branches.items():
            end = b.x[0] if side < 0 else b.x[-1]
            if (side < 0 and end <= x_a) or (side > 0 and end >= x_b):
                reasons.append(f"the {name} wall {b.why[0 if side < 0 else 1]}")
        return " and ".join(reasons)

    x_in = _reach(xs, local, k, inlet_ratio * g_min, -1, where, "inlet", ends)
    x_out = _reach(xs, local, k, outlet_ratio * g_min, +1, where, "outlet", ends)
    n_in = points // 2  # the contact, x = 0, is the first outlet-side point
    x = np.concatenate([x_in * np.linspace(1.0, 0.0, n_in + 1)[:-1] ** CLUSTER,
                        x_out * np.linspace(0.0, 1.0, points - n_in) ** CLUSTER])
    lower = np.column_stack([x, lo_b.exact(lower_xy, x)])
    upper = np.column_stack([x, up_b.exact(upper_xy, x)])
    exact_min = float(np.min(upper[:, 1] - lower[:, 1]))
    if abs(exact_min - gap) > GAP_TOL * gap + 1e-9 * pair.diameter:
        raise CaseError(f"{where}: the narrowest gap across the section is "
                        f"{exact_min * 1e6:.5g} um, not the clearance {gap * 1e6:.5g} um "
                        "(the walls are not parallel where they are closest)")
    return lower, upper


class _Branch:
    """The stretch of a sampled wall through the contact on which it is a graph y(x)."""

    def __init__(self, u, x, y, why):
        self.u, self.x, self.y, self.why = u, x, y, why

    def exact(self, xy, x_target: np.ndarray) -> np.ndarray:
        """y of the wall at each x, by bisection in the wall parameter (x monotone)."""
        i = np.clip(np.searchsorted(self.x, x_target) - 1, 0, len(self.x) - 2)
        a, b = self.u[i].copy(), self.u[i + 1].copy()
        for _ in range(BISECTIONS):
            m = 0.5 * (a + b)
            left = xy(m)[0] < x_target
            a, b = np.where(left, m, a), np.where(left, b, m)
        return xy(0.5 * (a + b))[1]


def _branch(xy, u, u_contact: float, y_contact: float) -> _Branch:
    x, y = xy(u)
    k0 = int(np.argmin(np.hypot(x, y - y_contact)))
    dx = np.sign(np.diff(x))
    lo = k0
    while lo > 0 and dx[lo - 1] == dx[k0]:
        lo -= 1
    hi = k0
    while hi < len(dx) - 1 and dx[hi + 1] == dx[k0]:
        hi += 1
    why = ["reaches the end of the searched span" if lo == 0 else
           f"turns back across the gap {1e3 * abs(x[lo]):.3g} mm from the contact",
           "reaches the end of the searched span" if hi == len(dx) - 1 else
           f"turns back across the gap {1e3 * abs(x[hi + 1]):.3g} mm from the contact"]
    sl = slice(lo, hi + 2)
    u, x, y = u[sl], x[sl], y[sl]
    if x[0] > x[-1]:
        u, x, y, why = u[::-1], x[::-1], y[::-1], why[::-1]
    return _Branch(u, x, y, why)


def _reach(x, gap, k, target, side, where, name, ends):
    """x on the given side of the throat k where the local gap first reaches ``target``."""
    idx = range(k, -1, -1) if side < 0 else range(k, len(x))
    prev, widest = k, gap[k]
    for i in idx:
        if widest > 2.0 * gap[k] and gap[i] < SECOND_CONTACT_RATIO * gap[k]:
            raise CaseError(
                f"{where}: on the {name} side the walls close in again to "
                f"{gap[i] / gap[k]:.3g} times the gap {1e3 * abs(x[i] - x[k]):.3g} mm from "
                f"the contact (another contact) before opening {target / gap[k]:.3g}-fold")
        widest = max(widest, gap[i])
        if gap[i] >= target:
            a, b = gap[prev], gap[i]
            f = (target - a) / (b - a) if b != a else 0.0
            return float(x[prev] + f * (x[i] - x[prev]))
        prev = i
    raise CaseError(
        f"{where}: on the {name} side the gap opens only {widest / gap[k]:.3g}-fold of the "
        f"{target / gap[k]:.3g} asked before {ends(side)}")
