"""The compiled right-hand side (quasi1d.kernel.rhs_fused through quasi1d.compiled)
against the model's numpy evaluation of the same pieces: an independent assembly (one
compiled function against the model's piecewise calls with its own node arrays) that
must agree to round-off on every fluid, port and leakage law it covers, and whole
cycles that agree far inside the integration tolerance.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from rotorflow.quasi1d import (
    Leakage,
    Operating,
    Ports,
    compiled,
    integrate,
    kernel,
    simulate,
    stepping,
)
from rotorflow.quasi1d.simulate import build_model
from rotorflow.quasi1d.synthetic import sin2_table

# Round-off of the two evaluations: the same operations, compiled (LLVM's pow and exp)
# or in numpy, on dy of ~1e2 terms each; relative to the largest |dy| of each component
# over the states compared.
RHS_RTOL = 1e-11
# Whole cycles: identical but for round-off unless a step is accepted by one and
# rejected by the other; then they differ by the integration error, below rtol (1e-4).
CYCLE_RTOL = 1e-5
# One segment's step ends and end state, compiled against Python: the step sizes follow
# the error estimates' round-off through the controller's fifth root, compounded.
STEP_RTOL = 1e-7


def _op(**kw):
    d = {"p_suction_bar": 1.0, "p_discharge_bar": 6.0, "T_suction_K": 300.0,
         "speed_rpm": 3000.0, "volume_ratio": 3.5}
    d.update(kw)
    return Operating.from_section(d, "test")


CASES = {
    "dry air, ideal ports, nozzle leakage": (
        _op(), Leakage(gap_m=10e-6, model="nozzle", coefficient=0.8), Ports()),
    "perfect gas, nozzle ports, Fanno leakage, heat transfer": (
        _op(heat_capacity="constant", heat_transfer_W_m2K=200.0),
        Leakage(gap_m=10e-6, model="fanno", zeta=3.0), Ports(model="nozzle")),
    "CoolProp air table, nozzle ports, no leakage": (
        _op(fluid="CoolProp::Air"), Leakage(model="none"),
        Ports(model="nozzle", coefficient=1.0)),
    # oil injected (quasi1d.oil): it leaks with the gas as a homogeneous mixture, heats
    # the gas and leaves with it through the ideal or the nozzle discharge port
    "oil injected, ideal ports, Fanno leakage": (
        _op(p_discharge_bar=11.0, volume_ratio=5.0, oil_mass_ratio=4.0, T_oil_K=323.15,
            oil_time_constant_ms=14.0),
        Leakage(gap_m=20e-6, model="fanno", zeta=3.0), Ports()),
    "oil injected, nozzle ports, nozzle leakage, heat transfer": (
        _op(oil_mass_ratio=1.0, T_oil_K=300.0, heat_capacity="constant",
            heat_transfer_W_m2K=200.0),
        Leakage(gap_m=10e-6, model="nozzle", coefficient=0.8), Ports(model="nozzle")),
    # a vacuum pump's gaps (quasi1d.rarefied: Kn ~ 0.01-0.1 at 0.05 bar over 100 um)
    "rarefied leakage at 0.05 bar, ideal ports, heat transfer": (
        _op(p_suction_bar=0.05, p_discharge_bar=1.0, volume_ratio=2.0,
            heat_transfer_W_m2K=100.0, T_wall_K=353.15),
        Leakage(gap_m=100e-6, model="rarefied", land_m=2e-3), Ports()),
    # a multiphase pump's water (quasi1d.liquid): it fills volume, leaks with the gas by
    # the omega method, pays its push-out work and leaves through the port with the gas
    "liquid filling volume, rarefied leakage, ideal ports, heat transfer": (
        _op(p_discharge_bar=8.0, volume_ratio=2.0, liquid_density_kg_m3=998.0,
            liquid_cp_J_kgK=4180.0, gas_volume_fraction=0.7, heat_transfer_W_m2K=100.0),
        Leakage(gap_m=30e-6, model="rarefied", land_m=2e-3), Ports()),
    "liquid filling volume, nozzle leakage, nozzle ports": (
        _op(p_discharge_bar=4.0, volume_ratio=2.0, liquid_density_kg_m3=998.0,
            liquid_cp_J_kgK=4180.0, gas_volume_fraction=0.8),
        Leakage(gap_m=20e-6, model="nozzle", coefficient=0.8), Ports(model="nozzle")),
}


@pytest.fixture(scope="module")
def table():
    return sin2_table(rows=481)


@pytest.fixture
def compiled_on(monkeypatch):
    monkeypatch.setenv("ROTORFLOW_COMPILED", "1")
    fn = compiled.kernel_for_point()
    assert fn is not None
    return fn


@pytest.mark.parametrize("name", list(CASES))
def test_compiled_rhs_equals_numpy(table, compiled_on, name):
    op, leak, ports = CASES[name]
    model = build_model(table, op, leak, ports)
    z = model.initial_state()
    rng = np.random.default_rng(7)
    y = np.repeat(z[None], 5, axis=0)
    # perturbed states: every slot's masses and energies moved by up to 5 %
    nn = model.nv * model.n
    y[:, :nn] *= 1.0 + 0.05 * rng.uniform(-1, 1, (5, nn))
    checked = 0
    for seg in model.segments:
        if seg.end <= seg.start or not kernel.fusable(model, seg):
            continue
        for theta in np.linspace(seg.start, seg.end, 4)[1:-1]:
            yy = y.copy()
            n, na = model.n, seg.n_act
            V = model.geo.volume(theta + seg.kP)
            new = np.nonzero(z[:na] <= 0.0)[0]  # the newborn slot: suction gas
            yy[:, new] = model.suc.rho * V[new]
            yy[:, n + new] = yy[:, new] * model.suc.u
            yy[:, na:n] = 0.0  # inactive slots hold nothing
            yy[:, n + na:2 * n] = 0.0
            if model.inv_rho_liquid:  # a liquid in 25-35 % of each slot, 5 K warmer
                ml = (0.3 + 0.05 * rng.uniform(-1, 1, (5, na))) * V[:na] / model.inv_rho_liquid
                yy[:, 2 * n:2 * n + na] = ml
                yy[:, 3 * n:3 * n + na] = ml * op.oil_cp_J_kgK * 5.0
            model.fast["kernel"] = None
            ref = model.rhs(theta, yy, seg)
            model.fast["kernel"] = compiled_on
            got = model.rhs(theta, yy, seg)
            scale = np.maximum(np.max(np.abs(ref), axis=0), 1e-300)
            assert np.max(np.abs(got - ref) / scale) < RHS_RTOL, (seg.index, theta)
            checked += 1
    assert checked >= 4


@pytest.mark.parametrize("method, name", [
    ("dopri5", "dry air, ideal ports, nozzle leakage"),
    ("ros23", "perfect gas, nozzle ports, Fanno leakage, heat transfer"),
    ("ros23", "dry air, ideal ports, nozzle leakage")])
def test_compiled_segment_equals_python_steps(table, compiled_on, method, name):
    """A whole segment in one compiled call (quasi1d.stepping through kernel.segment_fused,
    or kernel.segment_ros23) against the same loop run as Python around the model's numpy
    right-hand side: the same steps chosen, the same end state to round-off, and a
    replay of those steps."""
    op, leak, ports = CASES[name]
    model = build_model(table, op, leak, ports)
    seg = max((s for s in model.segments if kernel.fusable(model, s)),
              key=lambda s: s.end - s.start)
    y = np.repeat(model.initial_state()[None], 3, axis=0)
    y[1:, 1:model.n] *= 1.0 + 1e-3 * np.arange(1, 3)[:, None]  # a batch, as Newton's
    V = model.geo.volume(seg.start + seg.kP)
    y[:, 0], y[:, model.n] = model.suc.rho * V[0], model.suc.rho * V[0] * model.suc.u
    atol = 1e-6 * model.atol_scales()
    model.fast["kernel"] = None
    k1 = model.rhs(seg.start, y, seg)

    def rhs(tt, y3, _a):
        return model.rhs(tt, y3, seg)

    geo = model.fused_geometry(seg)
    if method == "ros23":
        cols = model.state_columns(seg)
        order, entry, args = 3, compiled_on.segment_ros23, ((atol, cols), geo,
                                                             model._fused_args(seg))

        def py_step(t, yy, h, kk, _):
            return stepping.ros23_step(rhs, None, t, yy, h, kk, atol, cols)
    else:
        tab = integrate.DOPRI5
        order, entry, args = tab.order, compiled_on.segment, ((tab.c, tab.A, tab.b, tab.e),
                                                              geo, model._fused_args(seg))

        def py_step(t, yy, h, kk, _):
            return stepping.rk_step(rhs, None, tab.c, tab.A, tab.b, tab.e, t, yy, h, kk)

    common = (seg.start, seg.end, np.empty(0), y, k1, np.nan, 1e-6, atol, order, 10_000,
              0.0, True)
    ref = stepping.segment(py_step, None, *common)
    got = entry(args, *common)
    assert ref[0] == got[0] == stepping.DONE
    # the same steps: round-off in the error estimates (RHS_RTOL of them) moves each step
    # size, and so each later step end, by far less than STEP_RTOL
    assert got[4].size == ref[4].size > 5
    assert np.allclose(got[4], ref[4], rtol=STEP_RTOL, atol=0.0)
    scale = np.max(np.abs(ref[2]), axis=0) + atol
    assert np.max(np.abs(got[2] - ref[2]) / scale) < STEP_RTOL
    again = entry(args, seg.start, seg.end, got[4], y, k1, np.nan, 1e-6, atol, order, 0, 4.0,
                  False)
    assert again[0] == stepping.DONE and np.array_equal(again[2], got[2])


#: Whole cycles compared: not the CoolProp table's (slow to build; its right-hand side is
#: compared above) nor a liquid's (stiff: 11-70 s a cycle either way on the sin2 chamber,
#: the Rosenbrock Jacobian's batches, where numpy's arrays are as fast as the loops; its
#: segments' thousands of steps drift apart by round-off beyond STEP_RTOL; the pump
#: examples' figures agree within 1e-9 on the full machine, docs/quasi1d.md).
CYCLE_CASES = [name for i, name in enumerate(CASES) if i != 2 and "liquid" not in name]


@pytest.mark.parametrize("name", CYCLE_CASES)
def test_compiled_cycle_equals_numpy(table, monkeypatch, name):
    op, leak, ports = CASES[name]
    monkeypatch.setenv("ROTORFLOW_COMPILED", "0")
    ref = simulate(table, op, leak, ports).figures
    monkeypatch.setenv("ROTORFLOW_COMPILED", "1")
    got = simulate(table, op, leak, ports).figures
    for key in ("mass_flow_kg_s", "indicated_power_W", "discharge_T_K"):
        if key in ref:
            assert got[key] == pytest.approx(ref[key], rel=CYCLE_RTOL), key


@pytest.mark.parametrize("kernel", ["0", "1"])
@pytest.mark.parametrize("name", list(CASES)[:2])
def test_recorded_derivatives_are_the_right_hand_side(table, monkeypatch, name, kernel):
    """The derivatives the steps record beside the trace (the dense traces' Hermite
    data) are f(theta, y) at the recorded points, evaluated anew by the numpy
    right-hand side: a stale stage or a shifted row would differ by O(1)."""
    op, leak, ports = CASES[name]
    monkeypatch.setenv("ROTORFLOW_COMPILED", kernel)
    run = simulate(table, op, leak, ports).solution.run
    model = build_model(table, op, leak, ports)
    th, ys, fs = (np.asarray(v, float) for v in (run.trace_theta, run.trace_y, run.trace_f))
    assert fs.shape == ys.shape
    scale = np.max(np.abs(np.nan_to_num(fs)), axis=0) + 1e-300  # (as RHS_RTOL's)
    first = 0
    for seg, ends in zip(model.segments, run.steps, strict=True):
        count = 1 + len(ends)
        if count > 1:
            sl = slice(first, first + count)
            ref = model.rhs(th[sl], ys[sl], seg)
            # round-off as RHS_RTOL, which the cancellation inside dy over a trace's
            # smaller component scales lifts to ~1.5e-11: 1e-9 still tells a stale or
            # shifted derivative (off by O(1e-2) of the scale at least)
            assert np.max(np.abs(fs[sl] - ref) / scale) < 1e-9
        first += count


def test_a_volatile_or_centrifuged_liquid_stays_in_numpy(table):
    """Injected oil and a liquid that takes chamber volume (a pump's water) leaking as a
    homogeneous mixture are compiled (CASES); a liquid that evaporates, or one flung
    onto the bores (its own law in the casing gaps), is not (its laws are numpy's
    alone)."""
    leak = Leakage(gap_m=10e-6, model="nozzle", coefficient=0.8)
    water = {"gas_volume_fraction": 0.8, "liquid_density_kg_m3": 998.0}
    for extra, lk in (({"oil_mass_ratio": 1.0, "liquid_volatile": "Water",
                        "heat_capacity": "constant"}, leak),
                      (water, dataclasses.replace(leak, mixture="centrifuged"))):
        model = build_model(table, _op(**extra), lk, Ports())
        assert not any(kernel.fusable(model, seg) for seg in model.segments), extra
    for extra in ({"oil_mass_ratio": 2.0}, water):
        model = build_model(table, _op(**extra), leak, Ports())
        assert all(kernel.fusable(model, seg) for seg in model.segments)


def test_importing_the_model_does_not_load_numba():
    code = ("import sys, rotorflow.quasi1d, rotorflow.quasi1d.model; "
            "print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_the_cache_is_taken_as_filled_only_under_this_checkouts_own_folder(monkeypatch, tmp_path):
    """numba files each source directory's cache under its own sub-folder (its locator,
    asked here, is the independent construction): another checkout's entries of the same
    sources must not count, or a point would compile inside its time budget."""
    from numba.core.caching import UserProvidedCacheLocator

    compiled._cache_dir.cache_clear()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    try:
        root = compiled._cache_dir()
        own = root / UserProvidedCacheLocator.get_suitable_cache_subpath(kernel.__file__)
        other = root / "quasi1d_0123456789abcdef0123456789abcdef01234567"
        names = [f"kernel.{fn.__name__}-1.py311.nbi" for fn in compiled._entries()]
        other.mkdir(parents=True)
        for n in names:
            (other / n).touch()
        assert not compiled._cached()
        own.mkdir()
        for n in names[:-1]:
            (own / n).touch()
        assert not compiled._cached()
        (own / names[-1]).touch()
        assert compiled._cached()
    finally:
        compiled._cache_dir.cache_clear()


def test_the_warm_up_calls_every_entry_the_cache_is_judged_by(monkeypatch):
    """compiled._cached takes numba's cache as filled when it holds every entry point
    (compiled._entries), and `make venv` fills it by compiled.warm_up: so the warm-up
    must call each of them.  It missed the fused right-hand side's own entry (the cycles
    call it only inside the compiled segments), and a fresh checkout ran in numpy."""
    monkeypatch.setenv("ROTORFLOW_COMPILED", "1")
    fn = compiled.kernel_for_point()
    called = set()

    def counting(field):
        inner = getattr(fn, field)

        def wrapper(*args):
            called.add(field)
            return inner(*args)
        return wrapper

    entries = {"rhs": "rhs_fused", "rhs_segment": "rhs_segment", "segment": "segment_fused",
               "segment_ros23": "segment_ros23"}
    assert sorted(entries.values()) == sorted(f.__name__ for f in compiled._entries())
    monkeypatch.setitem(compiled._state, "kernel",
                        fn._replace(**{field: counting(field) for field in entries}))
    compiled.warm_up()
    assert called == set(entries)
