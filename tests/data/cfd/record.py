"""Re-record the small OpenFOAM outputs the offline CFD tests read.

    .venv/bin/python tests/data/cfd/record.py      (needs OpenFOAM; about 15 s)

Writes, next to this file:
    channel_study.json            the case parameters of the channel study
    channel_study/<level>/        postProcessing mass-flow tables and result.json of a
                                  plane Poiseuille channel on three meshes
    log.checkMesh                 checkMesh's report on the default channel mesh
    log.checkMesh.failed          checkMesh's report on a mesh it rejects
    diverged/                     mass-flow tables and the log tail of a run made to
                                  diverge (plain SIMPLE, no under-relaxation, at a
                                  pressure ratio of 2.5)
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from dataclasses import asdict
from pathlib import Path

from foamlib import FoamFile

from rotorflow.cases import foam, foam_mesh, gap_case, gap_mesh, gap_study, gap_walls
from rotorflow.errors import ExternalRunError
from rotorflow.quasi1d.perfect_gas import PerfectGas

HERE = Path(__file__).resolve().parent

#: The channel of the recorded study and of the OpenFOAM test: 10 um by 1 mm, 0.5 % over
#: atmospheric, constant viscosity.  Re ~ 0.15 and L/h = 100, so the flow is fully
#: developed Stokes flow and the analytic plane Poiseuille flow is the exact answer.
CHANNEL = {"gap_m": 10e-6, "length_m": 1e-3, "p_total_Pa": 1.005e5, "p_exit_Pa": 1.0e5,
           "T_total_K": 300.0, "cells_across": 16, "cells_along": 20}


def channel_case() -> gap_case.GapCase:
    c = CHANNEL
    flow = gap_case.GapFlow(p_total_Pa=c["p_total_Pa"], T_total_K=c["T_total_K"],
                            p_exit_Pa=c["p_exit_Pa"], gas=PerfectGas(transport="const"))
    mesh = gap_mesh.GapMeshSpec(cells_across=c["cells_across"], cells_along=c["cells_along"])
    return gap_case.GapCase(gap_walls.parallel_channel(c["gap_m"], c["length_m"]), flow, mesh)


def keep_tables(src: Path, dst: Path) -> None:
    for name in ("massFlowInlet", "massFlowOutlet"):
        table = src / "postProcessing" / name / "0" / "surfaceFieldValue.dat"
        (dst / "postProcessing" / name / "0").mkdir(parents=True, exist_ok=True)
        shutil.copy(table, dst / "postProcessing" / name / "0" / table.name)


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        case = channel_case()
        study = gap_study.run_mesh_study("channel", case, work, progress=None)
        out = HERE / "channel_study"
        shutil.rmtree(out, ignore_errors=True)
        for level in gap_study.LEVELS:
            keep_tables(work / "channel" / level, out / level)
            shutil.copy(work / "channel" / level / "result.json", out / level / "result.json")
        shutil.copy(work / "channel" / "default" / "log.checkMesh", HERE / "log.checkMesh")
        gas = case.flow.gas
        (HERE / "channel_study.json").write_text(json.dumps(
            {**CHANNEL, "mu_Pa_s": gas.mu_Pa_s, "R_J_kgK": gas.R, "gamma": gas.gamma,
             "depth_m": CHANNEL["gap_m"], "refinement_ratio": study.ratio,
             "mesh": asdict(case.mesh)}, indent=2) + "\n")

        bad = work / "bad"
        bad.mkdir()
        try:
            gap_mesh.build_foam_mesh(bad, gap_walls.parallel_channel(10e-6, 0.1),
                                     gap_mesh.GapMeshSpec(cells_across=4, cells_along=1))
        except foam_mesh.MeshCheckError:
            shutil.copy(bad / "log.checkMesh", HERE / "log.checkMesh.failed")
        else:
            sys.exit("expected checkMesh to reject the 40000:1 mesh")

        div = work / "diverged"
        walls = gap_walls.rotor_tip_gap(50e-6, 0.02)
        flow = gap_case.GapFlow(p_total_Pa=2.5e5, T_total_K=300.0, p_exit_Pa=1e5,
                                turbulence="laminar")
        unstable = gap_case.GapCase(walls, flow, gap_mesh.GapMeshSpec(refinement=2.0))
        gap_case.write_case(unstable, div)
        fv = FoamFile(div / "system" / "fvSolution")
        fv["SIMPLE"]["transonic"] = False
        fv["SIMPLE"]["consistent"] = False
        fv["relaxationFactors"]["equations"]["U"] = 1.0
        fv["relaxationFactors"]["equations"]["e"] = 1.0
        try:
            foam.run(div, gap_case.SOLVER)
        except ExternalRunError:
            pass
        else:
            sys.exit("expected the unrelaxed run to diverge")
        out = HERE / "diverged"
        shutil.rmtree(out, ignore_errors=True)
        keep_tables(div, out)
        (out / f"log.{gap_case.SOLVER}").write_text(
            foam.log_tail(div / f"log.{gap_case.SOLVER}", 60) + "\n")


if __name__ == "__main__":
    main()
