"""STEP solids of the rotors through gmsh's OpenCASCADE kernel.

Each flank piece (pin arc, fillet, inner lobe) becomes one B-spline surface built here,
not approximated by OCC: the bicubic Hermite interpolant of the analytic flank, i.e.
at every node of a (u, z) grid it takes the exact point S, tangents S_u, S_z and twist
S_uz, written as a degree 3 x 3 B-spline with triple interior knots (Bezier patches,
C1 across them).  Its error is of fourth order in the node spacing: the nodes are
profile samples at a coarse chordal tolerance and z levels a few degrees of rotor
turn apart, and the deviation is measured on the re-imported file.  The faces share
their boundary curves exactly; with planar end faces (and for the outer rotor the
ruled bore cylinder, a cone when scaled) they are sewn into one shell and one solid.
Model units are millimetres (STEP's default unit).

Each face spans at most FACE_SPANS nodes along the profile and along z, with z as its
first parameter: OpenCASCADE's mass properties integrate a face with one Gauss rule
over the whole face (see FACE_SPANS), so a face of many spans reads a wrong volume.

Checks, on the file as re-imported in a fresh gmsh session: exactly one volume, a
closed shell (every edge bounds two faces, or one face twice along a seam), the volume
against the analytic one (divergence theorem on the imported faces, and OCC's own
mass property), and the largest distance of points of the B-spline faces from the
analytic flank.
"""

import logging
import math
import os
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import ExternalRunError

from ..curves import sample
from .surface import SweptSurface, foot_points

log = logging.getLogger(__name__)

MM = 1e3
#: Largest rotor turn between z nodes [rad]: the Hermite error along a helix of radius
#: r is about r (turn)^4 / 384, 0.6 um at r = 45 mm (measured on the file).
SECTION_TURN = math.radians(15.0)
#: Largest relative change of the section scale between z nodes (conical).
SECTION_SCALE = 0.05
#: Share of the tolerance the Hermite arc of a profile interval may deviate (the rest is
#: left to the interpolation along z).
HERMITE_SHARE = 0.1
#: Sections at least, also for straight rotors (two suffice there).
MIN_SECTIONS = 2
#: Profile nodes: chordal tolerance of the first sampling, in export tolerances (then
#: split where the Hermite arc is not within HERMITE_SHARE of the tolerance).
SPLINE_POINTS_TOL = 50.0
#: Gauss-Legendre points per knot span of the volume integral (5: exact for degree 9),
#: and the uniform panels used on faces that are not flank patches (the bore).
GAUSS_POINTS = 5
GAUSS_PANELS = (64, 8)
#: Hermite spans of one flank face, along the profile and along z.  OpenCASCADE's
#: mass properties (BRepGProp, non-adaptive, as gmsh and FreeCAD call it) integrate a
#: face with one Gauss rule over its whole parameter range, not span by span:
#: min(2 (degree + 1) spans in V, 61) points in both directions, V being the profile
#: here (a z=const edge's line pcurve asks for fewer).  Eight bicubic spans in V reach
#: the 61-point cap, about 8 points a span in either direction; a whole lobe in one
#: face left it 61 points for ~50 spans (1.2e-4 on co2_transcritical's inner rotor),
#: and a straight rotor built with the profile as U got 8 (1.9 %).
FACE_SPANS = 8


@dataclass(frozen=True)
class StepCheck:
    volumes: int
    volume_m3: float  # divergence theorem on the imported faces
    occ_volume_m3: float  # OCC's own mass property (what a CAD user sees)
    faces: int
    closed: bool
    deviation_m: float


@contextmanager
def _quiet_stdout():
    """OCC's STEP translator prints statistics straight to file descriptor 1; send them
    to the log instead (the command's stdout carries only its result)."""
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)
            tmp.seek(0)
            text = tmp.read().decode("utf-8", "replace")
            if text.strip():
                log.debug("OCC: %s", text.strip())


def _section_levels(surface: SweptSurface, z0: float, z1: float) -> np.ndarray:
    """z nodes spread so that each step turns the section by at most SECTION_TURN and
    scales it by at most SECTION_SCALE (relative), whatever the lead and scale laws."""
    z = np.linspace(z0, z1, 4001)
    rate = np.hypot(surface.dtheta(z) / SECTION_TURN,
                    surface.sweep.dscale(z) / surface.sweep.scale(z) / SECTION_SCALE)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(z))])
    n = max(int(math.ceil(cum[-1])), MIN_SECTIONS - 1)
    levels = np.interp(np.linspace(0.0, cum[-1], n + 1), cum, z) if cum[-1] > 0 else \
        np.linspace(z0, z1, n + 1)
    levels[0], levels[-1] = z0, z1
    return levels


def _hermite_error(curve, a, b):
    """Largest distance of the cubic Hermite arc on [a, b] (exact end points and
    derivatives) from the curve, at t = 1/4, 1/2, 3/4 of the parameter interval."""
    h = (b - a)[:, None]
    p0, p1 = curve.point(a), curve.point(b)
    d0, d1 = curve.derivative(a), curve.derivative(b - 1e-12)
    worst = np.zeros(len(a))
    for t in (0.25, 0.5, 0.75):
        h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
        h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
        herm = h00 * p0 + h10 * h * d0 + h01 * p1 + h11 * h * d1
        worst = np.maximum(worst, np.linalg.norm(herm - curve.point(a + t * (b - a)), axis=-1))
    return worst


def _piece_nodes(surface: SweptSurface, tol: float):
    """Profile nodes of each piece (ends included) for the Hermite patches: a coarse
    chordal sampling, split until the Hermite arc of every interval (in the profile's
    own parameter, which the patch uses) is within HERMITE_SHARE of the tolerance."""
    curve = surface.curve
    u = sample(curve, SPLINE_POINTS_TOL * tol)
    out = []
    for j in range(curve.n):
        uj = np.concatenate([[float(j)], u[(u > j) & (u < j + 1)], [j + 1.0]])
        for _ in range(40):
            bad = _hermite_error(curve, uj[:-1], uj[1:]) > HERMITE_SHARE * tol
            if not bad.any():
                break
            uj = np.sort(np.concatenate([uj, 0.5 * (uj[:-1] + uj[1:])[bad]]))
        out.append(uj)
    return out


def _chunks(nodes):
    """Consecutive runs of at most FACE_SPANS spans (about equal), sharing their ends."""
    cuts = np.round(np.linspace(0, len(nodes) - 1, (len(nodes) - 2) // FACE_SPANS + 2))
    cuts = np.unique(cuts.astype(int))
    return [nodes[a:b + 1] for a, b in zip(cuts[:-1], cuts[1:], strict=True)]


def _face_nodes(surface: SweptSurface, tol: float):
    """(z nodes [m], profile nodes) of each flank face: every piece and the length cut
    into runs of FACE_SPANS Hermite spans; a piece with fewer has its longest spans
    bisected up to that many (more nodes only refine the interpolant)."""
    out = []
    z = _chunks(_section_levels(surface, 0.0, surface.length))
    for uj in _piece_nodes(surface, tol):
        while len(uj) - 1 < FACE_SPANS:
            h = np.diff(uj)
            k = int(np.argmax(h))
            uj = np.insert(uj, k + 1, uj[k] + 0.5 * h[k])
        out += [(zk, uk) for zk in z for uk in _chunks(uj)]
    return out


def hermite_net(surface: SweptSurface, u: np.ndarray, z: np.ndarray):
    """Control net (3m+1, 3n+1, 3) [mm] of the bicubic Hermite patches over the nodes.

    Node (i, j) sits at control index (3i, 3j); its neighbours carry the tangents
    (+-h/3 S_u, +-k/3 S_z) and the corners the twist (h k / 9 S_uz).  The last u node
    is a piece end: its point comes from the next piece (the same point), its
    derivatives from this piece.
    """
    m, n = len(u) - 1, len(z) - 1
    U, Z = np.meshgrid(u, z, indexing="ij")
    P = surface.evaluate(U, Z)
    Ud = U.copy()
    Ud[-1] = u[-1] - 1e-12  # one-sided derivatives at the piece end
    _, su, sz, suz = surface.evaluate(Ud, Z, jacobian=True, twist=True)
    _, _, sz_end = surface.evaluate(U[-1], Z[-1], jacobian=True)
    sz[-1] = sz_end
    hu, hz = np.diff(u), np.diff(z)
    net = np.empty((3 * m + 1, 3 * n + 1, 3))
    for a in (-1, 0, 1):
        ia = np.arange(m + 1)[(np.arange(m + 1) + a >= 0) & (3 * np.arange(m + 1) + a <= 3 * m)]
        if a == 1:
            du = hu[ia] / 3.0
        elif a == -1:
            du = -hu[ia - 1] / 3.0
        else:
            du = np.zeros(len(ia))
        for b in (-1, 0, 1):
            jb = np.arange(n + 1)[(np.arange(n + 1) + b >= 0) & (3 * np.arange(n + 1) + b <= 3 * n)]
            if b == 1:
                dz = hz[jb] / 3.0
            elif b == -1:
                dz = -hz[jb - 1] / 3.0
            else:
                dz = np.zeros(len(jb))
            I, J = np.meshgrid(ia, jb, indexing="ij")
            DU, DZ = np.meshgrid(du, dz, indexing="ij")
            net[3 * I + a, 3 * J + b] = (P[I, J] + DU[..., None] * su[I, J] + DZ[..., None]
                                         * sz[I, J] + (DU * DZ)[..., None] * suz[I, J])
    return net * MM


def _knots(nodes):
    mult = [4] + [3] * (len(nodes) - 2) + [4]
    return list(map(float, nodes)), mult


def _patch(occ, net, u, z) -> int:
    """The B-spline face over the net, z [mm] its first (U) parameter, the profile
    parameter its second (V)."""
    tags = [occ.addPoint(*p) for p in net.reshape(-1, 3)]  # U (z) runs fastest
    ku, mu = _knots(u)
    kz, mz = _knots(z * MM)
    return occ.addBSplineSurface(tags, net.shape[1], degreeU=3, degreeV=3, knotsU=kz,
                                 knotsV=ku, multiplicitiesU=mz, multiplicitiesV=mu)


def _flank_faces(gmsh, surface: SweptSurface, tol: float):
    """The flank patches and, per end (z = 0, z = L), their boundary curves in order."""
    occ = gmsh.model.occ
    faces = [_patch(occ, hermite_net(surface, u, z), u, z) for z, u in _face_nodes(surface, tol)]
    occ.synchronize()
    ends = ([], [])
    for f in faces:
        for _, c in gmsh.model.getBoundary([(2, f)], oriented=False):
            box = gmsh.model.getBoundingBox(1, abs(c))
            if abs(box[5] - box[2]) < 1e-9 * MM:  # a curve in a z plane: which end?
                for k, z in enumerate((0.0, surface.length * MM)):
                    if abs(box[2] - z) < 1e-6 * MM and abs(box[5] - z) < 1e-6 * MM:
                        ends[k].append(abs(c))
    return faces, ends


def write_rotor_step(path: Path, surface: SweptSurface, tol: float,
                     bore_radius: float | None, log_dir: Path | None = None) -> None:
    """Build the rotor in OCC and write it to ``path`` (STEP, mm)."""
    from rotorflow.gmsh_session import gmsh_session

    L = surface.length
    with gmsh_session(Path(path).stem, log_dir=log_dir) as gmsh:
        occ = gmsh.model.occ
        faces, (bottom, top) = _flank_faces(gmsh, surface, tol)
        caps = []
        if bore_radius is None:  # inner rotor: the profile closes each end face
            for ring in (bottom, top):
                caps.append(occ.addPlaneSurface([occ.addCurveLoop(ring)]))
        else:  # outer rotor: end faces between the bore circle and the profile
            sl = float(surface.sweep.scale(L))
            c0 = occ.addCircle(0, 0, 0, bore_radius * MM)
            c1 = occ.addCircle(0, 0, L * MM, bore_radius * sl * MM)
            w0, w1 = occ.addWire([c0]), occ.addWire([c1])
            bore = occ.addThruSections([w0, w1], makeSolid=False, makeRuled=True)
            caps += [t for d, t in bore if d == 2]
            for circle, ring in ((c0, bottom), (c1, top)):
                caps.append(occ.addPlaneSurface([occ.addCurveLoop([circle]),
                                                 occ.addCurveLoop(ring)]))
        write_solid(gmsh, faces + caps, path)


def write_solid(gmsh, faces: list, path: Path) -> None:
    """Sew ``faces`` into one solid and write it; an error if OCC makes any other count."""
    occ = gmsh.model.occ
    occ.addVolume([occ.addSurfaceLoop(faces, sewing=True)])
    occ.synchronize()
    vols = gmsh.model.getEntities(3)
    if len(vols) != 1:
        raise ExternalRunError(f"OCC made {len(vols)} solids for {Path(path).name}, not one")
    with _quiet_stdout():
        gmsh.write(str(path))


def check_step(path: Path, surface: SweptSurface | None = None, tol: float | None = None,
               log_dir: Path | None = None) -> StepCheck:
    """Re-import a STEP file and check it (see the module docstring)."""
    from rotorflow.gmsh_session import gmsh_session

    with gmsh_session(Path(path).stem + "_check", log_dir=log_dir) as gmsh:
        occ = gmsh.model.occ
        with _quiet_stdout():
            ents = occ.importShapes(str(path))
        occ.synchronize()
        vols = [t for d, t in ents if d == 3] or [t for _, t in gmsh.model.getEntities(3)]
        # The faces' knots are the Hermite nodes: integrate span by span (exact for the
        # bicubic patches) and sample each span for the deviation.
        grid = _span_grid(surface, tol) if surface is not None and tol else None
        volume = sum(_flux_volume(gmsh, t, grid) for t in vols)
        occ_volume = sum(occ.getMass(3, t) for t in vols) * 1e-9
        faces = gmsh.model.getEntities(2)
        count: dict[int, int] = {}
        for _, f in faces:
            for _, c in gmsh.model.getBoundary([(2, f)], combined=False, oriented=False):
                count[abs(c)] = count.get(abs(c), 0) + 1
        closed = bool(count) and all(v == 2 for v in count.values())
        deviation = 0.0
        if surface is not None:
            deviation = _face_deviation(gmsh, surface, faces, grid)
    return StepCheck(len(vols), volume, occ_volume, len(faces), closed, deviation)


def _gauss(edges):
    x, w = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    edges = np.asarray(edges, dtype=float)
    h = np.diff(edges)
    t = (edges[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
    return t, (0.5 * h[:, None] * w[None, :]).ravel()


def _span_grid(surface: SweptSurface, tol: float) -> list:
    """Knot vectors of the flank faces as built, in the faces' parameter order:
    (z nodes [mm], profile nodes) per face."""
    return [(z * MM, u) for z, u in _face_nodes(surface, tol)]


def _patch_piece(lo, hi, grid) -> int | None:
    """The index of the flank face with the parameter bounds (lo, hi), if any."""
    for j, (z, u) in enumerate(grid or ()):
        if abs(lo[1] - u[0]) < 1e-9 and abs(hi[1] - u[-1]) < 1e-9 \
                and abs(lo[0] - z[0]) < 1e-6 and abs(hi[0] - z[-1]) < 1e-6:
            return j
    return None


def _edges(lo, hi, grid):
    """Span edges of a face: its patch knots if it is flank piece j, else uniform."""
    j = _patch_piece(lo, hi, grid)
    if j is not None:
        return grid[j]
    return (np.linspace(lo[0], hi[0], GAUSS_PANELS[0] + 1),
            np.linspace(lo[1], hi[1], GAUSS_PANELS[1] + 1))


def _flux_volume(gmsh, vol: int, grid=None) -> float:
    """Volume [m^3] by the divergence theorem with F = (x, y, 0) / 2 (div F = 1, no
    flux through the planar end faces), by Gauss-Legendre on the curved faces'
    parameter rectangles, span by span on the flank patches (exact there: the
    integrand is a polynomial of degree 8 in each parameter).  OCC's own mass
    properties use one rule per face (FACE_SPANS keeps them within ~1e-6 of this)."""
    total = 0.0
    for _, f in gmsh.model.getBoundary([(3, vol)], oriented=True):
        tag, sign = abs(f), (1.0 if f > 0 else -1.0)
        if gmsh.model.getType(2, tag) == "Plane":
            continue
        lo, hi = gmsh.model.getParametrizationBounds(2, tag)
        eu, ev = _edges(lo, hi, grid)
        a, wa = _gauss(eu)
        b, wb = _gauss(ev)
        A, B = np.meshgrid(a, b, indexing="ij")
        uv = np.stack([A.ravel(), B.ravel()], -1).ravel()
        x = np.asarray(gmsh.model.getValue(2, tag, uv)).reshape(-1, 3)
        d = np.asarray(gmsh.model.getDerivative(2, tag, uv)).reshape(-1, 6)
        n = np.cross(d[:, :3], d[:, 3:])
        integrand = 0.5 * (x[:, 0] * n[:, 0] + x[:, 1] * n[:, 1])
        total += sign * float(integrand @ np.outer(wa, wb).ravel())
    return abs(total) * 1e-9


def _face_deviation(gmsh, surface: SweptSurface, faces, grid) -> float:
    """Largest distance from the analytic flank of points of the curved faces: the
    midpoints and quarter points of every span of the flank patches.  A flank patch's
    parameters are the profile parameter and z [mm], so each point's foot point is
    sought from its own parameters; other faces start from the nearest point of a
    dense sampling of the flank."""
    L = surface.length
    worst = 0.0
    for _, f in faces:
        if gmsh.model.getType(2, f) in ("Plane", "Cylinder", "Cone"):
            continue
        lo, hi = gmsh.model.getParametrizationBounds(2, f)
        eu, ev = _edges(lo, hi, grid)
        q = np.array([0.25, 0.5, 0.75])
        a = (eu[:-1, None] + np.diff(eu)[:, None] * q[None, :]).ravel()
        b = (ev[:-1, None] + np.diff(ev)[:, None] * q[None, :]).ravel()
        A, B = np.meshgrid(a, b)
        uv = np.stack([A.ravel(), B.ravel()], -1).ravel()
        pts = np.asarray(gmsh.model.getValue(2, f, uv)).reshape(-1, 3) / MM
        inside = (pts[:, 2] >= 0.0) & (pts[:, 2] <= L)
        pts = pts[inside]
        if not len(pts):
            continue
        if _patch_piece(lo, hi, grid) is not None:
            u0, z0 = B.ravel()[inside], A.ravel()[inside] / MM
        else:
            u0, z0 = _nearest_start(surface, pts)
        d = foot_points(surface, pts, u0, z0, iterations=12)
        worst = max(worst, float(d.max()))
    return worst


def _nearest_start(surface: SweptSurface, pts):
    """(u, z) of the nearest points of a dense sampling of the flank."""
    from scipy.spatial import cKDTree

    u = sample(surface.curve, 1e-6)
    zg = np.linspace(0.0, surface.length, 201)
    U, Z = np.meshgrid(u, zg)
    _, i = cKDTree(surface.point(U, Z).reshape(-1, 3)).query(pts)
    return U.ravel()[i], Z.ravel()[i]
