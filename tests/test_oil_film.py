"""The oil films' shear loss (geometry.films, quasi1d.oil_film) against closed forms.

* A rotor that is its bore's circle is a concentric journal bearing: Petroff's law,
  P = 2 pi mu omega^2 R^3 L / h (Petroff 1883; Hamrock et al., Fundamentals of Fluid Film
  Lubrication, ch. 8).
* A circle of radius rho off its axis by a (a rounded tip): r(theta) = a cos theta +
  sqrt(rho^2 - a^2 sin^2 theta) in closed form, its film integral by adaptive quadrature;
  its polar moment by the parallel-axis theorem, pi rho^4 / 2 + pi rho^2 a^2.
* Two bores of radii R1, R2 at distance C: the casing's share of bore 1 is
  1 - acos((R1^2 + C^2 - R2^2) / (2 R1 C)) / pi.
* ASTM D341's line passes through the two datasheet viscosities it is drawn from.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import quad

from rotorflow.geometry.curves import PieceCurve
from rotorflow.geometry.films import (
    FaceFilm,
    TipFilm,
    covered_share,
    film_from_dict,
    polar_moment,
    radial_deficit,
)
from rotorflow.quasi1d.oil_film import film_dissipation, walther_viscosity

from .conftest import CASES


class OffCircle(PieceCurve):
    """The circle of radius ``rho`` centred at (a, 0), one piece, counter-clockwise."""

    name, lobes, material_inside = "off-circle", 1, True

    def __init__(self, rho: float, a: float):
        self.rho, self.a = rho, a

    @property
    def n(self) -> int:
        return 1

    def _eval(self, u, order):
        t = 2.0 * math.pi * np.asarray(u, float)
        if order == 0:
            return np.stack([self.a + self.rho * np.cos(t), self.rho * np.sin(t)], -1)
        return 2.0 * math.pi * self.rho * np.stack([-np.sin(t), np.cos(t)], -1)


def exact_deficit(rho, a, theta):
    return (a + rho) - (a * np.cos(theta) + np.sqrt(rho**2 - (a * np.sin(theta)) ** 2))


MU, OMEGA, LENGTH = 0.015, 600.0, 0.13


def test_concentric_rotor_is_petroffs_journal_bearing():
    R, h = 0.05, 40e-6
    d = radial_deficit(OffCircle(R, 0.0), R)
    assert np.max(np.abs(d)) < 1e-12
    film = TipFilm("rotor", "tip", R, 1.0, tuple(d))
    petroff = 2.0 * math.pi * MU * OMEGA**2 * R**3 * LENGTH / h
    assert film_dissipation(film, OMEGA, MU, h, LENGTH) == pytest.approx(petroff, rel=1e-9)


def test_deficit_of_an_off_axis_circle():
    rho, a = 0.03, 0.02
    d = radial_deficit(OffCircle(rho, a), a + rho, bins=1024)
    theta = -math.pi + (np.arange(1024) + 0.5) * 2.0 * math.pi / 1024
    # the rays cross sampled chords: their sag (2 pi rho / 32768)^2 / (8 rho) ~ 5e-9 m
    assert np.max(np.abs(d - exact_deficit(rho, a, theta))) < 1e-8


@pytest.mark.parametrize("h", [20e-6, 40e-6, 100e-6])
def test_rounded_tip_film_converges_to_the_integral(h):
    rho, a = 0.03, 0.02
    R = a + rho

    def f(t):
        d = exact_deficit(rho, a, t)
        return R * (R - d) ** 2 / (h + d)

    # the film of width ~ sqrt(2 r_eff h) about theta = 0, its tail to the far side
    exact = 2.0 * quad(f, 0.0, math.pi, limit=400, epsabs=0, epsrel=1e-13)[0]
    errors = []
    for bins in (1024, 2048, 4096):
        film = TipFilm("rotor", "tip", R, 1.0, tuple(radial_deficit(OffCircle(rho, a), R, bins)))
        power = film_dissipation(film, OMEGA, MU, h, LENGTH)
        errors.append(abs(power / (MU * OMEGA**2 * LENGTH * exact) - 1.0))
    # midpoint rule on a smooth integrand: second order
    assert errors[-1] < 1e-6
    assert math.log2(errors[0] / errors[1]) > 1.8
    assert math.log2(errors[1] / errors[2]) > 1.8


def test_polar_moment_parallel_axis():
    rho, a = 0.03, 0.02
    J = math.pi * rho**4 / 2.0 + math.pi * rho**2 * a**2
    assert polar_moment(OffCircle(rho, a)) == pytest.approx(J, rel=1e-12)
    # a disc's face film: mu omega^2 pi R^4 / (2 h)
    face = FaceFilm("rotor", "face", polar_moment(OffCircle(0.05, 0.0)))
    assert film_dissipation(face, OMEGA, MU, 40e-6, LENGTH) == pytest.approx(
        MU * OMEGA**2 * math.pi * 0.05**4 / (2.0 * 40e-6), rel=1e-12)


def test_casing_share_of_two_intersecting_bores():
    R1, R2, C = 0.05, 0.048, 0.08
    bores = (((0.0, 0.0), R1), ((C, 0.0), R2))
    exact = 1.0 - math.acos((R1**2 + C**2 - R2**2) / (2.0 * R1 * C)) / math.pi
    assert covered_share((0.0, 0.0), R1, bores, bins=8192) == pytest.approx(exact, abs=2 / 8192)


def test_walther_line_through_the_datasheet_points():
    assert walther_viscosity(46.0, 6.8, 313.15) == pytest.approx(46.0, rel=1e-12)
    assert walther_viscosity(46.0, 6.8, 373.15) == pytest.approx(6.8, rel=1e-12)
    nu = [walther_viscosity(46.0, 6.8, T) for T in (300.0, 330.0, 360.0, 400.0)]
    assert np.all(np.diff(nu) < 0.0)


def test_film_records_round_trip():
    tip = TipFilm("male", "tip-male-lead+1", 0.05, 0.8, (0.0, 1e-3, 2e-3))
    face = FaceFilm("male", "hp-front+1", 4e-6)
    assert film_from_dict(tip.to_dict()) == tip
    assert film_from_dict(face.to_dict()) == face
    with pytest.raises(ValueError, match="unknown kind"):
        film_from_dict({"kind": "wall"})


def _simulate(case):
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "simulate", str(case),
                          "--json"], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def test_the_4_6_machine_books_its_films_at_their_paths_clearances(tmp_path):
    """The 4/6 of seed 004 (oil-flooded) with the end faces' clearance doubled: per unit
    viscosity (the film temperature follows the cycle) the face films halve exactly, the
    tip films stay; the mechanical loss is bearings, seal, films and the oil's
    acceleration to the rotors' speed."""
    text = (CASES / "twin_screw_4_6.toml").read_text()
    base = tmp_path / "base.toml"
    base.write_text(text)
    wide = tmp_path / "wide.toml"
    wide.write_text(text.replace("[leakage.end-face]\n", "[leakage.end-face]\ngap_um = 80\n"))
    a, b = _simulate(base), _simulate(wide)
    for fig in (a, b):
        mech = fig["mechanical"]
        bearings = sum(r["bearing_loss_W"] for r in fig["loads"]["rotors"].values())
        assert fig["mechanical_loss_W"] == pytest.approx(
            bearings + mech["seal_loss_W"] + sum(mech["oil_film_W"].values())
            + mech["liquid_acceleration_W"], rel=1e-12)
        assert fig["shaft_power_W"] == pytest.approx(
            fig["indicated_power_W"] + fig["mechanical_loss_W"], rel=1e-12)
    mu_a = a["mechanical"]["oil_film_viscosity_Pa_s"]
    mu_b = b["mechanical"]["oil_film_viscosity_Pa_s"]
    films_a, films_b = a["mechanical"]["oil_film_W"], b["mechanical"]["oil_film_W"]
    assert len(films_a) == 6  # two rotors: a tip and two end faces each
    for name, power in films_a.items():
        ratio = (films_b[name] / mu_b) / (power / mu_a)
        assert ratio == pytest.approx(1.0 if " tip-" in name else 0.5, rel=1e-12), name
