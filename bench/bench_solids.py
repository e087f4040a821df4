"""Run time and file size of the rotor solids against the tolerance.

For the default case (a helical pair, Table 1 "inner_ev2"), at each tolerance: the time
to build both rotor STLs through :func:`rotorflow.geometry.export.export` (flank
meshes, their measurement against the analytic flank, closed-solid checks, writing),
the measured largest deviation, the volume errors against the analytic volumes (exact:
PinSpace areas times the integral of the scale squared) and the STL size; then the
STEP pair at the default tolerance.  Target: the helical pair at 5 um in under 2 s and
under 50 MB of STL.

The same for the twin screw of examples/twin_screw_export.toml (the 4/6 of seed 004,
130 mm, wrap 325 deg): male and female STLs against the tolerance, then at 5 um the
fluid domain (both bores less both rotors with 40 um clearances, ports included; its
time includes the chamber table and the ports) and the STEP pair.
"""

from __future__ import annotations

import csv
import shutil
import tempfile
import time
from pathlib import Path

from rotorflow.geometry.export.driver import export
from rotorflow.geometry.export.settings import Export
from rotorflow.workflow.case import load_case

REPO = Path(__file__).resolve().parents[1]
TOLERANCES_UM = (40.0, 20.0, 10.0, 5.0, 2.5)
TWIN_TOLERANCES_UM = (20.0, 10.0, 5.0)
TARGET_S, TARGET_MB = 2.0, 50.0
FIELDS = ["case", "format", "tolerance_um", "time_s", "size_MB", "triangles",
          "max_deviation_um", "err_V_outer", "err_V_inner", "err_V_male", "err_V_female",
          "err_V_fluid", "err_chamber_sum"]


def _one(case, fmt: str, tol_um: float, **keys) -> dict:
    out = Path(tempfile.mkdtemp(prefix="bench-solids-"))
    try:
        t0 = time.perf_counter()
        man = export(case, Export(formats=(fmt,), tolerance_m=tol_um * 1e-6, **keys), out)
        wall = time.perf_counter() - t0
    finally:
        shutil.rmtree(out, ignore_errors=True)
    ext = "stl" if fmt == "fluid" else fmt
    files = {k: v for k, v in man["files"].items() if k.endswith("." + ext)}
    row = {
        "case": case.name,
        "format": fmt,
        "tolerance_um": tol_um,
        "time_s": wall,
        "size_MB": sum(v["bytes"] for v in files.values()) / 1e6,
        "max_deviation_um": max(v["max_deviation_m"] for v in files.values()) * 1e6,
    }
    for name, v in files.items():
        row[f"err_V_{name.rsplit('.', 1)[0]}"] = v["volume_rel_error"]
    if fmt != "step":
        row["triangles"] = sum(v["triangles"] for v in files.values())
    if fmt == "fluid":
        row["err_chamber_sum"] = files["fluid.stl"]["chamber_sum_rel_error"]
    return row


def _twin_rows() -> list[dict]:
    case = load_case(REPO / "examples" / "twin_screw_export.toml")
    clear = {"clearance_m": (40e-6,), "clearance_on": "female", "tip_clearance_m": 40e-6}
    rows = [_one(case, "stl", tol, **clear) for tol in TWIN_TOLERANCES_UM]
    rows.append(_one(case, "fluid", 5.0, **clear))
    try:
        import gmsh  # noqa: F401

        rows.append(_one(case, "step", 5.0, **clear))
    except ImportError:
        pass
    return rows


def run(results_dir: Path) -> list[dict]:
    results_dir.mkdir(parents=True, exist_ok=True)
    case = load_case(REPO / "examples" / "default.toml")
    _one(case, "stl", 40.0)  # warm the imports and caches out of the timings
    rows = []
    for tol in TOLERANCES_UM:
        best = min((_one(case, "stl", tol) for _ in range(2)), key=lambda r: r["time_s"])
        rows.append(best)
    try:
        import gmsh  # noqa: F401

        rows.append(_one(case, "step", 5.0))
    except ImportError:
        pass
    rows += _twin_rows()
    with (results_dir / "solids.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    _plot([r for r in rows if r["format"] == "stl" and r["case"] == case.name],
          results_dir / "solids.png")
    at5 = next(r for r in rows if r["format"] == "stl" and r["tolerance_um"] == 5.0)
    at5["meets_target"] = at5["time_s"] < TARGET_S and at5["size_MB"] < TARGET_MB
    return rows


def _plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    tol = [r["tolerance_um"] for r in rows]
    a.loglog(tol, [r["time_s"] for r in rows], "o-", label="time [s]")
    a.loglog(tol, [r["size_MB"] for r in rows], "s-", label="STL size [MB]")
    a.axhline(TARGET_S, color="grey", ls=":")
    a.axhline(TARGET_MB, color="grey", ls="--")
    a.axvline(5.0, color="grey", ls=":")
    a.set_xlabel("tolerance [um]")
    a.set_title("helical pair (default case): cost")
    a.legend()
    b.loglog(tol, [r["max_deviation_um"] for r in rows], "o-", label="max deviation [um]")
    b.loglog(tol, tol, "k:", label="tolerance")
    b.loglog(tol, [max(r["err_V_outer"], 1e-12) * 1e6 for r in rows], "s-",
             label="outer volume error [1e-6]")
    b.loglog(tol, [max(r["err_V_inner"], 1e-12) * 1e6 for r in rows], "^-",
             label="inner volume error [1e-6]")
    b.set_xlabel("tolerance [um]")
    b.set_title("measured error")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
