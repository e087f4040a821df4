"""The case report opens in headless Chromium from disk, with every picture loaded.

The page carries a small script that, on load, writes the number of ``<img>`` elements
and the sources of those that did not decode (``naturalWidth == 0``) into the body's
``data-images`` / ``data-images-broken`` attributes; Chromium's ``--dump-dom`` shows
the DOM after that script ran.  A perturbed copy of the report (one picture removed)
must be caught, so the check can fail.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

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


def open_in_chromium(index, tmp_path) -> dict:
    """Body attributes after the page loaded in headless Chromium."""
    out = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         f"--user-data-dir={tmp_path / 'chromium-profile'}", "--virtual-time-budget=10000",
         "--dump-dom", index.resolve().as_uri()],
        capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    body = re.search(r"<body([^>]*)>", out.stdout)
    assert body, out.stdout[:2000]
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
    pytest.importorskip("matplotlib")
    import matplotlib.image as mpimg

    for name in DEMO_IMAGES:
        img = mpimg.imread(demo_report / "report" / name)
        assert img.shape[0] > 200 and img.shape[1] > 200
        assert img[..., :3].std() > 0.02, name  # not one flat colour


def test_rotor_picture_follows_the_geometry(tmp_path):
    """Different wraps give different pictures; the same case the same picture size."""
    pytest.importorskip("pyvista")
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
