"""Contact points of the whole pin-generated pair against outer-rotor angle
(a :class:`..contacts.ContactTable`).

Tooth space k (between pins k - 1 and k) at outer angle phi is, in the fixed frame,
tooth space 0 at ``phi + 2 pi k / N1``: the outer rotor has moved on by k pin pitches
and the inner rotor by ``m21 2 pi k / N1 = 2 pi k / N2``, a whole number of its own
lobes.  So every contact of the machine comes from the vectorised tooth space of
:mod:`.split_space`: each space contributes its leading pin contact (the trailing one
is its neighbour's leading one) and the fillet contacts that split it.

Rows (long format, one per contact and angle; lengths in metres, angles in degrees):
``angle_deg`` outer-rotor angle from the pin-0-at-top position; ``kind`` pin or fillet;
``space`` k; ``x_m, y_m`` the point in the fixed frame (O1 at the origin, O2 at
(0, -E)); ``radius_outer_m`` and ``radius_inner_m`` its distance from each rotor's axis
(a contact path's radial position on each rotor, the classic gerotor diagram).
"""

from __future__ import annotations

import numpy as np

from ..contacts import ContactTable
from ..planar import TWO_PI
from .pair import PinGerotor
from .split import SplitSpace


def contact_table(pair: PinGerotor, step_deg: float = 1.0, span_deg: float | None = None
                  ) -> ContactTable:
    """Every contact of the pair every ``step_deg`` of outer angle over ``span_deg``
    (default: one lobe period, after which the pattern repeats)."""
    n1 = pair.lobes_outer
    span = 360.0 / n1 if span_deg is None else span_deg
    if not step_deg > 0.0 or not span > 0.0:
        raise ValueError("contact table step and span must be positive")
    angles = np.arange(0.0, span + 0.5 * step_deg, step_deg)
    angles = angles[angles < span - 1e-9] if span_deg is None else angles
    k = np.arange(n1)
    phi = (np.radians(angles)[:, None] + TWO_PI * k[None, :] / n1).ravel()
    reg = SplitSpace(pair.space).regions(phi)
    n_slots = reg.points.shape[1]
    slot = np.arange(n_slots)[None, :]
    # Drop the trailing pin (slot 0): it is the leading pin of the space behind.
    keep = (slot >= 1) & (slot < reg.count[:, None])
    is_pin = slot == reg.count[:, None] - 1
    rows, slots = np.nonzero(keep)
    pts = reg.points[rows, slots]
    o2 = pair.O2
    return ContactTable(
        angle_deg=np.repeat(angles, n1)[rows],
        kind=np.where(is_pin[rows, slots], "pin", "fillet"),
        space=np.tile(k, len(angles))[rows],
        x_m=pts[:, 0],
        y_m=pts[:, 1],
        radius_outer_m=np.hypot(pts[:, 0], pts[:, 1]),
        radius_inner_m=np.hypot(pts[:, 0] - o2[0], pts[:, 1] - o2[1]),
    )


def pitch_point_distance(table: ContactTable, pair: PinGerotor) -> np.ndarray:
    """Distance of each pin contact's normal line from the pitch point (law of gearing:
    zero for a correct pair), for tests and checks."""
    pins = table.kind == "pin"
    phi = np.radians(table.angle_deg[pins]) + TWO_PI * table.space[pins] / pair.lobes_outer
    centres = np.stack([-pair.a * np.sin(phi), pair.a * np.cos(phi)], -1)
    pts = np.stack([table.x_m[pins], table.y_m[pins]], -1)
    n = pts - centres
    d = pair.P - centres
    return np.abs(n[:, 0] * d[:, 1] - n[:, 1] * d[:, 0]) / np.linalg.norm(n, axis=-1)
