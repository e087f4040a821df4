"""A real fluid from CoolProp, tabulated for the chamber equations.

:class:`TabulatedFluid` tabulates ln p, T, kappa and the two pressure derivatives once on a
regular grid of (ln rho, u) covering the states a run can reach and interpolates them
bilinearly (ln p is nearly linear in ln rho, so the interpolation error is small: below
1e-4 on the default grid); the few event and performance evaluations call CoolProp
directly.  It answers the chamber equations' fluid interface
(:mod:`rotorflow.quasi1d.fluids`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import CaseError

# Grid of the property table: 200 x 200 nodes in (ln rho, u).  The interpolation error of
# p, which is nearly linear in ln rho, stays below 1e-4 over a 1e4 span of density.
TABLE_NODES = 200


@dataclass(frozen=True)
class TabulatedFluid:
    """A CoolProp fluid tabulated in (ln rho, u) over [rho_lo, rho_hi] x [T_lo, T_hi]."""

    name: str  # CoolProp name, e.g. "Air"
    x0: float
    dx: float
    u0: float
    du: float
    nx: int
    nu: int
    table: np.ndarray = field(repr=False)  # (5, nx*nu): ln p, T, kappa, dp/drho|u, dp/du|rho

    @classmethod
    def build(cls, name: str, rho_lo: float, rho_hi: float, T_lo: float, T_hi: float,
              nodes: int = TABLE_NODES) -> TabulatedFluid:
        import CoolProp.CoolProp as CP

        x = np.linspace(math.log(rho_lo), math.log(rho_hi), nodes)
        Tf = np.geomspace(T_lo, T_hi, 2 * nodes)
        rho = np.exp(x)
        uf = _props_grid(CP, name, "Umass", rho[:, None], Tf[None, :])
        u_lo = np.nanmax(uf[:, 0])
        u_hi = np.nanmin(uf[:, -1])
        if not (np.isfinite(u_lo) and np.isfinite(u_hi) and u_hi > u_lo):
            raise CaseError(f"CoolProp cannot tabulate {name} between {T_lo:.0f} and {T_hi:.0f} K")
        ug = np.linspace(u_lo, u_hi, nodes)
        Tg = np.empty((nodes, nodes))
        for i in range(nodes):
            ok = np.isfinite(uf[i])
            Tg[i] = np.interp(ug, uf[i, ok], Tf[ok])
        R = np.broadcast_to(rho[:, None], Tg.shape)
        p = _props_grid(CP, name, "P", R, Tg)
        a = _props_grid(CP, name, "A", R, Tg)
        dpdr = _props_grid(CP, name, "d(P)/d(Dmass)|Umass", R, Tg)
        dpdu = _props_grid(CP, name, "d(P)/d(Umass)|Dmass", R, Tg)
        kappa = R * a**2 / p
        tab = np.stack([np.log(p), Tg, kappa, dpdr, dpdu]).reshape(5, -1)
        if not np.all(np.isfinite(tab)):
            raise CaseError(f"CoolProp {name}: the operating range reaches states it cannot "
                            "evaluate (two-phase or outside the equation of state)")
        return cls(name, float(x[0]), float(x[1] - x[0]), float(ug[0]), float(ug[1] - ug[0]),
                   nodes, nodes, tab)

    def _interp(self, rho, u, rows):
        fx = (np.log(rho) - self.x0) / self.dx
        fu = (u - self.u0) / self.du
        i = np.clip(fx.astype(np.intp), 0, self.nx - 2)
        j = np.clip(fu.astype(np.intp), 0, self.nu - 2)
        tx = fx - i
        tu = fu - j
        k = i * self.nu + j
        t = self.table[rows]
        c00 = t[:, k]
        c01 = t[:, k + 1]
        c10 = t[:, k + self.nu]
        c11 = t[:, k + self.nu + 1]
        a = c00 + tu * (c01 - c00)
        b = c10 + tu * (c11 - c10)
        return a + tx * (b - a)

    def props(self, rho, u):
        v = self._interp(rho, u, slice(0, 3))
        return np.exp(v[0]), v[1], v[2]

    def dp(self, rho, u):
        v = self._interp(rho, u, slice(3, 5))
        return v[0], v[1]

    def in_range(self, rho, u) -> bool:
        fx = (np.log(rho) - self.x0) / self.dx
        fu = (u - self.u0) / self.du
        return bool(np.all((fx >= 0) & (fx <= self.nx - 1) & (fu >= 0) & (fu <= self.nu - 1)))

    def u_from_rho_p(self, rho, p):
        """u at (rho, p) on the table (the inverse of props in u, for starting states)."""
        from scipy.optimize import brentq

        def dp(uu):
            return float(self.props(np.array([rho]), np.array([uu]))[0][0]) - p

        return brentq(dp, self.u0, self.u0 + self.du * (self.nu - 1))

    # -- direct CoolProp evaluations (a few per run) -------------------------------------
    @functools.cached_property
    def _state(self):
        import CoolProp.CoolProp as CP

        return CP.AbstractState("HEOS", self.name)

    def _upd(self, pair, a, b):
        import CoolProp.CoolProp as CP

        st = self._state
        st.update(getattr(CP, pair), float(a), float(b))
        return st

    def state_pT(self, p: float, T: float):
        st = self._upd("PT_INPUTS", p, T)
        return st.rhomass(), st.umass(), st.hmass()

    def T_ph(self, p, h):
        return self._upd("HmassP_INPUTS", h, p).T()

    def isentropic(self, rho, u, p2):
        rho = np.atleast_1d(rho)
        u = np.atleast_1d(u)
        out_r = np.empty_like(rho)
        out_u = np.empty_like(u)
        for i in range(rho.size):
            s = self._upd("DmassUmass_INPUTS", rho.flat[i], u.flat[i]).smass()
            st = self._upd("PSmass_INPUTS", p2, s)
            out_r.flat[i], out_u.flat[i] = st.rhomass(), st.umass()
        return out_r, out_u

    def fill(self, m, U, V, h_in, p2):
        from scipy.optimize import brentq

        m = np.atleast_1d(m)
        U = np.atleast_1d(U)
        m2 = np.empty_like(m)
        for i in range(m.size):
            mi, Ui = m.flat[i], U.flat[i]

            def f(mm, mi=mi, Ui=Ui):
                uu = (Ui + (mm - mi) * h_in) / mm
                return self._upd("DmassUmass_INPUTS", mm / V, uu).p() - p2

            hi = mi * 2.0
            while f(hi) < 0:
                hi *= 2.0
            m2.flat[i] = brentq(f, mi, hi, xtol=1e-15 * mi, rtol=1e-14)
        return m2, U + (m2 - m) * h_in

    def work_isentropic(self, p1, T1, p2):
        st = self._upd("PT_INPUTS", p1, T1)
        h1, s1 = st.hmass(), st.smass()
        return self._upd("PSmass_INPUTS", p2, s1).hmass() - h1

    def work_isothermal(self, p1, T1, p2):
        st = self._upd("PT_INPUTS", p1, T1)
        h1, s1 = st.hmass(), st.smass()
        st = self._upd("PT_INPUTS", p2, T1)
        return (st.hmass() - h1) - T1 * (st.smass() - s1)


def _props_grid(CP, name, out, rho, T):
    """PropsSI on a grid; rows that CoolProp rejects are filled point by point (NaN where
    it cannot evaluate)."""
    rho, T = np.broadcast_arrays(rho, T)
    res = np.full(rho.shape, np.nan)
    for i in range(rho.shape[0]):
        try:
            res[i] = CP.PropsSI(out, "Dmass", rho[i], "T", T[i], name)
        except ValueError:
            for j in range(rho.shape[1]):
                try:
                    res[i, j] = CP.PropsSI(out, "Dmass", rho[i, j], "T", T[i, j], name)
                except ValueError:
                    pass
    res[~np.isfinite(res)] = np.nan
    return res


@functools.lru_cache(maxsize=16)
def tabulated(name, ps, pd, Ts, Tw, To, vr):
    """CoolProp's ``name`` tabulated over the states reachable from suction (ps, Ts),
    discharge pressure pd, wall and oil temperatures Tw, To and volume ratio vr (the range
    is stated in :func:`rotorflow.quasi1d.fluids.make_fluid`)."""
    import CoolProp.CoolProp as CP

    cp = CP.PropsSI("CPMASS", "P", ps, "T", Ts, name)
    gamma = cp / CP.PropsSI("CVMASS", "P", ps, "T", Ts, name)
    p_hi = 3.0 * max(pd, ps * vr**gamma)
    p_lo = 0.01 * ps
    T_end = Ts * max(pd / ps, vr ** gamma) ** ((gamma - 1.0) / gamma)
    T_lo = 0.6 * min(Ts, Tw, To)
    T_hi = 2.5 * max(Ts, Tw, To, T_end)
    rho_lo = CP.PropsSI("Dmass", "P", p_lo, "T", T_hi, name)
    rho_hi = CP.PropsSI("Dmass", "P", p_hi, "T", max(T_lo, 0.9 * Ts), name)
    return TabulatedFluid.build(name, rho_lo, rho_hi, T_lo, T_hi)
