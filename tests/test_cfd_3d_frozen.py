"""A small 3D case of the internal gear at a frozen angle, run with rhoSimpleFoam
(issue 16): the helical O-grid stack with the ports on its end faces.

20 mm of the default machine's pair at its lead (136 deg per 100 mm), coarse: 512
columns, 4 cells across a 100 um clearance, 8 layers and 0.2 mm end layers (32,768
cells).  Skipped without OpenFOAM.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotorflow.cases import foam
from rotorflow.cases.foam_mesh import parse_check_mesh
from rotorflow.cases.grid3d_case import (
    Frozen3DCase,
    chamber_pressures,
    inside,
    mass_flows,
    port_polygons,
    write_case,
)
from rotorflow.cases.ogrid import OGridSpec
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep

LENGTH = 0.02
MACHINE = SweptMachine(examples()["table1"],
                       Sweep("helical", LENGTH, math.radians(136.0) * LENGTH / 0.1))
CASE = Frozen3DCase(MACHINE, 0.0, 100e-6, 8, 1.0e5, 2.6e5, 293.15, 2500 * math.pi / 30,
                    spec=OGridSpec(columns=512, cells_across_gap=4), end_layer=2e-4,
                    iterations=500)
#: The brief's mass balance: what enters through the ports leaves through them.
BALANCE = 5e-3
#: How far a chamber open to a port may sit from the plenum: the leakage flow's drop
#: through the port's open part (0.4 % measured at suction, 0.02 % at discharge).
PORT_DROP = 1e-2

pytestmark = [
    pytest.mark.openfoam,
    pytest.mark.skipif(not foam.is_available(),
                       reason="OpenFOAM not installed: run `make openfoam`"),
]


def test_even_odd_inside():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    hole = square[::-1] * 0.5 + 0.25
    pts = np.array([[0.1, 0.1], [0.5, 0.5], [1.5, 0.5], [0.9, 0.5]])
    assert inside(pts, [square, hole]).tolist() == [True, False, False, True]


@pytest.fixture(scope="module")
def frozen_run(tmp_path_factory):
    case_dir = tmp_path_factory.mktemp("frozen3d")
    counts = write_case(CASE, case_dir)
    check = parse_check_mesh(foam.run(case_dir, "checkMesh").read_text())
    foam.run(case_dir, "rhoSimpleFoam", timeout_s=900)
    return case_dir, counts, check


def test_mesh_passes_check_mesh_with_the_ports_on_its_ends(frozen_run):
    case_dir, counts, check = frozen_run
    assert check.ok, check.failed_checks
    assert check.cells == counts["cells"] == 512 * 4 * (8 + 2 * 4)
    assert set(counts["patches"]) == {"innerRotor", "outerRotor", "suction", "discharge",
                                      "endPlates"}
    # One chamber per tooth space (cellZones), one faceZone per sealing line.
    assert sum(z.startswith("chamber") for z in counts["zones"]) == 6


def test_port_patches_cover_the_open_ports():
    """The end faces whose centres lie in a port cover the part of it that the rotors
    leave open at this angle (the port less the inner rotor's end face: the annulus
    between the grid's walls, clipped by Clipper), up to the faces straddling its edge
    (half in, half out: they about balance; bounded by the edge's length times the
    largest face's half width)."""
    from manifold3d import CrossSection, FillRule

    from rotorflow.cases.grid3d_case import end_labels
    from rotorflow.cases.polymesh import build_polymesh, helical_stack

    polygons = port_polygons(MACHINE, CASE.volume_ratio)
    sections, z = helical_stack(MACHINE.pair, CASE.phi, CASE.gap, MACHINE.sweep, CASE.layers,
                                CASE.spec, CASE.end_layer)
    pts, faces, _, _, patches = build_polymesh(sections, z, end_labels(polygons))
    for name, _, start, count in patches:
        if name not in polygons:
            continue
        end = sections[0] if name == "suction" else sections[-1]
        annulus = CrossSection([np.ascontiguousarray(end.points[:, -1]),
                                np.ascontiguousarray(end.points[::-1, 0])], FillRule.EvenOdd)
        port = CrossSection([np.ascontiguousarray(r) for r in polygons[name]],
                            FillRule.EvenOdd)
        open_part = port ^ annulus
        q = pts[faces[start:start + count]]
        area = 0.5 * np.linalg.norm(np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]), axis=1)
        edge = sum(float(np.sum(np.linalg.norm(np.roll(r, -1, 0) - r, axis=1)))
                   for r in open_part.to_polygons())
        band = edge * 0.5 * math.sqrt(area.max())
        assert open_part.area() > 0.0
        assert abs(area.sum() - open_part.area()) < band, (name, area.sum(), open_part.area())


def test_steady_run_balances_its_mass_flows(frozen_run):
    """At a frozen angle the rotors pump nothing: the gas leaks from the discharge
    plenum to the suction one through the sealing gaps, and what comes in through one
    port leaves through the other (walls carry nothing: rotatingWallVelocity keeps only
    the tangential velocity)."""
    case_dir, _, _ = frozen_run
    flows = mass_flows(case_dir)
    inflow = -flows["discharge"]
    assert inflow > 0.0 and flows["suction"] > 0.0
    assert abs(flows["suction"] - inflow) < BALANCE * inflow
    for wall in ("innerRotor", "outerRotor", "endPlates"):
        assert abs(flows[wall]) < 1e-12 * inflow


def test_chambers_take_their_ports_pressure_and_closed_ones_settle_between(frozen_run):
    """The chamber most open to a port takes that plenum's pressure (within the drop of
    the leakage flow through the port); a chamber just opening to a port through a
    sliver is throttled (seed 004's point) and a closed one settles where its leakage in
    and out balance: both between the plenums."""
    case_dir, counts, _ = frozen_run
    p = chamber_pressures(case_dir)
    assert len(p) == sum(z.startswith("chamber") for z in counts["zones"])
    open_to = counts["open_to"]
    for port, p_port in (("suction", CASE.p_suction_Pa), ("discharge", CASE.p_discharge_Pa)):
        most = max(open_to[port], key=open_to[port].get)
        assert p[most] == pytest.approx(p_port, rel=PORT_DROP)
    for value in p.values():
        assert CASE.p_suction_Pa * (1 - PORT_DROP) < value < CASE.p_discharge_Pa * (1 + PORT_DROP)
    closed = set(p) - set(open_to["suction"]) - set(open_to["discharge"])
    assert closed
    for zone in closed:
        assert 1.05 * CASE.p_suction_Pa < p[zone] < 0.95 * CASE.p_discharge_Pa
