"""Viscous shear of the injected oil in the rotor-casing clearances: a shaft loss.

In an oil-flooded machine the clearances between the rotors and the casing run full of
oil, and every rotor surface close to the casing drags it.  Model (plane Couette flow in
the lubrication approximation; e.g. Hamrock, Schmid & Jacobson, *Fundamentals of Fluid
Film Lubrication*, ch. 7): a wall sliding at speed U over a gap h of oil of viscosity
mu dissipates mu U^2 / h per unit area.  Over the surfaces of :mod:`rotorflow.geometry.films`
(a rotor turning at omega):

    tips   P = mu omega^2 L covered sum_i arc (R - d_i)^2 / (h_tip + d_i),
           arc = 2 pi R / bins, d_i the rotor's radial deficit below its bore in bin i
           (a flat land adds its width / h, a rounded tip of radius r about
           pi sqrt(2 r / h)), L the rotor length, ``covered`` the casing's share;
    faces  P = mu omega^2 J / h_face per end plate, J = int r^2 dA of the rotor section.

The clearances are those of the leakage paths the films name (one clearance serves the
leakage and the shear).  Assumed, and stated with the figures:

* the films are full of oil over the whole surface (flooded; the lubrication integral
  is taken over the whole circumference: the far flanks add ~10 % of a rounded tip's
  own part, nothing to a land's);
* Couette shear only: the pressure-driven part of the gap flow is the leakage, whose
  losses the chamber model already has; the hydrodynamic wedge pressure of a rounded tip
  (which, fully flooded, would add as much again on that tip) is left out;
* the oil's viscosity at the film temperature, taken as the mean of the oil's injection
  temperature and the cycle's discharge mixture temperature, from the oil's two
  datasheet viscosities by ASTM D341 (Walther): log log (nu + 0.7) = A - B log T
  (nu in mm2/s, T in K);
* the shear heat is not fed back into the cycle: the discharge temperature of the
  figures lacks it; ``oil_film_heating_K`` estimates the rise it would give the
  discharged gas and oil;
* not modelled: shear in the interlobe gap between the rotors (the sliding speed along
  the contact is not in the table), the suction port's share of the suction-end face
  (the face is counted whole); the momentum the rotors give the injected oil is
  :func:`.mechanical.liquid_acceleration_W`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotorflow.geometry.films import FaceFilm, TipFilm

#: ASTM D341's constant for kinematic viscosities above 2 mm2/s.
WALTHER_C = 0.7
#: Reference temperatures of the datasheet viscosities (40 and 100 C).
T40_K, T100_K = 313.15, 373.15


def walther_viscosity(nu40: float, nu100: float, T: float) -> float:
    """Kinematic viscosity (mm2/s) at T (K) between the datasheet's values at 40 and
    100 C, by ASTM D341's line in log log (nu + 0.7) against log T."""
    def ll(nu):
        return math.log10(math.log10(nu + WALTHER_C))

    b = (ll(nu40) - ll(nu100)) / (math.log10(T100_K) - math.log10(T40_K))
    a = ll(nu40) + b * math.log10(T40_K)
    return 10.0 ** (10.0 ** (a - b * math.log10(T))) - WALTHER_C


def film_dissipation(film, omega: float, mu: float, gap: float, length: float) -> float:
    """Time-mean power (W) of one film of the table at rotor speed ``omega`` (rad/s), oil
    viscosity ``mu`` (Pa s) and clearance ``gap`` (m); ``length`` the rotor length."""
    if isinstance(film, TipFilm):
        d = np.asarray(film.deficit_m)
        arc = 2.0 * math.pi * film.radius_m / d.size
        per_length = float(np.sum(arc * (film.radius_m - d) ** 2 / (gap + d)))
        return mu * omega**2 * length * film.covered * per_length
    if isinstance(film, FaceFilm):
        return mu * omega**2 * film.polar_moment_m4 / gap
    raise TypeError(f"not an oil film: {film!r}")


@dataclass(frozen=True)
class OilFilmLoss:
    by_surface_W: dict  # "<rotor> <path>" -> W
    viscosity_Pa_s: float
    temperature_K: float
    not_modelled: tuple[str, ...]

    @property
    def total_W(self) -> float:
        return float(sum(self.by_surface_W.values()))


def oil_film_loss(films, gaps: dict, omegas: dict, length: float, oil, T_film: float
                  ) -> OilFilmLoss:
    """The films' shear losses.  ``gaps``: clearance (m) per leakage path name;
    ``omegas``: |rad/s| per rotor name; ``oil``: the [mechanical] section's oil
    (``density``, ``nu40``, ``nu100``, :class:`.mechanical.Mechanical`)."""
    nu = walther_viscosity(oil.oil_viscosity_40C_cSt, oil.oil_viscosity_100C_cSt, T_film)
    mu = oil.oil_density_kg_m3 * nu * 1e-6
    out, missing = {}, []
    for f in films:
        gap = gaps.get(f.path, 0.0)
        if gap <= 0.0:
            missing.append(f"oil film of {f.rotor} on {f.path}: the path is sealed (no gap)")
            continue
        out[f"{f.rotor} {f.path}"] = film_dissipation(f, omegas[f.rotor], mu, gap, length)
    missing += ["shear in the interlobe gap", "the suction port's share of the suction-end "
                "face"]
    return OilFilmLoss(out, mu, T_film, tuple(missing))
