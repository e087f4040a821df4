"""What a chamber case is (case B, see :mod:`rotorflow.cases.chamber_case`): the
compression phase it follows, its time stepping and checks, its domain and its key.

:func:`compression_from_table` takes the compression phase from a chamber table as the
quasi-1D model times it (suction closing to discharge opening, the model's Hermite
volume curve); the slab's depth is a representative sealing-line length toward suction.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from rotorflow.errors import CaseError
from rotorflow.postprocess.chamber_history import VolumeCurve
from rotorflow.quasi1d.perfect_gas import PerfectGas

from .chamber_mesh import ChamberDomain, ChamberMeshSpec
from .foam_case import digest
from .gap_walls import GapWalls, rotor_tip_gap

#: Version of the case this module writes: bump it when dictionaries or judgement change,
#: so that stored results of older cases are recomputed rather than reused.
CASE_FORMAT = 1

#: Default radius of the two convex walls of the rotor-tip gap: the radius of case A's
#: matrix points (MatrixPoint.radius_mm), so that its fitted correlation applies.
TIP_RADIUS_M = 0.02

#: Points of the piston's displacement table per degree of rotor angle.  The volume
#: curve is smooth on that scale: linear interpolation between 0.1 deg samples departs
#: from it by ~1e-7 of the volume.
VOLUME_SAMPLES_PER_DEG = 10


@dataclass(frozen=True)
class Compression:
    """The chamber's compression phase: volume against outer-rotor angle, and the gas."""

    angle_rad: tuple[float, ...]
    """Outer-rotor angles since the chamber's birth, from suction closing to discharge
    opening (increasing)."""
    volume_m3: tuple[float, ...]
    omega_outer_rad_s: float
    p_suction_Pa: float
    T_suction_K: float
    seal_length_m: float
    """The slab's depth: the sealing-line length the gap stands for."""
    gap_m: float
    """Minimum gap; 0: a sealed chamber."""
    tip_radius_m: float = TIP_RADIUS_M
    gas: PerfectGas = field(default_factory=PerfectGas)

    def __post_init__(self) -> None:
        a, v = np.asarray(self.angle_rad), np.asarray(self.volume_m3)
        if a.ndim != 1 or a.shape != v.shape or len(a) < 2:
            raise CaseError("compression: angle and volume must be equal-length 1D sequences")
        if np.any(np.diff(a) <= 0) or np.any(v <= 0) or not np.all(np.isfinite(v)):
            raise CaseError("compression: angles must increase and volumes be positive")
        if min(self.omega_outer_rad_s, self.p_suction_Pa, self.T_suction_K,
               self.seal_length_m) <= 0 or self.gap_m < 0:
            raise CaseError("compression: speed, pressure, temperature, sealing length must "
                            "be > 0 and the gap >= 0")

    @property
    def duration_s(self) -> float:
        return (self.angle_rad[-1] - self.angle_rad[0]) / self.omega_outer_rad_s

    def time_s(self, angle_rad) -> np.ndarray:
        return (np.asarray(angle_rad, dtype=float) - self.angle_rad[0]) / self.omega_outer_rad_s

    def angle_of(self, time_s) -> np.ndarray:
        return self.angle_rad[0] + np.asarray(time_s, dtype=float) * self.omega_outer_rad_s

    def volume_curve(self) -> VolumeCurve:
        return VolumeCurve(np.asarray(self.angle_rad), np.asarray(self.volume_m3),
                              self.omega_outer_rad_s)

    def walls(self) -> GapWalls | None:
        return None if self.gap_m == 0 else rotor_tip_gap(self.gap_m, self.tip_radius_m)

    def limited_to(self, end_deg: float) -> Compression:
        """The same compression stopped ``end_deg`` after its start (for short runs)."""
        a = np.asarray(self.angle_rad)
        end = a[0] + math.radians(end_deg)
        if not a[0] < end <= a[-1]:
            raise CaseError(f"end_deg {end_deg} lies outside the compression phase")
        keep = a < end - 1e-12
        angles = np.append(a[keep], end)
        vol = np.append(np.asarray(self.volume_m3)[keep], np.interp(end, a, self.volume_m3))
        return replace(self, angle_rad=tuple(angles), volume_m3=tuple(vol))


@dataclass(frozen=True)
class TransientControls:
    """Time stepping, sampling and what a finished run must satisfy."""

    max_courant: float = 1.0
    """Largest cell Courant number (rhoPimpleFoam's adjustable time step)."""
    max_dt_s: float = 2.0e-6
    """Upper bound of the time step on the default mesh (divided by the mesh refinement):
    a twentieth of the chamber's acoustic time W/c (~40 us), so the pressure in the
    chamber stays uniform as it is in the quasi-1D model; the leakage flow's Courant
    number takes over below it once the gap flow is fast."""
    first_dt_s: float = 1.0e-9
    outer_correctors: int = 1
    """PISO (one outer corrector): outer iterations without under-relaxation made the
    gap's flow unstable at these time steps."""
    correctors: int = 3
    """Pressure correctors: with 2 the splitting error let noise grow in the gap's
    smallest cells (acoustic Courant number ~15) on the refined mesh; 3 keeps it still."""
    sample_deg: float = 0.5
    """Rotor angle between samples of the function objects."""
    mass_tol: float = 1.0e-3
    """Largest |mass now + mass out - mass at start| / mass at start: finite volumes
    conserve mass to the linear solvers' tolerance, far below this."""
    volume_tol: float = 1.0e-3
    """Largest relative difference between the chamber zone's volume and the prescribed
    one: the motion is exact, so anything above round-off means the zones or the table
    are wrong."""
    timeout_s: float | None = 900.0


@dataclass(frozen=True)
class ChamberCase:
    """Everything that defines one chamber run."""

    compression: Compression
    mesh: ChamberMeshSpec = field(default_factory=ChamberMeshSpec)
    controls: TransientControls = field(default_factory=TransientControls)

    def refined(self, factor: float) -> ChamberCase:
        return replace(self, mesh=self.mesh.refined(factor))

    @property
    def with_gap(self) -> bool:
        return self.compression.gap_m > 0

    def domain(self) -> ChamberDomain:
        """Square at the start; its area less the gap's area upstream of the throat."""
        c = self.compression
        walls = c.walls()
        area = c.volume_m3[0] / c.seal_length_m - upstream_gap_area(walls)
        side = math.sqrt(area)
        return ChamberDomain(side, side, c.seal_length_m, walls)

    def key(self) -> str:
        """A digest of everything that determines the result (reuse of finished runs)."""
        return digest({"format": CASE_FORMAT, "compression": asdict(self.compression),
                       "mesh": asdict(self.mesh), "controls": asdict(self.controls)})

    def description(self) -> dict[str, Any]:
        """What the comparison needs to know of the case (``case.json``)."""
        c, d = self.compression, self.domain()
        walls = c.walls()
        return {
            "angle_rad": list(c.angle_rad),
            "volume_m3": list(c.volume_m3),
            "omega_outer_rad_s": c.omega_outer_rad_s,
            "p_suction_Pa": c.p_suction_Pa,
            "T_suction_K": c.T_suction_K,
            "seal_length_m": c.seal_length_m,
            "gap_m": c.gap_m,
            "gap_length_m": walls.narrow_length() if walls is not None else 0.0,
            "tip_radius_m": c.tip_radius_m,
            "gas": asdict(c.gas),
            "gamma": c.gas.gamma,
            "R_J_kgK": c.gas.R,
            "width_m": d.width_m,
            "height_m": d.height_m,
            "depth_m": d.depth_m,
            "upstream_gap_area_m2": upstream_gap_area(walls),
            "gap_flow_area_m2": d.gap_flow_area_m2,
            "mesh": asdict(self.mesh),
            "controls": asdict(self.controls),
        }


def upstream_gap_area(walls: GapWalls | None) -> float:
    """Area of the gap between its inlet and its throat (m2 of the 2D section)."""
    if walls is None:
        return 0.0
    x = np.linspace(walls.x_inlet, walls.throat_x, 2001)
    return float(np.trapezoid(walls.gap(x), x))


# --- building a case from a chamber table ------------------------------------------------


def seal_length_to_suction(table, start_rad: float, end_rad: float) -> float:
    """Mean over [start, end] of the sealing lines toward suction: the previous (younger)
    chamber's line and the low-pressure end face's."""
    a = np.asarray(table.angle_rad)
    lines = np.asarray(table.seal_prev_m) + np.asarray(table.seal_lp_face_m)
    x = np.linspace(start_rad, end_rad, 1001)
    return float(np.mean(np.interp(x, a, lines)))


def compression_from_table(table, operating, leakage, *, seal_length_m: float | None = None,
                           tip_radius_m: float = TIP_RADIUS_M,
                           samples_per_deg: int = VOLUME_SAMPLES_PER_DEG) -> Compression:
    """The compression phase of ``table`` at ``operating`` with ``leakage``'s gap.

    ``table``: a ChamberTable; ``operating``/``leakage``: quasi-1D ``Operating`` and
    ``Leakage``.  Suction closing and discharge opening follow the quasi-1D model's rules
    (:func:`rotorflow.quasi1d.chamber.prepare`), and the volume is its Hermite curve.
    """
    from rotorflow.quasi1d.chamber import prepare

    if operating.fluid != "air":
        raise CaseError(f"the chamber CFD case models air as a perfect gas, not "
                        f"{operating.fluid}")
    geo = prepare(table, operating.volume_ratio, operating.suction_close_rad,
                  operating.discharge_open_rad, operating.speed_rpm, 1e-3)
    span_deg = math.degrees(geo.discharge_open - geo.suction_close)
    n = max(2, int(math.ceil(span_deg * samples_per_deg)) + 1)
    angles = np.linspace(geo.suction_close, geo.discharge_open, n)
    seal = seal_length_m if seal_length_m is not None else seal_length_to_suction(
        table, geo.suction_close, geo.discharge_open)
    gas = operating.constant_cp_gas
    return Compression(
        angle_rad=tuple(float(a) for a in angles),
        volume_m3=tuple(float(v) for v in geo.volume(angles)),
        omega_outer_rad_s=geo.omega_outer,
        p_suction_Pa=operating.p_suction_Pa,
        T_suction_K=operating.T_suction_K,
        seal_length_m=seal,
        gap_m=leakage.gap_m if leakage.model != "none" else 0.0,
        tip_radius_m=tip_radius_m,
        gas=gas,
    )
