"""Geometry figures of a case as one flat dictionary (the `rotorflow geometry` JSON)."""

from __future__ import annotations

import math

import numpy as np

from .films import polar_moment
from .forces import power_split
from .machine import SweptMachine
from .section import POINTS_PER_PERIOD
from .table import ChamberTable, opening_column, track_column


def build_machine(case, points_per_period: int | None = None) -> SweptMachine:
    """The case's pair swept by its sweep law (a wrap given as wrap_bar needs the
    chamber's planar life first), at the case's points per period unless given."""
    ppp = points_per_period or getattr(case, "points_per_period", POINTS_PER_PERIOD)
    if case.wrap is not None:
        return SweptMachine(case.pair, case.sweep(None), ppp)
    if case.pair.life_on_nodes:
        sec = case.pair.section(ppp)
        return SweptMachine(case.pair, case.sweep(sec.phi_f - sec.phi_i), ppp)
    # The planar life between the section nodes (the twin screw's) does not depend on
    # the sweep: found on a machine with the nodes' life, handed to the one with the wrap
    # it sets (so that wrap_bar names one wrap at every resolution).
    first = SweptMachine(case.pair, case.sweep(0.0), ppp)
    birth, death = first.planar_life
    m = SweptMachine(case.pair, case.sweep(death - birth), ppp)
    m.__dict__["planar_life"] = (birth, death)  # (the cached property's slot)
    return m


def case_power_split(case, m: SweptMachine, driven: str = "auto"):
    """The ideal cycle's power split (:func:`.forces.power_split`) at 1 bar suction; a
    case without internal compression (volume_ratio = 1) discharges into its
    [operating] pressure ratio, which it must then give."""
    if case.volume_ratio != 1.0:
        return power_split(m, case.volume_ratio, driven)
    from rotorflow.errors import CaseError

    op = case.raw.get("operating", {})
    if not all(isinstance(op.get(k), (int, float)) for k in ("p_suction_bar", "p_discharge_bar")):
        raise CaseError(f"volume_ratio = 1 (no internal compression) in [operating] of "
                        f"{case.name}: the ideal cycle needs p_suction_bar and p_discharge_bar")
    ratio = float(op["p_discharge_bar"]) / float(op["p_suction_bar"])
    return power_split(m, 1.0, driven, p_discharge=1.0e5 * ratio)


def _deg(x):
    return math.degrees(x)


def _volume_peak(m: SweptMachine, k_max: int) -> float:
    from .ports import _volume_peak

    return _volume_peak(m, k_max)


def geometry_figures(case, machine: SweptMachine | None = None) -> dict:
    """The family's own figures, then the sweep's, volumes, loads and port timing."""
    m = machine or build_machine(case)
    pair, sec, cur = m.pair, m.section, m.curves
    d = pair.diameter
    reference = pair.rotors[0]
    split = case_power_split(case, m, case.driven)
    v_sw_bar = m.swept_volume / m.cylinder_volume
    n_dr = pair.rotor(split.driven).lobes
    phi = cur.phi
    k_max = int(np.argmax(cur.volume))
    radial = {}  # the radial port's figures, where the case asks for one
    if getattr(pair, "port_areas", False):
        # The chamber meets the end plates long before and after its ports (a twin-screw
        # groove reaches the discharge plate while still filling): the port timing.
        timing = case_port_timing(case, m)
        suction_close = phi[0] + timing.suction_close
        discharge_open = phi[0] + timing.discharge_open
        if "radial" in _discharge_ports(case):
            radial = pair.radial_port(m, timing).figures()
    else:
        suction_close = phi[np.nonzero(cur.area_lp > 0.0)[0][-1]]
        discharge_open = phi[np.nonzero(cur.area_hp > 0.0)[0][0]]
    # (angles since the birth itself, not the grid's first node: :attr:`.SweptMachine.
    # birth_age`)
    birth, death = m.planar_life
    wraps = {f"wrap_{r.name}_deg": _deg(m.sweep.wrap * abs(r.speed_ratio)) for r in pair.rotors}
    return {
        "case": case.name,
        "machine": pair.family,
        **pair.figures(),
        **pair.swept_figures(m),
        "phi_i_deg": _deg(birth),
        "phi_f_deg": _deg(death),
        **wraps,
        "wrap_bar": m.wrap_bar,
        "pitch_over_length": None if m.pitch_length is None else m.pitch_length / m.sweep.length,
        "A_wc_bar_max": 4.0 * sec.area_max / (math.pi * d * d),
        "V_sw_bar": v_sw_bar,
        # per revolution of the driven rotor (seed 000 section 5)
        "V_dr_bar": v_sw_bar * n_dr / reference.lobes,
        "driven": split.driven,
        "Pi_max": split.pi_max,
        "power_balance_error": split.power_balance_error,
        "chamber_volume_max_m3": m.volume_max,
        "swept_volume_m3": m.swept_volume,
        # between the nodes, as the suction port closes there (:func:`.ports.port_timing`)
        "angle_volume_max_deg": _deg(_volume_peak(m, k_max) - birth),
        "angle_suction_close_deg": _deg(suction_close - birth),
        "angle_discharge_open_deg": _deg(discharge_open - birth),
        "volume_suction_close_m3": float(m.volume_at(suction_close)[0]),
        "chamber_life_deg": _deg(death - birth + m.sweep.wrap),
        "volume_ratio": case.volume_ratio,
        **radial,
    }


def chamber_table(case, machine: SweptMachine | None = None,
                  port_areas: bool = True) -> ChamberTable:
    """The chamber table the quasi-1D model reads (see :mod:`.table`).  Without
    ``port_areas`` a family that sweeps its port areas (the twin screw: 40-50 % of its
    table's time) leaves them out (zeros, ``table.port_areas`` False): ideal ports follow
    the port timing alone, which is kept."""
    m = machine or build_machine(case)
    cur = m.curves
    pair = m.pair
    driven = case.driven if case.driven != "auto" else case_power_split(case, m).driven
    # Reference-rotor turns per driven-rotor turn: the inverse of the speed ratio, from
    # the lobe counts (exact for gearing, N_driven / N_reference).
    ratio = pair.rotor(driven).lobes / pair.rotors[0].lobes
    lines = m.seal_lines
    far = {d: v for d, v in lines.items() if abs(d) >= 2}
    zero = np.zeros_like(cur.phi)
    load_columns, rotor_scalars = _rotor_loads(m)
    tracks = m.track_lines
    load_columns.update({track_column(name, d): v for (name, d), v in tracks.items()})
    openings = m.opening_areas
    load_columns.update({opening_column(name, d): v for (name, d), v in openings.items()})
    load_columns.update(pair.face_columns(m))
    area_lp, area_hp = cur.area_lp, cur.area_hp
    timing = {}
    swept = getattr(pair, "port_areas", False)
    if swept and port_areas:
        area_lp, area_hp, parts = _port_areas(case, m)
        load_columns.update(parts)
    elif swept:
        area_lp, area_hp = np.zeros_like(cur.phi), np.zeros_like(cur.phi)
    if swept:
        timing = _timing_scalars(case, m)
    paths = pair.leakage_paths(far, tracks, openings)
    return ChamberTable(
        angle_rad=cur.phi - m.planar_life[0],
        volume_m3=cur.volume,
        dVdangle_m3_rad=cur.dvolume,
        area_lp_m2=area_lp,
        area_hp_m2=area_hp,
        seal_next_m=lines.get(1, zero),
        seal_prev_m=lines.get(-1, zero),
        seal_lp_face_m=cur.perimeter_lp,
        seal_hp_face_m=cur.perimeter_hp,
        lobes_outer=pair.rotors[0].lobes,
        speed_ratio_outer_per_driven=ratio,
        length_m=m.sweep.length,
        diameter_m=pair.diameter,
        seal_far=far,
        machine=pair.family,
        leakage_paths=paths,
        columns=load_columns,
        rotor_names=tuple(r.name for r in pair.rotors),
        speed_ratios=tuple(float(r.speed_ratio) for r in pair.rotors),
        rotor_scalars=rotor_scalars,
        oil_films=pair.oil_films(paths),
        port_timing=timing,
        port_areas=port_areas or not swept,
    )


def _discharge_ports(case) -> tuple[str, ...]:
    """The discharge ports the case asks for ([operating] discharge_port, checked by the
    case loader): ("axial",), ("radial",) or ("axial", "radial")."""
    return tuple(getattr(case, "discharge_port", "axial").split("+"))


def _port_areas(case, m: SweptMachine):
    """(suction, discharge, columns): the areas open to the ports against age, for a
    family whose chamber meets an end plate long before the port (the twin screw's
    grooves reach the discharge plate while still filling): its face section inside the
    port, not the whole section.  The discharge is the sum of the ports the case asks
    for; with a radial port, each part is also a column of its own (area_hp_axial_m2,
    area_hp_radial_m2), so that reports can show them."""
    from .ports import open_areas

    cur = m.curves
    ages = cur.phi - cur.phi[0]
    timing = case_port_timing(case, m)
    kinds = _discharge_ports(case)
    area_lp, axial = open_areas(m, timing, ages, cut_discharge="axial" in kinds)
    if "radial" not in kinds:
        return area_lp, axial, {}
    radial = m.pair.radial_port(m, timing).open_area(ages)
    return area_lp, axial + radial, {"area_hp_axial_m2": axial, "area_hp_radial_m2": radial}


def _timing_scalars(case, m: SweptMachine) -> dict[str, float]:
    """The port timing the table's port areas follow, for the quasi-1D model to read
    (:func:`rotorflow.quasi1d.chamber.prepare`): one rule, :func:`.ports.port_timing`."""
    t = case_port_timing(case, m)
    op = case.raw.get("operating", {})
    b = m.birth_age  # (the table's angles are counted from the birth)
    return {"suction_close_rad": t.suction_close - b, "discharge_open_rad": t.discharge_open - b,
            "volume_ratio": float(case.volume_ratio),
            "early_opening_rad": math.radians(float(op.get("discharge_early_opening_deg", 0.0)))}


def case_port_timing(case, m: SweptMachine):
    """The case's port timing (volume ratio, early opening, or explicit angles)."""
    from .ports import port_timing

    op = case.raw.get("operating", {})
    early = math.radians(float(op.get("discharge_early_opening_deg", 0.0)))
    sc, do = op.get("suction_close_deg"), op.get("discharge_open_deg")
    return port_timing(m, case.volume_ratio, None if sc is None else math.radians(sc),
                       None if do is None else math.radians(do), early)


def _groove(rotor, area: float) -> dict[str, float]:
    """The rotor's grooves in its transverse section (its tip circle less its section):
    their area and their radius of gyration about the rotor's axis, sqrt(int r^2 dA / A),
    for the liquid they carry (:func:`rotorflow.quasi1d.mechanical.liquid_acceleration_W`).
    """
    tip = float(rotor.profile.radius_max)
    groove = math.pi * tip**2 - area
    moment = 0.5 * math.pi * tip**4 - abs(float(polar_moment(rotor.profile)))
    return {f"groove_area_{rotor.name}_m2": groove,
            f"groove_gyration_{rotor.name}_m": math.sqrt(moment / groove)}


def _rotor_loads(m: SweptMachine) -> tuple[dict, dict]:
    """The gas-load columns and per-rotor scalars of the chamber table (see :mod:`.table`).

    Axial force on the flanks: rotor r's section at height z is its own section at
    z = 0 turned by -s_r twist(z) (:mod:`.sweep`), so with a constant lead the screw
    motion (turn by w, advance by -w / (s_r twist')) maps the rotor onto itself.  The
    fluid does no work on a surface that slides along itself: T w + F_z V = 0, hence
    F_z = s_r twist' T (T: the fluid's torque).  A conical sweep has no such motion
    (its flanks taper and its lead varies): no scalar, the quasi-1D model says so.

    End face: the rotor's section at the high-pressure end (the rotor's material inside
    its profile, or for a rotor whose material lies outside its profile, the ring out to
    the casing bore about its axis), scaled by the sweep's end scale.
    """
    cur, pair, sw = m.curves, m.pair, m.sweep
    columns, scalars = {}, {}
    end_scale2 = float(sw.scale(sw.length)) ** 2
    for r, rotor in enumerate(pair.rotors):
        name = rotor.name
        columns[f"force_{name}_x_m2"] = cur.force[:, r, 0]
        columns[f"force_{name}_y_m2"] = cur.force[:, r, 1]
        columns[f"torque_{name}_m3"] = cur.torque[:, r]
        if sw.kind in ("straight", "helical"):
            scalars[f"axial_per_torque_{name}_per_m"] = float(
                rotor.speed_ratio * sw.wrap / sw.length)
        area = abs(float(rotor.profile.area))
        if rotor.material_inside and sw.kind in ("straight", "helical"):
            scalars.update(_groove(rotor, area))
        if not rotor.material_inside:
            bores = [rad for centre, rad in pair.casing_bores()
                     if np.allclose(centre, rotor.axis)]
            area = math.pi * bores[0] ** 2 - area if bores else None
        if area is not None:
            scalars[f"end_area_{name}_m2"] = area * end_scale2
    return columns, scalars
