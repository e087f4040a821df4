"""Twin-screw sections cut into groove parts: what must hold whatever the profile.

Independent references: the free area of a section is the two bores' union (a closed
form of the lens) less both rotors' areas (Green's theorem on the analytic profiles),
whatever the rotors' positions; every rotor's boundary is wetted all round, so at one
pressure everywhere the parts' forces and torques on each rotor sum to nothing; a whole
groove is its bore less its rotor shared by the lobes.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.geometry.twin_screw.family import build

#: Seed 004's 4/6 machine (male 100 mm, female 96 mm); the centre distance, not given
#: there, assumed 78 mm.
SIZE = (4, 6, 0.078, 0.100, 0.096)
ANGLES = 12


@functools.cache
def pair(profile):
    return build(profile, *SIZE)


@functools.cache
def scans(profile):
    p = pair(profile)
    psi = np.linspace(0.0, 2.0 * math.pi / 4, ANGLES, endpoint=False) + 0.0123
    return [(x, p.cutter.cut(float(x))) for x in psi]


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_parts_fill_the_free_area(profile):
    p = pair(profile)
    free = p.working_area - p.male.area - p.female.area
    for _, parts in scans(profile):
        # Polygons sampled to 1e-6 C with each edge's sliver to the true curve added:
        # what is left is the ends of runs at cuts and contacts (measured 2e-8).
        assert sum(q.area for q in parts) == pytest.approx(free, rel=1e-7)


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_uniform_pressure_loads_no_rotor_in_any_section(profile):
    p = pair(profile)
    for psi, parts in scans(profile):
        force = sum(q.force for q in parts)
        torque = sum(q.torque for q in parts)
        scale = p.male_radius
        # Wetted arcs meet end to end at tips and cuts exactly; at a contact both ends
        # of the rotors' overlap take one snapped point, but where a lens's ends are
        # matched to the fluid's corners across a conformal band they can differ by
        # ~1e-7 m (measured 5e-6 of the radius at worst, line-circle rack).
        assert np.abs(force).max() < 2e-5 * scale, (psi, force)
        assert np.abs(torque).max() < 2e-5 * scale * scale, (psi, torque)


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_whole_grooves_are_the_bore_less_the_rotor(profile):
    p = pair(profile)
    g = p.gearing
    whole = {0: (math.pi * p.male_radius ** 2 - p.male.area) / g.lobes_male,
             1: (math.pi * p.female_radius ** 2 - p.female.area) / g.lobes_female}
    seen = 0
    for _, parts in scans(profile):
        for q in parts:
            if q.side == "" and len(q.tips) == 2 and not q.contacts:
                assert q.area == pytest.approx(whole[q.rotor], rel=1e-6)
                seen += 1
    assert seen


def test_chamber_section_tables_sum_to_the_free_area():
    p = pair("circular")
    ppp = 24
    sec = p.section(ppp)
    n = len(sec.psi)
    k = -(-n // ppp) * ppp
    area = np.zeros(k)
    area[:n] = sec.area
    free = p.working_area - p.male.area - p.female.area
    # Every part of every section is booked to exactly one chamber's node.
    assert area.reshape(-1, ppp).sum(0) == pytest.approx(np.full(ppp, free), rel=1e-7)
