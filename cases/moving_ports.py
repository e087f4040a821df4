"""Suction and discharge ports on the end faces of the section in motion (issue 17).

What is modelled.  The closed section (:mod:`.moving_case`) is adiabatic and has no
periodic state; with ports it is the product's *straight* internal-gear machine as long
as the slab is deep: the suction port on the back face (z = 0, the low-pressure plate)
and the discharge port on the front face (z = depth, the high-pressure plate), each
opening on its plenum.  The port shapes are the product's own (:func:`slab_ports`:
:func:`..geometry.ports.ports` of the slab's machine, built from the case file as
:mod:`.moving_quasi1d` builds it, timed by its ``case_port_timing``: suction closes at
the volume maximum, discharge opens at V_max / volume_ratio), so the quasi-1D model of
the same slab sees the same ports.  Their polygons are in the machine frame, which is
the O-grid's (outer axis at the origin, inner at (0, e)): the grid at outer angle phi
holds slot s's chamber section ``chamber_polygons(phi + s P)``, checked by
:func:`port_overlap`.

One port per end face: with a port on both faces of a one-cell slab the cell's
z-velocity would be zero by symmetry and the gas would come in by the
pressure-correction flux alone (time-step dependent, unphysical).  So the end faces are
two patches, ``back`` and ``front``, whose faces switch between port and plate by their
centre's position as the mesh turns under the fixed ports: v1912's ``exprMixed`` with a
fraction 1 / 0 by the centre's winding number about the port's outline
(:func:`boundary_fields`):

* p: in the port, where the gas leaves, the plenum's pressure; where it enters, the
  plenum's pressure less the dynamic pressure of the face's normal velocity
  (``inflow = "total"``: the plenum's gas is at rest, as stock ``totalPressure``; the
  velocity from the face's last flux, u = phi / (rho A), the incompressible form, off by
  M^2 / 4 of the correction) or the plenum's pressure (``"static"``, which lets the gas
  in without the pressure drop that accelerates it: measured through-port speeds of
  14-49 m/s on the test run, a dynamic pressure up to 1.4 % of p, the same order as a
  suction chamber's depression); zero gradient on the plate;
* T: the plenum's temperature on port faces where the gas enters (phi < 0, the flux of
  the last evaluation), zero gradient where it leaves and on the plate (the entering
  gas brings u^2 / 2 more than the plenum's enthalpy: 1.2 K of cp T at 50 m/s);
* U: zero gradient in the port, no-slip at rest on the plate.  The end plates do not
  move; the closed section lets the gas slip on them, here they drag.  Their drag in a
  sealing gap is of the order gap / depth of the rotors' own there: 1 % at 100 um,
  0.2 % at 20 um on a 10 mm slab.

A plate face has U = 0 and no pressure gradient, so no flux: the domain's mass changes
only through port faces (:func:`.moving_case.judge` checks it against the port flows).

The expression.  v1912 reads a string token of at most 1024 characters (fatal
"is too long (max. 1024 characters)", ``ISstream::read``), and ``internalField(U)`` is
not available in patch expressions.  So an outline goes into exprMixed's ``variables``
(:data:`MAX_STRING` characters each, every one adding to the one before), in mm.  The
winding number (nonzero rule: Clipper's outlines run counter-clockwise, holes
clockwise, so a hole's ring takes away) is summed over the outline's y-monotone chains
(:func:`chain_winding`): a chain from y0 up to y1 counts +1 (down: -1) where
y0 <= y < y1 and the point lies left of it, x < x(y), the chain's abscissa written as
hinges x0 + k0 (y - y0) + sum_i dk_i max(y - y_i, 0).  That is the winding number of
the angle sum over the edges (:func:`winding`: sum atan2(cross, dot) / 2 pi, the numpy
side's test); ~4 field operations per vertex against ~16 and an atan2.  Measured on the
closed 512 x 4 case, p only, 211 vertices on 4096 end faces, 50 steps: 1.07 s without,
4.28 s with the angle sum, 2.91 s with the edge crossing number, 1.49 s with the chains.
The conditions are evaluated 9 times a step (p 4, U 4, T 1: v1912 keeps nothing between
evaluations, the variables included): on the ported 512 x 4 run (211 + 134 vertices on
2 x 2048 faces) 16.6 ms a step, against the solver's own 16-20 ms (the same run with
half-plane ports: 8.0 s for 512 steps, 16.5 s with the outlines evaluated alongside).

The outline is Clipper's ``simplify`` of the port (:data:`SIMPLIFY_M`, well below a
face of the grid) with its vertices rounded to :data:`ROUND_M`; that one outline is used
by the expression, the numpy tests and whatever model is compared with the run (the
simplification's area change is recorded by :func:`outline`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rotorflow.errors import CaseError

PATCHES = ("back", "front")  # suction (z = 0), discharge (z = depth)
#: Clipper's simplification of the outline (m): the default pair's suction port has
#: 1,581 vertices; at 50 um 211 (area -0.06 %, symmetric difference 0.2 %), the
#: discharge 1,016 -> 134 (-0.1 %, 0.4 %); at 100 um 103 and 84 (symmetric differences
#: 0.4 % and 0.8 %), which would halve the expressions' cost.  A face of the 512 x 4
#: grid is 0.57 mm wide along the walls (median; 0.18-0.97 mm, 10-90 %) and 0.5 mm
#: (median) to 4 mm across.
SIMPLIFY_M = 5e-5
#: Outline vertices are rounded to this (m), so that the expression's constants (mm,
#: three decimals) are the outline's vertices exactly.
ROUND_M = 1e-6
#: Longest variable string written (v1912's limit is 1024 characters).
MAX_STRING = 1000
INFLOW = ("total", "static")


@dataclass(frozen=True)
class SectionPorts:
    """The ports of the section: outlines (rings of (x, y), m, machine frame, outer
    rings counter-clockwise, holes clockwise) and the plenums' p (Pa) and T (K)."""

    suction: tuple
    discharge: tuple
    p_suction: float
    T_suction: float
    p_discharge: float
    T_discharge: float
    inflow: str = "total"  # or "static": the port's pressure where the gas enters

    def check(self) -> None:
        if not (self.suction and self.discharge):
            raise CaseError("a ported section needs both a suction and a discharge outline")
        if not min(self.p_suction, self.T_suction, self.p_discharge, self.T_discharge) > 0:
            raise CaseError("the plenums' pressures and temperatures must be positive")
        if self.inflow not in INFLOW:
            raise CaseError(f"port inflow {self.inflow!r} is not one of {', '.join(INFLOW)}")

    def key(self) -> dict:
        return {"suction": _rounded(self.suction), "discharge": _rounded(self.discharge),
                "plenums": [self.p_suction, self.T_suction, self.p_discharge,
                            self.T_discharge], "inflow": self.inflow}


def _rounded(rings) -> list:
    return [np.round(np.asarray(r, float) / ROUND_M).astype(int).tolist() for r in rings]


def _ring_area(q: np.ndarray) -> float:
    return 0.5 * float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - q[:, 1] * np.roll(q[:, 0], -1)))


def outline(region, tol: float = SIMPLIFY_M) -> tuple[tuple, dict]:
    """(rings, what it cost) of a manifold3d CrossSection: simplified by ``tol`` and
    rounded to :data:`ROUND_M`; the cost as the relative area change and the symmetric
    difference against the region, over the region's area."""
    from manifold3d import CrossSection, FillRule

    rings = []
    for q in region.simplify(tol).to_polygons():
        q = np.round(np.asarray(q, float) / ROUND_M) * ROUND_M
        q = q[np.any(q != np.roll(q, 1, 0), axis=1)]  # rounding may merge neighbours
        if len(q) >= 3 and _ring_area(q) != 0.0:
            rings.append(q)
    got = CrossSection([np.ascontiguousarray(q) for q in rings], FillRule.NonZero)
    area = region.area()
    info = {"vertices": [sum(len(q) for q in region.to_polygons()),
                         sum(len(q) for q in rings)],
            "area_m2": area, "area_change": got.area() / area - 1.0,
            "symmetric_difference": ((got - region).area() + (region - got).area()) / area}
    return tuple(tuple(map(tuple, q.tolist())) for q in rings), info


def slab_machine(pair, depth: float, gap: float, gas, raw: dict, where: Path, case_of):
    """(case, SweptMachine, PortTiming) of the slab of the case file ``raw``: its pair,
    straight, ``depth`` long, clearance ``gap``, the CFD's perfect ``gas``
    (:func:`.moving_quasi1d.slab_raw`, as the closed-section model builds it;
    ``case_of`` is the workflow's case_from_raw), timed by the case
    (``case_port_timing``).  The case's pair must be the section's ``pair``."""
    from rotorflow.geometry.summary import build_machine, case_port_timing

    from .moving_quasi1d import slab_raw

    case = case_of(slab_raw(raw, depth, gap, gas), Path(where))
    if case.pair.digest() != pair.digest():
        raise CaseError(f"the case file's pair ({case.pair.digest()}) is not the section's "
                        f"({pair.digest()})")
    machine = build_machine(case)
    return case, machine, case_port_timing(case, machine)


def slab_ports(pair, depth: float, gap: float, gas, raw: dict, where: Path, case_of,
               tol: float = SIMPLIFY_M) -> tuple[SectionPorts, dict]:
    """(ports, what was built) of the slab (:func:`slab_machine`): the product's port
    shapes as outlines (:func:`outline`); the plenums the case's [operating] suction
    state and discharge pressure, the discharge gas as the quasi-1D model's plenum holds
    it (:func:`rotorflow.quasi1d.plenums.plenums`)."""
    from rotorflow.geometry.ports import ports
    from rotorflow.quasi1d.plenums import plenums
    from rotorflow.quasi1d.simulate import case_settings

    case, machine, timing = slab_machine(pair, depth, gap, gas, raw, where, case_of)
    suction, discharge = ports(machine, timing)
    op = case_settings(case.raw, str(where))[0]
    suc, dis = plenums(op.constant_cp_gas, op)  # slab_raw: the CFD's perfect gas
    rings, info = {}, {"timing_deg": {k: math.degrees(v) for k, v in vars(timing).items()}}
    for name, region in (("suction", suction), ("discharge", discharge)):
        rings[name], info[name] = outline(region, tol)
    return SectionPorts(rings["suction"], rings["discharge"], suc.p, suc.T, dis.p,
                        dis.T), info


def winding(rings, xy: np.ndarray) -> np.ndarray:
    """Winding number of the outline about each point: the sum over the edges (a, b) of
    atan2(cross(a - p, b - p), dot(a - p, b - p)) / 2 pi."""
    xy = np.asarray(xy, float)
    total = np.zeros(len(xy))
    for q in rings:
        for k in range(0, len(xy), 4096):  # (points, vertices) arrays a few MB each
            a = np.asarray(q, float)[None, :, :] - xy[k:k + 4096, None, :]
            b = np.roll(a, -1, axis=1)
            total[k:k + 4096] += np.arctan2(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
                                            np.sum(a * b, -1)).sum(1)
    return total / (2.0 * math.pi)


def inside(rings, xy: np.ndarray) -> np.ndarray:
    return winding(rings, xy) > 0.5


def chains(ring) -> list[tuple[int, np.ndarray]]:
    """The ring's y-monotone chains, [(+1 up / -1 down, vertices (n, 2) by rising y)];
    level edges are left out (they cross no level)."""
    q = np.asarray(ring, float)
    n = len(q)
    dy = np.sign(np.roll(q[:, 1], -1) - q[:, 1]).astype(int)
    moving = np.flatnonzero(dy)
    # start where the direction turns, so no chain wraps past the start
    first = next(i for k, i in enumerate(moving) if dy[i] != dy[moving[k - 1]])
    out: list = []
    for i in ((first + k) % n for k in range(n)):
        if dy[i] == 0:
            continue
        if out and out[-1][0] == dy[i] and out[-1][1][-1] == i:
            out[-1][1].append((i + 1) % n)
        else:
            out.append((dy[i], [i, (i + 1) % n]))
    return [(s, q[idx] if s > 0 else q[idx[::-1]]) for s, idx in out]


def _hinges(pts: np.ndarray) -> tuple[float, float, np.ndarray, np.ndarray]:
    """(x0, y0, knots y_i, slopes): x(y) = x0 + sum_i slope_i max(y - y_i, 0) with the
    first knot at y0, on a chain by rising y."""
    k = np.diff(pts[:, 0]) / np.diff(pts[:, 1])
    return float(pts[0, 0]), float(pts[0, 1]), pts[:-1, 1], np.diff(k, prepend=0.0)


def chain_winding(rings, xy: np.ndarray) -> np.ndarray:
    """:func:`winding` as the expression computes it (the module docstring), in numpy."""
    xy = np.asarray(xy, float)
    x, y = xy[:, 0], xy[:, 1]
    total = np.zeros(len(xy))
    for q in rings:
        for s, pts in chains(q):
            x0, _, knots, slopes = _hinges(pts)
            xc = x0 + np.maximum(y[:, None] - knots[None, :], 0.0) @ slopes
            total += s * ((y >= pts[0, 1]) & (y < pts[-1, 1]) & (x < xc))
    return total


def _mm(v: float) -> str:
    return f"{v * 1e3:.3f}"


def _chain_term(s: int, pts: np.ndarray) -> str:
    x0, y0, knots, slopes = _hinges(pts)
    xs = _mm(x0) + "".join(f"+{k:.15g}*max(v-{_mm(y)},0)" for y, k in zip(knots, slopes,
                                                                            strict=True)
                           if k != 0.0)
    term = f"(v>={_mm(y0)}&&v<{_mm(pts[-1, 1])}&&u<{xs}?{s}:0)"
    return term.replace("+-", "-").replace("--", "+")


def _terms(rings) -> list[str]:
    """One term per chain, a chain cut at a vertex where its term would be too long
    (the two halves count the same: y0 <= y < y_i and y_i <= y < y1)."""
    out = []
    for q in rings:
        for s, pts in chains(q):
            i = 0
            while i < len(pts) - 1:
                j = len(pts)
                while len(term := _chain_term(s, pts[i:j])) > MAX_STRING - 20:
                    j = i + (j - i) // 2 + 1
                out.append(term)
                i = j - 1
    return out


def expression(rings) -> tuple[list[str], str]:
    """(variable strings, name of the winding number's variable) of an outline: u, v
    the face centre in mm, then the chains' terms summed into w0, w1, ... (each string
    at most :data:`MAX_STRING` characters)."""
    out = ["u=1e3*pos().x()", "v=1e3*pos().y()"]
    cur, k = "", 0
    for t in _terms(rings):
        if not cur:
            cur = f"w{k}=" + (f"w{k - 1}+" if k else "") + t
        elif len(cur) + 1 + len(t) <= MAX_STRING:
            cur += "+" + t
        else:
            out.append(cur)
            k += 1
            cur = f"w{k}=w{k - 1}+{t}"
    out.append(cur or "w0=0")
    if max(map(len, out)) > MAX_STRING:
        raise CaseError("a port outline's expression does not fit v1912's strings")
    return out, f"w{k}"


def _q(text: str) -> str:
    return f'"{text}"'


def boundary_fields(ports: SectionPorts, p0: float, T0: float) -> dict:
    """{field: {patch: condition}} of p, T and U on ``back`` (suction) and ``front``
    (discharge): the module docstring's exprMixed conditions, their values at the start
    those of the gas at rest (``p0``, ``T0``) until the first evaluation."""
    out: dict = {"p": {}, "T": {}, "U": {}}
    for patch, rings, p, T in (("back", ports.suction, ports.p_suction, ports.T_suction),
                               ("front", ports.discharge, ports.p_discharge,
                                ports.T_discharge)):
        variables, w = expression(rings)
        port = f"{w}>0.5"

        def mixed(value, value_expr, grad_expr, fraction, variables=variables):
            return {"type": "exprMixed", "value": value, "valueExpr": _q(value_expr),
                    "gradientExpr": _q(grad_expr), "fractionExpr": _q(fraction),
                    "variables": [_q(v) for v in variables]}

        dynamic = "-((phi<0)?0.5*sqr(phi/area())/rho:0)" if ports.inflow == "total" else ""
        out["p"][patch] = mixed(p0, f"{p!r}{dynamic}", "0", f"({port})?1:0")
        out["T"][patch] = mixed(T0, f"{T!r}", "0", f"({port}&&phi<0)?1:0")
        out["U"][patch] = mixed(np.zeros(3), "vector(0,0,0)", "vector(0,0,0)",
                                f"({port})?0:1")
    return out


def end_patches(xy: np.ndarray, end: str):
    """:func:`.polymesh.build_polymesh`'s end-face namer: z = 0 is ``back``, the top
    ``front``; plain patches (their plate faces are walls by their condition)."""
    name = PATCHES[0] if end == "lp" else PATCHES[1]
    return np.full(len(xy), name), {name: "patch"}


def face_centres(points: np.ndarray, mesh, patch: str) -> tuple[np.ndarray, np.ndarray]:
    """(centres (x, y), areas) of a patch's faces with the mesh's nodes at ``points``
    (the polyMesh's, e.g. moved): the quads' centroids, as OpenFOAM's for a plane quad."""
    _, faces, _, _, patches = mesh
    _, _, start, count = next(p for p in patches if p[0] == patch)
    q = np.asarray(points)[faces[start:start + count]][..., :2]
    a, b, c, d = (q[:, i] for i in range(4))
    t1 = 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    t2 = 0.5 * ((c - a)[:, 0] * (d - a)[:, 1] - (c - a)[:, 1] * (d - a)[:, 0])
    centre = ((a + b + c) * t1[:, None] + (a + c + d) * t2[:, None]) / (3.0 * (t1 + t2))[:, None]
    return centre, np.abs(t1 + t2)


def _centroid(rings) -> np.ndarray:
    q = [np.asarray(r, float) for r in rings]
    cross = [r[:, 0] * np.roll(r[:, 1], -1) - np.roll(r[:, 0], -1) * r[:, 1] for r in q]
    moment = sum(((r + np.roll(r, -1, 0)) * c[:, None]).sum(0) for r, c in zip(q, cross,
                                                                             strict=True))
    return moment / (3.0 * sum(c.sum() for c in cross))


def port_overlap(s, grid, phi: float, machine, port: str = "suction") -> dict:
    """The frame check on the O-grid ``grid`` of outer angle ``phi``: per slot, the
    product's chamber section at ``phi + slot P`` inside the ``port``'s outline against
    the end faces (back: suction, front: discharge) inside the outline whose cells are the slot's
    (:func:`.moving_case.chamber_cells`, gap columns left out): {slot: {"exact",
    "cfd": areas, m2; "band": the area of the slot's faces which the boundary of
    section and outline cuts (not all four corners on one side), about the most the two
    can differ by resolution (the grid's walls, relieved by the clearance, lie outside
    the section's profiles: the faces along them are in it); "offset": the distance
    between the two regions' centroids, m}}.  A frame turned by 1 deg moves a
    centroid 0.4-0.8 mm on the default pair."""
    from manifold3d import CrossSection, FillRule

    from rotorflow.geometry.ports import chamber_section

    from .moving_case import chamber_cells
    from .polymesh import build_polymesh

    mesh = build_polymesh([grid, grid], np.array([0.0, s.depth]), end_patches)
    pts, faces, owner, _, patches = mesh
    patch = PATCHES[0] if port == "suction" else PATCHES[1]
    rings = getattr(s.ports, port)
    _, _, start, count = next(p for p in patches if p[0] == patch)
    centre, area = face_centres(pts, mesh, patch)
    corners = pts[faces[start:start + count]][..., :2]
    owner = owner[start:start + count]
    hit = inside(rings, centre)
    port = CrossSection([np.ascontiguousarray(q) for q in map(np.asarray, rings)],
                        FillRule.NonZero)
    out = {}
    for slot, c in chamber_cells(s, grid, phi)[0].items():
        polys = chamber_section(machine, phi + slot * float(s.pair.period))
        rings = (CrossSection([np.ascontiguousarray(q) for q in polys], FillRule.Positive)
                 ^ port).to_polygons() if polys else []
        mine = np.isin(owner, c)
        if not rings or not (mine & hit).any():
            continue
        k = inside(rings, corners.reshape(-1, 2)).reshape(-1, 4).sum(1)
        sel = mine & hit
        cfd = (centre[sel] * area[sel, None]).sum(0) / area[sel].sum()
        out[slot] = {"exact": sum(map(_ring_area, map(np.asarray, rings))),
                     "cfd": float(area[sel].sum()),
                     "band": float(area[mine & (k > 0) & (k < 4)].sum()),
                     "offset": float(np.linalg.norm(cfd - _centroid(rings)))}
    return out
