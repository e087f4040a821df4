"""What the quasi-1D model is asked to do: the [operating], [leakage], [ports] and
[numerics] sections of a case file, validated, as frozen dataclasses in SI units.

Case-file keys carry their unit in their name (``p_suction_bar``, ``gap_um``); the
dataclass fields hold SI values (``p_suction_Pa``, ``gap_m``).  ``from_section(d, where)``
reads one TOML table; an unknown key or an impossible value raises
:class:`rotorflow.errors.CaseError` with one line naming the key, the section and the file.

Fluids (``[operating] fluid``):

``"air"`` (default)
    dry air as an ideal gas, p = rho R T.  ``heat_capacity``:

    ``"temperature"`` (default unless a key below is given): cp(T) of dry air (the ideal-gas
        part of CoolProp's air, Lemmon et al. 2000, to 7e-5 over 100-2500 K).  At the
        CRC.60 point it agrees with CoolProp's real-gas air within 0.02 % in flow and
        0.2 % in power; a constant cp of 1006.43 J/(kg K) is 0.4 % and 0.8 % off, because
        cp grows 6 % between suction and 650 K discharge.
    ``"constant"``: a calorically perfect gas with molar mass ``molar_mass_g_mol`` (28.97)
        and ``cp_J_kgK`` (1006.43, seed 001 Table 3); chosen by giving either key.  The
        closed forms of the textbook (pV^kappa, seed 000 Eq. 17) hold exactly; the CFD
        cases use this gas.
``"CoolProp::<name>"``
    a real fluid from CoolProp's Helmholtz equations of state (``"CoolProp::Air"``,
    ``"CoolProp::R134a"``, ...), evaluated through a table built once per run over the
    range of states the operating point can reach (see :mod:`rotorflow.quasi1d.fluids`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rotorflow.errors import CaseError

from . import heat
from .fluid_names import check_fluid
from .keys import _bool, _check_keys, _choice, _number
from .liquid import parse_keys
from .perfect_gas import PerfectGas

BAR = 1.0e5
AIR_MOLAR_MASS_G_MOL = 28.97  # seed 001, Table 3
AIR_CP_J_KGK = 1006.43  # seed 001, Table 3

LEAKAGE_MODELS = ("none", "nozzle", "fanno", "cfd-calibrated", "rarefied")
PORT_MODELS = ("ideal", "nozzle")
HEAT_CAPACITIES = ("temperature", "constant")
INTEGRATORS = ("auto", "dopri5", "bs3", "ros23", "radau", "bdf")


@dataclass(frozen=True)
class Operating:
    """Operating point; pressures in Pa, temperatures in K, speed in rpm of the driven rotor.

    Port angles are outer-rotor angles since the chamber's birth (radians); None means
    derived from the table: suction closes at the volume maximum, discharge opens where
    the volume has fallen to V_max / volume_ratio.
    """

    p_suction_Pa: float
    p_discharge_Pa: float
    T_suction_K: float
    speed_rpm: float
    fluid: str = "air"
    volume_ratio: float | None = None
    suction_close_rad: float | None = None
    discharge_open_rad: float | None = None
    # Seed 004: the discharge port opens this much earlier than the built-in volume
    # ratio says (ahead of over-compression; an interior optimum, its Fig. 7).
    discharge_early_opening_rad: float = 0.0
    T_wall_K: float | None = None  # None: equal to T_suction_K
    heat_transfer_W_m2K: float = 0.0  # 0: adiabatic chambers (seed 001 neglects heat transfer)
    heat_transfer_correlation: str = "none"  # or h from a named correlation (.heat)
    heat_capacity: str = "temperature"  # ideal-gas "air" only: cp(T), or "constant"
    molar_mass_kg_mol: float = AIR_MOLAR_MASS_G_MOL * 1e-3  # heat_capacity "constant" only
    cp_J_kgK: float = AIR_CP_J_KGK  # heat_capacity "constant" only
    oil_mass_ratio: float = 0.0  # injected oil mass per trapped gas mass; 0: no oil
    T_oil_K: float | None = None  # None: equal to T_suction_K
    oil_cp_J_kgK: float = 1900.0  # typical mineral compressor oil
    # Gas-oil heat exchange time tau = rho_oil c_oil d / (6 h): 1 ms for ~13 um droplets in
    # still gas (Nu = 2) or 50 um in a spray (h ~ 1.4e4 W/(m2 K)); 50 um in still gas: 14 ms.
    oil_time_constant_s: float = 1.0e-3
    suction_quality: float | None = None  # wet suction's vapour mass fraction (CoolProp only)
    # A liquid that fills chamber volume (quasi1d/liquid.py): its density (None: the oil's
    # volume is neglected), the inlet's gas volume fraction (1: gas only; below 1 the liquid,
    # of heat capacity oil_cp_J_kgK, is drawn in with the gas), viscosity (water at 20 C).
    liquid_density_kg_m3: float | None = None
    liquid_viscosity_Pa_s: float = 1.0e-3
    gas_volume_fraction: float = 1.0
    liquid_volatile: str | None = None  # a volatile liquid's CoolProp name (.vapour)
    suction_relative_humidity: float = 1.0
    lewis_number: float = 1.0

    KEYS = (
        "p_suction_bar", "p_discharge_bar", "T_suction_K", "speed_rpm", "fluid",
        "volume_ratio", "suction_close_deg", "discharge_open_deg", "T_wall_K",
        "discharge_early_opening_deg", "heat_transfer_W_m2K", "heat_transfer_correlation",
        "heat_capacity", "molar_mass_g_mol", "cp_J_kgK",
        "oil_mass_ratio", "T_oil_K", "oil_cp_J_kgK", "oil_time_constant_ms", "suction_quality",
        "liquid_density_kg_m3", "gas_volume_fraction", "liquid_cp_J_kgK", "liquid_volatile",
        "suction_relative_humidity", "lewis_number", "liquid_viscosity_Pa_s",
        "driven",  # a geometry key that the case file keeps in [operating]; not used here
        "discharge_port",  # a geometry key too: the chamber table's area_hp holds the ports
    )

    @property
    def constant_cp_gas(self) -> PerfectGas:
        """The perfect gas of ``molar_mass_g_mol`` and ``cp_J_kgK``: the fluid when
        heat_capacity is "constant", and the gas of the CFD chamber case."""
        return PerfectGas(molar_mass_kg_kmol=1e3 * self.molar_mass_kg_mol,
                          cp_J_kgK=self.cp_J_kgK)

    @property
    def R_J_kgK(self) -> float:
        return self.constant_cp_gas.R

    @property
    def perfect_gas(self) -> bool:
        """Air with a constant cp (closed-form properties)."""
        return self.fluid == "air" and self.heat_capacity == "constant"

    @property
    def pressure_ratio(self) -> float:
        return self.p_discharge_Pa / self.p_suction_Pa

    @property
    def wall_temperature_K(self) -> float:
        return self.T_suction_K if self.T_wall_K is None else self.T_wall_K

    @property
    def oil_temperature_K(self) -> float:
        return self.T_suction_K if self.T_oil_K is None else self.T_oil_K

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> Operating:
        s = "operating"
        _check_keys(d, cls.KEYS, s, where)
        ps = _number(d, "p_suction_bar", s, where, positive=True)
        pd = _number(d, "p_discharge_bar", s, where, positive=True)
        if pd <= ps:
            raise CaseError(
                f"p_discharge_bar = {pd} is not above p_suction_bar = {ps} in [{s}] of {where}; "
                "a compressor needs a discharge pressure above its suction pressure"
            )
        fluid = d.get("fluid", "air")
        if not isinstance(fluid, str):
            raise CaseError(f"key 'fluid' in [{s}] of {where} must be a string, got {fluid!r}")
        check_fluid(fluid, where)
        vr = d.get("volume_ratio")
        if vr is not None:
            vr = _number(d, "volume_ratio", s, where)
            if vr < 1.0:
                raise CaseError(
                    f"key 'volume_ratio' in [{s}] of {where} must be at least 1, got {vr}")
        sc = d.get("suction_close_deg")
        do = d.get("discharge_open_deg")
        if sc is not None:
            sc = math.radians(_number(d, "suction_close_deg", s, where, nonnegative=True))
        if do is not None:
            do = math.radians(_number(d, "discharge_open_deg", s, where, nonnegative=True))
        early = math.radians(_number(d, "discharge_early_opening_deg", s, where, 0.0,
                                     nonnegative=True))
        if early and do is not None:
            raise CaseError(f"give discharge_open_deg or discharge_early_opening_deg in [{s}] "
                            f"of {where}, not both")
        if sc is not None and do is not None and do <= sc:
            raise CaseError(
                f"discharge_open_deg must be later than suction_close_deg in [{s}] of {where}"
            )
        Tw = d.get("T_wall_K")
        Toil = d.get("T_oil_K")
        perfect = [k for k in ("cp_J_kgK", "molar_mass_g_mol") if k in d]
        own = perfect + (["heat_capacity"] if "heat_capacity" in d else [])
        if own and fluid != "air":
            raise CaseError(f"key '{own[0]}' in [{s}] of {where} is for fluid \"air\"; "
                            f"{fluid} brings its own properties")
        heat_capacity = _choice(d, "heat_capacity", s, where, HEAT_CAPACITIES,
                                "constant" if perfect else "temperature")
        if perfect and heat_capacity == "temperature":
            raise CaseError(f"key '{perfect[0]}' in [{s}] of {where} sets a constant-cp gas; "
                            "heat_capacity = \"temperature\" uses dry air's cp(T)")
        liquid = parse_keys(d, s, where)
        return cls(
            p_suction_Pa=ps * BAR,
            p_discharge_Pa=pd * BAR,
            T_suction_K=_number(d, "T_suction_K", s, where, positive=True),
            speed_rpm=_number(d, "speed_rpm", s, where, positive=True),
            fluid=fluid,
            volume_ratio=vr,
            suction_close_rad=sc,
            discharge_open_rad=do,
            discharge_early_opening_rad=early,
            T_wall_K=None if Tw is None else _number(d, "T_wall_K", s, where, positive=True),
            **heat.parse_keys(d, s, where),
            heat_capacity=heat_capacity,
            molar_mass_kg_mol=1e-3 * _number(d, "molar_mass_g_mol", s, where,
                                             AIR_MOLAR_MASS_G_MOL, positive=True),
            cp_J_kgK=_number(d, "cp_J_kgK", s, where, AIR_CP_J_KGK, positive=True),
            oil_mass_ratio=_number(d, "oil_mass_ratio", s, where, 0.0, nonnegative=True),
            T_oil_K=None if Toil is None else _number(d, "T_oil_K", s, where, positive=True),
            oil_cp_J_kgK=liquid.pop("cp", None) or _number(d, "oil_cp_J_kgK", s, where, 1900.0,
                                                           positive=True),
            oil_time_constant_s=1e-3 * _number(d, "oil_time_constant_ms", s, where, 1.0,
                                               positive=True),
            suction_quality=_number(d, "suction_quality", s, where)
            if "suction_quality" in d else None,  # checked by fluids.make_fluid
            **liquid,
        )

    def check_ideal_gas(self, where: str = "the case") -> None:
        """cp must exceed R for an ideal gas (gamma > 1)."""
        if self.perfect_gas and self.cp_J_kgK <= self.R_J_kgK:
            raise CaseError(
                f"cp_J_kgK = {self.cp_J_kgK} must exceed the gas constant "
                f"{self.R_J_kgK:.1f} J/(kg K) in [operating] of {where}"
            )


@dataclass(frozen=True)
class Leakage:
    """Leakage through the clearance gaps along every sealing line of the chamber table.

    ``model``: "none"; "nozzle" (isentropic nozzle, seed 001 Eqs. 7-8, mass flow times
    ``coefficient``); "fanno" (isothermal flow with friction, seed 003 Eq. 9, with the
    resistance ``zeta`` = f L_g / D_g + sum(xi), mass flow times ``coefficient``).
    ``wall_motion`` adds the Couette flow dragged through the interlobe gaps by the rotor
    surface (half the tip speed times the gap), from the older into the younger chamber.
    "cfd-calibrated": the isentropic nozzle times the flow coefficient Cd(Re, PR, L/h, V)
    fitted to the CFD leakage matrix (``correlation``: the fit's JSON file, written by the
    cfd.leakage stage), with the land length ``land_mm`` of the sealing lines and the gas
    viscosity ``viscosity_Pa_s`` for the gap Reynolds number.  With ``wall_motion`` and a
    fit that has a wall term (w != 0) the drag on the interlobe lines is the fit's own: the
    wall speed ratio V = U sqrt(rho / p) (U half the tip speed, positive when the drag runs
    from the upstream side) goes into the correlation and no separate Couette term is
    added; at equal pressures the flow is the fit's drag flow, about w rho U h.  A fit
    without a wall term (w = 0) keeps the separate Couette term.  ``mixture`` (a liquid):
    "homogeneous" (default, :mod:`rotorflow.quasi1d.oil`), "gas" (gas only), "centrifuged"
    (:func:`rotorflow.quasi1d.liquid.centrifuged_leakage`).
    "rarefied" (vacuum pumps): continuum, slip, transition and free-molecular flow in one
    law (:mod:`rotorflow.quasi1d.rarefied`: Beskok & Karniadakis's unified model along the
    land ``land_mm``, its free-molecular limit the slot's Clausing transmission
    probability, in series with the inertial nozzle flux of the same gap), with the gas
    viscosity ``viscosity_Pa_s`` for the mean free path and the walls' tangential
    momentum ``accommodation`` coefficient (1: diffuse, the default; 0 < sigma <= 1).

    Paths.  The chamber table declares the leakage paths (interlobe lines, end faces,
    and a family's tips, blow-holes, ...; see :mod:`rotorflow.geometry.table`).  These
    settings hold for every path; a sub-table overrides them for one kind of path or one
    named path, with the keys gap_um, model, coefficient, zeta, land_mm, correlation::

        [leakage.end-face]              # kinds: interlobe, tip, blow-hole, end-face, port
        gap_um = 40
        [leakage.paths."interlobe+2"]   # a path by the name the chamber table gives it
        model = "none"

    The most specific setting wins: the named path's, the kind's, the table's own
    declaration (its gap and model), then this section's.  ``model = "none"`` here seals
    every path the case file does not open in a sub-table.  ``wall_motion``, ``mixture``,
    ``viscosity_Pa_s`` and ``accommodation`` hold for all paths.  An unknown key, or a
    kind or path name the chamber table does not declare, is an error naming it and the
    file (the names are checked against the table when the model is built:
    :mod:`rotorflow.quasi1d.paths`).
    """

    gap_m: float = 0.0
    model: str = "nozzle"
    coefficient: float = 1.0
    # zeta = f L/D + sum(xi): f ~ 0.04, L/D ~ 10 for a 1 mm land over a 50 um gap,
    # plus ~1.5 for the entry and exit losses -> ~2; seed 003 takes it as an input.
    zeta: float = 2.0
    wall_motion: bool = False
    correlation: object = None  # a quasi1d.calibrated.FlowCoefficientFit
    land_m: float = 1.0e-3
    viscosity_Pa_s: float = 1.8e-5  # air near 300 K
    mixture: str = "homogeneous"  # with oil injected: gas and oil leak together, or "gas"
    accommodation: float = 1.0  # "rarefied": diffuse walls (machined metal: ~0.9-1)
    # Overrides, as ((kind or path name, paths.PathSettings), ...) in the file's order
    by_kind: tuple = ()
    by_path: tuple = ()

    KEYS = ("gap_um", "model", "coefficient", "zeta", "wall_motion", "correlation", "land_mm",
            "viscosity_Pa_s", "mixture", "accommodation")
    MIXTURES = ("homogeneous", "gas", "centrifuged")

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> Leakage:
        from .paths import OVERRIDE_SECTIONS, read_overrides

        s = "leakage"
        _check_keys(d, cls.KEYS + OVERRIDE_SECTIONS, s, where)
        model = _choice(d, "model", s, where, LEAKAGE_MODELS, "nozzle")
        gap = _number(d, "gap_um", s, where, 0.0 if model == "none" else None, nonnegative=True)
        if model != "none" and gap <= 0:
            raise CaseError(f"key 'gap_um' in [{s}] of {where} must be positive for model "
                            f'"{model}", got {gap}')
        fit = _load_correlation(d, s, where) if model == "cfd-calibrated" else None
        if fit is None and "correlation" in d:
            raise CaseError(f"key 'correlation' in [{s}] of {where} needs model "
                            '"cfd-calibrated"')
        by_kind, by_path = read_overrides(d, where, model, fit)
        return cls(
            gap_m=gap * 1e-6,
            model=model,
            coefficient=_number(d, "coefficient", s, where, 1.0, positive=True),
            zeta=_number(d, "zeta", s, where, 2.0, positive=True),
            wall_motion=_bool(d, "wall_motion", s, where, False),
            correlation=fit,
            land_m=_number(d, "land_mm", s, where, 1.0, positive=True) * 1e-3,
            viscosity_Pa_s=_number(d, "viscosity_Pa_s", s, where, 1.8e-5, positive=True),
            mixture=_choice(d, "mixture", s, where, cls.MIXTURES, "homogeneous"),
            accommodation=_accommodation(d, s, where),
            by_kind=tuple(by_kind.items()),
            by_path=tuple(by_path.items()),
        )


def _accommodation(d: dict, section: str, where: str) -> float:
    """sigma of Maxwell's wall model: the diffusely reflected fraction, in (0, 1]."""
    a = _number(d, "accommodation", section, where, 1.0, positive=True)
    if a > 1.0:
        raise CaseError(f"key 'accommodation' in [{section}] of {where} must be at most 1 "
                        f"(the diffusely reflected fraction), got {a}")
    return a


def _load_correlation(d: dict, section: str, where: str):
    """The CFD flow-coefficient fit named by ``correlation`` (relative to the case file)."""
    from .calibrated import FlowCoefficientFit, correlation_path

    name = d.get("correlation")
    if not isinstance(name, str):
        raise CaseError(f"key 'correlation' in [{section}] of {where} must name the fit's "
                        "JSON file (model \"cfd-calibrated\")")
    path = correlation_path(name, where)
    if not path.is_file():
        raise CaseError(f"flow-coefficient fit not found: {path} ([{section}] of {where})")
    try:
        return FlowCoefficientFit.from_json(path.read_text())
    except (ValueError, KeyError, TypeError) as exc:
        raise CaseError(f"malformed flow-coefficient fit {path}: {exc}") from None


@dataclass(frozen=True)
class Ports:
    """Suction and discharge through the end-face port areas.

    "ideal": lossless; a chamber open to a port is at the plenum pressure (an algebraic
    constraint, solved for the port flow), and a pressure mismatch when the discharge
    port opens is equalised at once (blow-down of the remaining gas isentropic, back-flow
    mixed at constant volume).  "nozzle": isentropic nozzle through the exposed end-face
    area times ``coefficient``.
    """

    model: str = "ideal"
    coefficient: float = 0.8  # discharge coefficient of a sharp-edged port
    # The gas the discharge plenum holds (what flows back from it): "isentropic", the end
    # state of the pressure ratio from suction; "delivered", the delivered gas's own
    # (:mod:`.delivered_plenum`: a dry gas, found by one cycle solve per iterate)
    discharge_plenum: str = "isentropic"
    discharge_plenum_K: float | None = None  # (set by that iteration, not a key)

    KEYS = ("model", "coefficient", "discharge_plenum")

    @property
    def reads_areas(self) -> bool:
        """Whether the ports flow through the chamber table's port areas (nozzle ports);
        ideal ones follow its port timing alone (:mod:`.network`), so a table for them
        may leave the areas out (:func:`rotorflow.geometry.summary.chamber_table`)."""
        return self.model != "ideal"

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> Ports:
        s = "ports"
        _check_keys(d, cls.KEYS, s, where)
        return cls(
            model=_choice(d, "model", s, where, PORT_MODELS, "ideal"),
            coefficient=_number(d, "coefficient", s, where, 0.8, positive=True),
            discharge_plenum=_choice(d, "discharge_plenum", s, where,
                                     ("isentropic", "delivered"), "isentropic"),
        )


@dataclass(frozen=True)
class Numerics:
    """How the chamber equations are integrated and when a cycle counts as converged."""

    # "auto" (the default): dopri5, switching to ros23 when a period proves stiff, and
    # ros23 from the start with nozzle ports; "dopri5": explicit Dormand-Prince 5(4);
    # "bs3": Bogacki-Shampine 3(2); "ros23": Rosenbrock 2(3), linearly implicit;
    # "radau"/"bdf": scipy's implicit solvers, the reference.
    integrator: str = "auto"
    # Tolerances per component: rtol relative; atol relative to reference scales (chamber
    # mass and energy of a chamber at birth; a cycle's mass, enthalpy and work for the
    # accumulated figures).
    # The error of every component is held to rtol (a max norm, quasi1d/integrate.py), so
    # each chamber's pressure trace is, not only the integrals: at 1e-4 the trace of the
    # PDSim benchmark (nozzle ports) is within 4e-5 of p_discharge of the Radau
    # reference, mass flow and power within 1.4e-4 on the default case (make bench).
    # 5e-4 would halve the run time, but on a coarse real-fluid table the period map is
    # then too rough for Newton's method (a stress point stalls at 3e-4).
    rtol: float = 1.0e-4
    atol: float = 1.0e-6
    max_cycles: int = 40
    # A cycle is periodic when p and T at the start of a lobe period change by less than
    # this (relative) and the cycle's mass and energy balance close to balance_tol.
    cycle_rtol: float = 1.0e-6
    # 1e-7 so that the 1e-6 required of mass and energy closure holds with margin.
    balance_tol: float = 1.0e-7
    # A chamber is born / dies (handed over with its mass and energy) where its volume
    # passes this fraction of V_max; its p V is booked as work, so no energy is lost.
    vanish_fraction: float = 1.0e-3
    max_steps: int = 200_000  # per lobe period; more means the problem is too stiff
    newton: bool = True  # Newton shooting on the period map (else plain cycle iteration)
    # Wall-clock budget of one cycle solve [s]: a point that needs more is returned
    # unconverged, with the budget named, rather than left to run on (a typical point
    # takes 0.1-5 s; an absurd pressure ratio can take minutes to exhaust max_cycles).
    max_seconds: float = 60.0

    KEYS = ("integrator", "rtol", "atol", "max_cycles", "cycle_rtol", "balance_tol",
            "vanish_fraction", "max_steps", "newton", "max_seconds")

    @classmethod
    def from_section(cls, d: dict, where: str = "the case") -> Numerics:
        s = "numerics"
        _check_keys(d, cls.KEYS, s, where)
        n = cls(
            integrator=_choice(d, "integrator", s, where, INTEGRATORS, "auto"),
            rtol=_number(d, "rtol", s, where, 1e-4, positive=True),
            atol=_number(d, "atol", s, where, 1e-6, positive=True),
            max_cycles=_number(d, "max_cycles", s, where, 40, positive=True, integer=True),
            cycle_rtol=_number(d, "cycle_rtol", s, where, 1e-6, positive=True),
            balance_tol=_number(d, "balance_tol", s, where, 1e-7, positive=True),
            vanish_fraction=_number(d, "vanish_fraction", s, where, 1e-3, positive=True),
            max_steps=_number(d, "max_steps", s, where, 200_000, positive=True, integer=True),
            newton=_bool(d, "newton", s, where, True),
            max_seconds=_number(d, "max_seconds", s, where, 60.0, positive=True),
        )
        if n.vanish_fraction >= 0.1:
            raise CaseError(f"key 'vanish_fraction' in [{s}] of {where} must be below 0.1")
        return n


