"""Readable names and units of the figures the report shows (geometry.json, the
quasi-1D summary.json), and the labelled table that shows them.

The JSON keys stay what they are (scripts, sweeps and the optimiser read them); only
the report spells them out.  A key this module does not know keeps its raw name, so a
new figure shows up before anyone labels it.

Angles: every angle of the chamber table is the reference rotor's (rotor 0: the outer
rotor of an internal gear, the male of a twin screw), counted from the chamber's birth
unless said otherwise.  The geometry's ``angle_suction_close_deg`` and
``angle_discharge_open_deg`` mean different things per family (:mod:`rotorflow.geometry.
summary`): where the pair has port areas (twin screw) they are the port timing; where it
does not (internal gear) they are the chamber's last contact with the low-pressure end
plane and its first contact with the high-pressure end plane, which are *not* when the
ports close and open (those come from the volume ratio: the quasi-1D section's
``suction_close_deg`` and ``discharge_open_deg``).
"""

from __future__ import annotations

import re

#: Geometry figures with the same meaning in every family: key -> (name, unit).  In
#: units, "{age}" becomes the reference rotor's angle since the chamber's birth and
#: "{ref}" the reference rotor's name.
GEOMETRY = {
    "case": ("Case", ""),
    "machine": ("Machine family", ""),
    # internal gear (seed 000 Eqs. 1, 4, 5)
    "lobes_outer": ("Lobes of the outer rotor N1", ""),
    "lobes_inner": ("Lobes of the inner rotor N2", ""),
    "m21": ("Speed ratio inner / outer rotor m21 = N1 / N2", ""),
    "lambda": ("Pin-circle radius / outer pitch radius λ = a / (N1 E)", ""),
    "sigma": ("Pin radius / outer pitch radius σ = ρ / (N1 E)", ""),
    "sigma_lim": ("Undercut limit of the pin radius σ_lim", ""),
    "sigma_bar": ("Pin radius / its undercut limit σ / σ_lim", ""),
    "E_over_D": ("Centre distance (eccentricity) E / D", ""),
    "a_over_D": ("Pin-circle radius a / D", ""),
    "rho_over_D": ("Pin radius ρ / D", ""),
    "pressure_angle_deg": ("Pressure angle at the pitch point", "deg"),
    "pitch_point_contact": ("Contact passes through the pitch point", ""),
    # twin screw (seed 004)
    "profile": ("Rack profile", ""),
    "lobes_male": ("Lobes of the male rotor", ""),
    "lobes_female": ("Lobes of the female rotor", ""),
    "centre_distance_mm": ("Centre distance", "mm"),
    "male_diameter_mm": ("Outer diameter of the male rotor", "mm"),
    "female_diameter_mm": ("Outer diameter of the female rotor", "mm"),
    "pitch_radius_male_mm": ("Pitch radius of the male rotor", "mm"),
    "pitch_radius_female_mm": ("Pitch radius of the female rotor", "mm"),
    "groove_area_male_mm2": ("Groove (interlobe) area of the male rotor", "mm²"),
    "groove_area_female_mm2": ("Groove (interlobe) area of the female rotor", "mm²"),
    "area_utilisation": ("Area utilisation N1 (A01 + A02) / D1²", ""),
    "cusp_mm": ("Cusp of the two bores (x, y)", "mm"),
    "blow_hole_area_mm2": ("Blow-hole area (largest opening at the discharge-side cusp)",
                           "mm²"),
    "contact_line_length_max_mm": ("Interlobe contact line, longest over a lobe period",
                                   "mm"),
    "contact_line_length_min_mm": ("Interlobe contact line, shortest over a lobe period",
                                   "mm"),
    # sweep, volumes, loads
    "phi_i_deg": ("Chamber birth in the transverse section φ_i", "deg, {ref} rotor"),
    "phi_f_deg": ("Chamber death in the transverse section φ_f", "deg, {ref} rotor"),
    "wrap_bar": ("Normalised wrap: wrap / transverse chamber life (φ_f − φ_i)", ""),
    "pitch_over_length": ("Axial advance per lobe period / rotor length", ""),
    "A_wc_bar_max": ("Largest transverse chamber area / (π D² / 4)", ""),
    "V_sw_bar": ("Normalised swept volume V_sw / (π D² L / 4)", ""),
    "V_dr_bar": ("Swept volume per driven-rotor revolution / (π D² L / 4)", ""),
    "driven": ("Driven rotor", ""),
    "Pi_max": ("Largest share of the input power through the gearing contact Π_max", ""),
    "power_balance_error": ("Power balance error of the ideal cycle (relative)", ""),
    "chamber_volume_max_m3": ("Largest chamber volume V_max", "m³"),
    "swept_volume_m3": ("Swept volume per {ref}-rotor revolution V_sw = N1 V_max", "m³"),
    "angle_volume_max_deg": ("Chamber volume is largest at", "{age}"),
    "chamber_life_deg": ("Chamber life, birth to death along the whole rotor", "{age}"),
    "volume_ratio": ("Built-in volume ratio", ""),
}

#: The three figures whose meaning depends on whether the family's table has port areas.
PORT_TIMED = {
    "angle_suction_close_deg": ("Suction port closes at", "{age}"),
    "angle_discharge_open_deg": ("Discharge port opens at", "{age}"),
    "volume_suction_close_m3": ("Chamber volume when the suction port closes", "m³"),
}
END_PLANE = {
    "angle_suction_close_deg": ("Chamber's last contact with the low-pressure end plane "
                                "(not the suction port closing)", "{age}"),
    "angle_discharge_open_deg": ("Chamber's first contact with the high-pressure end plane "
                                 "(not the discharge port opening)", "{age}"),
    "volume_suction_close_m3": ("Chamber volume at its last contact with the low-pressure "
                                "end plane", "m³"),
}

#: Per-rotor geometry figures: (pattern, name with {0} = rotor, unit).
GEOMETRY_PATTERNS = (
    (r"wrap_(\w+?)_deg", "Wrap angle of the {0} rotor", "deg"),
    (r"radial_window_area_(\w+?)_mm2", "Radial discharge window in the {0} bore: area",
     "mm²"),
    (r"radial_window_length_(\w+?)_mm", "Radial discharge window in the {0} bore: axial "
     "length", "mm"),
    (r"radial_window_span_(\w+?)_deg", "Radial discharge window in the {0} bore: span at "
     "the high-pressure end plane", "deg, {0} rotor"),
    (r"radial_latest_open_(\w+?)_deg", "Latest opening a radial window in the {0} bore "
     "allows", "{age}"),
)

#: The quasi-1D summary (quasi1d.performance, quasi1d.shaft), flattened keys.
QUASI1D = {
    "mass_flow_kg_s": ("Mass flow", "kg/s"),
    "suction_volume_flow_L_min": ("Volume flow at suction conditions", "L/min"),
    "indicated_power_W": ("Indicated power (work on the gas)", "W"),
    "specific_power_J_kg": ("Indicated work per mass delivered", "J/kg"),
    "volumetric_efficiency": ("Volumetric efficiency", "fraction"),
    "adiabatic_efficiency": ("Isentropic efficiency, indicated", "fraction"),
    "isothermal_efficiency": ("Isothermal efficiency, indicated", "fraction"),
    "discharge_temperature_K": ("Discharge temperature of the gas", "K"),
    "discharge_mixture_temperature_K": ("Discharge temperature, gas and oil mixed", "K"),
    "discharge_quality": ("Vapour mass fraction of the delivered refrigerant", "fraction"),
    "warning": ("Warning", ""),
    "suction_return_enthalpy_W": ("Enthalpy carried back into the suction above its own",
                                  "W"),
    "chamber_pressure_max_Pa": ("Highest chamber pressure over the cycle", "Pa"),
    "chamber_temperature_max_K": ("Highest chamber temperature over the cycle", "K"),
    "heat_to_gas_W": ("Heat to the gas", "W"),
    "oil_flow_kg_s": ("Oil flow delivered", "kg/s"),
    "liquid_flow_kg_s": ("Liquid flow delivered", "kg/s"),
    "evaporated_kg_s": ("Liquid evaporated into the gas, net (negative: condensed)", "kg/s"),
    "discharge_vapour_fraction": ("Vapour mass fraction of the delivered gas", "fraction"),
    "cycles": ("Cycles computed", ""),
    "converged": ("Cycle converged", ""),
    "mass_balance_error": ("Mass balance error (relative)", ""),
    "energy_balance_error": ("Energy balance error (relative)", ""),
    "chambers": ("Chambers in the model", ""),
    "speed_outer_rpm": ("Speed of the {ref} (reference) rotor", "rpm"),
    "trapped_volume_m3": ("Trapped volume (at suction port closing)", "m³"),
    "suction_close_deg": ("Suction port closes at (model's port timing)", "{age}"),
    "discharge_open_deg": ("Discharge port opens at (model's port timing)", "{age}"),
    "fluid": ("Fluid", ""),
    "message": ("Solver message", ""),
    "shaft_power_W": ("Shaft power (indicated + mechanical loss)", "W"),
    "mechanical_loss_W": ("Mechanical loss", "W"),
    "adiabatic_efficiency_shaft": ("Isentropic efficiency, shaft", "fraction"),
    "loads.power_balance_error": ("Gas-load power balance error (relative)", ""),
    "mechanical.bearing_bore_m": ("Bearing bore", "m"),
    "mechanical.seal_loss_W": ("Seal loss", "W"),
    "mechanical.liquid_acceleration_W": ("Work of turning the liquid up to the rotors' speed",
                                         "W"),
    "mechanical.not_modelled": ("Not modelled", ""),
}

#: Leakage report keys (the chamber table's path keys) spelt out.
LEAK_PATHS = {"interlobe": "between chambers (interlobe)",
              "lp_face": "across the low-pressure end face",
              "hp_face": "across the high-pressure end face"}

#: Per-rotor gas-load fields of loads.rotors.<rotor>.<field>: field -> (name, unit).
ROTOR_LOADS = {
    "radial_force_N_mean": ("mean radial gas force", "N"),
    "radial_force_N_max": ("largest radial gas force", "N"),
    "axial_force_N_mean": ("mean axial gas force", "N"),
    "axial_force_N_max_abs": ("largest axial gas force |F|", "N"),
    "axial_end_force_N": ("axial gas force on the end face", "N"),
    "axial_flank_force_N_mean": ("mean axial gas force on the flanks", "N"),
    "torque_Nm_mean": ("mean gas torque", "N m"),
    "torque_Nm_min": ("smallest gas torque", "N m"),
    "torque_Nm_max": ("largest gas torque", "N m"),
    "torque_sign_changes": ("gas torque sign changes per lobe period", ""),
    "bearing_loss_W": ("bearing loss", "W"),
}


def age_unit(reference: str) -> str:
    return f"deg of {reference}-rotor turn since chamber birth"


def geometry_label(key: str, port_areas: bool, reference: str = "reference"
                   ) -> tuple[str, str]:
    """(name, unit) of a geometry figure; an unknown key keeps its raw name."""
    name, unit = (PORT_TIMED if port_areas else END_PLANE).get(key) or GEOMETRY.get(
        key, (None, ""))
    groups: tuple = ()
    if name is None:
        for pattern, label, u in GEOMETRY_PATTERNS:
            hit = re.fullmatch(pattern, key)
            if hit:
                name, unit, groups = label, u, hit.groups()
                break
        else:
            return key, ""
    return _fill(name, groups, reference), _fill(unit, groups, reference)


def quasi1d_label(key: str, reference: str = "reference") -> tuple[str, str]:
    """(name, unit) of a flattened quasi-1D summary key; unknown keys keep theirs."""
    if key in QUASI1D:
        name, unit = QUASI1D[key]
        return _fill(name, (), reference), _fill(unit, (), reference)
    head, _, path = key.partition(".")
    if head in ("leakage_kg_s", "oil_leakage_kg_s", "liquid_leakage_kg_s") and path:
        what = {"oil": "Oil leakage", "liquid": "Liquid leakage"}.get(head.split("_")[0],
                                                                     "Leakage")
        return f"{what} {LEAK_PATHS.get(path, path)}, gross", "kg/s"
    hit = re.fullmatch(r"loads\.rotors\.(\w+)\.(\w+)", key)
    if hit and hit.group(2) in ROTOR_LOADS:
        name, unit = ROTOR_LOADS[hit.group(2)]
        return f"{hit.group(1).capitalize()} rotor: {name}", unit
    return key, ""


def _fill(text: str, groups: tuple, reference: str) -> str:
    return text.replace("{age}", age_unit(reference)).replace("{ref}", reference) \
        .format(*groups)


def labelled_table(figures: dict, label, fmt, esc) -> str:
    """Figure, value, unit and the JSON key of every entry of ``figures`` (flattened),
    in their order; ``label(key) -> (name, unit)``.  The key stays in view, small,
    because it is what a script or a sweep file names."""
    rows = []
    for key, value in figures.items():
        name, unit = label(key)
        if isinstance(value, list):
            shown = ", ".join(fmt(v) for v in value)
        else:
            shown = "n/a" if value is None else fmt(value)
        rows.append(f"<tr><th>{esc(name)}</th><td class='num'>{esc(shown)}</td>"
                    f"<td>{esc(unit)}</td><td class='muted'><code>{esc(key)}</code></td></tr>")
    return ("<table class='figures'><tr><th>figure</th><th>value</th><th>unit</th>"
            f"<th>key</th></tr>{''.join(rows)}</table>")
