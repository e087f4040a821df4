"""Heat transfer between the gas of a chamber and its walls (rotors, casing, end plates).

    Q = h A_w (T_w - T)        A_w = 6 V^(2/3)

(seed 003 Eq. 6's Q: "the heat exchanged between the fluid and the compressor screw
rotors and the casing").  The wall area is that of a cube of the chamber's volume: the
chamber table gives volumes, not wetted areas, and a cube's is the least area a volume
can have, so the wall area is if anything on the low side.  One wall temperature T_w
stands for rotors and casing alike.

The coefficient h (``[operating]`` keys, :func:`parse_keys`):

``heat_transfer_W_m2K`` (default 0: adiabatic)
    a constant h, the same at every pressure.
``heat_transfer_correlation = "dittus-boelter"``
    h from the Nusselt number of turbulent duct flow, Dittus & Boelter (1930, Univ.
    Calif. Publ. Eng. 2, 443; in the form restated by Winterton, Int. J. Heat Mass
    Transfer 41 (1998) 809):

        Nu = h D_h / k = 0.023 Re^0.8 Pr^n,   Re = rho w D_h / mu,
        n = 0.3 (the gas cooled by the walls), 0.4 (heated).

    Screw-machine chamber models use correlations of this form for the working chamber
    (Stosic, Smith & Kovacevic 2005, *Screw Compressors: Mathematical Modelling and
    Performance Calculation*, Springer, ch. 3, seed 003's reference [3]: cited from
    memory, its constants and velocity scale not checked against the book), here with
    the chamber's relative velocity w taken as the rotors' tip speed: the gas is carried
    by the rotors past the static casing, and in a closed chamber of a pump there is no
    other velocity scale (its axial transport speed, lead times speed, is ~1/3 of the
    tip speed in examples/screw_pump_vacuum.toml).  Tried on the vacuum pump of seed 003
    Table 2 it made the figures worse (power +20..47 % against +18..29 % with the
    example's constant h, and discharge temperatures far higher: at 0.01 bar h ~ 2
    W/m2K leaves the shaft power with the tiny delivered flow), so the example keeps
    its constant h; the correlation is an option, not the default.
    D_h = 4 V / A_w with the same A_w as above, so that area and diameter describe one
    shape.  mu(T) by Sutherland's law and
    k = mu cp / Pr of :class:`.perfect_gas.PerfectGas` (air); n is chosen per state from
    the sign of T_w - T, which is where h is multiplied by zero anyway.

    The correlation is stated for Re > 1e4.  A vacuum pump's chamber at 0.01 bar has
    Re ~ 1e3: there the value is an extrapolation (below the correlation's range it
    gives Nu ~ 4, the order of the laminar duct's 3.66, not a laminar law).  What it
    does capture, unlike a constant h, is that h falls with the gas density
    (h ~ rho^0.8): a rarefied gas carries little heat, in the chamber as in the gaps.

The chamber's gas is a continuum for heat transfer in every case here: its mean free
path at 0.01 bar and 300 K is ~7 um against a D_h of centimetres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotorflow.errors import CaseError

from .keys import _choice, _number

# Wall area of a chamber for heat transfer: that of a cube of the same volume, 6 V^(2/3).
WALL_AREA_FACTOR = 6.0
CORRELATIONS = ("none", "dittus-boelter")
# Dittus-Boelter (Winterton 1998): Nu = C Re^0.8 Pr^n
DB_C, DB_RE = 0.023, 0.8
DB_PR_COOLED, DB_PR_HEATED = 0.3, 0.4


def wall_area(V):
    return WALL_AREA_FACTOR * np.asarray(V, dtype=float) ** (2.0 / 3.0)


def hydraulic_diameter(V):
    """D_h = 4 V / A_w of a chamber of volume V (2/3 of the cube's edge)."""
    V = np.asarray(V, dtype=float)
    return 4.0 * V / wall_area(V)


def dittus_boelter(rho, T, T_wall, speed, d_h, gas):
    """h (W/(m2 K)) of gas of density rho and temperature T flowing at ``speed`` (m/s)
    in a duct of hydraulic diameter ``d_h`` (m) with walls at ``T_wall``: Nu = 0.023
    Re^0.8 Pr^n (n = 0.3 where the gas is hotter than the walls, else 0.4); ``gas``
    gives mu(T), cp and Pr (:class:`.perfect_gas.PerfectGas`)."""
    T = np.asarray(T, dtype=float)
    mu = gas.mu(T)
    re = np.asarray(rho, dtype=float) * speed * d_h / mu
    n = np.where(T > T_wall, DB_PR_COOLED, DB_PR_HEATED)
    k = mu * gas.cp_J_kgK / gas.prandtl
    return DB_C * re**DB_RE * gas.prandtl**n * k / d_h


@dataclass(frozen=True)
class WallHeat:
    """The heat-transfer law of a case: a constant ``coefficient`` (W/(m2 K)), or the
    named ``correlation`` with the rotors' tip ``speed`` (m/s) and the ``gas`` giving
    transport properties; walls at ``T_wall`` (K)."""

    coefficient: float
    correlation: str
    T_wall: float
    speed: float = 0.0
    gas: object = None

    @property
    def on(self) -> bool:
        return self.coefficient > 0.0 or self.correlation != "none"

    @property
    def constant(self) -> bool:
        """h does not depend on the gas's state (what the compiled kernel evaluates)."""
        return self.correlation == "none"

    def conductance(self, V, rho=None, T=None):
        """h A_w (W/K) of chambers of volume V (with their gas's rho, T for a
        correlation)."""
        A = wall_area(V)
        if self.constant:
            return self.coefficient * A
        return dittus_boelter(rho, T, self.T_wall, self.speed, hydraulic_diameter(V),
                              self.gas) * A

    def rate(self, V, conductance, rho, T):
        """Q (W) into the gas of each chamber; ``conductance`` the constant law's h A_w
        if the caller has it (the model's geometry cache), else None."""
        if not self.on:
            return None
        if conductance is None:
            conductance = self.conductance(V, rho, T)
        return conductance * (self.T_wall - T)


def parse_keys(d: dict, s: str, where: str) -> dict:
    """The [operating] keys of the heat transfer, as Operating's fields."""
    corr = _choice(d, "heat_transfer_correlation", s, where, CORRELATIONS, "none")
    if corr != "none" and "heat_transfer_W_m2K" in d:
        raise CaseError(f"give heat_transfer_W_m2K or heat_transfer_correlation in [{s}] of "
                        f"{where}, not both: the correlation sets the coefficient")
    if corr != "none" and d.get("fluid", "air") != "air":
        raise CaseError(f"heat_transfer_correlation = {corr!r} in [{s}] of {where} needs the "
                        "gas's viscosity and conductivity: fluid \"air\" only")
    return {"heat_transfer_W_m2K": _number(d, "heat_transfer_W_m2K", s, where, 0.0,
                                           nonnegative=True),
            "heat_transfer_correlation": corr}


def wall_heat(op, geo) -> WallHeat:
    """The case's law (``op``: Operating) on its chamber geometry ``geo`` (tip speed)."""
    return WallHeat(op.heat_transfer_W_m2K, op.heat_transfer_correlation,
                    op.wall_temperature_K, geo.omega_outer * geo.radius, op.constant_cp_gas)
