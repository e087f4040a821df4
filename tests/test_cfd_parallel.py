"""A case's solver on two processes (cases/parallel.py): decomposePar, mpirun, reconstructPar.

The plan is checked as data (no OpenFOAM); one real run checks that the decomposed
solve is the same computation: the plane channel of test_cfd_openfoam.py on two
processes passes the serial run's mass flow.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from rotorflow.cases import foam, gap_case
from rotorflow.cases.foam import Step
from rotorflow.cases.foam_case import Plan
from rotorflow.cases.parallel import SERIAL, Decomposition, parallel_plan
from rotorflow.errors import CaseError

sys.path.insert(0, str(Path(__file__).parent))
from test_cfd_openfoam import channel_case  # noqa: E402

SERIAL_PLAN = Plan(setup=(Step(("gmshToFoam", "gap.msh")), Step(("checkMesh",))),
                   solve=Step(("rhoSimpleFoam",)))


def test_parallel_plan_decomposes_runs_under_mpirun_and_reconstructs(tmp_path):
    plan = parallel_plan(SERIAL_PLAN, tmp_path, Decomposition(2, axis=2))
    cmds = plan.commands()
    assert cmds[:2] == [["gmshToFoam", "gap.msh"], ["checkMesh"]]
    assert cmds[2] == ["decomposePar", "-force"]
    assert cmds[3][0] == "mpirun" and cmds[3][-2:] == ["rhoSimpleFoam", "-parallel"]
    assert cmds[3][cmds[3].index("-np") + 1] == "2"
    assert cmds[4] == ["reconstructPar", "-latestTime"]
    # the solver's log keeps its name, so judging reads the same file
    assert plan.solve.name == "rhoSimpleFoam"
    text = (tmp_path / "system" / "decomposeParDict").read_text()
    assert "numberOfSubdomains 2;" in text and "hierarchical" in text
    assert "(1 1 2)" in " ".join(text.split())
    assert parallel_plan(SERIAL_PLAN, tmp_path, SERIAL) is SERIAL_PLAN


@pytest.mark.parametrize("kwargs, match", [
    ({"processes": 2, "method": "scotch"}, "stubs"),
    ({"processes": 0}, ">= 1"),
    ({"processes": 4, "split": (2, 1, 1)}, "does not make"),
])
def test_bad_decomposition_is_refused(kwargs, match):
    with pytest.raises(CaseError, match=match):
        Decomposition(**kwargs)


@pytest.mark.openfoam
@pytest.mark.gmsh
@pytest.mark.skipif(not foam.is_available(), reason="OpenFOAM not installed: run `make openfoam`")
def test_two_processes_give_the_serial_flow(tmp_path):
    case = channel_case()
    serial = gap_case.run_gap_case(case, tmp_path / "np1")
    two = gap_case.run_gap_case(case, tmp_path / "np2", decomposition=Decomposition(2))
    assert serial.status == two.status == "converged", (serial.message, two.message)
    assert (tmp_path / "np2" / "processor1").is_dir()
    # Both stop at the same residual target; the decomposed linear solves differ in
    # round-off and iteration count only (measured 4e-11 apart).  1e-5 is well inside
    # the iterative noise the serial study itself carries (~1e-4).
    assert two.mass_flow_kg_s_m == pytest.approx(serial.mass_flow_kg_s_m, rel=1e-5)
    assert two.imbalance < 5e-3
