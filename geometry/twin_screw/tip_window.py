"""Which rack tip radii generate a pair without undercut: the remedy an undercut names.

The circular and line-circle racks take one free dimension besides the diameters, the
male tip circle's radius (``tip_radius_mm``).  Its default (the radius that centres the
female tip's circle on the pitch line, :func:`.family.centred_tip_radius`) undercuts on
common pairs: on seed 004's diameters at C = 78 mm the circular 5/6 rack generates
cleanly only for radii from 15.92 to 16.68 mm, and its default is 16.95.  Below such a
window one rotor's flank turns back, above it the other's, so the refusal says where
the window lies (or that there is none, and the diameters must change) instead of
leaving the user to search it.  Only the undercut is looked for here: a radius in the
window may still give a loop or interference, which the pair's own checks then name.
"""

from __future__ import annotations

import math

from rotorflow.errors import CaseError

from .. import scalar
from .asymmetric import asymmetric_rack
from .circular import symmetric_circular_rack
from .meshing import Gearing
from .profiles import undercut_free_pair

#: The racks whose male tip radius is free.
RACKS = {"circular": symmetric_circular_rack, "line-circle": asymmetric_rack}
#: Radii tried across (0, the largest the circular rack admits): the 5/6 window above
#: is 3.4 % of that range, 3 samples (0.27 s on the error's path; 192 samples move its
#: edges by 1e-10 m).  A window narrower than their spacing (1 % of the range) can be
#: missed, and "none" said of it.
SAMPLES = 96
#: Bisection steps refining each edge (the range over 2^20: ~2e-8 m at C = 80 mm).
REFINE = 20


def clean(profile: str, gearing: Gearing, male_addendum: float, female_addendum: float,
          tip_radius: float) -> bool:
    """Whether the profile's rack of this tip radius exists and generates no undercut."""
    try:
        undercut_free_pair(gearing, RACKS[profile](gearing, male_addendum, female_addendum,
                                                   tip_radius))
    except CaseError:
        return False
    return True


def undercut_free_radii(profile: str, gearing: Gearing, male_addendum: float,
                        female_addendum: float) -> tuple[float, float] | None:
    """(lo, hi): the tip radii (m) between which the rack generates no undercut, the
    longest such run of the samples with its edges bisected; None if no sample does."""
    half, h = 0.5 * gearing.pitch, male_addendum + female_addendum
    top = (h * h + half * half) / (2.0 * h)  # two rack circles meet only below it
    radii = [top * k / SAMPLES for k in range(1, SAMPLES)]
    ok = [clean(profile, gearing, male_addendum, female_addendum, r) for r in radii]
    runs, start = [], None
    for k, good in enumerate([*ok, False]):
        if good and start is None:
            start = k
        elif not good and start is not None:
            runs.append((start, k - 1))
            start = None
    if not runs:
        return None
    i, j = max(runs, key=lambda run: run[1] - run[0])

    def edge(good, bad):  # (the end that generates cleanly: the window holds it)
        return scalar.edge(lambda r: clean(profile, gearing, male_addendum,
                                           female_addendum, r), good, bad, REFINE)[0]

    lo = edge(radii[i], radii[i - 1] if i > 0 else 0.0)
    hi = edge(radii[j], radii[j + 1] if j + 1 < len(radii) else top)
    return lo, hi


def remedy(profile: str, gearing: Gearing, male_addendum: float, female_addendum: float,
           tip_radius: float, given: bool) -> str:
    """What to say after an undercut of the profile's rack at ``tip_radius`` (``given``:
    the case's own tip_radius_mm, not the default)."""
    window = undercut_free_radii(profile, gearing, male_addendum, female_addendum)
    which = "" if given else f" (the default tip_radius_mm is {tip_radius * 1e3:.4g})"
    if window is None:
        return (f"no tip_radius_mm gives a {profile} rack without undercut on these "
                f"diameters and centre distance{which}: change them")
    # rounded inwards, to 0.01 mm where the window is wide enough, else to 1e-6 mm
    for unit in (1e5, 1e9):
        lo, hi = math.ceil(window[0] * unit) / unit * 1e3, math.floor(window[1] * unit) / unit * 1e3
        if lo < hi:
            break
    return (f"tip_radius_mm from {lo:.10g} to {hi:.10g} gives a {profile} rack without "
            f"undercut on these diameters{which}")
