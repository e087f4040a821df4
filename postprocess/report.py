"""Static HTML reports: one per case (the ``report`` stage) and one per sweep.

A report is a folder with ``index.html`` and the pictures it shows, all referenced by
relative paths, so it opens from disk.  Every figure is made from the run's own
artifacts (the upstream stage folders); nothing is drawn from defaults.

This module holds the building blocks (:class:`Section`, :func:`esc`, :func:`table`,
:func:`figure`, :func:`page`), the sections of the built-in stages, and the pages.  It
knows nothing of stages or caching: the workflow (:mod:`rotorflow.workflow.report_stage`)
decides which sections a case's report shows and hands them to :func:`case_page`.  A
section function has the signature::

    def my_section(artifact_dir: Path, report_dir: Path, case) -> Section | None

and may write pictures into ``report_dir`` (named after the stage).  A section's
``headline`` goes to the top of the page (:mod:`.report_headline`); the figure tables
spell their keys out (:mod:`.report_labels`).

A small script in the page checks, once it has loaded, that every ``<img>`` decoded
(``naturalWidth > 0``); it writes the count and any broken sources into the ``body``'s
``data-images`` and ``data-images-broken`` attributes and shows a warning on the page.
"""

from __future__ import annotations

import html
import json
import logging
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import report_labels as labels
from .report_headline import headline_html, reference_rotor
from .report_labels import labelled_table

log = logging.getLogger(__name__)

FIGSIZE = (6.4, 4.2)
DPI = 110

CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: .2em; }
table { border-collapse: collapse; margin: .5em 0 1em; font-size: .9em; }
td, th { border: 1px solid #ddd; padding: .25em .6em; text-align: left; }
th { background: #f3f3f3; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
figure { display: inline-block; margin: .5em 1em .5em 0; vertical-align: top; }
figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: .85em; color: #555; }
pre { background: #f7f7f7; padding: .8em; overflow-x: auto; font-size: .85em; }
.warn { background: #fee; border: 1px solid #c00; padding: .5em; }
.failed { color: #b00; } .muted { color: #777; font-size: .85em; }
table.headline { font-size: 1.05em; } table.headline td.num { font-weight: 600; }
"""

IMAGE_CHECK = """
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var bad = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); })
                .map(function (i) { return i.getAttribute('src'); });
  document.body.setAttribute('data-images', String(imgs.length));
  document.body.setAttribute('data-images-broken', bad.join(' '));
  if (bad.length) {
    var p = document.createElement('p');
    p.className = 'warn';
    p.textContent = 'Pictures that did not load: ' + bad.join(', ');
    document.body.insertBefore(p, document.body.firstChild);
  }
});
"""


@dataclass(frozen=True)
class Section:
    title: str
    html: str
    #: What the section puts at the top of the report, above every section (the
    #: quasi-1D stage's performance headline); empty for most.
    headline: str = ""


# ------------------------------------------------------------------ HTML helpers
def esc(x) -> str:
    return html.escape(str(x))


def fmt(v) -> str:
    if isinstance(v, bool) or v is None:
        return "" if v is None else str(v).lower()
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def flatten(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(flatten(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def key_value_table(d: dict) -> str:
    rows = "".join(
        f"<tr><th>{esc(k)}</th><td class='num'>{esc(fmt(v))}</td></tr>"
        for k, v in flatten(d).items())
    return f"<table>{rows}</table>"


def table(header: list[str], rows: list[list], classes: list[str] | None = None) -> str:
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = []
    for i, r in enumerate(rows):
        cls = f" class='{classes[i]}'" if classes and classes[i] else ""
        cells = "".join(
            f"<td class='num'>{esc(fmt(c))}</td>" if isinstance(c, int | float) and
            not isinstance(c, bool) else f"<td>{esc(fmt(c))}</td>" for c in r)
        body.append(f"<tr{cls}>{cells}</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def figure(src: str, caption: str, width: int | None = None) -> str:
    w = f" width='{width}'" if width else ""
    return (f"<figure><img src='{esc(src)}' alt='{esc(caption)}'{w}>"
            f"<figcaption>{esc(caption)}</figcaption></figure>")


def page(title: str, body: str) -> str:
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>{esc(title)}</title><style>{CSS}</style>"
        f"<script>{IMAGE_CHECK}</script></head>\n<body>\n{body}\n"
        f"<p class='muted'>Written by rotorflow {esc(_version())} on "
        f"{esc(time.strftime('%Y-%m-%d %H:%M'))}.</p>\n</body></html>\n")


def _version() -> str:
    from rotorflow import __version__

    return __version__


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _copy(src: Path, report_dir: Path, name: str) -> str:
    shutil.copyfile(src, report_dir / name)
    return name


# ------------------------------------------------------------------ stage sections
def geometry_section(artifact: Path, report_dir: Path, case) -> Section:
    fig = json.loads((artifact / "geometry.json").read_text())
    # The same criterion as geometry.summary: a pair with port areas times its ports,
    # any other's two angles are the chamber's contacts with the end planes.
    ported = bool(getattr(getattr(case, "pair", None), "port_areas", False))
    ref = reference_rotor(case)
    note = "" if ported else (
        "<p class='muted'>This family's end-plane angles below are when the chamber meets "
        "the end planes, not when its ports open and close; the port timing the model "
        "uses is in the quasi-1D section.</p>")
    return Section("Geometry", note + labelled_table(
        fig, lambda k: labels.geometry_label(k, ported, ref), fmt, esc))


def render_section(artifact: Path, report_dir: Path, case) -> Section:
    body = []
    for name, caption in (("rotors.png", "Rotors (outer rotor cut open), outer angle 0"),
                          ("section.png", "Low-pressure end plane (z = 0)")):
        if (artifact / name).is_file():
            body.append(figure(_copy(artifact / name, report_dir, f"render_{name}"), caption,
                               width=520))
    return Section("Rotors and chambers", "".join(body))


def table_section(artifact: Path, report_dir: Path, case) -> Section:
    from rotorflow.geometry import table as chamber

    tab = chamber.read(artifact / "chamber_table.csv")
    deg = np.degrees(tab.angle_rad)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE)
    ax.plot(deg, tab.volume_m3 * 1e6, lw=1.6, color="C0", label="volume")
    ax.set_xlabel("outer-rotor angle since chamber birth [deg]")
    ax.set_ylabel("chamber volume [cm$^3$]", color="C0")
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(deg, tab.area_lp_m2 * 1e4, color="C2", lw=1.0, label="low-pressure end area")
    ax2.plot(deg, tab.area_hp_m2 * 1e4, color="C3", lw=1.0, label="high-pressure end area")
    ax2.set_ylabel("open end-face area [cm$^2$]")
    lines = ax.get_lines() + ax2.get_lines()
    ax.legend(lines, [ln.get_label() for ln in lines], fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(report_dir / "table_volume.png", dpi=DPI)
    plt.close(fig)
    scalars = tab.scalars()
    return Section("Chamber volume curve",
                   figure("table_volume.png", "Chamber volume and end-face areas against "
                          "angle (chamber table)") + key_value_table(scalars))


def quasi1d_section(artifact: Path, report_dir: Path, case) -> Section:
    summary = json.loads((artifact / "summary.json").read_text())
    body = []
    if not summary.get("converged", True):
        body.append("<p class='warn'>The quasi-1D cycle did not converge.</p>")
    for name, caption in (("quasi1d_p_angle.png", "Chamber pressure against angle"),
                          ("quasi1d_p_V.png", "Chamber pressure against volume (p-V)")):
        if (artifact / name).is_file():
            body.append(figure(_copy(artifact / name, report_dir, name), caption))
    ref = reference_rotor(case)
    body.append(labelled_table(flatten(summary), lambda k: labels.quasi1d_label(k, ref),
                               fmt, esc))
    return Section("Quasi-1D performance", "".join(body),
                   headline=headline_html(summary, case, esc))


def solids_section(artifact: Path, report_dir: Path, case) -> Section:
    """The files of the export and the figures of their checks (export.json)."""
    try:
        manifest = json.loads((artifact / "export.json").read_text())
    except (OSError, ValueError):
        manifest = {}
    entries = manifest.get("files", {})
    checks = ("triangles", "volume_rel_error", "max_deviation_m", "genus", "points")
    rows = []
    for p in sorted(artifact.rglob("*")):
        if p.is_file() and not p.name.startswith("."):
            rel = p.relative_to(artifact).as_posix()
            e = entries.get(rel, {})
            rows.append([rel, p.stat().st_size] + [e.get(c, "") for c in checks])
    return Section("Solids and machining files",
                   f"<p>In <code>{esc(artifact)}</code>; the checks are those of "
                   "<code>export.json</code>.</p>"
                   + table(["file", "bytes", *checks], rows))


# ------------------------------------------------------------------ case report
def case_page(name: str, case_path, case_text: str, status: list[list],
              sections: list[tuple[str, Section]]) -> str:
    """The report of a case: the sections' headlines (the quasi-1D performance), the
    sections in the order given (anchored by stage name), its stages (``status``: stage,
    what, key, built, seconds) and the case file."""
    body = [f"<h1>rotorflow report: {esc(name)}</h1>",
            f"<p>Case file <code>{esc(case_path)}</code>.</p>"]
    # The designer's figures first; how the report was built (stages) after the sections.
    heads = [sec.headline for _, sec in sections if sec.headline]
    body.append("<h2 id='headline-section'>Headline</h2>" + "".join(heads) if heads else
                "<p class='muted'>No performance headline: the case ran no quasi-1D "
                "stage.</p>")
    for stage, sec in sections:
        body.append(f"<h2 id='{esc(stage)}'>{esc(sec.title)}</h2>\n{sec.html}")
    body.append("<h2>Stages</h2>"
                + table(["stage", "what", "key", "built", "seconds"], status))
    body.append(f"<h2>Case file</h2><pre>{esc(case_text)}</pre>")
    return page(f"rotorflow: {name}", "\n".join(body))


# ------------------------------------------------------------------ sweep report
#: Figures plotted over the sweep's parameters, when the points have them.
SWEEP_FIGURES = (
    ("quasi1d.volumetric_efficiency", "volumetric efficiency"),
    ("quasi1d.adiabatic_efficiency", "adiabatic efficiency"),
    ("quasi1d.mass_flow_kg_s", "mass flow [kg/s]"),
    ("quasi1d.indicated_power_W", "indicated power [W]"),
    ("geometry.swept_volume_m3", "swept volume [m^3]"),
    ("geometry.Pi_max", "Pi_max"),
)


def sweep_report(folder: Path, title: str, params: list[str], axes: list[str],
                 rows: list[dict]) -> Path:
    """index.html of a sweep in ``folder`` (written atomically by the caller)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    ok = [r for r in rows if r.get("status") in ("ok", "cached")]
    failed = [r for r in rows if r.get("status") not in ("ok", "cached")]
    body = [f"<h1>rotorflow sweep: {esc(title)}</h1>",
            f"<p>{len(rows)} points over {', '.join(map(esc, params))}: {len(ok)} complete, "
            f"{len(failed)} failed.</p>"]
    figs = []
    plt = _pyplot()
    # An axis that holds one value over the whole sweep (a setting shared by every point)
    # is no axis of a figure.
    axes = [a for a in axes if len({str(r.get(a)) for r in rows}) > 1] or axes
    for key, label in SWEEP_FIGURES:
        pts = [r for r in ok if _num(r.get(key)) is not None]
        if not pts:
            continue
        name = f"sweep_{key.replace('.', '_')}.png"
        _sweep_plot(plt, folder / name, axes, pts, failed, key, label)
        figs.append(figure(name, f"{label} over the sweep ({len(pts)} points; "
                                 "x: failed points)"))
    if figs:
        body.append("<h2>Figures</h2>" + "".join(figs))
    if failed:
        body.append("<h2 class='failed'>Failed points</h2>")
        body.append(table(["point"] + params + ["error"],
                          [[r["point"]] + [r.get(p) for p in params] + [r.get("error", "")]
                           for r in failed]))
    cols = ["point", "status"] + params + [k for k, _ in SWEEP_FIGURES
                                           if any(k in r for r in rows)]
    body.append("<h2>Points</h2>")
    body.append(table(cols, [[r.get(c, "") for c in cols] for r in rows],
                      ["failed" if r in failed else "" for r in rows]))
    body.append("<p>All columns are in <code>summary.csv</code>.</p>")
    path = folder / "index.html"
    path.write_text(page(f"rotorflow sweep: {title}", "\n".join(body)))
    return path


#: A two-axis sweep with at most this many values on its second axis is drawn as curves.
SWEEP_LINES = 8


def _num(v):
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if np.isfinite(x) else None


def _sweep_plot(plt, path, params, pts, failed, key, label):
    fig, ax = plt.subplots(figsize=FIGSIZE)
    val = np.array([_num(r[key]) for r in pts])
    groups = sorted({_num(r[params[1]]) for r in pts}, key=lambda v: (v is None, v or 0.0)) \
        if len(params) == 2 else []
    if len(params) == 2 and len(groups) <= SWEEP_LINES and None not in groups:
        # Few values of the second axis: one curve per value against the first (a
        # designer's figure, e.g. efficiency against port angle at three speeds).
        for g in groups:
            sel = [r for r in pts if _num(r[params[1]]) == g]
            sel.sort(key=lambda r: _num(r[params[0]]))
            ax.plot([_num(r[params[0]]) for r in sel], [_num(r[key]) for r in sel], "o-",
                    label=f"{params[1]} = {g:g}")
        ax.set_xlabel(params[0])
        ax.set_ylabel(label)
        ax.legend(fontsize=8)
    elif len(params) == 2:
        x = np.array([_num(r[params[0]]) for r in pts], dtype=float)
        y = np.array([_num(r[params[1]]) for r in pts], dtype=float)
        sc = ax.scatter(x, y, c=val, s=60, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=label)
        fx = [_num(r.get(params[0])) for r in failed]
        fy = [_num(r.get(params[1])) for r in failed]
        keep = [(a, b) for a, b in zip(fx, fy, strict=True) if a is not None and b is not None]
        if keep:
            ax.scatter(*zip(*keep, strict=True), marker="x", color="red", s=60, label="failed")
            ax.legend(fontsize=8)
        ax.set_xlabel(params[0])
        ax.set_ylabel(params[1])
    else:
        for p in params:
            x = np.array([_num(r[p]) for r in pts], dtype=float)
            ax.plot(x, val, "o", label=p, alpha=0.8)
        ax.set_xlabel(params[0] if len(params) == 1 else "parameter value")
        ax.set_ylabel(label)
        if len(params) > 1:
            ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
