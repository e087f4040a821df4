"""`rotorflow export` of a twin-screw pair: male and female solids, the fluid domain in
the two intersecting bores, STEP, profiles and both rotors' form cutters
(geometry/export/*).

The pair is the 4/6 of examples/twin_screw_4_6.toml (seed 004) on a short rotor of the
same lead (40 mm, wrap 100 deg: the same helix, so the same cutters), exported at a
coarse tolerance; the bounds are the internal gear's (tests/test_solids_*.py).  The
analytic figures are computed here from the profiles and the case's numbers, not
from the export's own code: Green's theorem for the areas (checked against a fine
polygon), the offset's area A - c P + pi c^2, the bores' union by circular segments,
and the rotors' placement at the fluid angle from design.md's sweep law.
"""

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from rotorflow.errors import CaseError
from rotorflow.geometry.curves import sample_polygon
from rotorflow.geometry.export import csvfile, dxf, ply, stl
from rotorflow.geometry.export.cutter import default_setup, form_cutter, round_trip
from rotorflow.geometry.export.driver import export
from rotorflow.geometry.export.settings import Export
from rotorflow.geometry.export.solids import validate_mesh
from rotorflow.geometry.polygons import signed_area
from rotorflow.geometry.summary import build_machine
from rotorflow.workflow.case import load_case

from .conftest import CASES

MACHINE = """
[machine]
type = "twin-screw"
profile = "circular"
lobes_male = 4
lobes_female = 6
centre_distance_mm = 78
male_diameter_mm = 100
female_diameter_mm = 96
length_mm = 40

[sweep]
kind = "helical"
wrap_male_deg = 100

[operating]
volume_ratio = 1.5
"""
LENGTH, WRAP, C = 0.040, math.radians(100.0), 0.078
TOL = 20e-6  # coarse: 4x the default, the bounds below are the same
CLEAR, TIP = 60e-6, 50e-6  # rotor to rotor (on the female), rotor tips to bores
ANGLE = math.radians(10.0)
SECTION = f"""
formats = ["stl", "fluid", "dxf", "csv", "ply", "cutter"]
tolerance_um = {TOL * 1e6:g}
clearance_um = {CLEAR * 1e6:g}
clearance_on = "female"
tip_clearance_um = {TIP * 1e6:g}
fluid_angle_deg = {math.degrees(ANGLE):g}
"""


def write_case(folder, section, machine=MACHINE):
    path = folder / "case.toml"
    path.write_text(machine + "\n[export]\n" + section)
    return path


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    folder = tmp_path_factory.mktemp("twin")
    case = load_case(write_case(folder, SECTION))
    out = folder / "out"
    out.mkdir()
    man = export(case, Export.from_section(case.raw["export"]), out)
    return case, out, man


def _areas(pair):
    """Male and (offset) female section areas, and the female's perimeter."""
    male, female = pair.male, pair.female
    for prof in (male, female):  # Green's theorem against a fine polygon
        assert signed_area(sample_polygon(prof, 1e-7)) == pytest.approx(prof.area, rel=2e-5)
    a_f = female.area - CLEAR * female.length + math.pi * CLEAR ** 2
    return male.area, a_f


def _union(r1, r2, d):
    """Two discs d apart: both areas less the lens (two circular segments)."""
    x1 = (d * d + r1 * r1 - r2 * r2) / (2 * d)  # chord's distance from each centre
    x2 = d - x1

    def segment(r, x):
        return r * r * math.acos(x / r) - x * math.sqrt(r * r - x * x)

    return math.pi * (r1 * r1 + r2 * r2) - segment(r1, x1) - segment(r2, x2)


def test_rotor_solids_are_closed_with_the_analytic_volume(exported):
    case, out, man = exported
    a_m, a_f = _areas(case.pair)
    assert man["clearance_on"] == "female" and man["files"]["male.stl"]["genus"] == 0
    for name, area in (("male", a_m), ("female", a_f)):
        verts, faces = stl.read(out / f"{name}.stl")
        tm = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
        assert tm.is_watertight and tm.is_winding_consistent, name
        # binary STL is single precision: the acceptance, 1e-4 relative
        assert abs(tm.volume * 1e-9 / (area * LENGTH) - 1.0) < 1e-4, name
        validate_mesh(verts, faces, name, with_trimesh=True)
        entry = man["files"][f"{name}.stl"]
        assert entry["max_deviation_m"] <= man["mesh_tolerance_m"] <= TOL, entry
        assert entry["measured_points"] > len(faces) // 2


def test_fluid_domain_volume_and_chambers(exported):
    case, out, man = exported
    a_m, a_f = _areas(case.pair)
    r_m, r_f = case.pair.male_radius, case.pair.female_radius
    # each bore: its rotor's largest radius (the female's shrunk by the clearance at
    # its convex tip) plus the tip clearance
    bores = man["casing_bores_m"]
    assert bores[0]["radius"] == pytest.approx(r_m + TIP, abs=1e-10)
    assert bores[1]["radius"] == pytest.approx(r_f - CLEAR + TIP, abs=1e-10)
    assert bores[1]["centre"] == [C, 0.0]
    core = (_union(r_m + TIP, r_f - CLEAR + TIP, C) - a_m - a_f) * LENGTH
    entry = man["files"]["fluid.stl"]
    assert entry["core_volume_m3"] == pytest.approx(core, rel=1e-4)
    verts, faces = stl.read(out / "fluid.stl")
    tm = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    ports = (entry["suction_port_area_m2"] + entry["discharge_port_area_m2"]) \
        * entry["port_depth_m"]
    assert entry["port_depth_m"] == pytest.approx(0.01)  # 0.1 D
    assert abs(tm.volume * 1e-9 / (core + ports) - 1.0) < 1e-4
    # the chamber table's chambers fill the space between the zero-clearance rotors
    # in their zero-clearance bores (1e-6: the table's accuracy), and the clearances
    # open what the offset and the grown bores add
    free = (case.pair.working_area - case.pair.male.area - case.pair.female.area) * LENGTH
    assert entry["chamber_sum_m3"] == pytest.approx(free, rel=1e-6)
    assert entry["clearance_volume_m3"] == pytest.approx(core - free, rel=1e-9)
    assert entry["chamber_sum_rel_error"] < 1e-4
    # the walls stay apart: two flanks deviate less than the narrowest gap together
    assert 2 * entry["max_deviation_m"] < man["fluid_gap_min_m"]


def _winding(verts, faces, pts):
    """Generalised winding number of a closed oriented mesh (1 inside, 0 outside)."""
    tri = verts[faces]
    out = np.empty(len(pts))
    for i, p in enumerate(pts):
        a, b, c = tri[:, 0] - p, tri[:, 1] - p, tri[:, 2] - p
        la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc
               + np.einsum("ij,ij->i", a, c) * lb + np.einsum("ij,ij->i", b, c) * la)
        out[i] = 2.0 * np.arctan2(num, den).sum() / (4.0 * math.pi)
    return out


def _flank_points(profile, u, z, rotor, offset):
    """Points of a rotor's section at height z, moved ``offset`` along the profile's
    outward normal, at the fluid angle (design.md: the section at z is the planar pair
    at ANGLE - twist(z); the female turns at -4/6 and sits at (C, 0))."""
    theta = ANGLE - WRAP * z / LENGTH
    p = profile.point(u) + offset * profile.normal(u)
    if rotor == "female":
        theta, centre = -4.0 / 6.0 * theta, np.array([C, 0.0])
    else:
        centre = np.zeros(2)
    c, s = math.cos(theta), math.sin(theta)
    q = np.stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]], -1) + centre
    return np.column_stack([q, np.full(len(q), z)])


def test_fluid_fills_the_gaps_and_not_the_rotors(exported):
    # Points in the clearances (half a gap off a rotor's flank) lie in the fluid, points
    # half a gap inside a rotor do not: the walls are where the case puts them.  Half a
    # gap (25-30 um, >= 15 um normal to the helical flank) exceeds the mesh deviation.
    case, out, _ = exported
    verts, faces = stl.read(out / "fluid.stl")
    verts = verts * 1e-3
    rng = np.random.default_rng(7)
    pts, want = [], []
    for rotor, prof, gap, surface_offset in (("male", case.pair.male, CLEAR, 0.0),
                                             ("female", case.pair.female, CLEAR, -CLEAR)):
        u = rng.uniform(0.0, prof.n, 12)
        for z in (0.3 * LENGTH, 0.7 * LENGTH):
            for sign in (1.0, -1.0):
                pts.append(_flank_points(prof, u, z, rotor, surface_offset + sign * 0.5 * gap))
                want.append(np.full(len(u), 1.0 if sign > 0 else 0.0))
    # tip gaps: half the tip clearance beyond each male tip lies in the fluid
    u_tip = 0.5 + 2.0 * np.arange(4)  # the male's tips (piece ends of its 2-arc lobes)
    pts.append(_flank_points(case.pair.male, u_tip, 0.5 * LENGTH, "male", 0.5 * TIP))
    want.append(np.ones(4))
    w = _winding(verts, faces, np.concatenate(pts))
    np.testing.assert_allclose(w, np.concatenate(want), atol=1e-6)


def test_profiles_and_clouds(exported):
    case, out, man = exported
    for name, prof in (("male", case.pair.male), ("female", case.pair.female)):
        pts = csvfile.read_profile_csv(out / f"{name}_profile.csv") * 1e-3
        poly, closed = dxf.read(out / f"{name}_profile.dxf")
        assert closed and np.array_equal(pts[0], pts[-1])
        np.testing.assert_allclose(poly * 1e-3, pts[:-1], rtol=0, atol=1e-12)
        # the profile in its own frame with the clearance: the female's area shrinks
        want = prof.area - (CLEAR * prof.length - math.pi * CLEAR ** 2
                            if name == "female" else 0.0)
        assert signed_area(pts[:-1]) == pytest.approx(want, rel=1e-3)  # 20 um chords
        cloud = ply.read(out / f"{name}_cloud.ply")
        csv = np.loadtxt(out / f"{name}_cloud.csv", delimiter=",", skiprows=1)
        np.testing.assert_allclose(csv, cloud, rtol=0, atol=1e-8)
        assert len(cloud) == man["files"][f"{name}_cloud.ply"]["points"]
        # normals point out of the material: away from the rotor's axis on average
        axis = np.array([0.0, 0.0]) if name == "male" else np.array([C * 1e3, 0.0])
        radial = cloud[:, :2] - axis
        assert np.mean(np.sum(radial * cloud[:, 3:5], 1) > 0) > 0.5
    assert "female_axis_m" in man and "male_axis_m" not in man


def test_both_form_cutters_round_trip(exported):
    _, out, man = exported
    for name, hand in (("male", "left"), ("female", "right")):
        tool = np.loadtxt(out / f"{name}_cutter.csv", delimiter=",", skiprows=1)
        side = json.loads((out / f"{name}_cutter.json").read_text())
        assert tool.shape[1] == 5 and len(tool) == side["points"]
        assert side["hand"] == hand
        # default: the helix angle at the pitch radius, tan S = k r (both rotors)
        k = (1.0 if name == "male" else -4.0 / 6.0) * WRAP / LENGTH
        r = 0.078 * (4 if name == "male" else 6) / 10
        assert math.tan(math.radians(side["setting_angle_deg"])) == pytest.approx(k * r)
        assert side["round_trip_max_m"] <= TOL and side["interference_m"] <= TOL
        assert man["files"][f"{name}_cutter.csv"]["round_trip_max_m"] <= TOL


@pytest.fixture(scope="module")
def pair_case(exported):
    return exported[0]


def test_cutters_at_a_helical_oblique_angle(pair_case, tmp_path):
    # Seed 004: the disc cutter at another setting (helical oblique) angle than the
    # helix's: one per rotor, as the rotors are of opposite hand.
    section = {"formats": ["cutter"], "tolerance_um": TOL * 1e6,
               "cutter_setting_angle_deg": {"male": 54.2, "female": -56.7}}
    man = export(pair_case, Export.from_section(section), tmp_path)
    for name, angle in (("male", 54.2), ("female", -56.7)):
        side = json.loads((tmp_path / f"{name}_cutter.json").read_text())
        assert side["setting_angle_deg"] == pytest.approx(angle)
        assert side["round_trip_max_m"] <= TOL and side["interference_m"] <= TOL
    # a different tool from the default one (the female's default is -53.7 deg): the
    # steeper disc is 0.47 mm wider
    default = form_cutter(pair_case.pair.female, default_setup(
        pair_case.pair, build_machine(pair_case).sweep, None, None, "female"), TOL)
    tool = np.loadtxt(tmp_path / "female_cutter.csv", delimiter=",", skiprows=1) * 1e-3
    assert np.ptp(tool[:, 0]) - np.ptp(default.axial) > 0.4e-3
    assert sorted(man["files"]) == ["female_cutter.csv", "female_cutter.json",
                                    "male_cutter.csv", "male_cutter.json"]


def test_cutter_with_a_front_angle(pair_case, tmp_path):
    # Seed 004: a disc cutter "with non-zero degree front angle": its cutting edge is the
    # tool's section by the rake plane, d = R_max sin(angle) from the axis; at the tool's
    # outermost point the edge lies R_max cos(angle) from the plane's foot.
    angle = 8.0
    section = {"formats": ["cutter"], "tolerance_um": TOL * 1e6,
               "cutter_front_angle_deg": angle}
    man = export(pair_case, Export.from_section(section), tmp_path)
    for name in ("male", "female"):
        axial = np.loadtxt(tmp_path / f"{name}_cutter.csv", delimiter=",", skiprows=1)
        rake = np.loadtxt(tmp_path / f"{name}_cutter_rake.csv", delimiter=",", skiprows=1)
        side = json.loads((tmp_path / f"{name}_cutter.json").read_text())
        r_max = axial[:, 1].max()
        d = r_max * math.sin(math.radians(angle))
        assert side["rake_offset_m"] * 1e3 == pytest.approx(d, rel=1e-9)
        assert rake[:, 1].max() == pytest.approx(r_max * math.cos(math.radians(angle)),
                                                 abs=1e-8)
        assert np.all(rake[:, 1] < axial[:, 1])
        assert side["rake_round_trip_max_m"] <= TOL
        assert man["files"][f"{name}_cutter_rake.csv"]["rake_round_trip_max_m"] <= TOL


def test_a_front_angle_past_the_tool_root_is_refused(pair_case, tmp_path):
    with pytest.raises(CaseError, match="between -45 and 45"):
        Export.from_section({"formats": ["cutter"], "cutter_front_angle_deg": 50.0})
    # a small tool (60 mm from the male's axis: radii ~10 to ~29 mm): a plane 0.5 R_max
    # from its axis passes beside its smallest circles
    section = {"formats": ["cutter"], "tolerance_um": TOL * 1e6,
               "cutter_centre_distance_mm": {"male": 60.0}, "cutter_front_angle_deg": 30.0}
    with pytest.raises(CaseError, match="rake plane"):
        export(pair_case, Export.from_section(section), tmp_path)
    assert not any(tmp_path.glob("male_cutter_rake.csv"))


def test_round_trip_fails_on_a_perturbed_tool(pair_case):
    pair = pair_case.pair
    curve = pair.female
    setup = default_setup(pair, build_machine(pair_case).sweep, None, None, "female")
    cut = form_cutter(curve, setup, TOL)
    ok = round_trip(curve, cut)
    assert ok["round_trip_max_m"] <= TOL and ok["interference_m"] <= TOL
    radius = cut.radius.copy()
    mid = slice(len(radius) // 3, 2 * len(radius) // 3)
    radius[mid] += 3 * TOL  # a tool 60 um too big over a third of its profile
    rt = round_trip(curve, cut, cut.axial, radius)
    assert rt["round_trip_max_m"] > TOL
    assert rt["interference_m"] > TOL


@pytest.mark.parametrize("section, words, first", [
    ({"clearance_on": "outer"}, "clearance_on = 'outer'", True),
    ({"clearance_um": 1500, "clearance_on": "female"}, "folds", True),
    ({"bore_diameter_mm": 110}, "bore_diameter_mm", True),
    ({"formats": ["fluid"], "clearance_um": 40, "tip_clearance_um": 0}, "tip_clearance_um",
     True),
    ({"formats": ["cutter"], "cutter_setting_angle_deg": {"gate": 50}}, "'gate'", True),
    # found by the round trip, after the male's tool file (the command line writes
    # into a temporary folder and drops it: see the next test)
    ({"formats": ["cutter"], "cutter_setting_angle_deg": {"male": 58.7}}, "form cutter",
     False),
])
def test_bad_input_is_a_case_error(pair_case, tmp_path, section, words, first):
    d = {"formats": ["stl"], "tolerance_um": 50, **section}
    with pytest.raises(CaseError) as err:
        export(pair_case, Export.from_section(d), tmp_path)
    assert words in str(err.value) and "\n" not in str(err.value)
    if first:
        assert not any(tmp_path.iterdir())  # it failed before writing anything


def test_bad_input_on_the_command_line_exits_2_and_writes_nothing(tmp_path):
    path = write_case(tmp_path, 'formats = ["cutter"]\ncutter_setting_angle_deg = '
                                "{male = 58.7}\n")
    out = tmp_path / "new" / "out"
    res = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "export", str(path),
                          "--out", str(out)], capture_output=True, text=True)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rotorflow: error:"), res.stderr
    assert "form cutter" in lines[0] and "male" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


@pytest.mark.gmsh
def test_step_solids_and_occ_volume(pair_case, tmp_path):
    """Both rotors and the fluid core as STEP solids; OpenCASCADE's own volume of each
    (a fresh import's mass properties, what a CAD user sees) is the analytic one."""
    from rotorflow.geometry.export.assembly import assemble
    from rotorflow.geometry.export.step import check_step
    from rotorflow.geometry.export.step_fluid import write_fluid_step

    settings = Export(formats=("step", "fluid"), tolerance_m=TOL, clearance_m=(CLEAR,),
                      clearance_on="female", tip_clearance_m=TIP)
    man = export(pair_case, Export(formats=("step",), tolerance_m=TOL,
                                   clearance_m=(CLEAR,), clearance_on="female"), tmp_path)
    a_m, a_f = _areas(pair_case.pair)
    for name, area in (("male", a_m), ("female", a_f)):
        e = man["files"][f"{name}.step"]
        assert e["solids"] == 1 and e["closed"], e
        assert e["max_deviation_m"] <= TOL, e
        chk = check_step(tmp_path / f"{name}.step")  # re-imported once more here
        assert chk.volumes == 1 and chk.closed
        assert chk.volume_m3 == pytest.approx(area * LENGTH, rel=1e-4)
        assert chk.occ_volume_m3 == pytest.approx(area * LENGTH, rel=1e-4)
        assert e["occ_volume_m3"] == pytest.approx(chk.occ_volume_m3, rel=1e-12)
    r_m, r_f = pair_case.pair.male_radius, pair_case.pair.female_radius
    core = (_union(r_m + TIP, r_f - CLEAR + TIP, C) - a_m - a_f) * LENGTH
    path = tmp_path / "fluid_core.step"
    write_fluid_step(path, assemble(pair_case, settings), TOL)
    chk = check_step(path)
    assert chk.volumes == 1 and chk.closed
    assert chk.occ_volume_m3 == pytest.approx(core, rel=1e-4)
    assert chk.volume_m3 == pytest.approx(core, rel=1e-4)


@pytest.mark.parametrize("section, words", [
    ({"tip_clearance_um": 20}, "tip_clearance_um"),
    ({"clearance_on": "male"}, "clearance_on = 'male'"),
    ({"cutter_setting_angle_deg": {"female": 40}}, "'female'"),
])
def test_twin_screw_keys_are_errors_on_an_internal_gear(tmp_path, section, words):
    case = load_case(CASES / "default.toml")
    with pytest.raises(CaseError, match=words):
        export(case, Export.from_section({"formats": ["stl"], **section}), tmp_path)
    assert not any(tmp_path.iterdir())


def test_the_pin_cycloid_exports_with_the_clearance_on_its_male(tmp_path):
    """The pin-cycloid male's root corners turn by -90 deg: shrunk by a clearance, its
    pieces' offsets part there and the offset goes round each on the clearance's arc
    (geometry/offset_corners.py).  Before the arcs the flank's chord across that gap
    stood 0.29 c off the offset and the export stopped with "male flank does not reach
    5 um after 4 refinements (measured 14.5 um)".  Now both solids close, the male's
    volume is the length times its profile's area less Clipper's erosion of its polygon
    (round joins: the arcs; an area not from the offset code), 1e-4 as above, and its
    surface meets the tolerance."""
    from manifold3d import CrossSection, JoinType

    from rotorflow.geometry.curves import sample

    case4_6 = (CASES / "twin_screw_4_6.toml").read_text()
    machine = case4_6.split("[operating]")[0].replace("length_mm = 130", "length_mm = 30")
    machine = machine.replace("wrap_male_deg = 325", "wrap_male_deg = 75")
    assert "length_mm = 30" in machine and "wrap_male_deg = 75" in machine
    section = ('formats = ["stl"]\ntolerance_um = 5\nclearance_um = 20\n'
               'clearance_on = "male"\ntip_clearance_um = 20\n')
    case = load_case(write_case(tmp_path, section, machine))
    out = tmp_path / "out"
    out.mkdir()
    man = export(case, Export.from_section(case.raw["export"]), out)
    male = case.pair.male
    base = male.point(sample(male, 1e-9))
    eroded = CrossSection([base * 1e3]).offset(-20e-3, JoinType.Round,
                                               circular_segments=4096).area() * 1e-6
    area = male.area - (signed_area(base) - eroded)  # (the sagittas cancel: 2e-8)
    verts, faces = stl.read(out / "male.stl")
    tm = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    assert abs(tm.volume * 1e-9 / (area * 0.030) - 1.0) < 1e-4
    assert man["files"]["male.stl"]["max_deviation_m"] <= 5e-6
