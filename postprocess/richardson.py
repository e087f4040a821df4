"""Richardson extrapolation with the observed order, from three systematically refined meshes.

For values f1 (coarse), f2, f3 (fine) on meshes refined by a constant ratio r (cell
size h, h/r, h/r^2), with f = f_exact + C h^p:

    p       = ln((f1 - f2) / (f2 - f3)) / ln r
    f_exact = f3 + (f3 - f2) / (r^p - 1)

and Roache's grid convergence index of the fine mesh, GCI = Fs |f3 - f2| / (r^p - 1) / |f3|
with the safety factor Fs = 1.25 for a three-mesh study.

The extrapolation and the GCI use the observed order clipped to ORDER_BOUNDS: an
observed order below 1 says the meshes are not in the asymptotic range of a scheme that
is at least first order (1 / (r^p - 1) would amplify the last difference many times),
one above 2 that errors of the second-order scheme cancel; the observed order itself is
reported unclipped.  Oscillating or diverging sequences have no observed order: they are
reported as such, with the spread of the three values as the uncertainty, and never
extrapolated.

Two meshes give no observed order: :func:`two_grid` extrapolates at an order given
beforehand (the scheme's formal one) and, with Roache's safety factor 3 for that case,
says how far the result can be off.  It is the quick estimate: a coarse and a medium
mesh cost a fraction of a fine one (a fine mesh of ratio r has r^d times the medium's
cells in d directions), and where the meshes are in the asymptotic range at that order
it lands on the three-mesh extrapolation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

#: Roache's safety factor for a grid convergence index from three meshes.
GCI_SAFETY = 1.25

#: Roache's safety factor for two meshes and an assumed order (Roache 1998, Verification
#: and Validation in Computational Science and Engineering, ch. 5).
GCI_SAFETY_TWO_GRIDS = 3.0

#: The formal order of the finite-volume schemes here (linear interpolation, central
#: gradients): the most the extrapolation uses, and what :func:`two_grid` assumes
#: unless told otherwise.
FORMAL_ORDER = 2.0

#: Orders used to extrapolate: at least first order (every scheme here is), at most the
#: formal second order of the finite-volume discretisation.
ORDER_BOUNDS = (1.0, FORMAL_ORDER)

#: Two mesh values closer than this fraction count as equal: the iterative convergence of
#: the solutions (mass flow settled to ~1e-4) makes smaller differences noise.
NOISE_TOL = 2e-4


@dataclass(frozen=True)
class Richardson:
    """The outcome of a three-mesh study."""

    values: tuple[float, float, float]
    """Coarse, medium, fine."""
    ratio: float
    kind: str
    """'monotone' (extrapolated with the observed order), 'converged' (the two finer
    values agree within NOISE_TOL), 'oscillatory' or 'divergent'."""
    order: float
    """Observed order p (nan unless monotone)."""
    order_used: float
    """The order the extrapolation used: ``order`` clipped to the bounds (nan unless
    monotone)."""
    extrapolated: float
    """Richardson value (the fine value unless monotone)."""
    uncertainty: float
    """Relative uncertainty of the fine value: the GCI when monotone, else the spread."""

    def relative_errors(self) -> tuple[float, float, float]:
        """Each mesh's value relative to the extrapolated one, minus 1."""
        return tuple(v / self.extrapolated - 1.0 for v in self.values)  # type: ignore[return-value]


def richardson(
    values: Sequence[float],
    ratio: float,
    noise_tol: float = NOISE_TOL,
    order_bounds: tuple[float, float] = ORDER_BOUNDS,
) -> Richardson:
    """Three-mesh Richardson extrapolation (``values`` ordered coarse to fine)."""
    if len(values) != 3:
        raise ValueError(f"Richardson extrapolation needs three values, got {len(values)}")
    if ratio <= 1:
        raise ValueError(f"refinement ratio must exceed 1, got {ratio}")
    f1, f2, f3 = (float(v) for v in values)
    if not all(math.isfinite(v) for v in (f1, f2, f3)):
        raise ValueError(f"non-finite value in a mesh study: {values}")
    scale = max(abs(f3), 1e-300)
    e21, e32 = f2 - f1, f3 - f2
    spread = (max(f1, f2, f3) - min(f1, f2, f3)) / scale
    if abs(e32) <= noise_tol * scale:
        return Richardson((f1, f2, f3), ratio, "converged", math.nan, math.nan, f3,
                          abs(e32) / scale)
    if e21 * e32 <= 0:
        return Richardson((f1, f2, f3), ratio, "oscillatory", math.nan, math.nan, f3, spread)
    if abs(e32) >= abs(e21):
        return Richardson((f1, f2, f3), ratio, "divergent", math.nan, math.nan, f3, spread)
    order = math.log(e21 / e32) / math.log(ratio)
    used = min(max(order, order_bounds[0]), order_bounds[1])
    gain = ratio**used - 1.0
    extrapolated = f3 + e32 / gain
    gci = GCI_SAFETY * abs(e32) / gain / scale
    return Richardson((f1, f2, f3), ratio, "monotone", order, used, extrapolated, gci)


@dataclass(frozen=True)
class TwoGrid:
    """A two-mesh extrapolation at an assumed order."""

    values: tuple[float, float]
    """Coarse, medium."""
    ratio: float
    order: float
    """The assumed order."""
    extrapolated: float
    uncertainty: float
    """Relative uncertainty of the extrapolated value: Roache's two-mesh GCI."""

    def relative_errors(self) -> tuple[float, float]:
        return tuple(v / self.extrapolated - 1.0 for v in self.values)  # type: ignore[return-value]


def two_grid(values: Sequence[float], ratio: float, order: float = FORMAL_ORDER) -> TwoGrid:
    """Richardson extrapolation of two meshes (``values`` coarse, then finer by
    ``ratio``) at the assumed ``order``."""
    if len(values) != 2:
        raise ValueError(f"a two-mesh extrapolation needs two values, got {len(values)}")
    if ratio <= 1 or order <= 0:
        raise ValueError(f"refinement ratio must exceed 1 and the order 0, got {ratio}, "
                         f"{order}")
    f1, f2 = (float(v) for v in values)
    if not (math.isfinite(f1) and math.isfinite(f2)):
        raise ValueError(f"non-finite value in a mesh study: {values}")
    gain = ratio**order - 1.0
    extrapolated = f2 + (f2 - f1) / gain
    gci = GCI_SAFETY_TWO_GRIDS * abs(f2 - f1) / gain / max(abs(extrapolated), 1e-300)
    return TwoGrid((f1, f2), ratio, order, extrapolated, gci)
