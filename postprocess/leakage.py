"""Leakage through a clearance gap: CFD against quasi-1D models, and a fitted flow coefficient.

Every model is a callable ``model(point) -> mass flow per metre of gap depth (kg/s/m)``,
so the comparison does not depend on where a model lives: the reference formulas here,
rotorflow.quasi1d's leakage models through :func:`quasi1d_models`, or the fitted
correlation (:meth:`FlowCoefficientFit.model`).

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

import csv
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

Model = Callable[["LeakagePoint"], float]

#: The definitions above, stored with every fit so a JSON file explains itself.
DEFINITIONS = " ".join(__doc__.split("Definitions (SI):")[1].split())


@dataclass(frozen=True)
class LeakagePoint:
    """One operating point of a gap, with its CFD mass flow when known."""

    name: str
    gap_m: float
    length_m: float
    p_up_Pa: float
    T_up_K: float
    p_down_Pa: float
    mu_Pa_s: float
    """Viscosity at T_up."""
    R_J_kgK: float = 287.05
    gamma: float = 1.4
    wall_speed_m_s: float = 0.0
    mass_flow_kg_s_m: float = math.nan
    """CFD mass flow per metre of depth (Richardson-extrapolated where available)."""

    @property
    def pressure_ratio(self) -> float:
        return self.p_up_Pa / self.p_down_Pa

    @property
    def length_over_gap(self) -> float:
        return self.length_m / self.gap_m

    @property
    def ideal_mass_flow(self) -> float:
        return self.gap_m * isentropic_mass_flux(self.p_up_Pa, self.T_up_K, self.p_down_Pa,
                                                 self.gamma, self.R_J_kgK)

    @property
    def reynolds(self) -> float:
        return self.ideal_mass_flow / self.mu_Pa_s

    @property
    def flow_coefficient(self) -> float:
        return self.mass_flow_kg_s_m / self.ideal_mass_flow

    @property
    def wall_speed_ratio(self) -> float:
        """V = U sqrt(rho_up / p_up): the wall speed over sqrt(R T_up)."""
        return self.wall_speed_m_s / math.sqrt(self.R_J_kgK * self.T_up_K)

    @property
    def couette_parameter(self) -> float:
        """W = rho_c U h / m_id (see the Definitions)."""
        return float(couette_parameter(self.wall_speed_ratio, self.pressure_ratio, self.gamma))


# --- reference formulas -------------------------------------------------------------------


def isentropic_mass_flux(p0: float, T0: float, p: float, gamma: float, R: float) -> float:
    """Mass flux (kg/s/m^2) of an isentropic nozzle from rest at p0, T0 to p; choked below
    the critical pressure."""
    p = max(p, p0 * (2 / (gamma + 1)) ** (gamma / (gamma - 1)))
    x = p / p0
    return p0 * math.sqrt(
        2 * gamma / ((gamma - 1) * R * T0) * (x ** (2 / gamma) - x ** ((gamma + 1) / gamma))
    )


def plane_poiseuille_mass_flow(point: LeakagePoint) -> float:
    """Isothermal, fully developed laminar flow between parallel plates (per metre depth):
    m' = h^3 (p_up^2 - p_down^2) / (24 mu R T L), the compressible form of
    m' = rho h^3 dp / (12 mu L) with rho varying along the channel as p does."""
    p = point
    return p.gap_m**3 * (p.p_up_Pa**2 - p.p_down_Pa**2) / (
        24 * p.mu_Pa_s * p.R_J_kgK * p.T_up_K * p.length_m
    )


def nozzle_model(coefficient: float = 1.0) -> Model:
    """The isentropic nozzle through the minimum gap times ``coefficient``."""
    return lambda p: coefficient * p.ideal_mass_flow


def quasi1d_models(coefficient: float | None = None, zeta: float | None = None) -> dict[str, Model]:
    """rotorflow.quasi1d's leakage models as callables, with its default parameters.

    Uses ``rotorflow.quasi1d.flows`` (``nozzle_f``, ``fanno_f``, ``fanno_choke_ratio``)
    and the defaults of ``rotorflow.quasi1d.Leakage``; raises ImportError naming what is
    missing when that module does not provide them.
    """
    try:
        from rotorflow.quasi1d import Leakage, flows
    except ImportError as exc:  # pragma: no cover - depends on the other package's state
        raise ImportError(f"rotorflow.quasi1d leakage models unavailable: {exc}") from exc
    missing = [n for n in ("nozzle_f", "fanno_f", "fanno_choke_ratio") if not hasattr(flows, n)]
    if missing:
        raise ImportError(f"rotorflow.quasi1d.flows lacks {', '.join(missing)}")
    defaults = Leakage()
    cd = defaults.coefficient if coefficient is None else coefficient
    z = defaults.zeta if zeta is None else zeta
    x_choke = flows.fanno_choke_ratio(z)

    def scale(p: LeakagePoint) -> float:  # gap * sqrt(p1 rho1), rho1 at the upstream state
        return cd * p.gap_m * math.sqrt(p.p_up_Pa * p.p_up_Pa / (p.R_J_kgK * p.T_up_K))

    def nozzle(p: LeakagePoint) -> float:
        return scale(p) * float(flows.nozzle_f(1.0 / p.pressure_ratio, p.gamma))

    def fanno(p: LeakagePoint) -> float:
        return scale(p) * float(flows.fanno_f(1.0 / p.pressure_ratio, z, x_choke))

    return {"quasi1d-nozzle": nozzle, f"quasi1d-fanno(zeta={z:g})": fanno}


# --- comparison ---------------------------------------------------------------------------


@dataclass(frozen=True)
class ModelSummary:
    model: str
    max_abs_error: float
    rms_error: float
    mean_error: float


@dataclass(frozen=True)
class ComparisonTable:
    """CFD mass flow against each model: ``errors[model][i]`` = model / CFD - 1."""

    points: tuple[LeakagePoint, ...]
    predictions: Mapping[str, np.ndarray]
    errors: Mapping[str, np.ndarray]

    def summary(self) -> list[ModelSummary]:
        out = []
        for name, err in self.errors.items():
            out.append(ModelSummary(name, float(np.max(np.abs(err))),
                                    float(np.sqrt(np.mean(err**2))), float(np.mean(err))))
        return out

    def rows(self) -> list[dict[str, float | str]]:
        rows = []
        for i, p in enumerate(self.points):
            row: dict[str, float | str] = {
                "point": p.name,
                "gap_um": p.gap_m * 1e6,
                "L_over_h": p.length_over_gap,
                "pressure_ratio": p.pressure_ratio,
                "wall_speed_m_s": p.wall_speed_m_s,
                "reynolds": p.reynolds,
                "cfd_kg_s_m": p.mass_flow_kg_s_m,
                "cfd_Cd": p.flow_coefficient,
            }
            for name in self.predictions:
                row[f"{name}_kg_s_m"] = float(self.predictions[name][i])
                row[f"{name}_error"] = float(self.errors[name][i])
            rows.append(row)
        return rows

    def write_csv(self, path: Path) -> Path:
        rows = self.rows()
        path = Path(path)
        with path.open("w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        return path

    def markdown(self) -> str:
        """The summary as a Markdown table (one row per model)."""
        lines = ["| model | max abs error | RMS error | mean error |", "| --- | --- | --- | --- |"]
        for s in self.summary():
            lines.append(f"| {s.model} | {s.max_abs_error:.1%} | {s.rms_error:.1%} | "
                         f"{s.mean_error:+.1%} |")
        return "\n".join(lines) + "\n"


def compare(points: Sequence[LeakagePoint], models: Mapping[str, Model]) -> ComparisonTable:
    """Evaluate every model at every point with a finite, positive CFD mass flow."""
    pts = tuple(points)
    if not pts:
        raise ValueError("no leakage points to compare")
    bad = [p.name for p in pts if not (math.isfinite(p.mass_flow_kg_s_m) and
                                       p.mass_flow_kg_s_m > 0)]
    if bad:
        raise ValueError(f"points without a valid CFD mass flow: {', '.join(bad)}")
    cfd = np.array([p.mass_flow_kg_s_m for p in pts])
    preds = {name: np.array([float(m(p)) for p in pts]) for name, m in models.items()}
    return ComparisonTable(pts, preds, {name: v / cfd - 1.0 for name, v in preds.items()})


def mismatches(
    measured: Mapping[str, float], reference: Mapping[str, float], rtol: float
) -> list[str]:
    """Names (with values) where ``measured`` differs from ``reference`` by more than rtol,
    or is missing or non-finite; an empty list means agreement."""
    out = []
    for name, ref in reference.items():
        val = measured.get(name, math.nan)
        if not math.isfinite(val) or abs(val - ref) > rtol * abs(ref):
            out.append(f"{name}: {val:.6g} against {ref:.6g} (rtol {rtol:g})")
    return out


# --- fitted flow coefficient --------------------------------------------------------------
#
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


def nozzle_psi(pressure_ratio, gamma: float = 1.4):
    """Dimensionless isentropic nozzle flux: m'' / sqrt(p_up rho_up) (choked below the
    critical pressure ratio)."""
    pr = np.asarray(pressure_ratio, dtype=float)
    x = np.maximum(1.0 / pr, (2 / (gamma + 1)) ** (gamma / (gamma - 1)))
    return np.sqrt(2 * gamma / (gamma - 1) * (x ** (2 / gamma) - x ** ((gamma + 1) / gamma)))


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
        pr, gamma)


def lubrication_ratio(pressure_ratio, gamma: float = 1.4):
    """Y = psi^2 / (1 - PR^-2), so that X = 24 (L/h) Y / Re.

    Both psi^2 and 1 - PR^-2 vanish like 2 (1 - 1/PR) at PR -> 1, where Y -> 1; written
    as a ratio of expm1 terms it is evaluated without the 0/0 (and Y = 1 at PR = 1).
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
    return (24 * np.asarray(length_over_gap, dtype=float) * nozzle_psi(pr, gamma) ** 2
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
        when the upstream side changes at equal pressures.  With psi = nozzle_psi(PR, gamma)
        this is exactly flow_coefficient(Re, PR, L/h, V) * psi (Re = h psi sqrt(p rho) / mu).

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

    def model(self) -> Model:
        """The fit as a leakage model for :func:`compare`."""
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


def _solve(points: Sequence[LeakagePoint], features: Sequence[str], gamma: float,
           wall: bool) -> FlowCoefficientFit:
    pr = np.array([p.pressure_ratio for p in points])
    cd = np.array([p.flow_coefficient for p in points])
    x = viscous_parameter([p.reynolds for p in points], pr,
                          [p.length_over_gap for p in points], gamma)
    # Residual A Cd|Cd| + b X Cd - bw X W - 1 changes by (1 + A Cd^2) dCd/Cd, between one
    # and two times the relative error of Cd: plain least squares weighs points evenly.
    columns = [cd * np.abs(cd) * INERTIAL_FEATURES[f](pr) for f in features] + [x * cd]
    if wall:
        columns.append(-x * np.array([p.couette_parameter for p in points]))
    coef, *_ = np.linalg.lstsq(np.column_stack(columns), np.ones(len(points)), rcond=None)
    n = len(features)
    b = float(coef[n])
    # A column of zeros (no moving wall left in a leave-one-out fit) gets a zero
    # coefficient from lstsq: w = 0, the static form.
    w = float(coef[n + 1]) / b if wall and b != 0.0 else 0.0
    return FlowCoefficientFit(tuple(features), tuple(float(c) for c in coef[:n]), b, gamma,
                              wall=w)


def fit_flow_coefficient(
    points: Sequence[LeakagePoint],
    features: Sequence[str] = DEFAULT_INERTIAL,
    *,
    wall: bool | None = None,
) -> FlowCoefficientFit:
    """Least-squares fit of the series-resistance form, with leave-one-out errors.

    ``wall``: fit the wall-drag coefficient w (default: when any point has moving walls;
    False fits the static form to every point, as the correlation did before).
    """
    pts = [p for p in points if math.isfinite(p.mass_flow_kg_s_m) and p.mass_flow_kg_s_m > 0]
    moving = [p.wall_speed_m_s != 0 for p in pts]
    wall = any(moving) if wall is None else wall
    n_coef = len(features) + 1 + int(wall)
    if len(pts) < n_coef + 1:
        raise ValueError(f"{len(pts)} valid points cannot fit {n_coef} coefficients "
                         "and leave one out")
    gammas = {p.gamma for p in pts}
    if len(gammas) != 1:
        raise ValueError("all points of a fit must share one gas (gamma)")
    gamma = gammas.pop()
    fit = _solve(pts, tuple(features), gamma, wall)
    loo = []
    for i, p in enumerate(pts):
        pred = _solve(pts[:i] + pts[i + 1 :], tuple(features), gamma, wall).model()(p)
        loo.append(pred / p.mass_flow_kg_s_m - 1.0)

    def span(values) -> tuple[float, float]:
        values = list(values)
        return (float(min(values)), float(max(values)))

    return replace(
        fit,
        ranges={
            "reynolds": span(p.reynolds for p in pts),
            "pressure_ratio": span(p.pressure_ratio for p in pts),
            "length_over_gap": span(p.length_over_gap for p in pts),
            "wall_speed_ratio": span(p.wall_speed_ratio for p in pts),
        },
        leave_out_errors=tuple(float(e) for e in loo),
        leave_out_moving=tuple(moving),
    )


# --- report -------------------------------------------------------------------------------


def write_report(
    points: Sequence[LeakagePoint],
    out_dir: Path,
    models: Mapping[str, Model],
    *,
    features: Sequence[str] = DEFAULT_INERTIAL,
) -> dict:
    """Fit the flow coefficient and compare every model with the CFD points.

    The fit ("cfd-calibrated") uses every point, with the wall-drag term when some walls
    move; its left-out errors are reported for static and moving walls apart.  Where
    there are both, the static form fitted to the static points alone
    ("cfd-calibrated-static", the correlation without its wall term) is compared too,
    which shows what the wall motion does to a correlation that ignores it.  Writes
    ``leakage_errors.csv``, ``leakage_errors.md``, ``flow_coefficient.json`` and
    ``flow_coefficient.png``; returns the summary figures.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fit = fit_flow_coefficient(points, features)
    fit.save(out_dir / "flow_coefficient.json")
    fitted = {"cfd-calibrated": fit.model()}
    static = [p for p in points if p.wall_speed_m_s == 0]
    if fit.wall != 0.0 and len(static) > len(features) + 2:
        fitted["cfd-calibrated-static"] = fit_flow_coefficient(static, features,
                                                               wall=False).model()
    table = compare(points, {**models, **fitted})
    table.write_csv(out_dir / "leakage_errors.csv")
    loo = fit.leave_out_summary()
    lines = [f"\ncfd-calibrated: w = {fit.wall:.4g}; left-out prediction error:"]
    for name in ("all", "static", "moving"):
        s = loo[name]
        if s["points"]:
            lines.append(f"- {name} walls: max {s['max']:.1%}, RMS {s['rms']:.1%} over "
                         f"{s['points']} points")
    (out_dir / "leakage_errors.md").write_text(table.markdown() + "\n".join(lines) + "\n")
    _plot_fit(points, fit, out_dir / "flow_coefficient.png")
    return {
        "models": [asdict(s) for s in table.summary()],
        "fit": {"inertial_features": fit.inertial_features, "inertial": fit.inertial,
                "viscous": fit.viscous, "wall": fit.wall,
                "leave_out_max_error": loo["all"]["max"],
                "leave_out_rms_error": loo["all"]["rms"],
                "leave_out": loo},
    }


def _plot_fit(points: Sequence[LeakagePoint], fit: FlowCoefficientFit, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    cd = np.array([p.flow_coefficient for p in points])
    pred = np.array([fit.flow_coefficient(p.reynolds, p.pressure_ratio, p.length_over_gap,
                                          p.wall_speed_ratio) for p in points])
    re = np.array([p.reynolds for p in points])
    pr = np.array([p.pressure_ratio for p in points])
    moving = np.array([p.wall_speed_m_s != 0 for p in points])
    sc = ax.scatter(re[~moving], cd[~moving], c=np.log(pr[~moving]), marker="o", label="CFD")
    ax.scatter(re[moving], cd[moving], c="k", marker="x", label="CFD, moving walls")
    ax.scatter(re, pred, facecolors="none", edgecolors="r", marker="s", label="fit")
    fig.colorbar(sc, ax=ax, label="ln(pressure ratio)")
    ax.set_xscale("log")
    ax.set_xlabel("Re = ideal mass flow per depth / mu")
    ax.set_ylabel("flow coefficient Cd")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _largest(values) -> float:
    v = np.asarray([x for x in values if x is not None], dtype=float)
    return float(np.max(v)) if len(v) and np.all(np.isfinite(v)) else math.nan


def report_section(artifact: Path, report_dir: Path, case):
    """The ``cfd.leakage`` stage's part of the HTML report: mesh studies (failed runs
    named with their reasons), the error table of each model and the fitted Cd."""
    from rotorflow.postprocess.report import Section, esc, figure, table

    artifact = Path(artifact)
    body = []
    studies = json.loads((artifact / "studies.json").read_text())
    failed = [s for s in studies if not s["ok"]]
    if failed:
        body.append("<p class='warn'>Failed runs, left out of the comparison and the fit: "
                    + "; ".join(esc(f"{s['name']}: {', '.join(s['failures'])}") for s in failed)
                    + "</p>")
    body.append(table(
        ["point", "mesh convergence", "observed order", "default mesh vs extrapolated",
         "extrapolated kg/s/m", "largest inlet/outlet imbalance", "run time s (3 meshes)"],
        [[s["name"], s["kind"], s["order"], s["default_error"], s["extrapolated_kg_s_m"],
          _largest(s.get("imbalance", [])), float(np.sum(s.get("run_time_s", [math.nan])))]
         for s in studies],
        ["failed" if not s["ok"] else "" for s in studies]))
    errors = artifact / "leakage_errors.csv"
    if errors.is_file():
        with errors.open() as fh:
            rows = list(csv.DictReader(fh))
        models = [k[: -len("_error")] for k in rows[0] if k.endswith("_error")]
        body.append(table(["point", "Re", "PR", "L/h", "wall speed m/s", "CFD Cd"]
                          + [f"{m} error" for m in models],
                          [[r["point"], float(r["reynolds"]), float(r["pressure_ratio"]),
                            float(r["L_over_h"]), float(r.get("wall_speed_m_s", 0.0)),
                            float(r["cfd_Cd"])]
                           + [float(r[f"{m}_error"]) for m in models] for r in rows]))
        body.append(f"<pre>{esc((artifact / 'leakage_errors.md').read_text())}</pre>")
    if (artifact / "flow_coefficient.png").is_file():
        name = "cfd_leakage_flow_coefficient.png"
        (Path(report_dir) / name).write_bytes((artifact / "flow_coefficient.png").read_bytes())
        body.append(figure(name, "Flow coefficient: CFD and the fitted correlation"))
    if (artifact / "flow_coefficient.json").is_file():
        fit = FlowCoefficientFit.load(artifact / "flow_coefficient.json")
        body.append(f"<p>Fitted correlation ({esc(fit.definitions)}): inertial "
                    f"{esc(dict(zip(fit.inertial_features, fit.inertial, strict=True)))}, "
                    f"viscous b = {fit.viscous:.4g}, wall drag w = {fit.wall:.4g}.</p>")
    return Section("CFD: leakage through clearance gaps", "".join(body))
