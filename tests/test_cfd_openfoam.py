"""Real OpenFOAM runs on meshes rotorflow builds (openfoam tier; ~15 s on 2 cores).

Skipped with a reason when OpenFOAM is not installed; ``make test`` installs it first
(``make openfoam``), so in CI these run.
"""

from __future__ import annotations

import pytest

from rotorflow.cases import foam, foam_mesh, gap_case, gap_mesh, gap_study, gap_walls
from rotorflow.errors import CaseError
from rotorflow.postprocess import leakage
from rotorflow.quasi1d.perfect_gas import PerfectGas

pytestmark = [
    pytest.mark.openfoam,
    pytest.mark.gmsh,
    pytest.mark.skipif(not foam.is_available(),
                       reason="OpenFOAM not installed: run `make openfoam`"),
]

#: Plane Poiseuille channel: 10 um x 1 mm, 0.5 % pressure drop, constant viscosity;
#: Re ~ 0.15, L/h = 100: fully developed Stokes flow, so the analytic law is exact.
GAP, LENGTH, P_EXIT, T0 = 10e-6, 1e-3, 1.0e5, 300.0
AIR = PerfectGas(transport="const")
SPEC = gap_mesh.GapMeshSpec(cells_across=16, cells_along=20)


def channel_case(wall_speed: float = 0.0) -> gap_case.GapCase:
    flow = gap_case.GapFlow(p_total_Pa=1.005 * P_EXIT, T_total_K=T0, p_exit_Pa=P_EXIT, gas=AIR,
                            wall_speed_lower_m_s=wall_speed)
    return gap_case.GapCase(gap_walls.parallel_channel(GAP, LENGTH), flow, SPEC)


@pytest.fixture(scope="module")
def channel_study(tmp_path_factory):
    return gap_study.run_mesh_study("channel", channel_case(), tmp_path_factory.mktemp("cfd"))


def test_openfoam_version_is_reported():
    inst = foam.find_installation()
    assert inst.api.isdigit()
    assert (inst.project_dir / "etc" / "controlDict").is_file()


def test_mesh_converts_with_named_typed_patches(tmp_path):
    walls = gap_walls.rotor_tip_gap(50e-6, 0.02)
    mesh, quality = gap_mesh.build_foam_mesh(tmp_path, walls, gap_mesh.GapMeshSpec(
        cells_across=8, cells_along=20, along_grading=20))
    assert quality.ok and quality.cells == mesh.cells == 8 * 40
    # OpenFOAM's own limits are 70 degrees non-orthogonality and aspect ratio 1000.
    assert quality.max_non_orthogonality_deg < 30
    assert quality.max_aspect_ratio < 100
    counts = foam_mesh.patch_face_counts(tmp_path)
    assert counts == {"frontAndBack": 2 * 8 * 40, "lowerWall": 40, "upperWall": 40,
                      "inlet": 8, "outlet": 8}
    text = (tmp_path / "constant" / "polyMesh" / "boundary").read_text()
    assert "type empty" in text and "type wall" in text


def test_mesh_checkmesh_rejects_stops_the_case(tmp_path):
    # 40000:1 cells: checkMesh fails the aspect-ratio check; the case must stop, quoting it.
    with pytest.raises(foam_mesh.MeshCheckError, match="High aspect ratio") as err:
        gap_mesh.build_foam_mesh(tmp_path, gap_walls.parallel_channel(10e-6, 0.1),
                                 gap_mesh.GapMeshSpec(cells_across=4, cells_along=1))
    assert isinstance(err.value, CaseError)  # exit status 2 at the command line


def test_channel_mass_balance_and_poiseuille_flow(channel_study):
    study = channel_study
    assert study.ok, study.failures
    for result in study.results:
        assert result.imbalance < 5e-3  # the 0.5 % between inlet and outlet
        assert result.turbulence == "laminar"
    exact = leakage.plane_poiseuille_mass_flow(study.leakage_point())
    rich = study.richardson
    # Second-order finite volumes on meshes 8, 16, 32 cells across.
    assert rich.kind == "monotone" and 1.7 < rich.order < 2.3
    # After extrapolation only the h^3 term and iterative noise (~1e-4) remain.
    assert rich.extrapolated == pytest.approx(exact, rel=2e-3)
    # The target: the default mesh within 2 % of the extrapolated value.
    assert abs(study.default_error) < 0.02


def test_sliding_wall_adds_the_couette_flow(channel_study, tmp_path):
    # Stokes flow is linear: a lower wall sliding at U adds rho U h / 2 per metre of depth
    # (exact on any mesh: the Couette profile is linear) to the pressure-driven flow.
    speed = 0.5
    moving = gap_case.run_gap_case(channel_case(speed), tmp_path / "moving")
    assert moving.ok, moving.message
    static = channel_study.results[1]
    rho_mean = AIR.density(0.5 * (1.005 + 1.0) * P_EXIT, T0)
    couette = rho_mean * speed * GAP / 2
    assert moving.mass_flow_kg_s_m - static.mass_flow_kg_s_m == pytest.approx(couette, rel=5e-3)


def test_rotor_tip_gap_runs_and_stays_below_the_ideal_nozzle(tmp_path):
    walls = gap_walls.rotor_tip_gap(50e-6, 0.02)
    flow = gap_case.GapFlow(p_total_Pa=2.0e5, T_total_K=T0, p_exit_Pa=1.0e5)
    spec = gap_mesh.GapMeshSpec(cells_across=16, cells_along=40, along_grading=20)
    result = gap_case.run_gap_case(gap_case.GapCase(walls, flow, spec), tmp_path / "tip")
    assert result.ok, result.message + result.log_tail
    assert result.imbalance < 5e-3
    point = leakage.LeakagePoint("tip", result.min_gap_m, result.gap_length_m, 2.0e5, T0, 1.0e5,
                                 flow.gas.mu(T0), flow.gas.R, flow.gas.gamma,
                                 mass_flow_kg_s_m=result.mass_flow_kg_s_m)
    # A real gap passes less than the loss-free nozzle through its throat, and a smooth
    # converging inlet loses little: 0.7 < Cd < 1.
    assert 0.7 < point.flow_coefficient < 1.0
    # A second call with the same case reuses the stored result instead of running.
    again = gap_case.run_gap_case(gap_case.GapCase(walls, flow, spec), tmp_path / "tip")
    assert again == result
