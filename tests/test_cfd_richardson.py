"""Richardson extrapolation on analytic sequences (plain tier: numpy only)."""

from __future__ import annotations

import math

import pytest

from rotorflow.postprocess.richardson import GCI_SAFETY, richardson


@pytest.mark.parametrize("order", [1.0, 2.0, 3.7])
@pytest.mark.parametrize("ratio", [2.0, 1.5])
def test_recovers_order_and_limit_of_power_law(order, ratio):
    # f(h) = f0 + C h^p exactly: the observed order and the limit are exact up to round-off.
    f0, c, h = 2.5, 0.8, 0.1
    values = [f0 + c * (h / ratio**k) ** order for k in range(3)]
    # Exact data: no noise floor, and the observed order used as it is.
    rich = richardson(values, ratio, noise_tol=0.0, order_bounds=(0.0, math.inf))
    assert rich.kind == "monotone"
    assert rich.order == pytest.approx(order, rel=1e-9)
    assert rich.extrapolated == pytest.approx(f0, rel=1e-12)
    # GCI of the fine mesh = Fs * |f3 - f0| / f3 for an exact power law.
    assert rich.uncertainty == pytest.approx(GCI_SAFETY * abs(values[2] - f0) / values[2],
                                             rel=1e-9)
    errors = rich.relative_errors()
    assert errors[2] == pytest.approx(values[2] / f0 - 1, rel=1e-9)


def test_higher_order_term_biases_the_observed_order_toward_the_leading_one():
    # f = f0 + h^2 + 10 h^3: the observed order lies between 2 and 3 and approaches 2 as
    # the meshes are refined; the extrapolation error shrinks like h^3.
    def f(h):
        return 1.0 + h**2 + 10 * h**3

    unbounded = {"noise_tol": 0.0, "order_bounds": (0.0, math.inf)}
    coarse = richardson([f(0.2), f(0.1), f(0.05)], 2.0, **unbounded)
    fine = richardson([f(0.02), f(0.01), f(0.005)], 2.0, **unbounded)
    assert 2.0 < fine.order < coarse.order < 3.0
    assert abs(fine.extrapolated - 1.0) < abs(coarse.extrapolated - 1.0) / 100


@pytest.mark.parametrize(("order", "used"), [(0.3, 1.0), (1.5, 1.5), (3.0, 2.0)])
def test_extrapolation_order_is_bounded_but_reported(order, used):
    values = [1.0 + 0.1 * 0.5 ** (k * order) for k in range(3)]
    rich = richardson(values, 2.0)
    assert rich.order == pytest.approx(order)
    assert rich.order_used == pytest.approx(used)
    e32 = values[2] - values[1]
    assert rich.extrapolated == pytest.approx(values[2] + e32 / (2.0**used - 1))


def test_oscillating_sequence_is_not_extrapolated():
    rich = richardson([1.00, 1.02, 1.01], 2.0)
    assert rich.kind == "oscillatory"
    assert math.isnan(rich.order)
    assert rich.extrapolated == 1.01
    assert rich.uncertainty == pytest.approx(0.02 / 1.01)


def test_diverging_sequence_is_flagged():
    rich = richardson([1.00, 1.01, 1.03], 2.0)
    assert rich.kind == "divergent"
    assert math.isnan(rich.order)


def test_sequence_converged_within_noise():
    rich = richardson([1.05, 1.00001, 1.0], 2.0)
    assert rich.kind == "converged"
    assert rich.extrapolated == 1.0


@pytest.mark.parametrize("bad", [[1.0, 2.0], [1.0, float("nan"), 1.0]])
def test_rejects_malformed_input(bad):
    with pytest.raises(ValueError):
        richardson(bad, 2.0)


def test_rejects_ratio_not_above_one():
    with pytest.raises(ValueError):
        richardson([1.0, 1.1, 1.2], 1.0)


@pytest.mark.parametrize("ratio", [1.5, 2.0])
def test_two_grid_estimate_is_exact_at_the_true_order_and_biased_off_it(ratio):
    """f = f0 + C h^p: at the true order two meshes give f0 back; assumed 2 where the
    true order is 1.5, the estimate keeps the share (r^2 - r^1.5) / (r^2 - 1) of the
    finer mesh's error, and the two-grid GCI (Fs = 3) covers it."""
    from rotorflow.postprocess.richardson import GCI_SAFETY_TWO_GRIDS, two_grid

    f0, c = 7.0e-4, 1.2e-4
    exact = two_grid([f0 + c, f0 + c / ratio**2], ratio, order=2.0)
    assert exact.extrapolated == pytest.approx(f0, rel=1e-12)
    assert exact.uncertainty == pytest.approx(
        GCI_SAFETY_TWO_GRIDS * (c - c / ratio**2) / (ratio**2 - 1) / f0, rel=1e-9)
    off = two_grid([f0 + c, f0 + c / ratio**1.5], ratio)
    medium_error = c / ratio**1.5
    share = (ratio**2 - ratio**1.5) / (ratio**2 - 1)
    assert off.extrapolated - f0 == pytest.approx(share * medium_error, rel=1e-9)
    assert abs(off.extrapolated / f0 - 1) < off.uncertainty
    with pytest.raises(ValueError, match="two values"):
        two_grid([1.0, 2.0, 3.0], ratio)
