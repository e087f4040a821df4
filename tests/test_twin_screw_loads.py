"""Section loads swept along the rotors between the events where they jump.

geometry.load_sweep against an independent construction (an analytic section load with
jumps, integrated exactly on its smooth pieces): fourth order with the events, first
without; nodes it is told not to trust weigh nothing; loads that cancel over the chambers
of a section still cancel when swept.  Then the twin screw's events
(geometry.twin_screw.load_events): the closed-form cusp passages are among them, and the
pin-cycloid's Pi_max, whose loads jump between nodes, converges (issue 13).
"""

import math
from pathlib import Path

import numpy as np
import pytest

from rotorflow.geometry.load_sweep import LoadEvents, sweep_loads
from rotorflow.geometry.sweep import Sweep

REPO = Path(__file__).resolve().parents[1]
BIRTH, DEATH = -0.3, 4.1
JUMPS = (0.77, 0.79, 1.9)  # two of them 0.02 apart: no node between at any step here


def _load(x):
    """A chamber's section load: smooth pieces, jumps at birth, death and JUMPS."""
    x = np.asarray(x, dtype=float)
    v = (np.sin(2.0 * x) + 0.3 * x * x + 0.5 * (x > JUMPS[0]) * (1.0 + np.cos(3.0 * x))
         - 0.7 * (x > JUMPS[1]) - 0.8 * (x > JUMPS[2]) * np.exp(-x))
    return np.where((x > BIRTH) & (x < DEATH), v, 0.0)


def _exact(sweep, power, phi):
    """int_0^wrap f(phi - theta) W(theta) d theta, Gauss on every smooth piece."""
    x, w = np.polynomial.legendre.leggauss(30)
    out = []
    for p in phi:
        ends = np.clip(np.r_[0.0, sweep.wrap, p - BIRTH, p - DEATH, p - np.array(JUMPS)],
                       0.0, sweep.wrap)
        ends = np.unique(ends)
        total = 0.0
        for lo, hi in zip(ends[:-1], ends[1:], strict=True):
            theta = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x
            z = sweep.z_of_twist(theta)
            weight = sweep.scale(z) ** power / sweep.dtwist(z)
            total += float(np.sum(_load(p - theta) * weight * 0.5 * (hi - lo) * w))
        out.append(total)
    return np.array(out)


def _swept(sweep, n, power=2, shadow=0.0, corrupt=False, events=True):
    h = (DEATH - BIRTH + 0.4) / n
    psi = (BIRTH - 0.2) + h * np.arange(n + 1)
    at = np.sort(np.r_[BIRTH, DEATH, JUMPS])
    values = _load(psi)
    if corrupt:  # nodes in the shadows hold garbage: they must weigh nothing
        for e in at:
            values = values + 10.0 * (np.abs(psi - e) <= shadow)
    sample = np.array([0.5 * (JUMPS[0] + JUMPS[1])])
    ev = LoadEvents(at, np.full(len(at), shadow), np.full(len(at), shadow), sample,
                    None, None) if events else None
    n_out = n + 2 + int(math.ceil(sweep.wrap / h))
    got = sweep_loads(psi, values[:, None], sweep, power, n_out, ev, _load(sample)[:, None])[:, 0]
    phi = psi[0] + h * np.arange(n_out)
    ref = _exact(sweep, power, phi)
    return float(np.abs(got - ref).max() / np.abs(ref).max())


def _slope(ns, errors):
    return -np.polyfit(np.log(ns), np.log(errors), 1)[0]


SWEEPS = [Sweep("helical", 0.13, 2.0), Sweep("conical", 0.13, 2.0, 0.8, 0.7)]


@pytest.mark.parametrize("sweep", SWEEPS, ids=["helical", "conical"])
def test_swept_loads_converge_at_fourth_order_across_jumps(sweep):
    ns = np.array([40, 80, 160])
    # The piece between the two close jumps is one sample, a constant: an error of ~1e-6
    # of the load's scale that does not shrink, below the others up to 80 steps.
    errors = [_swept(sweep, int(n)) for n in ns]
    linear = [_swept(sweep, int(n), events=False) for n in ns]
    # 4.8 and 4.7 measured: the cells next to the jumps carry O(h^5) each, the rest
    # O(h^4) in all; the linear interpolant across the jumps is first order (0.9-1.3).
    assert _slope(ns[:2], errors[:2]) > 3.5, errors
    assert errors[1] < 1e-5, errors
    assert _slope(ns, linear) < 1.5, linear
    assert linear[1] > 100.0 * errors[1]


def test_untrusted_nodes_weigh_nothing():
    sweep = Sweep("conical", 0.13, 2.0, 0.8, 0.7)
    clean = _swept(sweep, 160, shadow=0.01)
    garbage = _swept(sweep, 160, shadow=0.01, corrupt=True)
    # the shadows hold two nodes each at this step; the loads come from the others
    assert garbage == pytest.approx(clean, rel=1e-9, abs=1e-12)
    assert garbage < 1e-6


def test_loads_that_cancel_over_a_section_cancel_when_swept():
    """Chambers one period apart share the grid and the events: if the sections' loads
    sum to zero at every angle (a uniform pressure), so do the swept ones."""
    period, ppp = 1.0, 16
    h = period / ppp
    sweep = Sweep("conical", 0.13, 2.3, 0.8, 0.7)
    psi = h * np.arange(5 * ppp + 1)  # a chamber living five periods
    rng = np.random.default_rng(1)
    # f(x) = g(x) - g(x - period) with g compactly supported: the copies one period
    # apart telescope to zero at every angle, and so do the samples'
    g = np.concatenate([rng.normal(size=len(psi) - ppp), np.zeros(ppp)])
    g[0] = g[len(psi) - ppp - 1] = 0.0  # a zero node at either end, as the families'
    f = g - np.concatenate([np.zeros(ppp), g[:-ppp]])
    # events every period, as the families give them: at 0.0 too, where this chamber is
    # born and dies (a twin screw's at a band): beyond, its pieces hold only zeros
    phases = np.array([0.0, 0.23, 0.61])
    at = np.sort(np.concatenate([phases + k * period for k in range(-1, 7)]))
    shadows = np.full(len(at), 0.07)
    samples = np.array([0.42 + k * period for k in range(-1, 7)])
    r = np.concatenate([[0.0], rng.normal(size=4), np.zeros(3)])
    sval = r - np.concatenate([[0.0], r[:-1]])
    ev = LoadEvents(at, shadows, shadows, samples, None, None)
    n_out = len(psi) + int(math.ceil(sweep.wrap / h)) + 1
    swept = sweep_loads(psi, f[:, None], sweep, 1, n_out, ev, sval[:, None])[:, 0]
    # every chamber at the state of output j is at output j + k ppp
    total = np.array([swept[j::ppp].sum() for j in range(ppp)])
    assert np.abs(swept).max() > 0.1
    assert np.abs(total).max() < 1e-12 * np.abs(swept).max()


@pytest.fixture(scope="module")
def pin_cycloid():
    from rotorflow.workflow.case import load_case

    return load_case(REPO / "examples" / "twin_screw_4_6.toml")


def test_tips_passing_the_cusps_are_load_events(pin_cycloid):
    pair = pin_cycloid.pair
    sec = pair.section(48)
    period = pair.period
    xc, yc = pair.cusp
    # The male tip (at polar angle tip_angle + psi) reaches the top cusp (polar angle
    # atan2(yc, xc)) once per lobe period: closed form, independent of the module's.
    phase = (math.atan2(yc, xc) - pair.tip_angle(0)) % period
    at = sec.load_events.at % period
    # (the female land's corner reaches it 4e-8 rad earlier: one event, at the first)
    assert np.min(np.abs(np.remainder(at - phase + 0.5 * period, period) - 0.5 * period)) < 1e-6


def test_pin_cycloid_pi_max_converges_across_its_load_jumps(pin_cycloid):
    """Its loads jump between nodes where a tip passes a cusp; swept as their linear
    interpolant, Pi_max moved by 5.0e-4 from 24 to 48 points per period (0.37103 to
    0.37122 against 0.37137 at 768)."""
    import dataclasses

    from rotorflow.geometry.machine import SweptMachine
    from rotorflow.geometry.summary import case_power_split

    values = []
    for ppp in (24, 48):
        case = dataclasses.replace(pin_cycloid, pair=dataclasses.replace(pin_cycloid.pair))
        m = SweptMachine(case.pair, case.sweep(None), ppp)
        values.append(case_power_split(case, m, case.driven).pi_max)
    # 9e-6 measured; both lie within 3e-5 of 768 points per period (make bench)
    assert values[0] == pytest.approx(values[1], rel=4e-5)


def test_tip_band_ends_crossing_the_cusp_line_are_load_events(pin_cycloid):
    """The pin-cycloid male runs within TIP_BAND of its bore for 0.0038 rad behind its
    tip; a cut at the cusp line on that band ends at the tip, so the band's end crossing
    the line moves 1.6e-4 (per unit pressure and length) of the male between chambers.
    A fine scan of the sections (bisection on the chambers' loads, 2^-30 of a 4e-4 rad
    bracket) places each jump, after the tip leaves the top cusp and after it enters the
    bottom one; a declared event lies within the 1e-5 rad shadow of it (measured 1e-6)."""
    from rotorflow.geometry.twin_screw.section import _beta0, chamber_index

    pair = pin_cycloid.pair
    period, base = pair.period, -_beta0(pair)

    def loads(psi):
        q0 = math.floor((psi - base) / period)
        out = {}
        for part in pair.cutter.cut(float(psi)):
            q = chamber_index(pair, part, psi, pair.female_shift) - q0
            out[q] = out.get(q, 0.0) + part.force.ravel()
        return out

    def step(a, b):
        return max(np.abs(a.get(k, 0.0) - b.get(k, 0.0)).max() for k in set(a) | set(b))

    at = pair.section(48).load_events.at % period
    xc, yc = pair.cusp
    for y in (yc, -yc):
        tip = (math.atan2(y, xc) - pair.tip_angle(0)) % period
        a, b = tip + 0.0036, tip + 0.0040
        la, lb = loads(a), loads(b)
        for _ in range(30):
            m = 0.5 * (a + b)
            lm = loads(m)
            if step(lm, la) < step(lm, lb):
                a, la = m, lm
            else:
                b, lb = m, lm
        assert step(la, lb) > 1e-4  # a jump (1.6e-4), not the loads' slope
        jump = 0.5 * (a + b)
        assert np.min(np.abs(np.remainder(at - jump + 0.5 * period, period)
                             - 0.5 * period)) < 1e-5, (y, jump - tip)
