"""The twin-screw pair's own design figures (seed 004: area utilisation, groove areas)."""

from __future__ import annotations

import math


def pair_figures(pair) -> dict:
    """Lobes, pitch and outer radii, groove (interlobe) areas and the area utilisation.

    A whole groove is the bore less the rotor, shared by its lobes: the tips seal on the
    bore, so the N grooves of a rotor fill its bore exactly, A_0 = (pi R^2 - A_rotor) / N.
    The area utilisation coefficient is N1 (A_01 + A_02) / D1^2: the displacement per
    male turn of a straight pair of unit length (Xing's C_n; seed 004 names the figure).
    """
    g = pair.gearing
    d1 = 2.0 * pair.male_radius
    a1 = (math.pi * pair.male_radius ** 2 - pair.male.area) / g.lobes_male
    a2 = (math.pi * pair.female_radius ** 2 - pair.female.area) / g.lobes_female
    x, y = pair.cusp
    return {
        "profile": pair.label,
        "lobes_male": g.lobes_male,
        "lobes_female": g.lobes_female,
        "centre_distance_mm": g.centre_distance * 1e3,
        "male_diameter_mm": d1 * 1e3,
        "female_diameter_mm": 2.0 * pair.female_radius * 1e3,
        "pitch_radius_male_mm": g.r1 * 1e3,
        "pitch_radius_female_mm": g.r2 * 1e3,
        "groove_area_male_mm2": a1 * 1e6,
        "groove_area_female_mm2": a2 * 1e6,
        "area_utilisation": g.lobes_male * (a1 + a2) / (d1 * d1),
        "cusp_mm": [x * 1e3, y * 1e3],
        **_flank_angles(pair),
    }


def _flank_angles(pair) -> dict:
    """The straight rack flanks' angles from the line of centres (their pressure angles:
    each generates an involute of r cos(angle) on both rotors), where the rack has
    any (the involute pump rack, the line-circle rack)."""
    from .arcs import Line
    from .meshing import RackGenerated

    angles = [math.degrees(piece.arc.inclination()) for piece in pair.male.pieces
              if isinstance(piece, RackGenerated) and isinstance(piece.arc, Line)]
    return {"rack_flank_angles_deg": angles} if angles else {}
