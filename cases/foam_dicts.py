"""The OpenFOAM dictionaries both case kinds share: controlDict, fvSchemes, the gas, the
turbulence model, function objects and boundary conditions.

Builders return plain mappings for :func:`~rotorflow.cases.foam_files.write_dict`; the
order of their keys is the order of the written files, and the written files are what a
stored run was made from, so the order is kept as it is.  What differs between the
steady gap case (rhoSimpleFoam) and the moving chamber (rhoPimpleFoam) comes in as
arguments; the solution controls (fvSolution), which have nothing in common, stay with
each case.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rotorflow.quasi1d.perfect_gas import PerfectGas

#: The front and back of a one-cell-thick 2D mesh.
FRONT_AND_BACK = {"frontAndBack": {"type": "empty"}}


def control_dict(
    application: str,
    *,
    start_from: str,
    end_time: float,
    delta_t: float,
    write_control: str,
    write_interval: float,
    purge_write: int,
    time_precision: int,
    run_time_modifiable: bool,
    functions: Mapping[str, Any],
    time_step: Mapping[str, Any] | None = None,
    switches: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """``system/controlDict``: ASCII output with 10 digits, uncompressed; ``time_step``
    (adjustable time-step entries) follows ``deltaT``, ``switches`` (optimisation
    switches) precedes the function objects."""
    return {
        "application": application,
        "startFrom": start_from,
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": end_time,
        "deltaT": delta_t,
        **(time_step or {}),
        "writeControl": write_control,
        "writeInterval": write_interval,
        "purgeWrite": purge_write,
        "writeFormat": "ascii",
        "writePrecision": 10,
        "writeCompression": False,
        "timeFormat": "general",
        "timePrecision": time_precision,
        "runTimeModifiable": run_time_modifiable,
        **(switches or {}),
        "functions": dict(functions),
    }


def field_value(kind: str, region_type: str, operation: str, fields: list[str], *,
                write_control: str, write_interval: float, name: str | None = None
                ) -> dict[str, Any]:
    """A ``surfaceFieldValue`` or ``volFieldValue`` function object writing its table
    (``postProcessing/<object>/<start time>/<kind>.dat``) and nothing else."""
    entry: dict[str, Any] = {
        "type": kind,
        "libs": ["fieldFunctionObjects"],
        "writeControl": write_control,
        "writeInterval": write_interval,
        "log": False,
        "writeFields": False,
        "regionType": region_type,
        "operation": operation,
        "fields": fields,
    }
    if name is not None:
        entry["name"] = name
    return entry


def fv_schemes(ddt: str, convection: Mapping[str, Any], *, wall_distance: bool = False
               ) -> dict[str, Any]:
    """``system/fvSchemes``: second-order Gauss schemes with limited gradients, the
    ``ddt`` scheme and the ``convection`` (div) schemes of the case; ``wall_distance``
    adds the wall-distance method turbulence models need."""
    out: dict[str, Any] = {
        "ddtSchemes": {"default": ddt},
        "gradSchemes": {"default": ("Gauss", "linear"),
                        "limited": ("cellLimited", "Gauss", "linear", 1)},
        "divSchemes": {
            "default": "none",
            **convection,
            "div(((rho*nuEff)*dev2(T(grad(U)))))": ("Gauss", "linear"),
        },
        "laplacianSchemes": {"default": ("Gauss", "linear", "corrected")},
        "interpolationSchemes": {"default": "linear"},
        "snGradSchemes": {"default": "corrected"},
    }
    if wall_distance:
        out["wallDist"] = {"method": "meshWave"}
    return out


def thermophysical_properties(gas: PerfectGas) -> dict[str, Any]:
    """constant/thermophysicalProperties of ``gas``: a perfect gas with constant cp and
    Sutherland or constant viscosity (hePsiThermo, sensible internal energy)."""
    transport = (
        {"mu": gas.mu_Pa_s, "Pr": gas.prandtl}
        if gas.transport == "const"
        else {"As": gas.sutherland_As, "Ts": gas.sutherland_Ts_K}
    )
    return {
        "thermoType": {
            "type": "hePsiThermo",
            "mixture": "pureMixture",
            "transport": gas.transport,
            "thermo": "hConst",
            "equationOfState": "perfectGas",
            "specie": "specie",
            "energy": "sensibleInternalEnergy",
        },
        "mixture": {
            "specie": {"molWeight": gas.molar_mass_kg_kmol},
            "thermodynamics": {"Cp": gas.cp_J_kgK, "Hf": 0},
            "transport": transport,
        },
    }


def turbulence_properties(model: str) -> dict[str, Any]:
    """constant/turbulenceProperties: "laminar" or a RAS model such as "kOmegaSST"."""
    if model == "laminar":
        return {"simulationType": "laminar"}
    return {"simulationType": "RAS", "RAS": {"RASModel": model, "turbulence": True,
                                             "printCoeffs": True}}


def uniform(value: Any) -> tuple[str, Any]:
    """A field-valued entry other than value/inletValue (foamlib adds those itself)."""
    return ("uniform", value)


def inlet_outlet(value: Any) -> dict[str, Any]:
    """Zero gradient where the flow leaves, ``value`` where it comes back in."""
    return {"type": "inletOutlet", "inletValue": value, "value": value}
