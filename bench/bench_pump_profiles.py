"""Run time against error of the screw-pump profiles' geometry (seed 003 Fig. 3) as the
angle resolution grows: the circular, involute and trochoidal 1-1 pairs of the pump
tests (C = 78 mm, both rotors 110 mm, 200 mm long, wrapped three turns).

Per points per lobe period, the CPU time of the machine's chamber curves, sealing lines
and blow-hole openings from scratch, and the errors against the REFERENCE resolution
computed in the same run: of the largest chamber volume, of the largest blow-hole area
(each cusp's, booked for the chamber behind), of the blow-holes' area integrals over
the chamber's life (which chamber holds each, and when), and of the interlobe and tip
lines' largest
summed length (as functions of the angle, over the reference's largest value, at the
lower resolution's angles).  Output: results_dir/pump_profiles.csv.

    python -m bench.bench_pump_profiles

Last measured (2026-11-30, session 35, 39 s in all), at 24 / 48 / 96 points per
period: CPU 1.2-1.5 / 1.6-1.8 / 2.4-2.5 s for each profile; V_max within 9e-7
(involute at 24) and 4e-11 to 5e-9 at 96; the blow-hole within 2e-15 (its width is the
pocket's or the cusp line's cut at any angle: only which chamber lies beyond comes from
the nodes; at 384 the trochoidal's was twice its value until a stray node's booking was
outvoted, geometry/twin_screw/blowhole.py); tip lines 3.9e-7 / 2.5e-8 / 1.5e-9 (fourth
order).  The interlobe lines: circular 2e-7 / 8e-8 / 7e-9, involute 3e-14 (it
converged at first order, 8.3e-3 / 3.9e-3 / 1.7e-3, its largest length 108.36 to
109.27 mm from 24 to 384, until its contact's crossing of the cusp line, at the pitch
point and on a node, was located: geometry/twin_screw/track_ends.py, 109.32599 mm at
every resolution now), trochoidal 1.0e-5 / 3.0e-7 / 8.2e-9 (fifth order; it was
3.0e-2 / 1.2e-2 / 3.4e-3, first order, with 384 below 192 by 0.2 %, until the lands'
joints with the line of centres were located, the crossing of the cusp line sought
over lost nodes and a corner contact's rate taken with its rotor:
tests/test_twin_screw_trochoidal_lines.py checks both lines against closed forms).
The involute with 10 mm circles jumps by 0.3 % between 48 and 96 (located 2026-11-30,
not fixed: its third interlobe contact lives 0.082 rad at a time, at most one section
node at 24 and 48 points per period, and its line comes out 0.29 mm long there over
every angle where it is whole; 7.9e-6 at 96; its track's cuts are the same at every
resolution, so the line's sweep over a one-node run is what errs).
Rerun 2026-11-30 (session 36, 42 s, 49 added): the same figures at 24 / 48 / 96; at 49
V_max within 5e-8, blow-hole 9e-16, tip lines 8.7e-9, interlobe 3.6e-8 (circular),
3.1e-10 (involute), 4.5e-8 (trochoidal); the blow-holes' integrals within 7.7e-9 at
every resolution (the circular's at 49; the rest 7e-16).  Until this session the 1-1
circular and involute pairs booked each blow-hole over twice the quarter turn it joins
two chambers at every resolution, the reference included (so no error showed here;
tests/test_twin_screw_pumps.py checks the booking against the cuts), and none at 49.
"""

from __future__ import annotations

import csv
import math
import time
from pathlib import Path

import numpy as np

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.blowhole import NAMES
from rotorflow.geometry.twin_screw.family import build

from .bench_twin_screw import _line_error

PROFILES = ("circular", "involute", "trochoidal")
#: (49 = 4 k + 1: until 2026-11-30 the 1-1 circular and involute pairs booked no
#: blow-hole there, their nodes one short of a majority, geometry/twin_screw/blowhole.py)
RESOLUTIONS = (24, 48, 49, 96)
REFERENCE = 384
C, D, LENGTH, WRAP = 0.078, 0.110, 0.2, math.radians(1080.0)


def _machine(profile: str, ppp: int):
    """(CPU seconds, machine, V_max, largest blow-hole, the blow-holes' area integral
    over the chamber's life) from scratch."""
    c0 = time.process_time()
    m = SweptMachine(build(profile, 1, 1, C, D, D), Sweep("helical", LENGTH, WRAP), ppp)
    v_max = float(m.curves.volume.max())
    areas = m.opening_areas
    hole = max(float(a.max()) for (name, _), a in areas.items() if name == NAMES[False])
    held = sum(float(np.trapezoid(a, m.curves.phi)) for a in areas.values())
    _ = m.track_lines
    return time.process_time() - c0, m, v_max, (hole, held)


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for profile in PROFILES:
        _, ref, v_ref, (hole_ref, held_ref) = _machine(profile, REFERENCE)
        for ppp in RESOLUTIONS:
            cpu, m, v_max, (hole, held) = _machine(profile, ppp)
            rows.append({"profile": profile, "points_per_period": ppp, "cpu_s": cpu,
                         "err_V_max": abs(v_max / v_ref - 1.0),
                         "err_blow_hole": abs(hole / hole_ref - 1.0),
                         "err_blow_hole_integral": abs(held / held_ref - 1.0),
                         "err_tip_lines": _line_error(m, ref, "tip"),
                         "err_interlobe_lines": _line_error(m, ref, "interlobe")})
    with (results_dir / "pump_profiles.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows


if __name__ == "__main__":
    for row in run(Path(__file__).parent / "results"):
        print({k: (f"{v:.3g}" if isinstance(v, float) else v) for k, v in row.items()})
