"""The rotors' wall velocity for the section in motion (issue 17): each rotor's own
surface velocity omega x r tangentially, the mesh's motion normally, so that no gas
crosses a wall to round-off.

Why not a stock wall condition as it stands.  ``movingWallVelocity`` imposes the face
centres' velocity, i.e. the grid's *sliding* velocity (its nodes slide along the walls as
the angle changes: 11 % / 31 % of the tip speed RMS off omega x r).
``rotatingWallVelocity`` zeroes the normal part, which passes gas through a non-circular
moving wall; omega x r itself (tried with ``exprFixedValue``) has the true wall's normal
velocity, not the polygonal mesh's, and lets 1e-5 of the mass through the walls in 0.5
deg.  A condition computing omega x r plus the mesh flux's normal part needs compiled
code (``codedFixedValue``: Debian's v1912 ships no headers nor wmake), and ``meshPhi`` is
not a registered field an expression could read.

What is done instead.  Between key frames every node moves at a constant velocity (the
frames are linearly interpolated in time), so the mesh flux of a wall face is known in
closed form: with the face's edge e(t) = b - a in the plane, its nodes' velocities
va, vb, vbar = (va + vb) / 2 and dv = vb - va, the area swept per unit depth over a step
[t - dt, t] is dt vbar . perp(e(t) - dt dv / 2).  OpenFOAM's flux of the wall velocity
U(t) is U(t) . perp(e(t)) per unit depth; both agree for every step of a *fixed* dt when

    U(t) = vbar + lam dv + sig e(t),   lam = -(dt / 2) vbar . perp(dv) / (dv . perp(e0))

(e . perp(e) = 0 makes sig free, dv . perp(dv) = 0 makes the dt term constant).  U is
linear in time within an interval, so ``timeVaryingMappedFixedValue`` (``mapMethod
nearest`` on the faces' own centres) reproduces it exactly from two samples per interval;
``sig`` sets the tangential part to omega x r at the interval's middle.  dv . perp(e0)
is the face's turning rate, about -omega |e|^2 on a rotor, never near zero.

Requires a fixed time step that divides the key-frame interval (``steps_per_frame``):
without the dt term (an adjustable step) the error has one sign at every frame (a
polygon turned by theta with its nodes on chords dips in area by theta^2 / 4 between
frames), of the order of A theta^2 dt / T per frame: ~1e-7 of the mass at 0.25 deg
frames, an estimate, not measured.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Sample just after a frame time, as a fraction of the fixed step: no step ends between
#: a frame and this sample, where the mapped condition would blend two intervals.
AFTER_FRAME = 0.5


def _perp(v: np.ndarray) -> np.ndarray:
    return np.stack([-v[..., 1], v[..., 0]], -1)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, -1)


def wall_edges(mesh, patch: str) -> np.ndarray:
    """The two in-plane node numbers (first plane of the slab) of each face of
    ``patch``, in the patch's face order."""
    pts, faces, _, _, patches = mesh
    name, _, start, count = next(p for p in patches if p[0] == patch)
    f = faces[start:start + count]
    low = pts[f][..., 2] == pts[:, 2].min()  # the plane z = 0
    return f[low].reshape(count, 2)


def interval_velocity(x0: np.ndarray, x1: np.ndarray, edges: np.ndarray, T: float,
                      dt: float, omega: float, axis) -> tuple[np.ndarray, np.ndarray]:
    """(U at the interval's start, dU/dt) of every face of ``edges`` for one key-frame
    interval of length ``T`` in which the nodes move from ``x0`` to ``x1`` (2D), with
    the fixed step ``dt``: the module docstring's U(t), tangential part omega x r about
    ``axis`` at the interval's middle."""
    a0, b0 = x0[edges[:, 0]], x0[edges[:, 1]]
    va, vb = (x1[edges[:, 0]] - a0) / T, (x1[edges[:, 1]] - b0) / T
    vbar, dv, e0 = 0.5 * (va + vb), vb - va, b0 - a0
    lam = -0.5 * dt * _dot(vbar, _perp(dv)) / _dot(dv, _perp(e0))
    base = vbar + lam[:, None] * dv
    em = e0 + 0.5 * T * dv
    cm = 0.5 * (a0 + b0) + 0.5 * T * vbar
    rigid = omega * _perp(cm - np.asarray(axis, float))
    sig = _dot(rigid - base, em) / _dot(em, em)
    return base + sig[:, None] * e0, sig[:, None] * dv


def wall_samples(frames: list, times: np.ndarray, edges: np.ndarray, dt: float,
                 omega: float, axis) -> tuple[np.ndarray, np.ndarray]:
    """(sample times, U at each, (samples, faces, 2)): at every interval's start (its
    first interval only), just after it (:data:`AFTER_FRAME`) and at its end."""
    ts, us = [], []
    for k in range(len(frames) - 1):
        T = float(times[k + 1] - times[k])
        u0, du = interval_velocity(frames[k], frames[k + 1], edges, T, dt, omega, axis)
        taus = (0.0, AFTER_FRAME * dt, T) if k == 0 else (AFTER_FRAME * dt, T)
        for tau in taus:
            ts.append(float(times[k]) + tau)
            us.append(u0 + tau * du)
    return np.array(ts), np.stack(us)


def write_boundary_data(case_dir: Path, patch: str, centres: np.ndarray, times,
                        values: np.ndarray, field: str = "U") -> None:
    """``constant/boundaryData/<patch>``: the sample points (the faces' centres at the
    start, which ``mapMethod nearest`` maps onto themselves) and the field at every
    sample time."""
    root = Path(case_dir) / "constant" / "boundaryData" / patch
    root.mkdir(parents=True, exist_ok=True)

    def vectors(v):
        return f"{len(v)}\n(\n" + "\n".join(
            f"({x:.17g} {y:.17g} {z:.17g})" for x, y, z in v) + "\n)\n"

    (root / "points").write_text(vectors(centres))
    for t, u in zip(times, values, strict=True):
        folder = root / f"{t:.17g}"
        folder.mkdir(exist_ok=True)
        (folder / field).write_text(vectors(np.column_stack([u, np.zeros(len(u))])))


def check(frames: list, times: np.ndarray, edges: np.ndarray, dt: float, omega: float,
          axis, steps: int, built_for: float | None = None) -> dict:
    """The imposed wall velocity at the end of every step of every interval, against
    (a) the mesh: its flux per unit depth U . perp(e(t)) and the exact area swept over
    the step (the shoelace of the face's old and new edge), largest difference over the
    tip speed times the face length; (b) omega x r at the face's centre: largest and RMS
    tangential difference over the tip speed.  ``built_for``: the step the velocity is
    built for, if not ``dt`` (what an adjustable step would do)."""
    flux, tang, tip = [], [], 0.0
    axis = np.asarray(axis, float)
    for k in range(len(frames) - 1):
        T = float(times[k + 1] - times[k])
        u0, du = interval_velocity(frames[k], frames[k + 1], edges, T, built_for or dt,
                                   omega, axis)
        x0, x1 = frames[k], frames[k + 1]
        for j in range(1, steps + 1):
            tau = j * dt
            old = x0 + (x1 - x0) * ((tau - dt) / T)
            new = x0 + (x1 - x0) * (tau / T)
            a, b, ao, bo = new[edges[:, 0]], new[edges[:, 1]], old[edges[:, 0]], old[edges[:, 1]]
            e = b - a
            c = 0.5 * (a + b)
            # about the old node a: the shoelace's round-off scales with the coordinates
            a, b, bo, ao = a - ao, b - ao, bo - ao, ao - ao
            u = u0 + tau * du
            # signed area swept by the edge from (ao, bo) to (a, b), same sense as perp(e)
            swept = 0.5 * (_cross(ao, bo) + _cross(bo, b) + _cross(b, a) + _cross(a, ao))
            flux.append((_dot(u, _perp(e)) * dt - swept) / (dt * np.linalg.norm(e, axis=1)))
            rigid = omega * _perp(c - axis)
            t_hat = e / np.linalg.norm(e, axis=1)[:, None]
            tang.append(_dot(u - rigid, t_hat))
            tip = max(tip, abs(omega) * float(np.linalg.norm(c - axis, axis=1).max()))
    flux_d, tang_d = np.concatenate(flux), np.concatenate(tang)
    return {"normal_max": float(np.abs(flux_d).max()) / tip,
            "tangential_max": float(np.abs(tang_d).max()) / tip,
            "tangential_rms": float(np.sqrt(np.mean(tang_d**2))) / tip, "tip_speed": tip}


def _cross(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
