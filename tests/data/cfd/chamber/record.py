"""Re-record the small OpenFOAM outputs the offline chamber tests read.

    .venv/bin/python tests/data/cfd/chamber/record.py      (needs OpenFOAM; about 1 min)
    .venv/bin/python tests/data/cfd/chamber/record.py --expected-only
                    (expected.json alone, from the recorded runs: after a change of the
                    quasi-1D side, no OpenFOAM needed)

Writes, next to this file:
    leaking/        the default case's chamber (examples/default.toml: 20 um gap, 3000 rpm)
                    through its compression phase, default mesh: case.json, result.json
                    and the function-object tables, sampled every 2 deg
    sealed/         the same chamber with the gap closed (the adiabatic-compression check)
    expected.json   the comparison of the leaking run with the product's quasi-1D model
                    under each leakage model, as computed when recorded: the offline
                    test recomputes it and must agree

flow_coefficient.json (kept, not rewritten here) is the cfd-calibrated correlation the
cfd.leakage stage fitted to the default leakage matrix (rotor-tip gaps 5-200 um, pressure
ratios 1.1-4, radii 10 and 40 mm), copied from that stage's output.
"""

from __future__ import annotations

import json
import logging
import shutil
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from rotorflow.cases import chamber_case
from rotorflow.geometry.summary import chamber_table
from rotorflow.postprocess import chamber_compare
from rotorflow.quasi1d import Leakage, Operating
from rotorflow.quasi1d.calibrated import FlowCoefficientFit
from rotorflow.workflow.case import load_case

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[3]

#: Coarser than a production run so the recorded files stay a few kB: volume samples
#: every 0.5 deg (the piston table), function-object samples every 2 deg.
SAMPLES_PER_DEG = 2
SAMPLE_DEG = 2.0

TABLES = {"chamberAverage": "volFieldValue.dat", "chamberIntegral": "volFieldValue.dat",
          "domainMass": "volFieldValue.dat", "outletFlow": "surfaceFieldValue.dat"}


def default_leakage() -> Leakage:
    case = load_case(REPO / "examples" / "default.toml")
    return Leakage.from_section(case.raw["leakage"], "examples/default.toml")


def recorded_case(sealed: bool = False) -> chamber_case.ChamberCase:
    case = load_case(REPO / "examples" / "default.toml")
    where = "examples/default.toml"
    comp = chamber_case.compression_from_table(
        chamber_table(case), Operating.from_section(case.raw["operating"], where),
        default_leakage(), samples_per_deg=SAMPLES_PER_DEG)
    if sealed:
        comp = replace(comp, gap_m=0.0)
    controls = chamber_case.TransientControls(sample_deg=SAMPLE_DEG)
    return chamber_case.ChamberCase(comp, controls=controls)


def keep(src: Path, dst: Path) -> None:
    shutil.rmtree(dst, ignore_errors=True)
    dst.mkdir(parents=True)
    for name in ("case.json", "result.json"):
        shutil.copy(src / name, dst / name)
    for name, file_name in TABLES.items():
        table = src / "postProcessing" / name / "0" / file_name
        if table.is_file():
            (dst / "postProcessing" / name / "0").mkdir(parents=True)
            shutil.copy(table, dst / "postProcessing" / name / "0" / file_name)


def write_expected() -> None:
    """expected.json: the comparison of the recorded leaking run."""
    fit = FlowCoefficientFit.load(HERE / "flow_coefficient.json")
    _, comparison = chamber_compare.compare_run(HERE / "leaking", default_leakage(), fit)
    (HERE / "expected.json").write_text(json.dumps(comparison.summary(), indent=2) + "\n")


def main() -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    if sys.argv[1:] != ["--expected-only"]:
        with tempfile.TemporaryDirectory() as tmp:
            for name, sealed in (("leaking", False), ("sealed", True)):
                result = chamber_case.run_chamber_case(recorded_case(sealed),
                                                       Path(tmp) / name)
                if not result.ok:
                    sys.exit(f"{name} run failed: {result.status} {result.message}")
                keep(Path(tmp) / name, HERE / name)
    write_expected()


if __name__ == "__main__":
    main()
