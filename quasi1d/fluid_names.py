"""The fluid a case names: "air", or a CoolProp fluid by its name or an alias."""

from __future__ import annotations

from rotorflow.errors import CaseError


def check_fluid(name: str, where: str = "the case") -> str:
    """Return ``name`` if it is a fluid this model knows, else raise CaseError."""
    if name == "air":
        return name
    hint = ""
    if isinstance(name, str) and name.startswith("CoolProp::"):
        import difflib

        import CoolProp.CoolProp as CP

        fluid = name.split("::", 1)[1]
        known = CP.get_global_param_string("FluidsList").split(",")
        aliases = {a for f in known for a in CP.get_fluid_param_string(f, "aliases").split(",")}
        # (some fluid has an empty alias: "CoolProp::" named it)
        if fluid.strip() and (fluid in known or fluid in aliases):
            return name
        if any(c in fluid for c in "&[") or fluid.lower().endswith(".mix"):
            raise CaseError(
                f"fluid {name!r} in [operating] of {where} is a mixture: CoolProp's mixtures "
                "are not modelled; its predefined blends are, as pseudo-pure fluids "
                "(\"CoolProp::R410A\", \"CoolProp::R407C\", \"CoolProp::R404A\", "
                "\"CoolProp::R507A\")")
        near = difflib.get_close_matches(fluid, sorted(set(known) | aliases - {""}), n=3)
        hint = f" (did you mean {', '.join(f'CoolProp::{f}' for f in near)}?)" if near else ""
    raise CaseError(
        f"unknown fluid {name!r} in [operating] of {where}{hint}: use \"air\" (ideal gas) "
        f"or \"CoolProp::<name>\", e.g. \"CoolProp::Air\""
    )
