"""The case report opens in headless Chromium from disk, with every picture loaded.

The page carries a small script that, on load, writes the number of ``<img>`` elements
and the sources of those that did not decode (``naturalWidth == 0``) into the body's
``data-images`` / ``data-images-broken`` attributes; Chromium's ``--dump-dom`` shows
the DOM after that script ran.  A perturbed copy of the report (one picture removed)
must be caught, so the check can fail.
"""

from __future__ import annotations

import html
import json
import re
import resource
import shutil
import subprocess
import sys

import numpy as np
import pytest

from .conftest import CASES

CHROMIUM = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome")
                 if shutil.which(n)), None)
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (make report-deps installs it)")
#: Pictures every demo report must show: rotors, end-plane section, volume curve,
#: p-angle and p-V.
DEMO_IMAGES = {"render_rotors.png", "render_section.png", "table_volume.png",
               "quasi1d_p_angle.png", "quasi1d_p_V.png"}


@pytest.fixture(scope="module")
def demo_report(tmp_path_factory):
    build = tmp_path_factory.mktemp("build")
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "run",
                          str(CASES / "default.toml"), "--build", str(build)],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return build / "default"


def chromium(tmp_path, *args) -> str:
    """Headless Chromium's stdout for ``args`` (a fresh profile under ``tmp_path``)."""
    out = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         f"--user-data-dir={tmp_path / 'chromium-profile'}", *args],
        capture_output=True, text=True, timeout=120)
    # Chromium reserves far more address space than it uses (about 100 GB here); under
    # `ulimit -v` below that it dies at start-up (SIGTRAP) without saying why.
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    hint = "" if limit == resource.RLIM_INFINITY else (
        f" (address space limited to {limit / 2**30:.0f} GiB: Chromium needs ~100+ GiB of "
        "it, raise `ulimit -v`)")
    assert out.returncode == 0, f"chromium exit {out.returncode}{hint}: {out.stderr[-2000:]}"
    return out.stdout


def open_in_chromium(index, tmp_path) -> dict:
    """Body attributes after the page loaded in headless Chromium."""
    dom = chromium(tmp_path, "--virtual-time-budget=10000", "--dump-dom",
                   index.resolve().as_uri())
    body = re.search(r"<body([^>]*)>", dom)
    assert body, dom[:2000]
    return dict(re.findall(r'([\w-]+)="([^"]*)"', body.group(1)))


@needs_chromium
def test_demo_report_opens_with_every_image(demo_report, tmp_path):
    index = demo_report / "report" / "index.html"
    html = index.read_text()
    sources = re.findall(r"<img src='([^']+)'", html)
    assert DEMO_IMAGES <= set(sources)
    attrs = open_in_chromium(index, tmp_path)
    assert attrs.get("data-images") == str(len(sources)), attrs
    assert attrs.get("data-images-broken") == "", attrs


#: The screenshot's window; the headline must fit in its top part.
SHOT_W, SHOT_H = 1200, 900


def headline_cells(dom: str) -> dict[str, tuple[str, str, str]]:
    """quantity -> (value, unit, basis) of the headline table in a DOM dump."""
    tab = re.search(r'<table id="headline".*?</table>', dom, re.S)
    assert tab, "no headline table in the DOM"
    rows = re.findall(r"<tr><th>([^<]*)</th><td[^>]*>([^<]*)</td><td>([^<]*)</td>"
                      r"<td[^>]*>([^<]*)</td></tr>", tab.group(0))
    return {html.unescape(q): tuple(html.unescape(x) for x in rest) for q, *rest in rows}


@needs_chromium
def test_screenshot_shows_the_headline_first(demo_report, tmp_path):
    """The page as Chromium renders it leads with the headline, whose figures are the
    summary's in a designer's units, and a screenshot of it is a real picture."""
    index = (demo_report / "report" / "index.html").resolve()
    dom = chromium(tmp_path, "--dump-dom", index.as_uri())
    # Before every section (the geometry is the first) and before the stages table.
    at = dom.find('id="headline"')
    assert 0 < at < dom.find('id="geometry"') < dom.find(">Stages<")
    cells = headline_cells(dom)
    s = json.loads((demo_report / "quasi1d" / "summary.json").read_text())
    # Expected values from the summary, units converted here (not by the report).
    expected = {
        "Volume flow at suction": (s["suction_volume_flow_L_min"] / 1000.0, "m³/min"),
        "Mass flow": (s["mass_flow_kg_s"], "kg/s"),
        "Indicated power": (s["indicated_power_W"] / 1000.0, "kW"),
        "Shaft power": (s["shaft_power_W"] / 1000.0, "kW"),
        "Specific power": ((s["shaft_power_W"] / 1000.0)
                           / (s["suction_volume_flow_L_min"] / 1000.0), "kW/(m³/min)"),
        "Volumetric efficiency": (100.0 * s["volumetric_efficiency"], "%"),
        "Isentropic efficiency, indicated": (100.0 * s["adiabatic_efficiency"], "%"),
        "Isentropic efficiency, shaft": (100.0 * s["adiabatic_efficiency_shaft"], "%"),
        "Isothermal efficiency, indicated": (100.0 * s["isothermal_efficiency"], "%"),
        "Discharge temperature": (s["discharge_temperature_K"], "K"),
    }
    assert set(expected) <= set(cells), cells
    for quantity, (value, unit) in expected.items():
        shown, shown_unit, _ = cells[quantity]
        assert shown_unit == unit, quantity
        # Four significant figures: within half a unit of the fourth figure, no more.
        digits = re.sub(r"[^0-9]", "", shown).lstrip("0")
        assert len(digits) == 4, (quantity, shown)
        assert float(shown) == pytest.approx(value, rel=5e-4), quantity
    celsius = s["discharge_temperature_K"] - 273.15
    assert f"{celsius:.1f} °C" in cells["Discharge temperature"][2]

    shot = tmp_path / "report.png"
    chromium(tmp_path, "--hide-scrollbars", f"--window-size={SHOT_W},{SHOT_H}",
             f"--screenshot={shot}", index.as_uri())
    import matplotlib.image as mpimg

    img = mpimg.imread(shot)  # floats in [0, 1]
    assert img.shape[:2] == (SHOT_H, SHOT_W)
    rgb = img[..., :3]
    assert rgb.std() > 0.05 and rgb.min() < 0.2, "blank screenshot"
    # The headline's first column (header cells, #f3f3f3) runs down most of the top of
    # the first screen: a tall table leads the page (with the stages table first, the
    # longest grey column there is about half as long).
    grey = np.all(np.abs(rgb[: SHOT_H * 2 // 3] - 243 / 255) < 1.5 / 255, axis=-1)
    assert grey.sum(axis=0).max() > 250, grey.sum(axis=0).max()


def test_report_names_what_the_end_plane_angles_are(demo_report):
    """On the internal gear the geometry's two angles are the chamber's contacts with the
    end planes, not the port timing the model uses (the quasi-1D summary's), and the
    report names them so; the port timing appears under its own name."""
    page = html.unescape((demo_report / "report" / "index.html").read_text())
    geo = json.loads((demo_report / "geometry" / "geometry.json").read_text())
    s = json.loads((demo_report / "quasi1d" / "summary.json").read_text())
    assert abs(geo["angle_discharge_open_deg"] - s["discharge_open_deg"]) > 90.0
    row = re.search(r"<tr><th>([^<]*)</th><td class='num'>([^<]*)</td><td>([^<]*)</td>"
                    r"<td class='muted'><code>angle_discharge_open_deg</code>", page)
    assert row and "first contact with the high-pressure end plane" in row.group(1)
    assert "not the discharge port opening" in row.group(1)
    assert row.group(2) == f"{geo['angle_discharge_open_deg']:.6g}"
    assert row.group(3).startswith("deg of outer-rotor turn")
    assert (f"Discharge port opens at (model's port timing)</th><td class='num'>"
            f"{s['discharge_open_deg']:.6g}") in page
    assert "Normalised swept volume V_sw / (π D² L / 4)" in page


@needs_chromium
def test_image_check_catches_a_missing_picture(demo_report, tmp_path):
    copy = tmp_path / "report"
    shutil.copytree(demo_report / "report", copy)
    (copy / "quasi1d_p_V.png").unlink()
    (copy / "render_rotors.png").write_bytes(b"not a png")
    attrs = open_in_chromium(copy / "index.html", tmp_path)
    assert set(attrs["data-images-broken"].split()) == {"quasi1d_p_V.png",
                                                        "render_rotors.png"}


def test_report_is_made_from_the_runs_own_data(demo_report):
    """The report's numbers are the artifacts' numbers, and its pictures their files."""
    html = (demo_report / "report" / "index.html").read_text()
    summary = json.loads((demo_report / "quasi1d" / "summary.json").read_text())
    geometry = json.loads((demo_report / "geometry" / "geometry.json").read_text())
    for value in (summary["mass_flow_kg_s"], summary["indicated_power_W"],
                  geometry["swept_volume_m3"], geometry["sigma_lim"]):
        assert f"{value:.6g}" in html
    for name in ("quasi1d_p_angle.png", "quasi1d_p_V.png"):
        assert (demo_report / "report" / name).read_bytes() == \
            (demo_report / "quasi1d" / name).read_bytes()
    for name in ("rotors.png", "section.png"):
        assert (demo_report / "report" / f"render_{name}").read_bytes() == \
            (demo_report / "render" / name).read_bytes()
    # Every picture is a real, non-blank PNG.
    import matplotlib.image as mpimg

    for name in DEMO_IMAGES:
        img = mpimg.imread(demo_report / "report" / name)
        assert img.shape[0] > 200 and img.shape[1] > 200
        assert img[..., :3].std() > 0.02, name  # not one flat colour


def test_rotor_picture_follows_the_geometry(tmp_path):
    """Different wraps give different pictures; the same case the same picture size."""
    from rotorflow.postprocess.render import render_case
    from rotorflow.workflow.case import load_case

    case = load_case(CASES / "default.toml")
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    render_case(case, a, wrap_outer_deg=136.0)
    render_case(case, b, wrap_outer_deg=30.0)
    assert (a / "rotors.png").read_bytes() != (b / "rotors.png").read_bytes()
    assert (a / "section.png").stat().st_size > 0


# ------------------------------------------------------------- the hook CFD stages use
def fake_cfd_run(ctx):
    (ctx.out / "errors.json").write_text(json.dumps({"leak_rel_error": 0.042}))
    return {}


def fake_cfd_section(artifact, report_dir, case):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotorflow.postprocess.report import Section, figure, key_value_table

    err = json.loads((artifact / "errors.json").read_text())
    fig, ax = plt.subplots()
    ax.bar(["leakage"], [err["leak_rel_error"]])
    fig.savefig(report_dir / "cfd_fake.png")
    plt.close(fig)
    return Section("CFD against quasi-1D", figure("cfd_fake.png", "relative error")
                   + key_value_table(err))


def test_a_registered_stage_brings_its_section_into_the_report(tmp_path, monkeypatch):
    from rotorflow.workflow import stages
    from rotorflow.workflow.runner import run_case

    stage = stages.Stage(name="cfd.fake", run=f"{__name__}:fake_cfd_run",
                         description="stand-in for a CFD stage", reads=("machine",),
                         report=f"{__name__}:fake_cfd_section", figures="errors.json")
    monkeypatch.setitem(stages.REGISTRY, "cfd.fake", stage)
    case = tmp_path / "c.toml"
    case.write_text((CASES / "default.toml").read_text()
                    + '\n[outputs]\nwant = ["cfd.fake", "report"]\n')
    rec = run_case(case, tmp_path / "build")
    assert rec["status"] == "complete", rec
    assert rec["plan"] == ["geometry", "render", "cfd.fake", "report"]
    assert "cfd.fake" in rec["stages"]["report"]["upstream"]
    html = (tmp_path / "build" / "c" / "report" / "index.html").read_text()
    assert "CFD against quasi-1D" in html and "0.042" in html
    assert (tmp_path / "build" / "c" / "report" / "cfd_fake.png").stat().st_size > 0
