"""One working chamber in a transverse section, followed over its life.

The chamber of the tooth space between pin -1 and pin 0 is born at ``phi_i`` when the
inner tip first touches the conjugate fillet (the smallest contact time of the fillet,
seed 000 section 2.2) and dies at ``phi_f = 2 pi (1 + 1/N1) - phi_i`` (Eq. 2).  In
between it fills the whole space, except while the space passes the deep mesh, where
fillet contacts split it; then the sub-regions alternate between the newborn and the
dying chamber: a sub-region whose fillet points have already been touched by the inner
tip belongs to the newborn chamber, the others to the dying one
(:meth:`PinSpace.region_areas`).  This keeps both chamber areas continuous through every
split and merge.

Per unit length and unit pressure (the fields of :class:`..section.SectionChamber`):

* forces: with ``dx, dy`` the sum over its regions of (leading - trailing) contact
  point, fixed frame, the outer-rotor force is ``p (dy, -dx)`` and the inner-rotor force
  its opposite (seed 000 Eqs. 9, 11);
* torques *exerted by the fluid* on the outer rotor about O1 and on the inner rotor
  about O2, ``-1/2 (|l|^2 - |t|^2)`` and ``+1/2 (|l-O2|^2 - |t-O2|^2)`` (Eqs. 10, 12
  written with the chord midpoints);
* every contact traces an interlobe sealing line; ``lead_offset, trail_offset``: which
  chamber lies beyond the leading and trailing contact, in lobe periods of age (+1: the
  next, older chamber).  Beyond a pin contact is the neighbouring tooth space, whose
  occupant is one period older or younger unless that chamber has already died (or is
  not yet born) there, in which case it is the one a revolution younger (older):
  ``1 - N1`` (``N1 - 1``), seed 001's radial paths to C22 and C31.  Beyond a fillet
  contact is the other chamber of the same space, a revolution apart (``+-N1``: seed
  001's axial paths C11, C12).
"""

from __future__ import annotations

import math

import numpy as np

from ..planar import TWO_PI
from ..section import POINTS_PER_PERIOD, SectionChamber
from .pair import PinGerotor
from .split import PIN_LEADING, PIN_TRAILING, SplitRegions, SplitSpace


def _torques(a, b, o2):
    t1 = -0.5 * (np.sum(b * b, -1) - np.sum(a * a, -1))
    t2 = 0.5 * (np.sum((b - o2) ** 2, -1) - np.sum((a - o2) ** 2, -1))
    return t1, t2


def _fill_split(reg: SplitRegions, birth, o2, rows, area, dx, dy, tq1, tq2, trail, lead,
                perim_o, perim_i, lead_pin, trail_pin, lead_id, trail_id) -> None:
    """Sum the sub-regions that belong to this chamber (see the module docstring).

    While the split is open a newborn chamber owns the touched sub-regions and a dying
    one the others; when only the two pin contacts are left the space is whole.
    """
    valid = reg.valid
    keep = np.where(reg.count[:, None] == 2, np.arange(valid.shape[1])[None, :] == 0,
                    valid & (reg.touched == birth[:, None]))
    a, b = reg.points[:, :-1], reg.points[:, 1:]
    w = keep.astype(float)
    area[rows] = (reg.area * w).sum(1)
    perim_o[rows] = (reg.perimeter_outer * w).sum(1)
    perim_i[rows] = (reg.perimeter_inner * w).sum(1)
    d = ((b - a) * w[..., None]).sum(1)
    dx[rows], dy[rows] = d[:, 0], d[:, 1]
    t1, t2 = _torques(np.where(keep[..., None], a, 0.0), np.where(keep[..., None], b, 0.0), o2)
    tq1[rows], tq2[rows] = t1.sum(1), t2.sum(1)
    any_kept = keep.any(1)
    first = np.argmax(keep, axis=1)
    last = keep.shape[1] - 1 - np.argmax(keep[:, ::-1], axis=1)
    n = np.arange(len(first))
    # The very instant of birth or death: a point, where the first fillet contact is.
    trail[rows] = np.where(any_kept[:, None], a[n, first], reg.points[:, 1])
    lead[rows] = np.where(any_kept[:, None], b[n, last], reg.points[:, 1])
    trail_pin[rows] = any_kept & (first == 0)
    lead_pin[rows] = any_kept & (last == reg.count - 2)
    k = reg.branch.shape[1]
    point = -9  # a chamber born or dying as a point: no contact line to follow
    trail_id[rows] = np.where(any_kept, reg.branch[n, first], point)
    lead_id[rows] = np.where(any_kept, reg.branch[n, np.minimum(last + 1, k - 1)], point)


def _neighbour_offsets(splitter: SplitSpace, psi, birth, lead_pin, trail_pin, phi_i, phi_j,
                       phi_f):
    """Age offsets (in periods) of the chambers beyond the leading and trailing contact."""
    n1 = splitter.pair.lobes_outer
    period = TWO_PI / n1
    s = max(phi_j - phi_i, 0.0)  # length of the split phase

    def occupant(angle, region_of):
        """+0 where the chamber of age ``angle`` holds that side of its space, -1 where
        the chamber a revolution younger does (the older one has died there)."""
        out = np.where(angle < phi_f, 0, -1)
        both = (angle >= phi_f - s) & (angle < phi_f) if s > 0.0 else np.zeros_like(out, bool)
        if both.any():
            reg = splitter.regions(angle[both])
            touched = region_of(reg)
            out[both] = np.where(touched, -1, 0)
        return out

    # Ahead: the space one period on, seen at its trailing pin (its first sub-region).
    ahead = occupant(psi + period, lambda reg: reg.touched[:, 0] & (reg.count > 2))
    # Behind: the space one period back; where its own chamber is not yet born there
    # (angle below phi_i), the occupant is the one a revolution older.
    back = psi - period
    behind = np.where(back < phi_i, 1, 0)
    if s > 0.0:
        young = (back >= phi_i) & (back < phi_j)
        if young.any():
            reg = splitter.regions(back[young])
            last = np.take_along_axis(reg.touched, np.maximum(reg.count - 2, 0)[:, None], 1)[:, 0]
            behind[young] = np.where(last | (reg.count == 2), 0, 1)
    other = np.where(birth, n1, -n1)  # the other chamber of the same space
    lead_offset = np.where(lead_pin, 1 + n1 * ahead, other)
    trail_offset = np.where(trail_pin, -1 + n1 * behind, other)
    return lead_offset.astype(int), trail_offset.astype(int)


def chamber_life(pair: PinGerotor) -> tuple[float, float, float]:
    """(birth phi_i, end of the split phase after birth phi_j, death phi_f)."""
    n1 = pair.lobes_outer
    period = TWO_PI / n1
    if pair.fillet_kind == "conjugate":
        t_lo, t_hi = pair.space.fillet_time_range
        # Fillet -1 touches at fillet-0 times shifted by one period.
        phi_i = math.remainder(t_lo + period, TWO_PI)
        phi_j = phi_i + (t_hi - t_lo)  # end of the split phase after birth
        phi_f = TWO_PI + period - phi_i
    else:
        # No fillet contact: the space is never split and its smallest area (not zero:
        # a clearance volume) comes when it straddles the deep mesh, at phi = pi / N1.
        phi_i = math.pi / n1
        phi_j = phi_i - 1.0  # no split phase
        phi_f = phi_i + TWO_PI
    return phi_i, phi_j, phi_f


def section_chamber(pair: PinGerotor, points_per_period: int = POINTS_PER_PERIOD) -> SectionChamber:
    """Tabulate the chamber of ``pair`` from birth to death."""
    space = pair.space
    n1 = pair.lobes_outer
    period = TWO_PI / n1
    phi_i, phi_j, phi_f = chamber_life(pair)
    # The grid is aligned with the lobe period, so chambers one period apart share
    # nodes and their loads cancel exactly at uniform pressure; it runs one node past
    # the death, where the chamber is gone (zero).
    step = period / points_per_period
    n = int(math.ceil((phi_f - phi_i) / step * (1.0 - 1e-12))) + 1
    psi = phi_i + step * np.arange(n)

    area = np.empty(n)
    trail = np.empty((n, 2))
    lead = np.empty((n, 2))
    dx = np.empty(n)
    dy = np.empty(n)
    tq1 = np.empty(n)
    tq2 = np.empty(n)
    o2 = pair.O2

    dead = psi >= phi_f
    whole = ((psi > phi_j) & (psi < phi_f - (phi_j - phi_i))) | (phi_j < phi_i)
    perim_o = np.empty(n)
    perim_i = np.empty(n)
    a, t, lpt = space.whole_space(psi[whole])
    perim_o[whole], perim_i[whole] = space.whole_space_perimeters(psi[whole])
    area[whole], trail[whole], lead[whole] = a, t, lpt
    d = lpt - t
    dx[whole], dy[whole] = d[:, 0], d[:, 1]
    tq1[whole], tq2[whole] = _torques(t, lpt, o2)

    lead_pin = np.ones(n, dtype=bool)
    trail_pin = np.ones(n, dtype=bool)
    lead_id = np.full(n, PIN_LEADING)
    trail_id = np.full(n, PIN_TRAILING)
    splitter = SplitSpace(space)
    split = ~whole & ~dead
    birth = psi < phi_j + 1e-12
    if split.any():
        _fill_split(splitter.regions(psi[split]), birth[split],
                    o2, split, area, dx, dy, tq1, tq2, trail, lead, perim_o, perim_i,
                    lead_pin, trail_pin, lead_id, trail_id)
    lead_offset, trail_offset = _neighbour_offsets(splitter, psi, birth, lead_pin, trail_pin,
                                                   phi_i, phi_j, phi_f)
    # The chamber is born and dies as a point: exact zeros at the ends (there the
    # contact search may already see the neighbouring chamber's whole space).
    ends = np.zeros(n, dtype=bool)
    ends[0] = pair.fillet_kind == "conjugate"
    ends |= dead
    for arr in (area, dx, dy, tq1, tq2, perim_o, perim_i):
        arr[ends] = 0.0
    if ends[0]:
        trail[0] = lead[0] = 0.5 * (trail[0] + lead[0])
    trail[dead] = trail[~dead][-1]
    lead[dead] = lead[~dead][-1]
    # The fluid's force on the outer rotor is p (dy, -dx) (Eqs. 9, 11), on the inner
    # rotor its opposite.
    force1 = np.stack([dy, -dx], -1)
    return SectionChamber(
        psi=psi,
        area=area,
        force=np.stack([force1, -force1], 1),
        torque=np.stack([tq1, tq2], 1),
        perimeter=np.stack([perim_o, perim_i], 1),
        trail=trail,
        lead=lead,
        phi_i=phi_i,
        phi_f=phi_f,
        speed_ratio=(1.0, pair.m21),
        lead_offset=lead_offset,
        trail_offset=trail_offset,
        lead_id=lead_id,
        trail_id=trail_id,
        lead_kind=np.full(n, "interlobe"),
        trail_kind=np.full(n, "interlobe"),
    )
