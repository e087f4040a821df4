"""The "cfd-calibrated" leakage correlation: a flow coefficient Cd(Re, PR, L/h, V) of the
isentropic nozzle, fitted to CFD of clearance gaps and loaded from its JSON file.

The quasi-1D model evaluates it (:meth:`FlowCoefficientFit.reduced_flux`); the fitting, the
comparison with CFD and the report live in the post-processing (``postprocess.leakage``).

Definitions (SI):
    pressure ratio    PR = p_up / p_down (upstream total over downstream static)
    ideal flow        m_id = h * isentropic nozzle flux(p_up, T_up -> p_down), h the
                      minimum gap: what a loss-free nozzle of that throat passes
    flow coefficient  Cd = m / m_id
    Reynolds number   Re = m_id / mu(T_up), the ideal flow's gap Reynolds number
                      rho U h / mu: known before the flow is, so a correlation in it can
                      be evaluated directly by the quasi-1D model
    gap length        L: the stretch where the gap is at most twice its minimum (a
                      parallel channel: its length)
    wall speed        U: mean of the two walls' speeds along the flow (from upstream to
                      downstream), in the frame where the gap keeps its shape (at a
                      sealing line: relative to the moving contact point)
    wall speed ratio  V = U sqrt(rho_up / p_up) = U / sqrt(R T_up)
    Couette parameter W = rho_c U h / m_id = V kappa(PR) / psi, the flow the walls drag
                      through the gap over the ideal flow, with rho_c = kappa rho_up,
                      kappa = (2/3) (1 - PR^-3) / (1 - PR^-2) (-> 1 at PR -> 1): the density
                      that carries the drag flow of isothermal lubrication flow
    correlation       A Cd|Cd| + b X (Cd - w W) = 1 with A = sum_i a_i phi_i(PR) (phi: "1",
                      "ln(PR)", "1/PR"), X = 24 (L/h) psi^2 / (Re (1 - PR^-2)),
                      psi = m_id / (h sqrt(p_up rho_up)); so with q = 1 + b w X W,
                      Cd = 2 q / (bX + sqrt((bX)^2 + 4 A |q|)); w = 0 for static walls
                      (and in fits saved before the wall term existed)
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .flows import nozzle_psi

#: The definitions above, stored with every fit so a JSON file explains itself.
DEFINITIONS = " ".join(__doc__.split("Definitions (SI):")[1].split())


# A gap is a nozzle and a channel in series.  For incompressible flow the pressure drop is
# the sum of a loss m^2 / (2 rho h^2 Cd0^2) and a laminar friction 12 mu L m / (rho h^3),
# which in terms of Cd = m / m_id reads
#
#     A Cd^2 + b X Cd = 1,    A = 1 / Cd0^2,    X = 24 (L/h) / Re,
#
# with Cd0 the inviscid coefficient and b = 1 for a plane channel of length L.  For a
# compressible gap the isothermal lubrication flow replaces the friction term, which
# turns X into 24 (L/h) psi^2 / (Re (1 - 1/PR^2)), psi the nozzle's dimensionless flux
# (m_id = h psi sqrt(p_up rho_up)); at PR -> 1 both forms agree.  The fit finds b (how
# long the curved gap is in effect, relative to L) and A as a linear function of
# INERTIAL_FEATURES of the pressure ratio; both enter linearly, so it is least squares.
#
# Walls sliding along the flow at mean speed U drag rho U h through a channel whatever
# the pressure (Couette flow): the friction loss acts on the pressure-driven part only,
#
#     A Cd|Cd| + b X (Cd - w W) = 1,    W = rho_c U h / m_id,
#
# with w = 1 for a plane channel (4/3 for the parabolic throat of two cylinders, whose
# drag flow is U h_min I2/I3 with I_n = integral of h^-n) and rho_c the density that
# carries the drag flow (drag_density_ratio).  In the viscous limit Cd = 1/(bX) + w W,
# lubrication theory's pressure flow plus drag flow; in the inertial limit the walls do
# nothing.  b w is one more linear coefficient (of -X W), so the fit stays least squares.
# Cd|Cd| keeps the loss opposed to the flow when walls running backwards reverse it.

#: Functions of the pressure ratio whose combination is 1 / Cd0^2 of the inviscid part.
INERTIAL_FEATURES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "1": np.ones_like,
    "ln(PR)": np.log,
    "1/PR": np.reciprocal,
}

DEFAULT_INERTIAL = ("1", "ln(PR)")


def drag_density_ratio(pressure_ratio):
    """kappa = rho_c / rho_up = (2/3) (1 - PR^-3) / (1 - PR^-2), in (2/3, 1].

    In isothermal lubrication flow between walls moving at U, m' R T = -h^3 p p' / (12 mu)
    + U h p; to first order in U the walls add U h rho_c to the pressure flow, rho_c the
    mean of p^2 over the mean of p across the pressure drop, over R T.
    """
    r = 1.0 / np.asarray(pressure_ratio, dtype=float)
    near = np.abs(1.0 - r) < 1e-6  # the 0/0 limit: (2/3)(1 + r + r^2)/(1 + r) -> 1
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = np.where(near, 1.0, (2.0 / 3.0) * (1.0 - r**3) / (1.0 - r**2))
    return kappa


def couette_parameter(wall_speed_ratio, pressure_ratio, gamma: float = 1.4):
    """W = V kappa(PR) / psi(PR): the wall-dragged flow rho_c U h over the ideal flow."""
    pr = np.asarray(pressure_ratio, dtype=float)
    return np.asarray(wall_speed_ratio, dtype=float) * drag_density_ratio(pr) / nozzle_psi(
        1.0 / pr, gamma)


def lubrication_ratio(pressure_ratio, gamma: float = 1.4):
    """Y = psi^2 / (1 - PR^-2), so that X = 24 (L/h) Y / Re.

    Both psi^2 and 1 - PR^-2 vanish like 2 (1 - 1/PR) at PR -> 1, where Y -> 1; written
    as a ratio of expm1 terms (psi^2 is :func:`~.flows.nozzle_psi` squared, rearranged)
    it is evaluated without the 0/0 (and Y = 1 at PR = 1).
    """
    pr = np.asarray(pressure_ratio, dtype=float)
    c = (gamma - 1.0) / gamma
    t = -np.log(pr)  # ln(1/PR) <= 0
    tx = np.maximum(t, math.log((2 / (gamma + 1)) ** (1.0 / c)))  # choked below x_cr
    # psi^2 = 2/c x^(2/gamma) (1 - x^c) with x = exp(tx)
    num = (2.0 / c) * np.exp(2.0 * tx / gamma) * -np.expm1(c * tx)
    den = -np.expm1(2.0 * t)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0.0, num / den, 1.0)


def viscous_parameter(reynolds, pressure_ratio, length_over_gap, gamma: float = 1.4):
    """X = 24 (L/h) psi^2 / (Re (1 - 1/PR^2)): Cd of laminar lubrication flow is 1 / X."""
    pr = np.asarray(pressure_ratio, dtype=float)
    return (24 * np.asarray(length_over_gap, dtype=float) * nozzle_psi(1.0 / pr, gamma) ** 2
            / (np.asarray(reynolds, dtype=float) * (1 - pr**-2.0)))


@dataclass(frozen=True)
class FlowCoefficientFit:
    """Cd(Re, PR, L/h, V) from A(PR) Cd|Cd| + b X (Cd - w W) = 1 (see the comment above)."""

    inertial_features: tuple[str, ...]
    inertial: tuple[float, ...]
    """Coefficients of A = sum_i a_i phi_i(PR) = 1 / Cd0^2."""
    viscous: float
    """b: the friction of the gap relative to a plane channel of length L."""
    gamma: float = 1.4
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)
    """The range of Re, PR, L/h and V the fit saw; outside it Cd is an extrapolation."""
    leave_out_errors: tuple[float, ...] = ()
    """Mass-flow errors of each point predicted by a fit without it (model/CFD - 1)."""
    definitions: str = DEFINITIONS
    wall: float = 0.0
    """w: the wall-dragged flow relative to rho_c U h_min (0: walls not fitted)."""
    leave_out_moving: tuple[bool, ...] = ()
    """Which of the leave_out_errors belong to points with moving walls."""

    def flow_coefficient(self, reynolds, pressure_ratio, length_over_gap,
                         wall_speed_ratio=0.0):
        """Cd at gap Reynolds number, pressure ratio, L/h and wall speed ratio
        V = U sqrt(rho_up / p_up) (U along the flow; 0: static walls)."""
        pr = np.asarray(pressure_ratio, dtype=float)
        a = self._inertial(pr)
        b = self.viscous * viscous_parameter(reynolds, pr, length_over_gap, self.gamma)
        q = 1.0
        if self.wall != 0.0 and np.any(np.asarray(wall_speed_ratio) != 0.0):
            q = 1.0 + self.wall * b * couette_parameter(wall_speed_ratio, pr, self.gamma)
        # The root of A Cd|Cd| + b Cd = q with the sign of q, free of cancellation.
        cd = 2.0 * q / (b + np.sqrt(b * b + 4.0 * a * np.abs(q)))
        return float(cd) if np.ndim(cd) == 0 else cd

    def _inertial(self, pr):
        """A(PR): the inertial coefficient of the fit."""
        return sum(c * INERTIAL_FEATURES[f](pr) for f, c in zip(self.inertial_features,
                                                                self.inertial, strict=True))

    def reduced_flux(self, psi, pressure_ratio, viscous_number, wall_speed_ratio=None,
                     reverse_density_ratio=None):
        """G = Cd psi = m' / (h sqrt(p_up rho_up)): the fit's mass flow in a form that stays
        finite through PR -> 1, for models that evaluate it at every pressure ratio.

        ``psi``: the nozzle flux of the caller (m_id = h psi sqrt(p_up rho_up));
        ``viscous_number``: K = 24 L mu / (h^2 sqrt(p_up rho_up)), so that X psi = K Y with
        Y = lubrication_ratio(PR); ``wall_speed_ratio``: V = U sqrt(rho_up / p_up), U the
        mean wall speed from upstream to downstream (None: static walls).  The correlation
        times psi^2 reads

            A G|G| + b K Y G = psi^2 + b w K Y kappa V,

        every term finite at PR = 1.  There, with moving walls, the flow is the drag flow
        G = 2 b w K V / (b K + sqrt((b K)^2 + 4 A b w K |V|)), which tends to w V (m' = w
        rho U h) when friction dominates; G is odd in V, so the flow keeps its direction
        when the upstream side changes at equal pressures.  With psi = nozzle_psi(1/PR, gamma)
        (:mod:`~.flows`) this is exactly flow_coefficient(Re, PR, L/h, V) * psi
        (Re = h psi sqrt(p rho) / mu).

        ``reverse_density_ratio``: rho_down / rho_up.  Where the walls drive the flow
        against the pressure difference (the right-hand side above < 0), the gas that
        enters the gap is the downstream side's; the correlation is then evaluated with
        that density at p_up (K and V change with it, the right-hand side does not, so the
        flow stays continuous: it is zero where it turns).  At equal pressures the flow
        is then the drag flow of the side the walls drag from, whichever side counts as
        upstream.  None: rho_up throughout (the CFD points have one temperature on both
        sides and cannot tell).
        """
        pr = np.asarray(pressure_ratio, dtype=float)
        psi = np.asarray(psi, dtype=float)
        a = self._inertial(pr)
        bky = self.viscous * np.asarray(viscous_number, dtype=float) * lubrication_ratio(
            pr, self.gamma)
        q = psi * psi
        if self.wall != 0.0 and wall_speed_ratio is not None:
            q = q + self.wall * bky * drag_density_ratio(pr) * np.asarray(wall_speed_ratio,
                                                                           dtype=float)
        sr = 1.0
        if reverse_density_ratio is not None:
            # rho = r rho_up: K / sqrt(r) and V sqrt(r), a flux sqrt(r) times as large
            sr = np.where(q < 0.0, np.sqrt(reverse_density_ratio), 1.0)
            bky = bky / sr
        den = bky + np.sqrt(bky * bky + 4.0 * a * np.abs(q))
        # den = 0 only without friction and without flow (b = 0, psi = 0): G = 0 there.
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.where(den > 0.0, 2.0 * q / den, 0.0) * sr
        return float(g) if np.ndim(g) == 0 else g

    def model(self) -> Callable[[Any], float]:
        """The fit as a leakage model: mass flow per metre of gap depth of a
        ``postprocess.leakage.LeakagePoint``, for the comparison with CFD."""
        return lambda p: p.ideal_mass_flow * self.flow_coefficient(
            p.reynolds, p.pressure_ratio, p.length_over_gap, p.wall_speed_ratio)

    def leave_out_summary(self) -> dict[str, dict[str, float | int]]:
        """Max and RMS left-out errors of all points, static and moving walls apart."""
        err = np.asarray(self.leave_out_errors, dtype=float)
        moving = (np.asarray(self.leave_out_moving, dtype=bool) if self.leave_out_moving
                  else np.zeros(len(err), dtype=bool))
        out = {}
        for name, sel in (("all", np.ones(len(err), dtype=bool)), ("static", ~moving),
                          ("moving", moving)):
            e = err[sel]
            out[name] = {"points": int(sel.sum()),
                         "max": float(np.max(np.abs(e))) if len(e) else math.nan,
                         "rms": float(np.sqrt(np.mean(e**2))) if len(e) else math.nan}
        return out

    def to_json(self) -> str:
        d = asdict(self)
        d["kind"] = "rotorflow flow-coefficient fit: A(PR) Cd|Cd| + b X (Cd - w W) = 1"
        return json.dumps(d, indent=2) + "\n"

    @classmethod
    def from_json(cls, text: str) -> FlowCoefficientFit:
        """A saved fit; files written before the wall term existed load with w = 0."""
        d = json.loads(text)
        unknown = [f for f in d["inertial_features"] if f not in INERTIAL_FEATURES]
        if unknown:
            raise ValueError(f"unknown flow-coefficient feature(s): {', '.join(unknown)}")
        return cls(
            inertial_features=tuple(d["inertial_features"]),
            inertial=tuple(float(c) for c in d["inertial"]),
            viscous=float(d["viscous"]),
            gamma=float(d.get("gamma", 1.4)),
            ranges={k: (float(v[0]), float(v[1])) for k, v in d.get("ranges", {}).items()},
            leave_out_errors=tuple(float(e) for e in d.get("leave_out_errors", ())),
            definitions=d.get("definitions", ""),
            wall=float(d.get("wall", 0.0)),
            leave_out_moving=tuple(bool(m) for m in d.get("leave_out_moving", ())),
        )

    def save(self, path: Path) -> Path:
        path = Path(path)
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_text(self.to_json())
        tmp.replace(path)
        return path

    @classmethod
    def load(cls, path: Path) -> FlowCoefficientFit:
        return cls.from_json(Path(path).read_text())


def correlation_path(name: str, where: str) -> Path:
    """Where the flow-coefficient fit a case names (``correlation``) lies: relative to
    the case file ``where``."""
    path = Path(name)
    if not path.is_absolute() and Path(where).parent.is_dir():
        path = Path(where).parent / path
    return path
