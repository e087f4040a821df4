"""Re-record the rotor-section mass-flow study the offline tests read.

    .venv/bin/python tests/data/cfd/rotor_section/record.py [RUNS_DIR]

(needs OpenFOAM; about a minute; with RUNS_DIR, a [cfd] runs_dir that holds the two
points already, nothing is run).  The points: the sealing-line gap of the example machine
of examples/cfd_leakage.toml at outer-rotor angle 300 deg (next to the inner rotor's sharp
edge of sigma_bar = 1), 10 um clearance on the outer rotor, pressure ratio 1.2; static
walls, and walls at the rotor surface speeds of 5000 rpm (outer rotor).

Writes, next to this file, for each point ``<name>/<level>/``: ``result.json`` and
``case.key`` of the coarse, default and fine meshes, and for the default mesh its
inlet and outlet mass-flow tables (``postProcessing/massFlow*/0/surfaceFieldValue.dat``).
"""

from __future__ import annotations

import math
import shutil
import sys
import tempfile
from pathlib import Path

from rotorflow.cases.gap_study import LEVELS, RotorMachine, SectionPoint, run_leakage_matrix
from rotorflow.geometry.internal_gear.pair import PinGerotor, sigma_limit

HERE = Path(__file__).resolve().parent

PAIR = PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 0.1)
MACHINE = RotorMachine(PAIR, 5000 * math.pi / 30)
POINTS = [SectionPoint(10, 1.2, 300, MACHINE, moving) for moving in (False, True)]


def copy(runs: Path) -> None:
    for point in POINTS:
        out = HERE / point.name
        shutil.rmtree(out, ignore_errors=True)
        for level in LEVELS:
            src, dst = runs / point.name / level, out / level
            dst.mkdir(parents=True)
            for name in ("result.json", "case.key"):
                shutil.copy(src / name, dst / name)
            if level == "default":
                for table in ("massFlowInlet", "massFlowOutlet"):
                    rel = Path("postProcessing") / table / "0" / "surfaceFieldValue.dat"
                    (dst / rel.parent).mkdir(parents=True)
                    shutil.copy(src / rel, dst / rel)


def main() -> None:
    if len(sys.argv) > 1:
        copy(Path(sys.argv[1]))
        return
    with tempfile.TemporaryDirectory() as tmp:
        studies = run_leakage_matrix(Path(tmp), POINTS)
        bad = [s.name for s in studies if not s.ok]
        if bad:
            raise SystemExit(f"failed: {', '.join(bad)}")
        copy(Path(tmp))


if __name__ == "__main__":
    main()
