"""The chamber table prepared for fast evaluation, and the timing of one chamber's life.

Volume is interpolated by cubic Hermite polynomials through (V, dV/dangle) of the table,
so that V and dV/dangle are consistent (the work -p dV integrates exactly what the
volume does) and smooth; the areas and sealing lengths are interpolated linearly.

Timing, in outer-rotor angle since birth (the table's ``angle_rad``):

    birth          where V first exceeds vanish_fraction * V_max
    suction_close  the volume maximum, or the case's explicit angle
    discharge_open where V has fallen to V_max / volume_ratio after the maximum, or the
                   case's explicit angle
    death          where V last exceeds vanish_fraction * V_max

A table whose port areas follow the geometry's port timing carries it
(``table.port_timing``, :func:`rotorflow.geometry.ports.port_timing`: with a transport
plateau, seed 003's screw pumps, suction closes at the plateau's start and, at
``volume_ratio = 1``, the discharge opens at its end).  That timing is read, not
re-derived, when it was made for the volume ratio and early opening asked here and the
case gives no explicit angle; the rules above are the fallback for tables without one
(the internal gear's, synthetic ones).

A chamber is handed in at birth with the suction state and handed over at death to the
discharge plenum, with its mass, energy and p V booked, so that a vanishing volume is
never divided by.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import CaseError

# The first rows of ChamberGeometry.columns: the port areas.  The rows after them are the
# columns the declared leakage paths read, in the order of the declarations.
PORT_COLUMNS = ("area_lp_m2", "area_hp_m2")
ROW_AREA_LP, ROW_AREA_HP = 0, 1


@dataclass(frozen=True)
class ChamberGeometry:
    nodes: np.ndarray = field(repr=False)  # angle_rad of the table
    coef: np.ndarray = field(repr=False)  # (4 + 2 * len(columns), n_nodes - 1)
    period: float
    lobes: int
    v_max: float
    birth: float
    death: float
    suction_close: float
    discharge_open: float
    v_trapped: float  # volume at suction close
    v_discharge: float  # volume at discharge opening
    omega_outer: float  # rad/s
    radius: float  # outer-rotor radius, for the wall speed in the gaps
    columns: tuple[str, ...] = PORT_COLUMNS  # rows of ``lin``: table column names
    paths: tuple = ()  # the table's LeakagePath declarations

    def row(self, column: str) -> int:
        """Row of ``lin`` holding the table column ``column``."""
        return self.columns.index(column)

    @property
    def rows(self) -> int:
        return len(self.columns)

    @property
    def slots(self) -> int:
        """Chambers present at once: slot k holds the chamber of age angle + k*period."""
        return int(math.floor((self.death - self.birth) / self.period * (1 + 1e-12))) + 1

    def evaluate(self, ages: np.ndarray):
        """V, dV/dangle and the linear columns at the given ages (rows, then ages.shape)."""
        return spline_at(self.nodes, self.coef, ages)

    def volume(self, ages):
        return self.evaluate(np.asarray(ages, dtype=float))[0]


def spline_at(nodes, coef, ages):
    """V, dV/dangle and the linear columns (rows, then ages.shape) of the coefficients
    ``coef`` on the table's ``nodes`` at ``ages`` (also compiled, :mod:`.compiled`)."""
    i = np.minimum(np.maximum(np.searchsorted(nodes, ages, side="right") - 1, 0),
                   coef.shape[1] - 1)  # (np.clip costs ~5 us more a call)
    s = ages - nodes[i]
    c = coef[:, i]
    V = ((c[3] * s + c[2]) * s + c[1]) * s + c[0]
    dV = (3.0 * c[3] * s + 2.0 * c[2]) * s + c[1]
    lin = c[4::2] + c[5::2] * s
    return V, dV, np.maximum(lin, 0.0)


def prepare(table, volume_ratio, suction_close, discharge_open, speed_rpm,
            vanish_fraction, early_opening: float = 0.0) -> ChamberGeometry:
    """Check a ChamberTable and derive everything the model needs from it
    (``early_opening``: how much before the built-in volume ratio's angle the discharge
    port opens, seed 004)."""
    # contiguous: the compiled segments take the nodes as a C array (a strided view,
    # as a table read from disk gives, is another type: numba compiles anew, ~60 s)
    a = np.ascontiguousarray(table.angle_rad, dtype=float)
    V = np.asarray(table.volume_m3, dtype=float)
    dV = np.asarray(table.dVdangle_m3_rad, dtype=float)
    if a.ndim != 1 or a.size < 4:
        raise CaseError("chamber table has fewer than 4 rows")
    if not np.all(np.diff(a) > 0):
        raise CaseError("chamber table angles must increase strictly")
    paths = _declared_paths(table)
    names = list(PORT_COLUMNS)
    for path in paths:
        names += [c for c in path.columns if c not in names]
    cols = [_column(table, name) for name in names]
    for name, col in zip(("volume_m3", "dVdangle_m3_rad", *names), [V, dV, *cols],
                         strict=True):
        if col.shape != a.shape or not np.all(np.isfinite(col)):
            raise CaseError(f"chamber table column {name} is missing values or not finite")
        if name != "dVdangle_m3_rad" and np.any(col < 0):
            raise CaseError(f"chamber table column {name} has negative values")
    if table.lobes_outer < 1:
        raise CaseError("chamber table: lobes_outer must be at least 1")
    h = np.diff(a)
    d = np.diff(V) / h
    coef = np.empty((4 + 2 * len(cols), a.size - 1))
    coef[0] = V[:-1]
    coef[1] = dV[:-1]
    coef[2] = (3.0 * d - 2.0 * dV[:-1] - dV[1:]) / h
    coef[3] = (dV[:-1] + dV[1:] - 2.0 * d) / h**2
    for j, col in enumerate(cols):
        coef[4 + 2 * j] = col[:-1]
        coef[5 + 2 * j] = np.diff(col) / h
    period = 2.0 * math.pi / table.lobes_outer
    imax = int(np.argmax(V))
    vmax = float(V[imax])
    if vmax <= 0:
        raise CaseError("chamber table volume is zero everywhere")
    geo = ChamberGeometry(a, coef, period, table.lobes_outer, vmax, 0.0, 0.0, 0.0, 0.0, 0.0,
                          0.0, 0.0, 0.0)
    thr = vanish_fraction * vmax
    birth = float(a[0]) if V[0] >= thr else _crossing(geo, a, V, thr, 0, imax)
    death = float(a[-1]) if V[-1] >= thr else _crossing(geo, a, V, thr, imax, a.size - 1)
    given = _table_timing(table, volume_ratio, early_opening)
    if given is not None:
        suction_close = given[0] if suction_close is None else suction_close
        discharge_open = given[1] if discharge_open is None else discharge_open
    sc = float(a[imax]) if suction_close is None else float(suction_close)
    if not birth < sc < death:
        raise CaseError(f"suction port closing at {math.degrees(sc):.1f} deg lies outside the "
                        f"chamber's life ({math.degrees(birth):.1f}-{math.degrees(death):.1f} deg)")
    if discharge_open is None:
        if volume_ratio is None:
            raise CaseError("the case needs [operating] volume_ratio or discharge_open_deg")
        target = vmax / volume_ratio
        if target <= thr:
            raise CaseError(f"volume_ratio {volume_ratio} leaves a discharge volume below the "
                            f"vanishing threshold of the chamber table")
        do = _crossing(geo, a, V, target, imax, a.size - 1) - early_opening
        if do <= sc:
            raise CaseError("the discharge port would open before the suction port closes; "
                            "lower volume_ratio or set suction_close_deg")
    else:
        do = float(discharge_open)
        # Without internal compression or transport, suction closes and the discharge
        # opens at one angle, the volume maximum (the geometry's port timing).
        if not (sc < do < death or (sc == do < death and given is not None)):
            raise CaseError(f"discharge port opening at {math.degrees(do):.1f} deg must lie "
                            f"between suction closing and the chamber's death")
    omega = 2.0 * math.pi * speed_rpm / 60.0 * table.speed_ratio_outer_per_driven
    return ChamberGeometry(a, coef, period, table.lobes_outer, vmax, birth, death, sc, do,
                           float(geo.volume(sc)), float(geo.volume(do)), omega,
                           0.5 * float(table.diameter_m), tuple(names), paths)


def _table_timing(table, volume_ratio, early_opening) -> tuple[float, float] | None:
    """(suction close, discharge open) of the table's own port timing, if it has one made
    for this volume ratio and early opening (else None: derive)."""
    t = getattr(table, "port_timing", None) or {}
    if not {"suction_close_rad", "discharge_open_rad", "volume_ratio"} <= set(t):
        return None
    if volume_ratio is None or float(t["volume_ratio"]) != float(volume_ratio):
        return None
    if abs(float(t.get("early_opening_rad", 0.0)) - float(early_opening)) > 1e-12:
        return None
    return float(t["suction_close_rad"]), float(t["discharge_open_rad"])


def _declared_paths(table) -> tuple:
    """The table's leakage paths (an object without declarations: the internal-gear set)."""
    from rotorflow.geometry.table import internal_gear_paths

    paths = getattr(table, "paths", None)
    return internal_gear_paths(getattr(table, "seal_far", {})) if paths is None else paths


def _column(table, name: str) -> np.ndarray:
    try:
        col = table.column(name) if hasattr(table, "column") else getattr(table, name)
    except (KeyError, AttributeError):
        raise CaseError(f"chamber table has no column {name}, which a declared leakage "
                        "path reads") from None
    return np.asarray(col, dtype=float)


def _crossing(geo, a, V, level, i0, i1) -> float:
    """First angle between nodes i0..i1 where the Hermite volume passes ``level``."""
    from rotorflow.geometry.scalar import root  # not scipy's: its import costs 0.2 s

    s = V[i0:i1 + 1] - level
    idx = np.nonzero(np.sign(s[:-1]) != np.sign(s[1:]))[0]
    if idx.size == 0:
        raise CaseError(f"chamber volume never passes {level:.3e} m3 where it should")
    k = i0 + int(idx[0])
    # the cell's cubic in plain floats: ~1 us a call against ~15 us through spline_at,
    # and a point's model finds three crossings (issue 19: per-point overheads)
    c0, c1, c2, c3 = (float(c) for c in geo.coef[:4, k])
    a0 = float(a[k])

    def excess(t):
        s = t - a0
        return ((c3 * s + c2) * s + c1) * s + c0 - level

    return float(root(excess, a0, float(a[k + 1]), xtol=1e-14))
