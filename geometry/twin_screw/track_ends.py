"""Where a twin-screw chamber's sealing points begin, end and change hands, exactly.

The section table has a track only at its nodes; a sealing line is the track swept
along the rotors, so where the track begins or ends between two nodes decides the
line's length (half a step of wrap, ~1 % of a tip line at 48 nodes per period).  Every
such event here has a closed form or a root (:attr:`..section.Track.cuts`):

* a tip seals on its bore until it reaches a cusp, where the other bore begins; the
  tip turns with its rotor at a constant rate, so the angle is a closed form;
* an interlobe contact changes the chamber beyond it, or leaves the chamber, where it
  crosses the cusp line x = x_c: the section's fluid is split into male and female
  groove parts there (:mod:`.regions`), so the part on either side of the contact
  belongs to another groove from then on.  The angle is the root of x(psi) - x_c along
  the contact, the law of gearing solved at every trial angle (:meth:`.TwinScrewPair
  .contact_near`);
* a band: a male arc that is a circle centred on the male pitch circle (both racks
  here put their female tip circle's centre on the pitch line) lies on its mate along
  the whole arc at the instant that centre passes the pitch point, and the section's
  contact jumps from one end of the arc to the other.  The rotors touch along the arc
  in that transverse plane, a piece of the sealing line no swept point draws: the
  track carries it as a bridge (3.3 mm each on seed 004's 4/6 circular pair, 2.8 mm on
  the line-circle one, three or four along the rotor: the 5 % the swept contacts
  lacked against the rack's contact line);
* a joint: where the contact passes from one arc of the profile to the next its rate
  jumps (the curvature does), so the cubic through the nodes either side must not span
  it; the male angle at which the joint meshes is the arc's own rolling angle there;
* a land's corner (the trochoidal pump's): a land touches its mate's root at one
  fixed point of the line of centres while it passes it, and its corners' contacts
  on the mate's flanks set out from there or come back to it: the angle at which a
  corner meets that line, a closed form.

An event with no such form keeps the half step (NaN cut).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..planar import TWO_PI
from .regions import FEMALE, GROW, MALE

#: A male piece whose rolling angle varies by less than this (rad) along it meshes all
#: at once: a band (closed forms give ~1e-15; a true flank turns through degrees).
BAND_TOL = 1e-9
#: Samples per piece for the band test and the part of a band inside both bores.
BAND_SAMPLES = 65
#: Gauss-Legendre nodes for a band's length (an analytic arc: rounding).
BAND_GAUSS = 16
#: Nodes this near a band's instant (in units of the angle at which the two circles'
#: centres are 2 GROW C apart, the grown rotors' overlap) hold the band's middle as
#: their contact, not the contact: the centres part only like the square of the angle
#: (both roll on their pitch circles through the pitch point), by C r1 / (2 r2) dpsi^2,
#: so that angle is sqrt(4 GROW r2 / r1), 3.5e-3 rad for a 4/6 pair; twice it to be safe.
BAND_SHADOW = 2.0
#: A node this near a joint's instant (rad) is at the joint: its rate is either arc's.
JOINT_NODE = 1e-9
#: Absent nodes a track may have lost next to an event it begins or ends at (a sliver
#: below the polygons' resolution near a cusp), and the angle (rad) they may span: the
#: loss is an angle, not a count of nodes.  The pin-cycloid's interlobe tracks lose
#: 0.0082 rad before the joint at the top cusp (0.0061 with polygons 4 times finer),
#: two nodes at 96 points per period, four at 384: counted in nodes alone, the tracks
#: ended half a step after their last node from 384 on, and their lines to the
#: chamber 4 periods on fell short by 0.3 mm (4e-3).  The angle allows 2.4 times the
#: largest loss measured.
EVENT_REACH = 3
EVENT_ANGLE = 0.02
#: Two joints within this (rad, and per C in position) are one: where a piece ends and
#: the next begins (closed forms agree to ~1e-13).
SAME_EVENT = 1e-9
#: Newton's steps for a contact's crossing of the cusp line, and the angle (rad) within
#: which it is found: the contact's rate is exact, so three or four steps reach 1e-13.
NEWTON_STEPS = 30
CROSSING_XTOL = 1e-13
#: A contact this near (per C) the cusp line at a node crosses it there: the contact
#: is found to ~1e-11 m (2.2e-11 on the 1-1 involute at the pitch point, where it
#: crosses), and at the contacts' speeds (~10 mm/rad) 1e-9 C is ~1e-5 rad of angle.
AT_NODE = 1e-9


def refine(pair, psi: np.ndarray, track):
    """``track`` with the exact angles of its events and the bridges of its bands."""
    if track.kind == "tip":
        return _tip_runs(pair, psi, track)
    present, offset, ids = track.present.copy(), track.offset, track.ids.copy()
    cuts = np.full(len(psi), np.nan)
    start = np.nan
    bridges = []
    h = psi[1] - psi[0]
    n = len(psi)
    reach = _reach(h)
    tol = SAME_EVENT * pair.gearing.centre_distance
    for psi_b, length, mid, shadow in _breaks(pair, psi):
        before = np.nonzero(psi <= psi_b - shadow)[0]
        after = np.nonzero(psi >= psi_b + shadow)[0]
        lo = int(before[-1]) if len(before) else -1
        hi = int(after[0]) if len(after) else n
        # Nodes in the shadow that hold a point of the band (its middle, where no
        # contact was found) stand for nothing, whatever the nodes either side.
        shadowed = np.arange(lo + 1, hi)
        near = np.linalg.norm(track.points[shadowed] - mid, axis=-1) <= 0.5 * length + h * (
            np.linalg.norm(track.rates[shadowed], axis=-1))
        present[shadowed[near]] = False
        # A track that ends (begins) at the event may have lost its last (first) nodes
        # before it: near a cusp the sliver beyond the contact is below the polygons'
        # resolution.  Its nearest node within that loss's reach stands for it.
        lo = _nearest_present(track.present, lo, -1, reach)
        hi = _nearest_present(track.present, hi, 1, reach)
        # The sides on which the track has this contact there: it may begin or end at
        # the event (a chamber born at a band), or change its chamber beyond.  A contact
        # at rest there (a land on its mate's root) has no rate to allow for, only its
        # rounding.
        sides = [j for j in (lo, hi) if 0 <= j < n and track.present[j]
                 and np.linalg.norm(track.points[j] + (psi_b - psi[j]) * track.rates[j] - mid)
                 <= 0.5 * length + 2.0 * (h + shadow) * np.linalg.norm(track.rates[j]) + tol]
        if not sides:
            continue  # this chamber's contact is elsewhere
        # The stretches either side end there (no rate is interpolated across), and
        # nodes in its shadow stand for nothing.
        if lo in sides:
            cuts[lo] = psi_b
        if hi in sides:
            if hi > 0:
                cuts[hi - 1] = psi_b
            else:
                start = psi_b
        present[lo + 1:hi] = False
        ids[min(hi, n):] += 1
        if length > 0.0 and sides == [lo, hi] and offset[lo] == offset[hi]:
            bridges.append((float(psi_b), length, int(offset[hi])))
    _crossing_cuts(pair, psi, track, present, cuts, reach)
    return dataclasses.replace(track, present=present, ids=ids, cuts=cuts, start=start,
                               bridges=tuple(bridges))


def _crossing_cuts(pair, psi, track, present, cuts, reach: int) -> None:
    """Fill ``cuts`` where the track begins, ends or changes its chamber beyond with no
    cut yet: where its contact crosses the cusp line (NaN where it does not)."""
    offset, n = track.offset, len(psi)
    change = (present[:-1] != present[1:]) | (present[:-1] & present[1:]
                                              & (offset[:-1] != offset[1:]))
    for i in np.nonzero(change & np.isnan(cuts[:-1]))[0]:
        j, k = (i, i + 1) if present[i] else (i + 1, i)
        cut = _cusp_line_cut(pair, track.points[j], track.rates[j], psi[j], psi[k])
        # Near a cusp the track may have lost the nodes next to its crossing, as next to
        # an event (the sliver beyond the contact below the polygons' resolution): the
        # crossing is sought over them too, up to the track's next node.  At 768 nodes
        # per period the trochoidal's corner contacts lose one node either side of the
        # crossing, and their lines ended half a step off it (6e-3 of the line).  Only
        # nodes the track lost are crossed, not those an event's shadow took from it:
        # the contact is not extrapolated across an event.
        far = k
        while (np.isnan(cut) and not track.present[far] and abs(far - j) < reach
               and 0 <= far + (k - j) < n):
            far += k - j
            cut = _cusp_line_cut(pair, track.points[j], track.rates[j], psi[j], psi[far])
        cuts[i] = cut


def _reach(h: float) -> int:
    """Absent nodes, ``h`` apart, a track may have lost next to its event."""
    return max(EVENT_REACH, math.ceil(EVENT_ANGLE / h))


def _nearest_present(present, j: int, step: int, reach: int) -> int:
    """Node j if the track is there, else its nearest node that is, going ``step`` (+-1)
    over absent nodes only, at most ``reach`` of them; j if none."""
    n = len(present)
    for k in range(reach + 1):
        i = j + step * k
        if not 0 <= i < n:
            return j
        if present[i]:
            return i
    return j


def _tip_runs(pair, psi, track):
    """A tip seals from the cusp where it comes out of the other bore to the cusp where
    it goes in, and only then: its longest run of nodes, turned out to those cusps.

    Nodes the section's cut saw a little late are filled by turning the tip (just past
    a cusp the fluid beyond the tip is a sliver below the polygons' resolution), and
    nodes it saw a little early or astray dropped (a tip a few microns into the other
    bore, a tip deep in the mesh seen twice by one chamber); a track with no run that
    covers most of its tip's sealing stretch is no tip line at all."""
    rotor = FEMALE if "female" in track.name else MALE
    g = pair.gearing
    axis = np.zeros(2) if rotor == MALE else g.female_axis
    speed = 1.0 if rotor == MALE else -g.lobes_male / g.lobes_female
    xc, yc = pair.cusp
    cusps = [math.atan2(y - axis[1], xc - axis[0]) for y in (yc, -yc)]
    n = len(psi)
    edges = np.diff(np.concatenate([[0], track.present.astype(int), [0]]))
    starts, stops = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
    if not len(starts):
        return track
    k = int(np.argmax(stops - starts))
    j0, j1 = int(starts[k]), int(stops[k]) - 1
    ends = []
    for j in (j0, j1):
        rel = track.points[j] - axis
        theta = math.atan2(rel[1], rel[0])
        ends.append(psi[j] + min((math.remainder(c - theta, TWO_PI) / speed
                                  for c in cusps), key=abs))
    inside = (psi >= ends[0]) & (psi <= ends[1])
    if 2 * (j1 - j0 + 1) < inside.sum():
        inside[:] = False  # strays, no stretch of a sealing tip
    # The chamber beyond, as most of the run sees it (a node at a cusp can see a
    # sliver of the wrong groove there).
    values, counts = np.unique(track.offset[j0:j1 + 1], return_counts=True)
    beyond = int(values[np.argmax(counts)])
    base = track.points[j0] - axis
    turn = (psi - psi[j0]) * speed
    spun = np.stack([np.cos(turn) * base[0] - np.sin(turn) * base[1],
                     np.sin(turn) * base[0] + np.cos(turn) * base[1]], -1)
    cuts = np.full(n, np.nan)
    start = np.nan
    idx = np.nonzero(inside)[0]
    if len(idx):
        if idx[0] > 0:
            cuts[idx[0] - 1] = ends[0]
        else:
            start = ends[0]  # the tip sealed before the chamber's section showed
        cuts[min(idx[-1], n - 1)] = ends[1]
    return dataclasses.replace(
        track, points=np.where(inside[:, None], axis + spun, track.points),
        rates=np.where(inside[:, None], speed * np.stack([-spun[:, 1], spun[:, 0]], -1),
                       track.rates),
        present=inside, offset=np.where(inside, beyond, 0),
        ids=np.zeros(n, dtype=int), cuts=cuts, start=start)


def _cusp_line_cut(pair, point, rate, psi_j: float, psi_k: float) -> float:
    """The angle between ``psi_j`` and ``psi_k`` at which the contact at ``point``
    (rate ``rate``) crosses the cusp line; NaN if it does not.  Newton's steps on
    x(psi) - x_c with the contact's own rate (each trial angle solves the law of
    gearing near the last contact moved on by its rate), kept in the bracket."""
    xc = pair.cusp[0]
    c_k, _ = pair.contact_near(point + (psi_k - psi_j) * rate, psi_k)
    lo, hi, f_lo = psi_j, psi_k, point[0] - xc
    if f_lo == 0.0:
        return psi_j
    # A crossing at the node itself (identical rotors cross the cusp line at the pitch
    # point, x_c = r1, which a node can hit exactly): rounding puts the contact on
    # either side of the line there.
    if abs(c_k[0] - xc) <= AT_NODE * pair.gearing.centre_distance:
        return psi_k
    if np.sign(f_lo) == np.sign(c_k[0] - xc):
        return np.nan
    x, c, dc = psi_j, point, rate
    for _ in range(NEWTON_STEPS):
        step = -(c[0] - xc) / dc[0] if dc[0] != 0.0 else np.inf
        new = x + step
        if not min(lo, hi) < new < max(lo, hi):
            new = 0.5 * (lo + hi)  # out of the bracket: bisect
        if abs(new - x) < CROSSING_XTOL:
            return float(new)
        # Sought near the first contact moved on by its rate: within a cell that is
        # the same contact (a trial far off could find another root of the law).
        x = new
        c, dc = pair.contact_near(point + (x - psi_j) * rate, x)
        if np.sign(c[0] - xc) == np.sign(f_lo):
            lo = x
        else:
            hi = x
    return float(x)


def _breaks(pair, psi):
    """(angle, bridge length, contact point, shadow) of every band and joint that
    meshes within the table's span ``psi``: one of phase a meshes at a + k period (lobe
    -k then meets the female where lobe 0 does at a, at the same fixed point)."""
    period = TWO_PI / pair.gearing.lobes_male
    # A chamber's first and last sealing points can lie a little beyond its table's
    # ends (the sliver there is below the polygons' resolution): as far as it may
    # have lost nodes.
    reach = _reach(psi[1] - psi[0]) * (psi[1] - psi[0])
    out = []
    for phase, length, point, shadow in pair.contact_breaks:
        k0 = math.ceil((psi[0] - reach - phase) / period)
        k1 = math.floor((psi[-1] + reach - phase) / period)
        out.extend((phase + k * period, length, point, shadow) for k in range(k0, k1 + 1))
    return out


def contact_breaks(pair) -> tuple:
    """(male angle of contact, bridge length inside both bores, point in the fixed frame
    at that angle, shadow) of every band and joint of the male's lobe 0 (module
    docstring); a band's point is its middle.

    A joint is either end of a piece that is not a band: there the contact passes to
    the next piece, or comes to rest on a corner of either rotor (the pin-cycloid's male
    tip seals while the female's flank it generates meshes) until the next piece's
    first point meshes; either way its rate jumps.  An end that meshes at a band's
    instant is the band's (its cuts end the stretches there)."""
    g = pair.gearing
    period = TWO_PI / g.lobes_male
    t = np.linspace(0.0, 1.0, BAND_SAMPLES)
    x, w = np.polynomial.legendre.leggauss(BAND_GAUSS)
    tg = 0.5 * (x + 1.0)
    shadow = BAND_SHADOW * math.sqrt(4.0 * GROW * g.r2 / g.r1)
    bands, ends = [], []
    for piece in pair.male.pieces:
        rolling = np.asarray(piece.rolling_angle(t), dtype=float)
        if not np.all(np.isfinite(rolling)):
            continue
        if np.ptp(rolling) > BAND_TOL:
            for angle, end in ((rolling[0], 0.0), (rolling[-1], 1.0)):
                point = piece.eval(np.array([end]), 0)[0] @ _turn(float(angle)).T
                ends.append((float(angle), 0.0, point, JOINT_NODE))
            continue
        phase = float(rolling.mean())
        # At that instant the arc lies on its mate in the fixed frame: turned by phase.
        turn = _turn(phase)
        pts = piece.eval(tg, 0) @ turn.T
        # Only what lies in both bores touches (the rotors meet nowhere else).
        inside = ((np.linalg.norm(pts, axis=-1) <= pair.male_radius * (1.0 + BAND_TOL))
                  & (np.linalg.norm(pts - g.female_axis, axis=-1)
                     <= pair.female_radius * (1.0 + BAND_TOL)))
        length = float(np.sum(0.5 * w * np.linalg.norm(piece.eval(tg, 1), axis=-1) * inside))
        if length > 0.0:
            bands.append((phase, length, piece.eval(np.array([0.5]), 0)[0] @ turn.T, shadow))
    out = list(bands)
    tol = SAME_EVENT * g.centre_distance
    for e in ends + _land_joints(pair):
        if any(abs(math.remainder(e[0] - b[0], period)) < SAME_EVENT for b in bands):
            continue
        if any(abs(math.remainder(e[0] - o[0], period)) < SAME_EVENT
               and np.linalg.norm(e[2] - o[2]) < tol for o in out):
            continue  # one piece's end is the next one's start
        out.append(e)
    return tuple(out)


def _land_joints(pair) -> list:
    """(male angle, 0, point, JOINT_NODE) of every corner of lobe 0's lands passing the
    line of centres on its mate's side.  A land is a circle about its own rotor's axis:
    its normals pass the pitch point on that line alone, so it touches its mate's root
    there, at one fixed point, from the instant one corner reaches the line until the
    other leaves it; and the corners' own contacts on the mate's flanks (the trochoidal
    pump's) begin or end at those instants, at that point.  The land's piece is given
    no rolling angle, so these joints are not among the pieces' ends (given one, the
    contact search would rest the contact on a corner between the instants its two
    pieces mesh their ends there, and a trochoidal corner seals on the far side of
    them: from the line of centres to the cusp, not from the cusp back).  Left halfway
    they cost the trochoidal's interlobe lines half a step of wrap each, an error of
    the first order (5e-3 of the land's line at 96 points per period)."""
    g = pair.gearing
    out = []
    for rotor, profile in ((MALE, pair.male), (FEMALE, pair.female)):
        if not pair.land_half_width(rotor) > 0.0:
            continue
        for p in pair.corner_points(profile)[:2]:
            theta = math.atan2(p[1], p[0])
            radius = float(np.linalg.norm(p))
            if rotor == MALE:  # turned by psi: at polar angle 0, facing the female
                angle, x = -theta, radius
            else:  # turned by -psi N1 / N2: at polar angle pi about the female axis
                angle, x = (theta - math.pi) * g.lobes_female / g.lobes_male, \
                    g.centre_distance - radius
            out.append((angle, 0.0, np.array([x, 0.0]), JOINT_NODE))
    return out


def _turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])
