"""The clearance gap at a contact of two rotors, as a 2D section: the family-neutral cut.

A family supplies the gap's frame and its two walls; this module cuts the section.  The
frame: origin at the contact point of the conjugate (unrelieved) pair, y along the
contact normal (from the lower wall's rotor into the upper wall's), x along the common
tangent, pointing from the older (higher-pressure) chamber into the younger one.  A wall
is one rotor's true profile (one of them relieved by the clearance, a normal offset,
:func:`.offsets.offset_profile`) as a function ``xy(u)`` of its own parameter into that
frame, sampled over a span ``u`` through the contact.

:func:`cut_section` returns both walls as polylines y(x) over the same x range, cut where
the gap has opened to ``inlet_ratio`` and ``outlet_ratio`` times its minimum, every point
put exactly on its wall by bisection, ready for :class:`rotorflow.cases.gap_walls.GapWalls`;
where no such section exists it raises a CaseError that starts with ``where`` (the family
names the angle there) and says why.  :func:`surface_speeds` gives the tangential speeds of
the walls relative to the moving contact.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

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


@dataclass(frozen=True)
class Wall:
    """One wall of a gap: ``xy(u) -> (x, y)`` in the gap frame (arrays in, arrays out),
    the parameters ``u`` searched (in order, through the contact) and ``y_contact``, the
    y of the wall's point at the contact (0, or -+ the clearance on the relieved wall)."""

    name: str
    xy: Callable
    u: np.ndarray
    y_contact: float
    #: What ends the wall at the first and the last of ``u`` (in messages).
    span_ends: tuple[str, str] = ("reaches the end of the searched span",) * 2


def check_arguments(gap: float, inlet_ratio: float, outlet_ratio: float) -> None:
    if not gap > 0.0:
        raise CaseError(f"the gap must be positive, got {gap}")
    if inlet_ratio <= 1.0 or outlet_ratio <= 1.0:
        raise CaseError("inlet and outlet gap ratios must exceed 1")


class Branch:
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


def branch(wall: Wall) -> Branch:
    """The wall's samples nearest the contact and on either side as long as x keeps its
    sense, in increasing x; ``why`` says what ends it on each side."""
    u = wall.u
    x, y = wall.xy(u)
    k0 = int(np.argmin(np.hypot(x, y - wall.y_contact)))
    dx = np.sign(np.diff(x))
    lo = k0
    while lo > 0 and dx[lo - 1] == dx[k0]:
        lo -= 1
    hi = k0
    while hi < len(dx) - 1 and dx[hi + 1] == dx[k0]:
        hi += 1
    why = [wall.span_ends[0] if lo == 0 else
           f"turns back across the gap {1e3 * abs(x[lo]):.3g} mm from the contact",
           wall.span_ends[1] if hi == len(dx) - 1 else
           f"turns back across the gap {1e3 * abs(x[hi + 1]):.3g} mm from the contact"]
    sl = slice(lo, hi + 2)
    u, x, y = u[sl], x[sl], y[sl]
    if x[0] > x[-1]:
        u, x, y, why = u[::-1], x[::-1], y[::-1], why[::-1]
    return Branch(u, x, y, why)


def local_gap(lower: Branch, upper: Branch) -> tuple[np.ndarray, np.ndarray]:
    """(x, upper y - lower y) on SEARCH_SAMPLES points of the x range both branches span."""
    x_a = max(lower.x[0], upper.x[0])
    x_b = min(lower.x[-1], upper.x[-1])
    xs = np.linspace(x_a, x_b, SEARCH_SAMPLES)
    return xs, np.interp(xs, upper.x, upper.y) - np.interp(xs, lower.x, lower.y)


def cut_section(lower: Wall, upper: Wall, gap: float, inlet_ratio: float,
                outlet_ratio: float, points: int, where: str, scale: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper walls, (points, 2) arrays of (x, y) in the gap frame (module
    docstring); ``scale`` is the machine's size, for the rounding allowance of the check
    that the narrowest gap is the clearance."""
    branches = {upper.name: branch(upper), lower.name: branch(lower)}
    lo_b, up_b = branches[lower.name], branches[upper.name]
    xs, local = local_gap(lo_b, up_b)
    x_a, x_b = xs[0], xs[-1]
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
    low = np.column_stack([x, lo_b.exact(lower.xy, x)])
    up = np.column_stack([x, up_b.exact(upper.xy, x)])
    exact_min = float(np.min(up[:, 1] - low[:, 1]))
    if abs(exact_min - gap) > GAP_TOL * gap + 1e-9 * scale:
        raise CaseError(f"{where}: the narrowest gap across the section is "
                        f"{exact_min * 1e6:.5g} um, not the clearance {gap * 1e6:.5g} um "
                        "(the walls are not parallel where they are closest)")
    return low, up


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


def surface_speeds(x0: np.ndarray, t: np.ndarray, contact_velocity: np.ndarray,
                   omega: float, rotors: Sequence[tuple[np.ndarray, float]]
                   ) -> tuple[float, ...]:
    """Each rotor's surface speed at the contact ``x0`` along ``t``, relative to the
    contact point moving at ``contact_velocity`` [m/s] (fixed frame).

    ``rotors``: (axis, speed ratio) per wall, the rotor turning at ``ratio * omega``
    [rad/s] counter-clockwise about its axis.  In a frame travelling with the contact the
    gap keeps its shape and both surfaces slide along it at ``(v_rotor - dX/dt) . t``
    (their normal components are equal to the contact's: it stays on both); the
    difference of two is the sliding speed, zero where the contact passes the pitch point.
    """
    out = []
    for axis, ratio in rotors:
        r = x0 - axis
        v = ratio * omega * np.array([-r[1], r[0]])
        out.append(float((v - contact_velocity) @ t))
    return tuple(out)
