"""The clearance gap at a sealing line, as a 2D section for a CFD gap case.

At outer-rotor angle ``phi1`` the leading pin (pin 0) of the chamber space touches the
inner rotor.  In a real machine the inner rotor is relieved by a clearance ``gap``: its
profile is offset inward along its own normal (a true normal offset, not a shift).  The
section is written in the gap's own frame: origin at the contact point, y along the
contact normal (from the inner rotor into the pin), x along the common tangent, pointing
from the older (leading, higher-pressure) chamber into the younger one, so the flow of a
compressor's leakage runs toward +x.  Both walls come out as polylines y(x) over the same
x range, cut where the gap has opened to ``inlet_ratio`` and ``outlet_ratio`` times its
minimum, ready for :class:`rotorflow.cases.gap_mesh.GapWalls`.
"""

from __future__ import annotations

import math

import numpy as np

from rotorflow.errors import CaseError

from .pin_gerotor import PinGerotor, rotate
from .pin_space import PinSpace

#: Parameter span searched on each side of the contact on the inner profile [rad of g].
SEARCH_SPAN = 1.0


def sealing_gap_walls(
    pair: PinGerotor,
    phi1: float,
    gap: float,
    inlet_ratio: float = 20.0,
    outlet_ratio: float = 3.0,
    points: int = 201,
) -> tuple[np.ndarray, np.ndarray]:
    """Lower (inner rotor, offset by ``gap``) and upper (pin) walls in the gap frame."""
    if not gap > 0.0:
        raise CaseError(f"the gap must be positive, got {gap}")
    if inlet_ratio <= 1.0 or outlet_ratio <= 1.0:
        raise CaseError("inlet and outlet gap ratios must exceed 1")
    space = PinSpace(pair)
    lead = space.contacts(phi1)[-1]
    if lead.kind != "pin":
        raise CaseError(f"no pin contact leads the chamber at {math.degrees(phi1):.3f} deg")
    x0 = lead.point
    centre = rotate(pair.pin_centre(0), phi1)
    n = (centre - x0) / pair.rho
    t = np.array([n[1], -n[0]])
    e_theta = np.array([-x0[1], x0[0]])
    if t @ e_theta > 0.0:  # point from the older (ccw-ahead) chamber to the younger
        t = -t

    def inner_in_frame(g):
        phi2 = pair.m21 * phi1
        p = rotate(pair.inner_point(g), phi2) + pair.O2
        nrm = rotate(pair.inner_normal(g), phi2)
        p = p - gap * nrm  # relieve the inner rotor by the clearance, along its normal
        d = p - x0
        return d @ t, d @ n

    g = lead.g2 + np.linspace(-SEARCH_SPAN, SEARCH_SPAN, 20001)
    xi, yi = inner_in_frame(g)
    # Keep the branch through the contact, where the inner wall is a graph over x.
    k0 = int(np.argmin(np.abs(xi) + np.abs(yi + gap)))
    dx = np.sign(np.diff(xi))
    lo = k0
    while lo > 0 and dx[lo - 1] == dx[k0]:
        lo -= 1
    hi = k0
    while hi < len(dx) - 1 and dx[hi + 1] == dx[k0]:
        hi += 1
    xi, yi = xi[lo : hi + 2], yi[lo : hi + 2]
    if xi[0] > xi[-1]:
        xi, yi = xi[::-1], yi[::-1]

    def upper(x):
        r = pair.rho
        inside = np.abs(x) < r
        return np.where(inside, r - np.sqrt(np.maximum(r * r - x * x, 0.0)), np.inf)

    local_gap = upper(xi) - yi
    g_min = float(local_gap.min())
    x_in = _reach(xi, local_gap, inlet_ratio * gap, side=-1)
    x_out = _reach(xi, local_gap, outlet_ratio * gap, side=+1)
    x = np.linspace(x_in, x_out, points)
    lower = np.column_stack([x, np.interp(x, xi, yi)])
    up = np.column_stack([x, upper(x)])
    if not np.all(np.isfinite(up[:, 1])):
        raise CaseError("the gap opens beyond the pin radius; lower the gap ratios")
    if abs(g_min - gap) > 1e-3 * gap + 1e-9 * pair.diameter:
        raise CaseError(f"the offset inner profile leaves {g_min:.4g} m, not the gap {gap:.4g} m")
    return lower, up


def _reach(x, gap, target, side):
    """x on the given side of the throat where the local gap first reaches ``target``."""
    k = int(np.argmin(gap))
    idx = range(k, -1, -1) if side < 0 else range(k, len(x))
    prev = k
    for i in idx:
        if gap[i] >= target:
            a, b = gap[prev], gap[i]
            f = (target - a) / (b - a) if b != a else 0.0
            return float(x[prev] + f * (x[i] - x[prev]))
        prev = i
    raise CaseError("the gap does not open to the requested ratio within the profile span")
