"""Whether the cycle solver's states are physical: an iterate before its period
(:func:`plausible`), a period's end state (:func:`check_states`), and a Newton iterate
whose period is rejected rather than fatal (:func:`rejected`)."""

from __future__ import annotations

import numpy as np

from .integrate import IntegrationError


def plausible(model, z) -> bool:
    """Masses positive in every living slot, oil non-negative, states inside the fluid's range."""
    n = model.n
    ages = model.geo.birth + model.geo.period * np.arange(1, n)
    live = ages <= model.geo.death
    m = z[1:n][live]
    if not np.all(np.isfinite(z)) or np.any(m <= 0):
        return False
    # masses only: the liquid's energy counts from its inlet temperature, below which an
    # evaporating or gas-cooled liquid may fall
    if model.oil and (np.any(z[2 * n:3 * n] < 0) or np.any(z[4 * n:model.nv * n] < 0)):
        return False
    V = model.geo.volume(ages[live])
    if model.inv_rho_liquid:
        V = V - z[2 * n + 1:3 * n][live] * model.inv_rho_liquid
        if np.any(V <= 0):
            return False
    return model.fluid.in_range(m / V, z[n + 1:2 * n][live] / m)


def rejected(model, y_end, retreat: bool) -> bool:
    """Whether a period from a damped Newton iterate ended outside the fluid's table or
    unphysical (:func:`check_states`): where ``retreat``, that iterate is rejected as
    one whose residual grew, and Newton halves its step from the best iterate.  A wet
    n-pentane pump's full Newton step, after a stall had tightened the tolerance, filled
    its chambers from the plenum past the table's densest liquid (on an AVX2 machine;
    the same solve converged on the AVX-512 ones, the rounding of their BLAS kernels
    giving another step).  Before Newton has a best iterate, under the plain iteration
    (``newton = false``) and under Anderson's, there is nothing to retreat to."""
    try:
        check_states(model, y_end)
    except IntegrationError:
        if retreat:
            return True
        raise
    return False


def check_states(model, y):
    n = model.n
    m, U = y[:n], y[n:2 * n]
    if not (np.all(np.isfinite(y)) and np.all(m >= 0)):
        raise IntegrationError("state not finite or chamber mass negative at the end of a period")
    live = m > 0
    if np.any(live):
        ages = model.geo.birth + model.geo.period * (1 + np.arange(n))
        # end of period: slot k has age birth + (k+1) period
        V = model.geo.volume(np.minimum(ages, model.geo.death))
        if model.inv_rho_liquid:
            V = V - y[2 * n:3 * n] * model.inv_rho_liquid
            if np.any(V[live] <= 0):
                raise IntegrationError("the liquid fills a chamber (hydraulic lock): lower "
                                       "the volume ratio or raise the gas volume fraction")
        rho, u = m[live] / V[live], U[live] / m[live]
        if not model.fluid.in_range(rho, u):
            why = getattr(model.fluid, "out_of_range", None)
            raise IntegrationError("chamber state left the range of the fluid's property table"
                                   + (f": {why(rho, u)}" if why else ""))
