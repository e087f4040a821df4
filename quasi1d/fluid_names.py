"""The fluid a case names: "air", or a CoolProp fluid by its name or an alias."""

from __future__ import annotations

from rotorflow.errors import CaseError


def check_fluid(name: str, where: str = "the case") -> str:
    """Return ``name`` if it is a fluid this model knows, else raise CaseError."""
    if name == "air":
        return name
    hint = ""
    if isinstance(name, str) and not name.startswith("CoolProp::") and name.strip():
        # a CoolProp name without its prefix ("CO2", "R134a"): name the spelling it needs
        near = _near(name)
        hint = f" (did you mean {', '.join(f'CoolProp::{f}' for f in near)}?)" if near else ""
    if isinstance(name, str) and name.startswith("CoolProp::"):
        fluid = name.split("::", 1)[1]
        known, aliases = _coolprop_names()
        # (some fluid has an empty alias: "CoolProp::" named it)
        if fluid.strip() and (fluid in known or fluid in aliases):
            return name
        if any(c in fluid for c in "&[") or fluid.lower().endswith(".mix"):
            raise CaseError(
                f"fluid {name!r} in [operating] of {where} is a mixture: CoolProp's mixtures "
                "are not modelled; its predefined blends are, as pseudo-pure fluids "
                "(\"CoolProp::R410A\", \"CoolProp::R407C\", \"CoolProp::R404A\", "
                "\"CoolProp::R507A\")")
        near = _near(fluid)
        hint = f" (did you mean {', '.join(f'CoolProp::{f}' for f in near)}?)" if near else ""
    raise CaseError(
        f"unknown fluid {name!r} in [operating] of {where}{hint}: use \"air\" (ideal gas) "
        f"or \"CoolProp::<name>\", e.g. \"CoolProp::Air\""
    )


def _coolprop_names() -> tuple[list[str], set[str]]:
    """CoolProp's fluid names and their aliases."""
    import CoolProp.CoolProp as CP

    known = CP.get_global_param_string("FluidsList").split(",")
    return known, {a for f in known for a in CP.get_fluid_param_string(f, "aliases").split(",")}


def _near(fluid: str) -> list[str]:
    """Up to three CoolProp names (or aliases) close to ``fluid`` (itself first if it is one)."""
    import difflib

    known, aliases = _coolprop_names()
    return difflib.get_close_matches(fluid, sorted(set(known) | aliases - {""}), n=3)
