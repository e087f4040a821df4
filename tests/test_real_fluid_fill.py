"""The ideal discharge port's filling of a chamber with a real fluid
(:meth:`rotorflow.quasi1d.coolprop_fluid.TabulatedFluid.fill`): the mass that brings the
chamber to the plenum's pressure, found without scipy.optimize (whose import took ~1 s
CPU of a real-fluid `simulate` on a slow machine, for this one root)."""

from __future__ import annotations

import json
import subprocess
import sys

import CoolProp.CoolProp as CP

CODE = """
import json, sys
import numpy as np
from rotorflow.quasi1d.coolprop_fluid import tabulated
f = tabulated("R134a", 3e5, 9e5, 285.0, 285.0, 285.0, 2.7)
rho, u, h = f.state_pT(9e5, 330.0)
m, V = np.array([1e-4, 5e-4]), np.array([1e-5, 5e-5])
U = m * (u - 20000.0)
m2, U2 = f.fill(m, U, V, h, 9e5)
print(json.dumps({"m": m.tolist(), "U": U.tolist(), "V": V.tolist(), "h": h,
                  "m2": m2.tolist(), "U2": U2.tolist(),
                  "scipy_optimize": "scipy.optimize" in sys.modules}))
"""


def test_fill_reaches_the_plenum_pressure_without_scipy_optimize():
    out = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True,
                         check=True)
    r = json.loads(out.stdout)
    assert not r["scipy_optimize"]
    for m, U, V, m2, U2 in zip(r["m"], r["U"], r["V"], r["m2"], r["U2"], strict=True):
        # the gas let in carries the plenum's enthalpy; the filled state is at 9 bar
        assert abs(U2 - (U + (m2 - m) * r["h"])) < 1e-9 * abs(U2)
        p = CP.PropsSI("P", "Dmass", m2 / V, "Umass", U2 / m2, "R134a")
        assert abs(p / 9e5 - 1.0) < 1e-10 and m2 > m
