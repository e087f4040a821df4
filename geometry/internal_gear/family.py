"""The internal-gear family's [machine] section: pin-generated pairs (seeds 000, 001)."""

from __future__ import annotations

from rotorflow.errors import CaseError

from ..family import Family, number, register
from .pair import ROUNDING, PinGerotor, sigma_limit

KEYS = frozenset({
    "lobes_outer",
    "lambda",
    "sigma",
    "sigma_bar",
    "diameter_mm",
    "fillet",
    "fillet_apex_diameter_mm",
})


def from_section(m: dict, where: str) -> PinGerotor:
    """The pair a [machine] section describes (keys already checked against KEYS)."""
    for key in ("lobes_outer", "lambda", "diameter_mm"):
        if key not in m:
            raise CaseError(f"missing key '{key}' in {where}")
    n1 = number(m, "lobes_outer", where, integer=True)
    if n1 < 2:
        raise CaseError(f"lobes_outer must be at least 2 in {where}, got {n1}")
    lam = number(m, "lambda", where)
    if not lam > 1.0:
        raise CaseError(f"lambda must be greater than 1 in {where}, got {lam}")
    diameter = number(m, "diameter_mm", where) * 1e-3
    if not diameter > 0.0:
        raise CaseError(f"diameter_mm must be positive in {where}")
    if ("sigma" in m) == ("sigma_bar" in m):
        raise CaseError(f"give exactly one of 'sigma' or 'sigma_bar' in {where}")
    lim = sigma_limit(n1, lam)
    if "sigma" in m:
        sigma = number(m, "sigma", where)
    else:
        sigma_bar = number(m, "sigma_bar", where)
        if not 0.0 < sigma_bar <= 1.0 + ROUNDING:
            raise CaseError(f"sigma_bar must lie in (0, 1] in {where}, got {sigma_bar}")
        sigma = min(sigma_bar, 1.0) * lim
    if not sigma > 0.0:
        raise CaseError(f"sigma must be positive in {where}, got {sigma}")
    if sigma > lim * (1.0 + ROUNDING):
        raise CaseError(
            f"sigma = {sigma:.6g} is above the undercut limit sigma_lim = {lim:.6g} in {where}"
        )
    fillet = m.get("fillet", "conjugate")
    if fillet not in ("conjugate", "arc"):
        raise CaseError(f"fillet must be 'conjugate' or 'arc' in {where}, got {fillet!r}")
    apex = None
    if "fillet_apex_diameter_mm" in m:
        if fillet != "arc":
            raise CaseError(f"fillet_apex_diameter_mm needs fillet = 'arc' in {where}")
        apex = number(m, "fillet_apex_diameter_mm", where) * 1e-3
    return PinGerotor(n1, lam, min(sigma, lim), diameter, fillet, apex)


def examples() -> dict[str, PinGerotor]:
    """Pairs for the family contract tests: seed 000's optimum, a short-pin pair with no
    pitch-point contact, and a non-conjugate (arc) fillet with a clearance volume."""
    return {
        "table1": PinGerotor(6, 1.39934, sigma_limit(6, 1.39934), 0.1),
        "n5-lambda1.3": PinGerotor(5, 1.3, 0.9 * sigma_limit(5, 1.3), 0.1),
        "crc60": PinGerotor(3, 2.0, 0.829059829, 0.086),
        "arc-fillet": PinGerotor(5, 1.3, sigma_limit(5, 1.3), 0.1, "arc", 0.11),
    }


FAMILY = register(Family("internal-gear", KEYS, from_section, examples))
