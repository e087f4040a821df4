"""Running a performance map (:mod:`.perf_map`) here or on Dask, and writing it.

Outputs, written into a temporary folder and swapped in whole: map.csv (one row per
point, :data:`.perf_map.COLUMNS`), map.json (the run's record), one contour plot per
figure and report.html showing them with the points that failed.
"""

from __future__ import annotations

import csv
import json
import tempfile
import time
from pathlib import Path

from .perf_map import COLUMNS, MapSpec, log_pressures, map_spec, point_raw, run_point, shared_fluid

#: Figures drawn as contour plots: (column, label).
PLOTTED = (
    ("suction_volume_flow_m3_min", "suction volume flow, m3/min"),
    ("shaft_power_W", "shaft power, W"),
    ("specific_power_kW_per_m3_min", "specific power, kW/(m3/min)"),
    ("volumetric_efficiency", "volumetric efficiency"),
    ("adiabatic_efficiency_shaft", "adiabatic efficiency (shaft)"),
    ("isothermal_efficiency", "isothermal efficiency (indicated)"),
)


def run_map(case_path: Path, out: Path | None = None, *, cluster: dict | None = None,
            serial: bool = False, progress: bool = True) -> dict:
    """Compute the map of ``case_path`` into ``out`` (default build/map/<case>); its record."""
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.workflow.case import load_case

    from .cache import swap_in

    t0 = time.perf_counter()
    case = load_case(case_path)
    where = str(case_path)
    spec = map_spec(case.raw, where)
    # Every point's settings are read before any is run: a bad value is refused whole.
    from rotorflow.quasi1d import case_settings

    jobs = [point_raw(case.raw, spec, n, p) for n in spec.speeds for p in spec.pressures]
    for raw in jobs:
        ports = case_settings(raw, where)[2]  # (the map varies speed and pressure only)
    table = chamber_table(case, port_areas=ports.reads_areas)
    fluid = shared_fluid(table, case.raw, spec, where)
    rows, where_run = _compute(table, fluid, jobs, where, cluster, serial, progress)
    out = Path(out) if out else Path("build") / "map" / case.name
    out.parent.mkdir(parents=True, exist_ok=True)
    record = {
        "case": where, "points": spec.size, "axes": ["speed_rpm", spec.pressure],
        "converged": sum(bool(r["converged"]) for r in rows),
        "failed": [f"{r['speed_rpm']:g} rpm, {r[spec.pressure]:g} bar: {r['message']}"
                   for r in rows if not r["converged"]],
        "seconds": time.perf_counter() - t0, "where": where_run,
        "csv": str(out / "map.csv"), "report": str(out / "report.html"),
    }
    tmp = Path(tempfile.mkdtemp(prefix=".map-", dir=out.parent))
    _write(tmp, rows, spec, record)
    swap_in(tmp, out)
    return record


def _compute(table, fluid, jobs: list[dict], where: str, cluster, serial, progress):
    from tqdm import tqdm

    bar = tqdm(total=len(jobs), desc="map", unit="point", disable=not progress,
               dynamic_ncols=True)
    rows: dict[int, dict] = {}
    try:
        if serial:
            for i, raw in enumerate(jobs):
                rows[i] = run_point(table, raw, where, fluid)
                bar.update(1)
            return [rows[i] for i in range(len(jobs))], "one process"
        from .dask_cluster import local_workers, open_client
        from .sweep_file import cluster_spec

        cspec = cluster_spec(Path(where), {}, cluster or {})
        client, close = open_client(cspec, len(jobs))
        try:
            # One copy of the table per worker, not one per point.
            shared = client.scatter(table, broadcast=True)
            tab = None if fluid is None else client.scatter(fluid, broadcast=True)
            futures = {client.submit(run_point, shared, raw, where, tab, pure=False): i
                       for i, raw in enumerate(jobs)}
            from dask.distributed import as_completed

            for fut in as_completed(futures):
                rows[futures[fut]] = fut.result()
                bar.update(1)
        finally:
            close()
        return [rows[i] for i in range(len(jobs))], cspec.describe(local_workers(cspec, len(jobs)))
    finally:
        bar.close()


def _write(folder: Path, rows: list[dict], spec: MapSpec, record: dict) -> None:
    with open(folder / "map.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r[k] is None else r[k]) for k in COLUMNS})
    (folder / "map.json").write_text(json.dumps(record, indent=2) + "\n")
    plots = _plot(folder, rows, spec)
    (folder / "report.html").write_text(_html(record, plots, spec))


def _plot(folder: Path, rows: list[dict], spec: MapSpec) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    ns, npr = len(spec.speeds), len(spec.pressures)
    x = np.array(spec.pressures)
    y = np.array(spec.speeds)
    names = []
    for column, label in PLOTTED:
        z = np.array([np.nan if r[column] is None or not r["converged"] else float(r[column])
                      for r in rows]).reshape(ns, npr)
        if not np.isfinite(z).any():
            continue
        # Levels over the 2-98 % range: a corner where the flow all but vanishes (low
        # speed, high pressure) would otherwise take every level.
        low, high = np.nanpercentile(z, [2, 98])
        levels = np.linspace(low, high, 13) if high > low else 12
        fig, ax = plt.subplots(figsize=(6.4, 4.8))
        cs = ax.contourf(x, y, z, levels=levels, cmap="viridis", extend="both")
        ax.contour(x, y, z, levels=levels, colors="k", linewidths=0.4)
        fig.colorbar(cs, ax=ax, label=label)
        bad = [(r[spec.pressure], r["speed_rpm"]) for r in rows if not r["converged"]]
        if bad:
            ax.plot(*zip(*bad, strict=True), "rx", label="not converged")
            ax.legend(loc="upper right")
        if log_pressures(spec):
            ax.set_xscale("log")
        ax.set_xlabel(spec.pressure.replace("_bar", ", bar").replace("_", " "))
        ax.set_ylabel("driven rotor speed, rpm")
        ax.set_title(label)
        fig.tight_layout()
        name = f"{column}.png"
        fig.savefig(folder / name, dpi=110)
        plt.close(fig)
        names.append(name)
    return names


def _html(record: dict, plots: list[str], spec: MapSpec) -> str:
    from html import escape

    failed = "".join(f"<li>{escape(f)}</li>" for f in record["failed"]) or "<li>none</li>"
    images = "".join(f'<figure><img src="{p}" alt="{p}"></figure>' for p in plots)
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>performance map</title>"
        "<style>body{font-family:sans-serif;max-width:1300px;margin:auto}"
        "figure{display:inline-block;margin:4px}img{width:420px}</style></head><body>"
        f"<h1>Performance map: {escape(record['case'])}</h1>"
        f"<p>{record['points']} points ({len(spec.speeds)} speeds x {len(spec.pressures)} "
        f"{escape(spec.pressure)}), {record['converged']} converged with balances within "
        f"1e-6, {record['seconds']:.1f} s on {escape(record['where'])}. "
        "Figures: <a href='map.csv'>map.csv</a>.</p>"
        f"<h2>Points not converged</h2><ul>{failed}</ul>{images}</body></html>\n"
    )
