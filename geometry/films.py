"""Where a rotor shears an oil film against the casing: the geometry of it.

In an oil-injected machine the clearances between a rotor and its casing run full of oil,
and the rotor drags it (Couette shear, :mod:`rotorflow.quasi1d.oil_film` turns this into
a power).  The shear depends on the gap across the whole surface that runs close to the
casing, not only on the sealing line: a rounded tip drags oil over a band about
sqrt(2 r h) wide, a flat land over its width.  This module gives that surface for each
rotor in a bore, once per machine and independent of the clearance:

* :class:`TipFilm`, the rotor's outer surface against its bore.  In the transverse
  section, the rotor's radial deficit below the bore radius, d(theta) = R - r(theta), at
  the centres of ``bins`` equal angular bins (r the outermost crossing of the ray at
  theta with the profile).  With the clearance h on the tips, the gap at theta is
  h + d(theta); the film integral the dissipation needs is the midpoint sum
  sum_i arc (R - d_i)^2 / (h + d_i), exact to O(bin^2) where d is smooth and to O(bin)
  at a land's sharp edge.  ``covered`` is the share of the bore's circle that is casing
  (the rest lies in the other bores); a turning rotor spends that share of the time under
  it, whatever its angle, so the time-mean film is ``covered`` times the whole circle's.
  Every transverse section of a helical (or variable-lead) rotor is the same profile
  turned, so the film per unit length holds along the whole rotor.
* :class:`FaceFilm`, a rotor's end face against an end plate: the polar second moment
  J = int r^2 dA of the rotor's transverse section about its own axis (Green's theorem on
  the analytic profile), since the face slides at omega r over the whole section.

Each film names the leakage path whose clearance it has (the tip path of that rotor, the
end-face path of that plate), so that one clearance serves the leakage and the shear.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

#: Angular bins per revolution of the tip film: 0.08 mm of arc on a 100 mm rotor, against
#: a rounded tip's film about 1.5 mm wide at 40 um (r_eff 28 mm).
TIP_BINS = 4096
#: Profile samples per bin for the ray crossings (chordal sag (R 2 pi / bins / 8)^2 / 2r
#: ~ 1e-11 m on the tips: far below any clearance).
SAMPLES_PER_BIN = 8


@dataclass(frozen=True)
class TipFilm:
    """A rotor's outer surface against its casing bore (see the module docstring)."""

    rotor: str
    path: str  # the leakage path whose clearance the tips have
    radius_m: float  # bore radius R (the rotor's outer radius)
    covered: float  # share of the bore's circle that is casing
    deficit_m: tuple[float, ...]  # R - r at the bin centres, bins of 2 pi / len equal

    kind = "tip"

    def to_dict(self) -> dict:
        return {"kind": self.kind, **asdict(self)}


@dataclass(frozen=True)
class FaceFilm:
    """A rotor's end face against an end plate (see the module docstring)."""

    rotor: str
    path: str  # the end-face leakage path of that plate
    polar_moment_m4: float  # int r^2 dA of the rotor's section about its axis

    kind = "face"

    def to_dict(self) -> dict:
        return {"kind": self.kind, **asdict(self)}


def film_from_dict(d: dict):
    """A film from its side-car record; ValueError names what is wrong."""
    kinds = {"tip": TipFilm, "face": FaceFilm}
    d = dict(d)
    cls = kinds.get(d.pop("kind", None))
    if cls is None:
        raise ValueError(f"oil film of unknown kind (not {', '.join(kinds)})")
    try:
        film = cls(**d)
    except TypeError as exc:
        raise ValueError(f"oil film record: {exc}") from None
    if isinstance(film, TipFilm):
        return TipFilm(film.rotor, film.path, float(film.radius_m), float(film.covered),
                       tuple(float(x) for x in film.deficit_m))
    return film


def radial_deficit(profile, radius: float, bins: int = TIP_BINS) -> np.ndarray:
    """R - r(theta) at the centres of ``bins`` angular bins, r the outermost crossing of
    the ray at theta with the closed ``profile`` (a PieceCurve in the rotor's frame)."""
    u = np.linspace(0.0, profile.n, bins * SAMPLES_PER_BIN * 4 + 1)
    p = profile.point(u)
    theta = np.arctan2(p[:, 1], p[:, 0])
    r = np.hypot(p[:, 0], p[:, 1])
    step = 2.0 * math.pi / bins
    # each segment (a, b) crosses the bin centres between its end angles (short way round)
    ta, tb = theta[:-1], theta[:-1] + _wrapped(np.diff(theta))
    lo = np.minimum(ta, tb)
    hi = np.maximum(ta, tb)
    # a hair of overlap, so that a centre on a sample point is crossed by a segment
    first = np.ceil((lo + math.pi) / step - 0.5 - 1e-9).astype(np.int64)
    last = np.floor((hi + math.pi) / step - 0.5 + 1e-9).astype(np.int64)
    count = np.maximum(last - first + 1, 0)
    seg = np.repeat(np.arange(lo.size), count)
    k = np.arange(seg.size) - np.repeat(np.cumsum(count) - count, count) + first[seg]
    centre = -math.pi + (k + 0.5) * step
    # the crossing radius along the segment, linear in the angle (the segments are far
    # shorter than their distance from the axis)
    span = tb[seg] - ta[seg]
    t = np.where(span != 0.0, (centre - ta[seg]) / np.where(span != 0.0, span, 1.0), 0.5)
    rc = r[:-1][seg] + t * (r[1:][seg] - r[:-1][seg])
    out = np.zeros(bins)
    np.maximum.at(out, np.mod(k, bins), rc)
    if np.any(out == 0.0):
        raise ValueError("the profile does not surround its axis (a ray finds no crossing)")
    return np.maximum(radius - out, 0.0)


def _wrapped(dtheta: np.ndarray) -> np.ndarray:
    return np.mod(dtheta + math.pi, 2.0 * math.pi) - math.pi


def covered_share(centre, radius: float, bores, bins: int = TIP_BINS) -> float:
    """Share of the circle (centre, radius) outside every other bore of ``bores``
    (((x, y), r) pairs; the circle's own bore is skipped)."""
    theta = (np.arange(bins) + 0.5) * 2.0 * math.pi / bins
    pts = np.asarray(centre, float) + radius * np.stack([np.cos(theta), np.sin(theta)], -1)
    inside = np.zeros(bins, dtype=bool)
    for c, rb in bores:
        if np.allclose(c, centre) and math.isclose(rb, radius):
            continue
        inside |= np.hypot(*(pts - np.asarray(c, float)).T) < rb
    return float(np.count_nonzero(~inside)) / bins


def polar_moment(profile) -> float:
    """int (x^2 + y^2) dA inside the closed counter-clockwise ``profile`` about its
    origin (Green: int x^2 + y^2 dA = 1/3 oint x^3 dy - y^3 dx)."""
    def f(u):
        p, d = profile.point(u), profile.derivative(u)
        return (p[:, 0] ** 3 * d[:, 1] - p[:, 1] ** 3 * d[:, 0]) / 3.0

    return profile.integrate(f)


def rotor_films(pair, paths) -> tuple:
    """The films of every rotor of ``pair`` that turns in its own bore, given the table's
    leakage paths: a tip film with the clearance of the rotor's tip path (kind "tip",
    named "tip-<rotor>-...") and a face film per end-face path (one per end plate)."""
    bores = pair.casing_bores()
    tip_paths = {}
    for p in paths:
        for rotor in pair.rotors:
            if p.kind == "tip" and p.name.startswith(f"tip-{rotor.name}-"):
                tip_paths.setdefault(rotor.name, p.name)
    face_paths = [p.name for p in paths if p.kind == "end-face"]
    films = []
    for rotor in pair.rotors:
        if not rotor.material_inside or rotor.name not in tip_paths:
            continue
        (centre, radius), = [(c, r) for c, r in bores if np.allclose(c, rotor.axis)]
        films.append(TipFilm(rotor.name, tip_paths[rotor.name], float(radius),
                             covered_share(centre, radius, bores),
                             tuple(float(d) for d in radial_deficit(rotor.profile, radius))))
        films.extend(FaceFilm(rotor.name, path, polar_moment(rotor.profile))
                     for path in face_paths)
    return tuple(films)
