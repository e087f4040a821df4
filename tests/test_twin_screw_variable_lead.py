"""Twin-screw rotors swept by the variable-lead law (geometry.sweep: the lead linear
along z, ``lead_ratio`` the lead at z = L over the lead at z = 0).

Independent references: the chamber's volume as its section areas, cut by the family
at the angle each height sees (psi = phi - twist(z), the sweep law inverted by hand),
integrated along z by Gauss-Legendre in numpy (not the table's hat kernel); a law whose
lead barely changes tends to the helical rotor; the contact line, computed from the
rack alone, tends to the helical one too; the case file accepts the law.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.family import build
from rotorflow.geometry.twin_screw.section import _beta0, chamber_index

#: Seed 004's 4/6 machine on the circular profile (C assumed 78 mm, as elsewhere).
SIZE = (4, 6, 0.078, 0.100, 0.096)
LENGTH, WRAP = 0.13, math.radians(300.0)
PPP = 24


@functools.cache
def pair():
    return build("circular", *SIZE)


@functools.cache
def machine(lead_ratio):
    return SweptMachine(pair(), Sweep("helical", LENGTH, WRAP, 1.0, lead_ratio), PPP)


def _area(p, psi):
    """Chamber 0's section area at male angle psi, summed over the parts of the cut."""
    period = p.period
    base = -_beta0(p)
    q = math.floor((psi - base) / period)
    residue = psi - q * period
    return sum(part.area for part in p.cutter.cut(float(residue))
               if chamber_index(p, part, residue, p.female_shift) == q)


def _quadrature_volume(sweep, phi, panels=40, nodes=6):
    """V(phi) = int_0^L A(phi - twist(z)) dz, twist(z) = wrap log(1 + (r - 1) z / L) /
    log r written here, not taken from the sweep."""
    r = sweep.lead_ratio
    x, w = np.polynomial.legendre.leggauss(nodes)
    edges = np.linspace(0.0, sweep.length, panels + 1)
    h = np.diff(edges)
    z = (edges[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
    wz = (0.5 * h[:, None] * w[None, :]).ravel()
    twist = sweep.wrap * np.log1p((r - 1.0) * z / sweep.length) / math.log(r)
    return float(np.sum(wz * np.array([_area(pair(), phi - t) for t in twist])))


def test_variable_lead_volume_against_the_sections_integrated_along_z():
    """Mid-life, where the chamber's whole length is in its life: the table's swept
    volume against the sections integrated along z: 5e-7 apart (the quadrature moves by
    6e-7 from 40 to 80 panels: the sections' kinks between Gauss nodes; the table moved
    by 1e-8 from 24 to 48 points per period).  The helical rotor's volume at the same
    angle differs by 8 %: the check tells the laws apart."""
    m = machine(2.0)
    sec = m.section
    phi = float(sec.phi_i + WRAP + 0.3)
    assert phi < sec.phi_f
    reference = _quadrature_volume(m.sweep, phi)
    assert float(m.volume_at(phi)[0]) == pytest.approx(reference, rel=2e-5)
    helical = float(machine(1.0).volume_at(phi)[0])
    assert abs(helical / reference - 1.0) > 100 * 2e-5


def test_a_lead_that_barely_varies_is_the_helical_rotor():
    """lead_ratio 1 + 1e-6 turns every section by at most ~1e-6 of the wrap against the
    helical rotor: the volume curve and the contact line follow within that (the
    volume: 1.2e-7 of its largest, measured)."""
    from rotorflow.geometry.twin_screw.contact_line import contact_line_lengths

    near, helical = machine(1.0 + 1e-6), machine(1.0)
    assert np.allclose(near.curves.phi, helical.curves.phi)
    scale = helical.curves.volume.max()
    assert np.abs(near.curves.volume - helical.curves.volume).max() < 1e-5 * scale
    arcs = pair().rack
    thetas = np.linspace(0.0, pair().period, 5)
    a = contact_line_lengths(pair(), arcs, near.sweep, thetas)
    b = contact_line_lengths(pair(), arcs, helical.sweep, thetas)
    assert np.abs(a - b).max() < 1e-5 * b.max()


def test_case_file_takes_a_lead_ratio_on_a_helical_twin_screw(tmp_path):
    from rotorflow.workflow.case import load_case

    from .conftest import CASES

    text = (CASES / "twin_screw_4_6.toml").read_text()
    assert 'kind = "helical"\n' in text
    good = tmp_path / "vl.toml"
    good.write_text(text.replace('kind = "helical"\n', 'kind = "helical"\nlead_ratio = 1.5\n'))
    assert load_case(good).sweep(None).lead_ratio == 1.5
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('kind = "helical"\n', 'kind = "helical"\nlead_ratio = -1\n'))
    with pytest.raises(CaseError, match="lead_ratio"):
        load_case(bad)
