"""Run time against error of the twin-screw geometry as the angle resolution grows.

Seed 004's 4/6 machine on two profiles, the pin-cycloid of examples/twin_screw_4_6.toml
and the circular rack of examples/twin_screw_export.toml (one process each, on two
cores).  Per points per lobe period of the chamber curves (the section table runs twice
as fine, TwinScrewPair): the CPU time of the geometry figures and the chamber table,
and their errors against references computed in the same run,

- of the largest chamber volume and of Pi_max, against the machine at REFERENCE points
  per period;
- of the chamber's tip and interlobe sealing lines, against the same machine (each kind
  summed over its lines, as functions of the angle: the largest difference from the
  reference's lines at the same angles over the reference's largest, with the order
  each shows against the previous resolution);
- of the table's port areas (the same measure), against the REFERENCE machine cut with
  polygons POLYGON_REFINE times finer in chord error and growth, its sealed regions
  swept REFERENCE_PORT_STEPS times per period: the polygons' error and the sweep's
  together.

Target (issue 13): geometry figures and table of a 4/6 pair at 1e-4 relative error in
under 1 s.  The figures of every run, and what changed between them, are in
docs/twin_screw.md.  The port reference costs ~17 min a profile.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.ports import open_areas
from rotorflow.geometry.summary import case_port_timing, chamber_table, geometry_figures
from rotorflow.workflow.case import load_case

REPO = Path(__file__).resolve().parents[1]
RESOLUTIONS = (24, 48, 96, 192)
#: The reference's points per period.  The section loads jump between table nodes where a
#: tip passes a cusp and are swept at fourth order between those events (geometry/
#: load_sweep.py): Pi_max at 24 to 192 lies within 2.5e-5 of 768, and 768 within 4e-7 of
#: 1536 (circular 1e-8).  (As the loads' linear interpolant it converged at first order:
#: 192 left it 1.2e-4 from its limit.)  The lines at 24 to 384 lie within 3e-9
#: (pin-cycloid; 6e-7 until 2026-11-30, when a contact resting on a male corner was
#: given the male's turning, geometry/twin_screw/contact_search.py) and 5.1e-5 / 7e-7 /
#: 1.6e-7 / 4.8e-9 / 1.8e-10 (circular, 24 to 384) of it.  (Their reference was 192
#: while the pin-cycloid's interlobe lines shrank by 4e-3 from 384 on: a track's lost
#: nodes before its joint were counted in steps, and a contact search started too far
#: from its contact, geometry/twin_screw/track_ends.py and contact_search.py.)
REFERENCE = 768
#: Samples per period of the reference's swept sealed regions (a table's: its section
#: grid, twice its points per period).  On one 24-point machine, 384 samples are 4e-5
#: (pin-cycloid) and 1.9e-5 (circular) of the largest discharge area off it (the
#: pin-cycloid's where 768 holds less than a union of real sections, geometry/
#: port_areas.py); its own section grid (1536) costs a section cut per sample.  768 was
#: not enough: a sliver born next to the cusp line (circular profile, 116 deg after the
#: chamber's birth) is swept within 1e-4 of its limit only from ~3072 samples on, and at
#: 768 its area moved by 1e-4 of the largest discharge area with the samples' phase (the
#: reference machine's birth node, 0.001 rad off the 96-point machine's); 3072 moves the
#: reference by 1.3e-4 there (4.5 min a sweep instead of 1).
REFERENCE_PORT_STEPS = 3072
#: The port reference's polygons, this many times finer (chord error and growth,
#: geometry/twin_screw/regions.py): the other references share the table's polygons,
#: whose areas are corrected to the true curves (slivers), while the ports' are not.
POLYGON_REFINE = 16.0
TARGET_TIME_S = 1.0
#: Timed runs per resolution (the least CPU counts: the machine is shared).
TIMED_RUNS = 2
TARGET_ERROR = 1e-4


@contextlib.contextmanager
def _finer_polygons(factor: float):
    """Sections cut with polygons ``factor`` times finer in chord error and growth."""
    from rotorflow.geometry.twin_screw import regions

    old = regions.SAMPLE_TOL, regions.GROW
    regions.SAMPLE_TOL, regions.GROW = old[0] / factor, old[1] / factor
    try:
        yield
    finally:
        regions.SAMPLE_TOL, regions.GROW = old


def _lines(lines, kind):
    return sum(x for (name, d), x in lines.items() if name.startswith(kind) and d > 0)


def _case(case, ppp, table=True):
    """(wall, CPU) time of `rotorflow geometry` and the chamber table at ``ppp`` from
    scratch (the CPU time is the one to compare on a shared machine), the machine, its
    (V_max, Pi_max) and its table (None without ``table``)."""
    t0, c0 = time.perf_counter(), time.process_time()
    case = dataclasses.replace(case, pair=dataclasses.replace(case.pair))  # no caches
    m = SweptMachine(case.pair, case.sweep(None), ppp)
    figures = geometry_figures(case, m)
    out = chamber_table(case, m) if table else None
    times = (time.perf_counter() - t0, time.process_time() - c0)
    return times, m, (figures["chamber_volume_max_m3"], figures["Pi_max"]), out


def _line_error(m, ref, kind):
    if m.points_per_period >= ref.points_per_period:
        return float("nan")
    here = _lines(m.track_lines, kind)
    there = _lines(ref.track_lines_at(m.curves.phi), kind)
    return float(np.abs(here - there).max() / there.max())


def _reference_ports(case):
    """(angles, suction areas, discharge areas) of the reference machine with finer
    polygons at every resolution's table angles (absolute: each resolution has its own
    birth node)."""
    phi = np.unique(np.concatenate([SweptMachine(case.pair, case.sweep(None), ppp).curves.phi
                                    for ppp in RESOLUTIONS]))
    with _finer_polygons(POLYGON_REFINE):
        fresh = dataclasses.replace(case, pair=dataclasses.replace(case.pair))
        ref = SweptMachine(fresh.pair, fresh.sweep(None), REFERENCE)
        lp, hp = open_areas(ref, case_port_timing(fresh, ref), phi - ref.curves.phi[0],
                            steps=REFERENCE_PORT_STEPS)
    return phi, lp, hp


def _port_errors(m, table, ports):
    phi, lp, hp = ports
    return [float(np.abs(mine - np.interp(m.curves.phi, phi, there)).max() / there.max())
            for mine, there in ((table.area_lp_m2, lp), (table.area_hp_m2, hp))]


#: (profile label, case file) benched.
CASES = (("pin-cycloid", "twin_screw_4_6.toml"), ("circular", "twin_screw_export.toml"))


def run(results_dir: Path) -> list[dict]:
    from concurrent.futures import ProcessPoolExecutor

    results_dir.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(max_workers=len(CASES)) as pool:
        rows = [row for rows in pool.map(_profile_rows, *zip(*CASES, strict=True))
                for row in rows]
    with (results_dir / "twin_screw.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return rows


def _profile_rows(label: str, name: str) -> list[dict]:
    case = load_case(REPO / "examples" / name)
    # The timed runs first, each the least of TIMED_RUNS: after the port reference the
    # same run took 3.06 s of CPU instead of 1.6 (pin-cycloid at 24, 2026-11-30; what
    # that reference leaves in the process, not this run's work).
    runs = {ppp: min((_case(case, ppp) for _ in range(TIMED_RUNS)), key=lambda r: r[0][1])
            for ppp in RESOLUTIONS}
    _, ref, ref_values, _ = _case(case, REFERENCE, table=False)
    ports = _reference_ports(case)
    rows = []
    for ppp in RESOLUTIONS:
        (dt, cpu), m, values, table = runs[ppp]
        err = [abs(v / r - 1) for v, r in zip(values, ref_values, strict=True)]
        err += [_line_error(m, ref, kind) for kind in ("tip", "interlobe")]
        err += _port_errors(m, table, ports)
        row = {"profile": label, "points_per_period": ppp, "time_s": dt, "cpu_s": cpu,
               "err_V_max": err[0], "err_Pi_max": err[1], "err_tip_lines": err[2],
               "err_interlobe_lines": err[3], "err_area_lp": err[4], "err_area_hp": err[5]}
        prev = rows[-1] if rows else None
        for kind in ("tip", "interlobe"):
            key = f"err_{kind}_lines"
            row[f"order_{kind}_lines"] = (math.log(prev[key] / row[key])
                                          / math.log(ppp / prev["points_per_period"])
                                          if prev else float("nan"))
        row["meets_time"] = cpu < TARGET_TIME_S
        row["meets_error"] = max(e for e in err if not math.isnan(e)) < TARGET_ERROR
        row["meets_target"] = row["meets_time"] and row["meets_error"]
        rows.append(row)
    return rows
