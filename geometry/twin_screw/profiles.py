"""Twin-screw rotor profiles: one lobe of generated (and primary) arcs, repeated.

Both profiles are closed counter-clockwise :class:`~..curves.PieceCurve` chains with
the rotor's material inside, each in its own frame (origin on its axis; the male's lobe
0 as the rack's period generates it at theta = 0, the female's likewise).  Lobe k is
lobe 0 turned by 2 pi k / N.

:func:`rack_pair` generates both rotors from one period of a rack and checks, in this
order, that nothing is wrong with them, raising :class:`CaseError` naming the arc and
where: the rack is a continuous chain over one pitch; no generated arc turns back
(undercut); no lobe crosses itself (a loop); the two rotors, turned at the gear ratio,
do not overlap (interference).  Nothing is trimmed or repaired.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from ..curves import PieceCurve, closest, sample
from ..planar import TWO_PI, rotate
from ..polygons import PolygonDistance, rings_intersections
from .meshing import Gearing, RackGenerated, check_no_undercut

#: Rack arcs must join end to start within 1e-9 of the pitch (a rounding slip of typed
#: in dimensions is ~1e-12; a visible gap is a wrong arc, not noise).
JOIN_TOL = 1e-9
#: Chordal tolerance of the polygons on which loops and interference are looked for, as
#: a fraction of the centre distance: 1e-6 (0.08 um at C = 80 mm) resolves any loop
#: larger than a machining tolerance.
CHECK_TOL = 1e-6
#: Overlap of the turned rotors, as a fraction of the centre distance, beyond which they
#: interfere: conjugate profiles touch exactly, and 1e-8 (0.8 nm at C = 80 mm) is far
#: above the foot-point error of curves.closest on analytic curves (~1e-12 m).
OVERLAP_TOL = 1e-8
#: Male angles over one male lobe at which interference is checked.
CHECK_ANGLES = 48


@dataclass(frozen=True)
class TwinProfile(PieceCurve):
    """One rotor's closed profile: ``pieces`` (one lobe, counter-clockwise) repeated
    ``lobes`` times."""

    name: str
    pieces: tuple
    lobes: int
    material_inside: bool = True

    @property
    def n(self) -> int:
        return self.lobes * len(self.pieces)

    def _eval(self, u, order: int):
        j, t = self._split(u)
        per = len(self.pieces)
        lobe, k = np.divmod(j, per)
        out = np.empty(t.shape + (2,))
        for i, piece in enumerate(self.pieces):
            m = k == i
            if m.any():
                out[m] = piece.eval(t[m], order)
        return rotate(out, TWO_PI * lobe / self.lobes)

    def piece_name(self, u) -> str:
        """Which arc the global parameter u lies on."""
        j, _ = self._split(u)
        return self.pieces[int(j) % len(self.pieces)].name


def check_rack(arcs, gearing: Gearing) -> None:
    """The rack arcs must form one continuous chain over exactly one pitch."""
    ends = [(a, a.eval(np.array([1.0]), 0)[0]) for a in arcs]
    starts = [a.eval(np.array([0.0]), 0)[0] for a in arcs]
    tol = JOIN_TOL * gearing.pitch
    for k, (arc, end) in enumerate(ends):
        nxt = starts[(k + 1) % len(arcs)]
        if k == len(arcs) - 1:
            nxt = nxt + np.array([0.0, gearing.pitch])
        gap = float(np.linalg.norm(end - nxt))
        if gap > tol:
            raise CaseError(f"rack arc '{arc.name}' ends {gap * 1e3:.4g} mm away from the "
                            f"start of the next arc (the rack must repeat every pitch, "
                            f"{gearing.pitch * 1e3:.4g} mm)")


def check_no_loop(profile: TwinProfile, scale: float) -> None:
    """Raise CaseError naming the arc where the profile crosses itself."""
    u = sample(profile, CHECK_TOL * scale)
    hits = rings_intersections([profile.point(u)])
    if len(hits):
        i, j = (int(v) for v in hits[0])
        raise CaseError(f"loop: the {profile.name} profile crosses itself between the "
                        f"{profile.piece_name(u[i])} (u = {u[i]:.4f}) and the "
                        f"{profile.piece_name(u[j])} (u = {u[j]:.4f})")


def signed_gap(male, female, gearing: Gearing, thetas, tol: float):
    """Smallest signed distance from the male profile (sampled to ``tol``) to the true
    female curve at each male angle of ``thetas`` (negative: overlap), and the male
    parameter where it is."""
    um = sample(male, tol)
    pm = male.point(um)
    uf = sample(female, tol)
    polygon = PolygonDistance(female.point(uf), nearest=6)  # (edges long near corners)
    reach = female.radius_max + tol  # male points farther from O2 cannot touch
    gaps, where = [], []
    for theta in np.atleast_1d(thetas):
        # male points in the female frame
        x = rotate(rotate(pm, theta) - gearing.female_axis, theta * gearing.r1 / gearing.r2)
        near = np.nonzero(np.linalg.norm(x, axis=-1) <= reach)[0]
        if not len(near):
            gaps.append(np.inf)
            where.append(np.nan)
            continue
        # The polygon lies within tol of the curve: only points within 2 tol of the
        # polygon's least gap can hold the curve's; their feet on the true curve.
        d, sign, k = polygon.nearest_points(x[near])
        d = sign * d
        close = d <= d.min() + 2.0 * tol
        near, k = near[close], k[close]
        _, _, signed = closest(female, x[near], uf[k])
        i = int(np.argmin(signed))
        gaps.append(float(signed[i]))
        where.append(float(um[near[i]]))
    return np.array(gaps), np.array(where)


def check_no_interference(male, female, gearing: Gearing) -> None:
    """Raise CaseError at the first male angle where the rotors overlap."""
    scale = gearing.centre_distance
    thetas = np.linspace(0.0, TWO_PI / male.lobes, CHECK_ANGLES, endpoint=False)
    gaps, where = signed_gap(male, female, gearing, thetas, CHECK_TOL * scale)
    bad = np.nonzero(gaps < -OVERLAP_TOL * scale)[0]
    if len(bad):
        i = int(bad[0])
        raise CaseError(f"interference: at male angle {np.degrees(thetas[i]):.3f} deg the "
                        f"{male.piece_name(where[i])} enters the female by "
                        f"{-gaps[i] * 1e6:.4g} um")


def rack_pair(gearing: Gearing, arcs) -> tuple[TwinProfile, TwinProfile]:
    """Male and female profiles generated by one pitch of rack ``arcs`` (ordered along
    +b, i.e. from the male's trailing to its leading side), checked."""
    male, female = undercut_free_pair(gearing, arcs)
    for profile in (male, female):
        check_no_loop(profile, gearing.centre_distance)
    check_no_interference(male, female, gearing)
    return male, female


def undercut_free_pair(gearing: Gearing, arcs) -> tuple[TwinProfile, TwinProfile]:
    """:func:`rack_pair`'s first two checks only (the rack's chain, no undercut): the
    profiles, not yet checked for loops or interference."""
    check_rack(arcs, gearing)
    male = TwinProfile("male", tuple(RackGenerated(a, gearing, "male") for a in arcs),
                       gearing.lobes_male)
    # Along +b the female is traversed clockwise: reverse the chain for counter-clockwise.
    female = TwinProfile("female", tuple(RackGenerated(a, gearing, "female", reverse=True)
                                         for a in reversed(arcs)), gearing.lobes_female)
    for piece in (*male.pieces, *female.pieces):
        check_no_undercut(piece)
    return male, female
