"""Gap walls and their gmsh meshes (gmsh tier: no OpenFOAM)."""

from __future__ import annotations

import math

import meshio
import numpy as np
import pytest

from rotorflow.cases import gap_mesh, gap_walls
from rotorflow.cases.gap_mesh import GapMeshSpec
from rotorflow.cases.gap_walls import GapWalls
from rotorflow.errors import CaseError, ExternalRunError
from rotorflow.gmsh_session import gmsh_session

# --- walls (pure numpy/scipy) -------------------------------------------------------------


def test_walls_copy_their_input_and_are_read_only():
    lower = np.array([[0.0, 0.0], [1.0, 0.0]])
    upper = np.array([[0.0, 1.0], [1.0, 1.0]])
    walls = GapWalls(lower, upper)
    lower[0, 1] = 5.0
    assert walls.lower[0, 1] == 0.0
    with pytest.raises(ValueError):
        walls.lower[0, 0] = 1.0


@pytest.mark.parametrize(
    ("lower", "upper", "match"),
    [
        ([[0, 0], [1, 0]], [[0, 1], [1, -0.1]], "touch or cross"),
        ([[0, 0], [1, 0]], [[0, 1], [2, 1]], "same x range"),
        ([[1, 0], [0, 0]], [[1, 1], [0, 1]], "increase"),
        ([[0, 0]], [[0, 1]], "n >= 2"),
    ],
)
def test_bad_walls_are_refused(lower, upper, match):
    with pytest.raises(CaseError, match=match):
        GapWalls(np.array(lower, float), np.array(upper, float))


def test_cylinder_pair_geometry():
    gap, radius = 50e-6, 0.02
    walls = gap_walls.cylinder_pair(gap, radius, radius, 4e-3, 1e-3)
    assert walls.throat_x == pytest.approx(0.0, abs=1e-9)
    assert walls.min_gap == pytest.approx(gap, rel=1e-9)
    # gap(x) = h + 2 (R - sqrt(R^2 - x^2)); the spline through 201 points is exact to ~1e-9.
    x = -3e-3
    assert walls.gap(x) == pytest.approx(gap + 2 * (radius - math.sqrt(radius**2 - x**2)),
                                         rel=1e-6)
    # Narrow stretch (gap <= 2h): |x| <= sqrt(R^2 - (R - h/2)^2) ~ sqrt(R h).
    half = math.sqrt(radius**2 - (radius - gap / 2) ** 2)
    assert walls.narrow_length() == pytest.approx(2 * half, rel=1e-6)


def test_parallel_channel_throat_is_its_middle():
    walls = gap_walls.parallel_channel(10e-6, 1e-3)
    assert walls.throat_x == pytest.approx(0.5e-3, rel=1e-3)
    assert walls.narrow_length() == pytest.approx(1e-3)


def test_rotor_tip_gap_ends_at_the_asked_gap_ratios():
    walls = gap_walls.rotor_tip_gap(20e-6, 0.03, inlet_gap_ratio=15, outlet_gap_ratio=3)
    assert walls.gap(walls.x_inlet) == pytest.approx(15 * 20e-6, rel=1e-6)
    assert walls.gap(walls.x_outlet) == pytest.approx(3 * 20e-6, rel=1e-6)


def test_extension_continues_the_walls_straight():
    walls = gap_walls.cylinder_pair(50e-6, 0.02, 0.02, 2e-3)
    ext = walls.extended(inlet_m=1e-3, outlet_m=0.5e-3)
    assert ext.x_inlet == pytest.approx(walls.x_inlet - 1e-3)
    assert ext.x_outlet == pytest.approx(walls.x_outlet + 0.5e-3)
    # Along the straight piece the wall keeps its end slope.
    slope = walls.slope_upper(walls.x_inlet)
    x = walls.x_inlet - 0.6e-3
    assert ext.y_upper(x) == pytest.approx(walls.y_upper(walls.x_inlet) - 0.6e-3 * slope,
                                           rel=1e-4)
    assert ext.min_gap == pytest.approx(walls.min_gap, rel=1e-6)


def test_mesh_spec_validation():
    with pytest.raises(CaseError, match="even"):
        GapMeshSpec(cells_across=15)
    with pytest.raises(CaseError, match="whole number"):
        GapMeshSpec(cells_across=16, refinement=0.3)
    assert GapMeshSpec(cells_across=16).refined(0.5).half_cells_across == 4


def test_refinement_keeps_the_spacing_law():
    # Halving every cell: the growth rate is square-rooted, the total growth kept.
    spec = GapMeshSpec(cells_across=16, wall_grading=3.0)
    fine = spec.refined(2.0)
    assert fine.across_rate == pytest.approx(math.sqrt(spec.across_rate))
    assert fine.across_rate ** (2 * 8) == pytest.approx(spec.across_rate**8)


# --- gmsh ---------------------------------------------------------------------------------


@pytest.mark.gmsh
def test_gmsh_session_always_finalizes():
    import gmsh

    with pytest.raises(KeyError), gmsh_session("t"):
        raise KeyError("boom")
    assert not gmsh.isInitialized()
    with pytest.raises(ExternalRunError, match="gmsh failed"), gmsh_session("t") as g:
        g.model.geo.addLine(1, 2)  # no such points
        g.model.geo.synchronize()
    assert not gmsh.isInitialized()


@pytest.mark.gmsh
def test_gmsh_sessions_do_not_nest():
    import gmsh

    with gmsh_session("outer"), pytest.raises(RuntimeError, match="already open"):
        with gmsh_session("inner"):
            pass
    assert not gmsh.isInitialized()


def read_mesh(path):
    mesh = meshio.read(path)
    return mesh, {name: tag for name, (tag, dim) in mesh.field_data.items()}


@pytest.mark.gmsh
def test_channel_mesh_cells_groups_and_wall_grading(tmp_path):
    spec = GapMeshSpec(cells_across=8, wall_grading=3.0, cells_along=5)
    walls = gap_walls.parallel_channel(10e-6, 1e-3)
    result = gap_mesh.write_msh(walls, spec, tmp_path / "gap.msh")
    assert result.cells == 8 * 10
    assert (tmp_path / "log.gmsh").is_file()
    mesh, groups = read_mesh(result.path)
    assert set(groups) == {"inlet", "outlet", "lowerWall", "upperWall", "frontAndBack", "fluid"}
    assert {c.type for c in mesh.cells} == {"hexahedron", "quad"}
    assert sum(len(c.data) for c in mesh.cells if c.type == "hexahedron") == 80
    # MSH 2.2 ASCII, the format gmshToFoam reads.
    assert result.path.read_text().startswith("$MeshFormat\n2.2 0 8")
    # Node rows across the gap: geometric toward both walls, centre/wall ratio 3.
    y = np.unique(np.round(mesh.points[:, 1] / 10e-6, 12))
    dy = np.diff(y)
    assert len(dy) == 8
    assert dy[3] / dy[0] == pytest.approx(3.0, rel=1e-6)  # gmsh computes nodes to ~1e-8
    np.testing.assert_allclose(dy, dy[::-1], rtol=1e-6)  # symmetric about the centre line
    assert mesh.points[:, 2].max() == pytest.approx(10e-6)  # depth: the gap


@pytest.mark.gmsh
def test_refined_mesh_nests_the_default_one(tmp_path):
    # Richardson needs the same spacing law at every level: the default mesh's node rows
    # must be every other row of the mesh refined by 2.
    walls = gap_walls.parallel_channel(10e-6, 1e-3)
    spec = GapMeshSpec(cells_across=8, wall_grading=3.0, cells_along=5)
    rows = []
    for factor, name in ((1.0, "a"), (2.0, "b")):
        m = gap_mesh.write_msh(walls, spec.refined(factor), tmp_path / name / "gap.msh")
        rows.append(np.unique(np.round(meshio.read(m.path).points[:, 1] / 10e-6, 9)))
    np.testing.assert_allclose(rows[1][::2], rows[0], atol=1e-9)


@pytest.mark.gmsh
def test_curved_gap_mesh_stays_between_the_walls(tmp_path):
    walls = gap_walls.rotor_tip_gap(50e-6, 0.02)
    spec = GapMeshSpec(cells_across=8, cells_along=20, along_grading=20)
    result = gap_mesh.write_msh(walls, spec, tmp_path / "gap.msh")
    pts = meshio.read(result.path).points
    x, y = pts[:, 0], pts[:, 1]
    # gmsh's splines through the control points follow the walls to ~1e-9 of the gap.
    tol = 1e-6 * walls.min_gap
    assert np.all(y >= walls.y_lower(x) - tol)
    assert np.all(y <= walls.y_upper(x) + tol)
    # Cells along the walls shrink toward the throat: the smallest spacing is there.
    wall_x = np.unique(np.round(x[np.abs(y - walls.y_lower(x)) < tol], 12))
    dx = np.diff(wall_x)
    assert abs(wall_x[np.argmin(dx)] - walls.throat_x) < 2 * dx.min()
    # End cell / throat cell = along_grading, in arc length (x spacing is a little less).
    assert dx.max() / dx.min() == pytest.approx(20.0, rel=0.03)


@pytest.mark.gmsh
def test_throat_at_the_end_is_refused(tmp_path):
    x = np.linspace(0, 1e-3, 50)
    walls = GapWalls(np.column_stack([x, 0 * x]), np.column_stack([x, 1e-4 - 5e-2 * x]))
    with pytest.raises(CaseError, match="extend them"):
        gap_mesh.write_msh(walls, GapMeshSpec(), tmp_path / "gap.msh")


def test_leakage_matrix_spans_the_issue_ranges():
    from rotorflow.cases.gap_study import default_matrix

    points = default_matrix()
    assert len({p.name for p in points}) == len(points)
    assert min(p.gap_um for p in points) == 5 and max(p.gap_um for p in points) == 200
    # From a small pressure ratio to beyond the critical one of air (1.89): choked.
    assert min(p.pressure_ratio for p in points) == 1.1
    assert max(p.pressure_ratio for p in points) > 1.9
    assert any(p.wall_speed_m_s for p in points)
    case = points[0].case()
    assert case.walls.min_gap == pytest.approx(5e-6, rel=1e-9)


def test_cfd_section_of_a_case_file():
    from rotorflow.cases.gap_study import default_matrix
    from rotorflow.cases.leakage_stage import matrix_from_section

    assert matrix_from_section({"matrix": "default"}) == default_matrix()
    with pytest.raises(CaseError, match="asks for no runs"):
        matrix_from_section({})  # an empty [cfd] starts no hours-long study by accident
    points = matrix_from_section({"gap_um": [5, 50], "pressure_ratio": [1.5, 3.0]})
    assert [(p.gap_um, p.pressure_ratio) for p in points] == [(5, 1.5), (5, 3.0), (50, 1.5),
                                                              (50, 3.0)]
    with pytest.raises(CaseError, match="unknown key.*gap_mm.*case.toml"):
        matrix_from_section({"gap_mm": [5]}, "case.toml")
    with pytest.raises(CaseError, match="list of numbers"):
        matrix_from_section({"gap_um": 5})
    with pytest.raises(CaseError, match="pressure ratios > 1"):
        matrix_from_section({"pressure_ratio": [0.9]})
