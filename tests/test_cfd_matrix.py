"""A slice of the leakage matrix, run for real: mesh studies, comparison and fit (slow tier).

About three minutes on 2 cores; excluded from ``make test`` by the ``slow`` marker.
"""

from __future__ import annotations

import math

import pytest

from rotorflow.cases import foam
from rotorflow.cases.gap_study import DEFAULT_MESH_TOL, MatrixPoint, run_leakage_matrix
from rotorflow.postprocess import leakage, leakage_report

pytestmark = [
    pytest.mark.slow,
    pytest.mark.openfoam,
    pytest.mark.gmsh,
    pytest.mark.skipif(not foam.is_available(),
                       reason="OpenFOAM not installed: run `make openfoam`"),
]

PRESSURE_RATIOS = (1.1, 2.5, 4.0)
POINTS = [MatrixPoint(g, pr, 20.0) for g in (5, 50) for pr in PRESSURE_RATIOS]


def test_matrix_slice_meets_the_mesh_target_and_fits(tmp_path):
    studies = run_leakage_matrix(tmp_path, POINTS)
    for study in studies:
        assert study.ok, study.failures
        for result in study.results:
            assert result.imbalance < 5e-3  # inlet and outlet within 0.5 %
        # The target: the default mesh within 2 % of the extrapolated mass flow
        # (or of the finest, where the three meshes oscillate within noise).
        assert abs(study.default_error) < DEFAULT_MESH_TOL, study.summary()
    points = [s.leakage_point() for s in studies]
    for p in points:
        # Less than the loss-free nozzle through the throat, and more than nothing.
        assert 0.0 < p.flow_coefficient < 1.0
    # Cd grows with Re at a fixed pressure ratio: viscous losses shrink with a wider gap.
    by = {(round(p.gap_m * 1e6), round(p.pressure_ratio, 3)): p.flow_coefficient
          for p in points}
    for pr in PRESSURE_RATIOS:
        assert by[(5, pr)] < by[(50, pr)]
    summary = leakage_report.write_report(points, tmp_path / "report", leakage.quasi1d_models())
    fit = summary["fit"]
    assert all(math.isfinite(c) for c in [*fit["inertial"], fit["viscous"]])
    # The correlation must predict points it did not see better than the plain nozzle
    # (Cd = 1) does: otherwise it is not worth loading.
    nozzle = next(m for m in summary["models"] if m["model"] == "quasi1d-nozzle")
    assert fit["leave_out_rms_error"] < nozzle["rms_error"]
