"""Form (disc) cutter for an externally toothed rotor of a helical pair (the internal
gear's inner rotor, either twin-screw rotor).

The rotor flank is a helical surface of constant lead; in the rotor's own frame (origin
on its axis, z along it)

    P(u, z) = R(-k z) p(u) + z e_z,     k = omega wrap / L  [rad/m]

(omega the rotor's speed ratio) with ``p`` the transverse profile turned so that the
tooth space being cut faces +x: its root (the smallest radius of the lobe period about
u = 0) on +x, u running from the tip before it to the tip after it (the largest radii
within a lobe period either side; for the internal gear's inner rotor u from -1/2 to
1/2, root g = 0), see :func:`tooth_space`.  The tool is a surface of
revolution about the axis through ``(C, 0, 0)`` with direction
``e_t = (0, cos S, sin S)``: C the centre distance, S the setting angle (tan S = k r gives
a disc plane along the helix at radius r).

Contact condition (forward): a surface of revolution touches the helical surface
along the curve where the rotor's normal meets the tool axis,
``(P - O_t) . (n x e_t) = 0``.  For every profile point u it is solved for z; the tool
profile (meridian) is then the axial position ``h = (P - O_t) . e_t`` and the radius
``R = |P - O_t - h e_t|`` of the contact point.

Round trip (inverse): the rotor is the envelope of the tool under the helical motion
whose velocity field is ``v = k e_z x X - e_z``; on each tool circle h the contact is
where the tool normal is orthogonal to v.  Screwing that point back to z = 0,
``q = R(k z) (x, y)``, regenerates the transverse profile, which must match ``p``
within the tolerance.  A tool point whose screw image lies inside the rotor material
would cut it (interference); the images of the tool surface are checked as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from rotorflow.errors import CaseError

from ..curves import closest, sample
from .cutter_check import interference
from .cutter_corners import CORNER_DEG, corner_limits, trim_swallowtails, turn_angles
from .tooth_space import BISECT, tooth_space

#: Samples of the bracket scan of the contact equations (bisected BISECT times after it).
SCAN = 801
#: A root where the rotor's normal is within this angle (radians) of the tool axis is
#: no contact: the condition vanishes there because the normal never meets the axis.
PARALLEL = 1e-9
#: Smallest spacing of written tool points, in tolerances.
MIN_SPACING = 0.01

@dataclass(frozen=True)
class CutterSetup:
    setting_angle: float  # S [rad]
    centre_distance: float  # C [m]
    k: float  # rotor twist rate [rad/m], right-handed positive; 0 for a straight rotor

    @property
    def origin(self) -> np.ndarray:
        return np.array([self.centre_distance, 0.0, 0.0])

    @property
    def axis(self) -> np.ndarray:
        return np.array([0.0, math.cos(self.setting_angle), math.sin(self.setting_angle)])


class _Turned:
    """The rotor profile turned so that the root at ``root`` faces +x (rotor frame)."""

    def __init__(self, curve, root: float = 0.0):
        self.curve = curve
        root_point = curve.point(np.array([root]))[0]
        self.turn = -math.atan2(root_point[1], root_point[0])
        self.c, self.s = math.cos(self.turn), math.sin(self.turn)
        self.n = curve.n
        self.name = curve.name

    def _r(self, v):
        return np.stack([self.c * v[..., 0] - self.s * v[..., 1],
                         self.s * v[..., 0] + self.c * v[..., 1]], -1)

    def point(self, u):
        return self._r(self.curve.point(u))

    def derivative(self, u):
        return self._r(self.curve.derivative(u))

    def normal(self, u):
        return self._r(self.curve.normal(u))


def _helix(p, dp, z, k):
    """P, P_u, P_z of the helical flank (arrays over u, z broadcast)."""
    c, s = np.cos(-k * z), np.sin(-k * z)
    x = c * p[..., 0] - s * p[..., 1]
    y = s * p[..., 0] + c * p[..., 1]
    P = np.stack([x, y, z * np.ones_like(x)], -1)
    Pu = np.stack([c * dp[..., 0] - s * dp[..., 1], s * dp[..., 0] + c * dp[..., 1],
                   np.zeros_like(x)], -1)
    Pz = np.stack([k * y, -k * x, np.ones_like(x)], -1)
    return P, Pu, Pz


def _bisect(f, lo, hi, flo):
    """Vectorised bisection of f on brackets [lo, hi] with f(lo) = flo."""
    for _ in range(BISECT):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        left = np.sign(fm) == np.sign(flo)
        lo = np.where(left, mid, lo)
        flo = np.where(left, fm, flo)
        hi = np.where(left, hi, mid)
    return 0.5 * (lo + hi)


def _roots(f, span: float, n: int):
    """Every root of f(t) in [-span, span] the scan brackets, for n problems at once.

    Returns (n, m) roots, NaN-padded, m the most sign changes of any problem.
    """
    t = np.linspace(-span, span, SCAN)
    vals = np.stack([f(np.full(n, ti)) for ti in t], -1)  # (n, SCAN)
    change = np.sign(vals[:, :-1]) * np.sign(vals[:, 1:]) <= 0.0
    m = int(change.sum(1).max()) if change.any() else 0
    out = np.full((n, max(m, 1)), np.nan)
    if m == 0:
        return out
    rows, cols = np.nonzero(change)
    slot = np.concatenate([np.arange(c) for c in np.bincount(rows, minlength=n)])
    lo, hi = t[cols], t[cols + 1]

    def fr(x):
        return _pick(f, x, rows, n)

    out[rows, slot] = _bisect(fr, lo.astype(float), hi.astype(float), vals[rows, cols])
    return out


def _pick(f, x, rows, n):
    """f evaluated for problems ``rows`` at their own x (f is vectorised over n)."""
    res = np.empty(len(x))
    order = np.argsort(rows, kind="stable")
    r, xs = rows[order], x[order]
    # evaluate in layers: each layer has at most one entry per problem
    layer = np.concatenate([np.arange(c) for c in np.bincount(r, minlength=n)])
    for k in range(int(layer.max()) + 1):
        sel = layer == k
        full = np.zeros(n)
        full[r[sel]] = xs[sel]
        res[order[sel]] = f(full)[r[sel]]
    return res


def _nearest_zero(roots, valid):
    """Per problem, the valid root of smallest |t| (NaN if none)."""
    score = np.where(valid & np.isfinite(roots), np.abs(roots), np.inf)
    j = np.argmin(score, axis=1)
    best = roots[np.arange(len(roots)), j]
    return np.where(np.isfinite(score[np.arange(len(roots)), j]), best, np.nan)


def _continued_zero(roots, valid, start: int):
    """Per problem (in profile order), the valid root nearest its neighbour's, walking
    out from problem ``start`` (its own: the one of smallest |t|), so that the contact
    runs on along the flank.  (The root of smallest |t| alone jumps where two are
    nearly as far: a one-lobe rotor's tooth space runs all the way round, and the tool
    reaches its tips half a lead either side.)"""
    cand = np.where(valid & np.isfinite(roots), roots, np.nan)
    out = np.full(len(roots), np.nan)
    out[start] = _nearest_zero(roots[start:start + 1], valid[start:start + 1])[0]
    for step in (1, -1):
        prev = out[start]
        for i in range(start + step, len(roots) if step > 0 else -1, step):
            row = cand[i]
            if np.isfinite(row).any():
                ref = 0.0 if np.isnan(prev) else prev
                out[i] = row[np.nanargmin(np.abs(row - ref))]
                prev = out[i]
    return out


@dataclass(frozen=True)
class Cutter:
    setup: CutterSetup
    u: np.ndarray  # rotor profile parameters (tooth space, tip to tip)
    contact: np.ndarray  # (n, 3) contact points on the rotor, rotor frame
    axial: np.ndarray  # h: position along the tool axis
    radius: np.ndarray  # R: tool radius
    turn: float  # rotation applied to the profile (root of the tooth space on +x)
    root: float = 0.0  # profile parameter of that root


def form_cutter(curve, setup: CutterSetup, tol: float, space=None) -> Cutter:
    """The tool profile generating the tooth space ``space`` = (tip, root, tip) of
    ``curve`` (default :func:`tooth_space`)."""
    lo, root, hi = tooth_space(curve) if space is None else space
    prof = _Turned(curve, root)
    us = sample(curve, 0.1 * tol)
    us = us - curve.n * np.floor((us - lo) / curve.n)  # into [lo, lo + n)
    u = np.sort(us[(us >= lo) & (us <= hi)])
    u = np.unique(np.concatenate([[lo], u, [hi]]))
    u, dp, corners = corner_limits(prof, u, lo, hi)
    p = prof.point(u)
    o, e = setup.origin, setup.axis
    k = setup.k
    radius = float(np.linalg.norm(p, axis=-1).max())
    # A profile point meets the tool about where the helix has turned it to face the
    # tool: within a quarter turn on a many-lobed rotor, up to half a turn at the tips
    # of a one-lobe rotor's tooth space, which runs all the way round.
    reach = max(0.5 * math.pi, float(np.abs(np.arctan2(p[:, 1], p[:, 0])).max()) + 0.25 * math.pi)
    span = radius if k == 0.0 else min(min(reach, math.pi) / abs(k), 4.0 * radius)

    def f(z):
        P, Pu, Pz = _helix(p, dp, z, k)
        n = np.cross(Pu, Pz)
        return np.sum((P - o) * np.cross(n, e), -1)

    roots = _roots(f, span, len(u))
    # A root is a contact only where the rotor's outward normal runs to the tool axis
    # (the normal line meets it in front of the flank, not through the rotor).
    valid = np.zeros(roots.shape, dtype=bool)
    for j in range(roots.shape[1]):
        zj = np.nan_to_num(roots[:, j])
        P, Pu, Pz = _helix(p, dp, zj, k)
        n = np.cross(Pu, Pz)
        ne = np.cross(n, e)
        lam = -np.sum(np.cross(P - o, e) * ne, -1) / np.maximum(np.sum(ne * ne, -1), 1e-300)
        # (a normal along the tool axis zeroes the condition without meeting the axis)
        along = np.sum(ne * ne, -1) <= PARALLEL ** 2 * np.sum(n * n, -1)
        valid[:, j] = (lam > 0.0) & ~along
    z = _continued_zero(roots, valid, int(np.argmin(np.abs(u - root))))
    # A corner's flank end, or a tooth space's end, that meets no tool circle leaves the
    # corner to its other flank's point, the end to the flank's next (the trochoidal
    # pump male: its tips' normals run along the tool axis).
    ends = np.array([0, len(u) - 1])
    lost = np.union1d(np.union1d(corners[np.isnan(z[corners])],
                                 (corners + 1)[np.isnan(z[corners + 1])]),
                      ends[np.isnan(z[ends])])
    if len(lost):
        u, p, dp, z = (np.delete(x, lost, axis=0) for x in (u, p, dp, z))
        kept = corners[~np.isin(corners, lost) & ~np.isin(corners + 1, lost)]
        corners = kept - np.searchsorted(lost, kept)
    if np.isnan(z).any():
        i = int(np.nonzero(np.isnan(z))[0][0])
        raise CaseError(
            f"no contact between the form cutter and the {curve.name} rotor at profile point "
            f"({p[i, 0] * 1e3:.3f}, {p[i, 1] * 1e3:.3f}) mm: change "
            "cutter_setting_angle_deg or cutter_centre_distance_mm")
    P, _, _ = _helix(p, dp, z, k)
    d = P - o
    h = d @ e
    R = np.linalg.norm(d - h[:, None] * e, axis=-1)
    if not (R > 0.0).all():
        raise CaseError(f"the form cutter's axis passes through the {curve.name} rotor: "
                        "increase cutter_centre_distance_mm")
    h, R, u, *xyz = trim_swallowtails(corners, h, R, u, *P.T)
    P = np.column_stack(xyz)
    # Near the sigma_bar = 1 point the flank barely moves with u: drop tool points
    # closer than MIN_SPACING * tol to the last one kept (they carry no shape).
    keep = [0]
    for i in range(1, len(u)):
        if math.hypot(h[i] - h[keep[-1]], R[i] - R[keep[-1]]) > MIN_SPACING * tol:
            keep.append(i)
    if keep[-1] != len(u) - 1:
        keep[-1] = len(u) - 1
    keep = np.array(keep)
    return Cutter(setup, u[keep], P[keep], h[keep], R[keep], prof.turn, root)


class _Broken:
    """A cubic spline by chord length, broken at the given nodes (value and slope)."""

    def __init__(self, s, y, breaks):
        self.edges = s[breaks]
        self.pieces = [CubicSpline(s[a:b + 1], y[a:b + 1])
                       for a, b in zip(breaks[:-1], breaks[1:], strict=True)]

    def __call__(self, s, nu=0):
        s = np.asarray(s, dtype=float)
        j = np.clip(np.searchsorted(self.edges, s, side="right") - 1, 0, len(self.pieces) - 1)
        out = np.empty(s.shape)
        for k in np.unique(j):
            out[j == k] = self.pieces[k](s[j == k], nu)
        return out


def _meridian(axial, radius):
    """(s, h(s), R(s)): the tool profile through its points by chord length, a cubic
    spline between its corners (a chord turning by more than CORNER_DEG from the last:
    a rotor's concave corner, the 4/6 pin-cycloid male's at its root, is a corner of
    the tool, which a spline through it overshoots by tens of micrometres)."""
    d = np.column_stack([np.diff(axial), np.diff(radius)])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(d[:, 0], d[:, 1]))])
    if not np.all(np.diff(s) > 0.0):
        raise CaseError("the form-cutter profile has repeated points")
    corners = np.nonzero(np.abs(turn_angles(d[:-1], d[1:])) > math.radians(CORNER_DEG))[0] + 1
    breaks = np.unique(np.concatenate([[0], corners, [len(s) - 1]]))
    return s, _Broken(s, axial, breaks), _Broken(s, radius, breaks)


def _frame(setup: CutterSetup):
    e = setup.axis
    a = np.array([-1.0, 0.0, 0.0])  # from the tool axis toward the rotor axis
    b = np.cross(e, a)
    return e, a, b


def _tool_points(setup, h, R, psi):
    e, a, b = _frame(setup)
    er = np.cos(psi)[..., None] * a + np.sin(psi)[..., None] * b
    return setup.origin + h[..., None] * e + R[..., None] * er, er


def _to_transverse(T, k):
    c, s = np.cos(k * T[..., 2]), np.sin(k * T[..., 2])
    return np.stack([c * T[..., 0] - s * T[..., 1], s * T[..., 0] + c * T[..., 1]], -1)


def regenerate(setup: CutterSetup, axial, radius, refine: int = 2):
    """Transverse rotor points enveloped by the tool profile (h, R) (rotor frame, turned).

    The meridian is a cubic spline through the given points by chord length; it is
    evaluated at the points and ``refine - 1`` points between each pair, so that the
    interpolation between the written points is checked too.  Returns (s, points).
    """
    s_nodes, hs, Rs = _meridian(np.asarray(axial, float), np.asarray(radius, float))
    s = np.concatenate([np.linspace(a, b, refine, endpoint=False)
                        for a, b in zip(s_nodes[:-1], s_nodes[1:], strict=True)]
                       + [s_nodes[-1:]])
    h, R = hs(s), Rs(s)
    dh, dR = hs(s, 1), Rs(s, 1)
    e, _, _ = _frame(setup)
    k = setup.k

    def g(psi):
        T, er = _tool_points(setup, h, R, psi)
        n = dh[:, None] * er - dR[:, None] * e
        v = k * np.cross(np.array([0.0, 0.0, 1.0]), T) - np.array([0.0, 0.0, 1.0])
        return np.sum(n * v, -1)

    roots = _roots(g, 0.5 * math.pi, len(s))
    psi = _nearest_zero(roots, np.isfinite(roots))
    if np.isnan(psi).any():
        bad = R[np.isnan(psi)]
        raise CaseError(f"the form-cutter profile does not envelope the rotor's flank "
                        f"everywhere: no contact where the tool's radius is "
                        f"{bad.min() * 1e3:.4g}-{bad.max() * 1e3:.4g} mm "
                        f"({int(np.isnan(psi).sum())} of its {psi.size} points)")
    T, _ = _tool_points(setup, h, R, psi)
    return s, _to_transverse(T, k)


def round_trip(curve, cutter: Cutter, axial=None, radius=None) -> dict:
    """Regenerate the rotor profile from the tool profile (as written, if given) and
    measure it against the analytic profile; also the deepest tool cut into the rotor."""
    prof = _Turned(curve, cutter.root)
    axial = cutter.axial if axial is None else np.asarray(axial, float)
    radius = cutter.radius if radius is None else np.asarray(radius, float)
    try:
        s, q = regenerate(cutter.setup, axial, radius)
    except CaseError as e:
        raise CaseError(f"the {curve.name} rotor's disc cutter: {e}; a disc tool cannot cut "
                        f"this profile at setting angle "
                        f"{math.degrees(cutter.setup.setting_angle):.4g} deg ([export] "
                        f"cutter_setting_angle_deg)") from None
    s_nodes = _meridian(axial, radius)[0]
    u0 = np.interp(s, s_nodes, cutter.u)
    _, dist, _ = closest(prof, q, u0, iterations=12)
    depth, where = interference(prof, cutter.setup, _meridian(axial, radius))
    out = {"round_trip_max_m": float(dist.max()), "round_trip_points": int(len(q)),
           "interference_m": depth}
    if where is not None:
        out["interference_at_m"] = [float(x) for x in where]
    return out


def default_setup(pair, sweep, angle: float | None, centre: float | None,
                  rotor: str | None = None) -> CutterSetup:
    """The cutter of a helical (or straight) externally toothed rotor (by default the
    pair's last, the internal gear's inner rotor); conical rotors have none.  The tool
    sits at the pair's diameter from the rotor axis unless ``centre`` is given."""
    if sweep.kind == "conical" or abs(sweep.lead_ratio - 1.0) > 1e-12:
        raise CaseError("a form cutter needs a rotor of constant section and lead "
                        "(straight or helical sweep); this rotor is "
                        + ("conical" if sweep.kind == "conical" else "of variable lead"))
    cut = pair.rotors[-1] if rotor is None else pair.rotor(rotor)
    k = cut.speed_ratio * sweep.wrap / sweep.length
    r_pitch = cut.pitch_radius
    if angle is None:
        angle = math.atan(k * r_pitch)
    return CutterSetup(angle, pair.diameter if centre is None else centre, k)
