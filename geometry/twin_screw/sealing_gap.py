"""The interlobe clearance gap of a twin-screw pair, as a 2D section for a CFD gap case.

At male angle ``psi`` the male and the female touch at one or more points of the
transverse section: where the male's normal passes through the pitch point P (the law
of gearing, :meth:`.pair.TwinScrewPair._law`) *and* the male point lies on the female
(the law alone has a second, phantom root per flank, where the female is elsewhere).
:func:`contacts` lists them from the bottom (discharge-side) cusp to the top one.  The
section is cut at the one nearest the pitch point by default (the contact that carries
the interlobe sealing line through the mesh; ``contact`` picks another by its index in
that list).

In a real machine one rotor is relieved by a clearance ``gap``: its profile is offset
along its own normal into its material (:func:`..offsets.offset_profile`, a true normal
offset), the male's by default (the reference rotor, as for the solids;
``clearance_on`` = "male" or "female").  The frame is the internal gear's
(:mod:`..gap_section`): origin at the contact of the conjugate (unrelieved) pair, y along
the male's outward normal there (from the male into the female: the lower wall is the
male, the upper the female), x along the common tangent, pointing from the older
(higher-pressure) chamber into the younger one.  Which side is older is read from the
section the chamber table is built from (:mod:`.regions`, :func:`.section.chamber_index`):
a point in the fluid on each side of the contact, where the unrelieved gap is
``PROBE_GAP``, and the ages of the chambers that hold them.  The walls are cut where
the gap has opened to ``inlet_ratio`` and ``outlet_ratio`` times its minimum
(:func:`..gap_section.cut_section`).

No section exists, and a CaseError names the angle and the reason, where no contact is
found, where the contact is at a sharp corner of either profile (the pin-cycloid's male
tip and female groove corners: the gap has no tangent there), where the clearance folds
the relieved profile, where both sides of the contact are one chamber (a pocket between
two contacts), and where the gap does not open far enough before a wall turns back,
another contact closes it, or the relieved wall reaches a sharp corner (its offset ends
there: the relieved rotor's corner is not modelled).

:func:`sealing_wall_speeds` gives both walls' speeds along +x relative to the moving
contact (male at omega, female at -omega N1 / N2), from the contact's exact rate
(:meth:`.pair.TwinScrewPair._contact_at`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from rotorflow.errors import CaseError

from ..curves import closest, sample
from ..gap_section import (
    SEARCH_SAMPLES,
    Wall,
    branch,
    check_arguments,
    cut_section,
    local_gap,
    surface_speeds,
)
from ..offset_corners import CORNER_TURN, joint_turn
from ..offsets import Clearance, offset_profile
from ..planar import rotate
from .regions import _inside
from .section import chamber_index

#: Samples per male piece on which the law of gearing is bracketed: a flank's contact and
#: its phantom are a sizeable part of a piece apart, far more than 1/512.
LAW_SAMPLES = 512
#: A root of the law whose male point lies within this (per C) of the true female curve
#: is a contact: conjugate arcs meet to ~1e-12 C; a phantom root lies millimetres off.
ON_FEMALE = 1e-8
#: Chordal tolerance and largest step (per C) of the female samples that seed the
#: foot-point search, and how many nearest samples seed it: a flat arc sampled to its
#: chord error alone has samples half a millimetre apart, and the nearest can lie across
#: a corner from the foot.
FOOT_SAMPLES = 1e-5
FOOT_STEP = 1e-3
FOOT_SEEDS = 4
#: A contact is a band (conformal arcs) where the male stays on the female for one step
#: of this (per C) of arc length beside it: at a point contact two profiles of relative
#: curvature k part by k s^2 / 2 = 5e-7 k C^2 there, above ON_FEMALE = 1e-8 C unless
#: their relative radius of curvature 1 / k exceeds 50 C (they are then conformal).
BAND_STEP = 1e-3
#: Two contacts closer than this (per C) are one (the section table's SAME_POINT).
SAME_POINT = 1e-6
#: A contact within this (per C) of a corner is at the corner.
CORNER_NEAR = 1e-7
#: Parameter span searched on each side of the contact on either profile, in lobes: half
#: a lobe reaches past the tips on both sides.
LOBE_SPAN = 0.5
#: Where the probes that tell the older side sit (per C): the unrelieved gap there is 8 um
#: at C = 80 mm, far wider than the cut's grown rotors (2e-6 C) and chord error (1e-6 C).
PROBE_GAP = 1e-4
#: Offset in the profile parameter from a sharp corner at which a relieved wall's search
#: stops (analytic pieces: far below any real corner's size).
JOINT_STEP = 1e-9
CLEARANCE_ON = ("male", "female")


@dataclass(frozen=True)
class Contact:
    """A contact of the pair at one male angle (fixed frame)."""

    point: np.ndarray
    rate: np.ndarray | None  # d point / d psi; None where no section can be cut
    u_male: float
    u_female: float
    #: Why no gap section can be cut there (a sharp corner, a conformal band), or None.
    defect: str | None


def _corners(profile) -> list[tuple[float, str]]:
    """(u, description) of every sharp corner of a profile (joints only: the pieces are
    smooth)."""
    out = []
    for j in range(profile.n):
        if _sharp(profile, j):
            k = len(profile.pieces)
            out.append((float(j), f"the {profile.name} profile (between its "
                                  f"{profile.pieces[(j - 1) % k].name} and its "
                                  f"{profile.pieces[j % k].name})"))
    return out


def _sharp(profile, j: int) -> bool:
    """Whether the joint before piece j is a corner (a vanishing tangent too: no
    tangent there)."""
    turn = joint_turn(profile, j)
    return math.isnan(turn) or abs(turn) > CORNER_TURN


def _female_angle(pair, psi: float) -> float:
    """The female's counter-clockwise turn at male angle psi (-psi N1 / N2)."""
    return psi * pair.rotors[1].speed_ratio


class _Feet:
    """Foot points on the true female curve of fixed-frame points at one male angle."""

    def __init__(self, pair, psi: float):
        c = pair.gearing.centre_distance
        self.pair, self.psi = pair, psi
        self.u = sample(pair.female, FOOT_SAMPLES * c, max_step=FOOT_STEP * c)
        self.tree = cKDTree(pair.female.point(self.u))

    def local(self, x):
        """Fixed-frame points x in the female's own frame."""
        return rotate(np.asarray(x) - self.pair.gearing.female_axis,
                      -_female_angle(self.pair, self.psi))

    def foot(self, x) -> tuple[float, float]:
        """(female parameter, distance) of the foot of fixed-frame point x: Newton from
        the FOOT_SEEDS nearest samples, the nearest result (one seed can sit across a
        corner of the profile, where Newton stops)."""
        y = self.local(x)
        _, k = self.tree.query(y, k=FOOT_SEEDS)
        uf, dist, _ = closest(self.pair.female, np.repeat(y[None, :], FOOT_SEEDS, 0), self.u[k])
        i = int(np.argmin(dist))
        return float(uf[i]), float(dist[i])


def _candidates(pair, psi: float) -> list[float]:
    """Male parameters where a contact may be: the law of gearing's roots and the
    male's sharp corners (where the law jumps instead)."""
    male = pair.male
    grid = np.linspace(0.0, male.n, LAW_SAMPLES * male.n + 1)
    law = pair._law(grid, psi)
    brackets = np.nonzero(np.sign(law[:-1]) != np.sign(law[1:]))[0]
    roots = [pair._root(grid[j], grid[j + 1], 0.5 * (grid[j] + grid[j + 1]), psi)
             for j in brackets]
    return sorted({float(u % male.n) for u in roots if u is not None}
                  | {u for u, _ in _corners(male)})


def _on_female(pair, feet: _Feet, psi: float, u: float) -> bool:
    x = rotate(pair.male.point(np.array([u % pair.male.n])), psi)[0]
    return feet.foot(x)[1] <= ON_FEMALE * pair.gearing.centre_distance


def _touching(pair, feet: _Feet, psi: float) -> list[list[float]]:
    """The candidates on the female, grouped into runs along which the male stays on it
    (a conformal band: many roots of a law that vanishes along it; the midpoint between
    two roots of one band is on the female too)."""
    groups: list[list[float]] = []
    for u in _candidates(pair, psi):
        if not _on_female(pair, feet, psi, u):
            continue
        if groups and _on_female(pair, feet, psi, 0.5 * (groups[-1][-1] + u)):
            groups[-1].append(u)
        else:
            groups.append([u])
    if len(groups) > 1 and _on_female(pair, feet, psi,
                                      0.5 * (groups[-1][-1] + groups[0][0] + pair.male.n)):
        groups[0] = groups.pop() + groups[0]  # a band across u = 0
    return groups


def _band(pair, feet: _Feet, psi: float, group: list[float]) -> float:
    """Length [m] of a band of contact (0 for a contact at a point): a run of roots, or
    one root beside which the male stays on the female for BAND_STEP C."""
    male, c = pair.male, pair.gearing.centre_distance
    ends = rotate(male.point(np.array(group)[[0, -1]] % male.n), psi)
    length = float(np.linalg.norm(ends[1] - ends[0]))
    if len(group) > 1:
        return length
    u = group[0]
    du = BAND_STEP * c / float(np.linalg.norm(male.derivative(np.array([u]))))
    on = [_on_female(pair, feet, psi, u + side * du) for side in (-1.0, 1.0)]
    return BAND_STEP * c if any(on) else 0.0


def contacts(pair, psi: float) -> list[Contact]:
    """Every contact of the pair at male angle ``psi``, bottom (y < 0) to top; one per
    conformal band (the rotors touching along an arc, as the pin-cycloid's pin arcs do
    when the pin's centre passes the pitch point)."""
    male, c = pair.male, pair.gearing.centre_distance
    feet = _Feet(pair, psi)
    corners_m = [(male.point(np.array([u]))[0], what) for u, what in _corners(male)]
    corners_f = [(pair.female.point(np.array([u]))[0], what) for u, what in _corners(pair.female)]
    found: list[Contact] = []
    for group in _touching(pair, feet, psi):
        u = group[len(group) // 2] % male.n
        x = rotate(male.point(np.array([u])), psi)[0]
        if any(np.linalg.norm(x - f.point) < SAME_POINT * c for f in found):
            continue
        band = _band(pair, feet, psi, group)
        local, y = male.point(np.array([u]))[0], feet.local(x)
        corner = next((f"at a sharp corner of {what}" for p, what in corners_m
                       if np.linalg.norm(p - local) < CORNER_NEAR * c), None) or next(
            (f"at a sharp corner of {what}" for p, what in corners_f
             if np.linalg.norm(p - y) < CORNER_NEAR * c), None)
        defect = corner or (f"on a band of contact at least {band * 1e3:.3g} mm long "
                            "(conformal arcs)" if band else None)
        rate = None if defect else pair._contact_at(u, psi)[1]
        found.append(Contact(x, rate, u, feet.foot(x)[0], defect))
    return sorted(found, key=lambda f: f.point[1])


def _where(psi: float) -> str:
    return f"no gap section at male angle {math.degrees(psi):.6g} deg"


def _pick(pair, psi: float, contact: int | None) -> Contact:
    """The contact the section is cut at: ``contact`` by index, or nearest the pitch point."""
    where = _where(psi)
    found = contacts(pair, psi)
    if not found:
        raise CaseError(f"{where}: the rotors touch nowhere in the section")
    if contact is None:
        pick = min(found, key=lambda f: float(np.linalg.norm(f.point - pair.gearing.pitch_point)))
    elif isinstance(contact, int) and not isinstance(contact, bool) and \
            -len(found) <= contact < len(found):
        pick = found[contact]
    else:
        raise CaseError(f"{where}: contact {contact!r} is not one of the {len(found)} "
                        f"contacts there (0 to {len(found) - 1}, bottom to top)")
    if pick.defect:
        p = pick.point * 1e3
        raise CaseError(f"{where}: the contact at ({p[0]:.4f}, {p[1]:.4f}) mm is "
                        f"{pick.defect}: the gap has no single throat and tangent there")
    return pick


def _walls(pair, psi, x0, n, t, profiles, ys, spans):
    """(lower = male, upper = female) :class:`Wall` of ``profiles`` in the frame (x0, n, t);
    ``spans``: per profile, the parameters searched and what ends them."""
    male, female = profiles
    ang_f = _female_angle(pair, psi)

    def male_xy(u):
        d = rotate(male.point(u), psi) - x0
        return d @ t, d @ n

    def female_xy(u):
        d = rotate(female.point(u), ang_f) + pair.gearing.female_axis - x0
        return d @ t, d @ n

    return (Wall("male", male_xy, spans[0][0], ys[0], spans[0][1]),
            Wall("female", female_xy, spans[1][0], ys[1], spans[1][1]))


def _spans(pick: Contact, profiles, relieved: str | None):
    """(parameters, end reasons) searched on each of ``profiles`` (male, female) around
    the contact.  The relieved one is an offset (its own parameters): its span stops
    short of its sharp corners, where its cut pieces meet (it goes round the corners it
    is grown about on the clearance's arc, which are no corners of it)."""
    out = []
    for name, profile, u0 in (("male", profiles[0], pick.u_male),
                              ("female", profiles[1], pick.u_female)):
        ends = ["reaches the end of the searched span"] * 2
        if name == relieved:
            u0 = float(profile.own_param(u0))
        half = LOBE_SPAN * profile.n / profile.lobes
        lo, hi = u0 - half, u0 + half
        corner = "reaches a sharp corner of its relieved profile, where the offset ends"
        if name == relieved:
            for j in filter(lambda k: _sharp(profile, k), range(profile.n)):
                for v in (j - profile.n, j, j + profile.n):
                    if u0 < v < hi:
                        hi, ends[1] = v - JOINT_STEP, corner
                    elif lo < v < u0:
                        lo, ends[0] = v + JOINT_STEP, corner
        out.append((np.linspace(lo, hi, SEARCH_SAMPLES), tuple(ends)))
    return out


def _frame(pair, psi: float, contact: int | None):
    """(contact, x0, n, t): the gap frame at the chosen contact, x from older to younger."""
    pick = _pick(pair, psi, contact)
    x0 = pick.point
    n = rotate(pair.male.normal(np.array([pick.u_male])), psi)[0]
    t = np.array([n[1], -n[0]])
    lower, upper = _walls(pair, psi, x0, n, t, (pair.male, pair.female), (0.0, 0.0),
                          _spans(pick, (pair.male, pair.female), None))
    lo_b, up_b = branch(lower), branch(upper)
    xs, gap = local_gap(lo_b, up_b)
    k = int(np.argmin(np.abs(xs)))
    ages = []
    for side in (-1, +1):
        idx = np.arange(k, -1, -1) if side < 0 else np.arange(k, len(xs))
        wide = idx[gap[idx] >= PROBE_GAP * pair.gearing.centre_distance]
        i = int(wide[0]) if len(wide) else int(idx[np.argmax(gap[idx])])
        y = 0.5 * (np.interp(xs[i], lo_b.x, lo_b.y) + np.interp(xs[i], up_b.x, up_b.y))
        ages.append(_chamber_at(pair, psi, x0 + xs[i] * t + y * n))
    if None in ages or ages[0] == ages[1]:
        why = ("the fluid beside it lies in no chamber of the section (a sliver the "
               "section's cut does not resolve)" if None in ages else
               "the fluid on both sides of it is one chamber (a pocket between contacts)")
        p = x0 * 1e3
        raise CaseError(f"{_where(psi)}: at the contact ({p[0]:.4f}, {p[1]:.4f}) mm {why}")
    return pick, x0, n, (t if ages[0] > ages[1] else -t)


def gap_frame(pair, psi: float, contact: int | None = None):
    """(origin, n, t) of the gap frame at male angle ``psi`` (fixed frame): the contact,
    the male's outward normal there, the common tangent from the older chamber into the
    younger."""
    _, x0, n, t = _frame(pair, psi, contact)
    return x0, n, t


def _chamber_at(pair, psi: float, x) -> int | None:
    """The chamber (periods of age, as the chamber table counts them) whose section part
    holds the point x; None if none does."""
    for part in pair.cutter.cut(psi):
        rings = part.polygons
        if rings and _inside(rings[0], x) and not any(_inside(r, x) for r in rings[1:]):
            return chamber_index(pair, part, psi, pair.female_shift)
    return None


def _relieved(pair, gap: float, clearance_on: str, where: str):
    """(male, female) profiles, the one named by ``clearance_on`` offset into its material."""
    profiles = {"male": pair.male, "female": pair.female}
    other = "female" if clearance_on == "male" else "male"
    try:
        profiles[clearance_on] = offset_profile(profiles[clearance_on], Clearance((gap,)), -1)
    except CaseError as exc:
        head = str(exc).split("; apply")[0]
        raise CaseError(f"{where}: {head}; put it on the {other} (clearance_on = "
                        f"'{other}') or make it smaller") from None
    return profiles["male"], profiles["female"]


def sealing_gap_walls(pair, psi: float, gap: float, inlet_ratio: float = 20.0,
                      outlet_ratio: float = 3.0, points: int = 201,
                      clearance_on: str = "male", contact: int | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Lower (male) and upper (female) walls in the gap frame at male angle ``psi``, the
    clearance ``gap`` on the rotor ``clearance_on``, at the contact ``contact`` (index
    in :func:`contacts`; None: the one nearest the pitch point)."""
    where = _where(psi)
    check_arguments(gap, inlet_ratio, outlet_ratio)
    if clearance_on not in CLEARANCE_ON:
        raise CaseError(f"clearance_on must be 'male' or 'female', not {clearance_on!r}")
    pick, x0, n, t = _frame(pair, psi, contact)
    profiles = _relieved(pair, gap, clearance_on, where)
    ys = (-gap, 0.0) if clearance_on == "male" else (0.0, gap)
    lower, upper = _walls(pair, psi, x0, n, t, profiles, ys,
                          _spans(pick, profiles, clearance_on))
    return cut_section(lower, upper, gap, inlet_ratio, outlet_ratio, points, where,
                       pair.diameter)


def sealing_wall_speeds(pair, psi: float, omega_male: float, contact: int | None = None
                        ) -> tuple[float, float]:
    """(lower = male, upper = female) wall speeds along +x of the gap frame [m/s],
    relative to the contact, the male turning at ``omega_male`` [rad/s]
    counter-clockwise and the female at ``-omega_male N1 / N2``; their difference is
    the sliding speed omega_male (1 + N1 / N2) |X - P|, zero at the pitch point."""
    pick, x0, _, t = _frame(pair, psi, contact)
    male, female = pair.rotors
    rotors = ((np.asarray(male.axis, float), male.speed_ratio),
              (np.asarray(female.axis, float), female.speed_ratio))
    lower, upper = surface_speeds(x0, t, omega_male * pick.rate, omega_male, rotors)
    return lower, upper
