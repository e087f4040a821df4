"""A real fluid from CoolProp, tabulated for the chamber equations, across the two-phase
dome.

:class:`TabulatedFluid` tabulates ln p, T, kappa and the two pressure derivatives once on a
regular grid of (ln rho, u) over the states the run can reach (:mod:`.coolprop_table`:
the range, the nodes, the homogeneous-equilibrium mixture inside the dome and its sound
speed) and interpolates them bilinearly; the few event and performance evaluations call
CoolProp directly, with input pairs that are regular inside the dome ((rho, u), (p, s),
(p, h), (p, quality)).  It answers the chamber equations' fluid interface
(:mod:`rotorflow.quasi1d.fluids`).

Interpolation error (tests/test_quasi1d_real_fluid.py: R134a over the range of a wet
3 -> 9 bar case, 200 x 200 nodes, against the flash at 3000 random states).  Away from
the saturation line the table is smooth: p within 6e-5 (ln p is nearly linear in ln rho
and in u), T within 1.2e-5, kappa within 3e-5, the pressure derivatives within 2.3e-4.  A
cell that the saturation line crosses (~1 % of the states) interpolates across the kink
of p: p is off by up to 1.2e-3 and T by 2.1e-3 there, and the derivatives, which jump at
the line, are a blend of their two sides: kappa off by up to 1.2 %, (dp/drho)_u 2 %,
(dp/du)_rho 35 % (it falls ~20 % into the dome).  kappa moves a nozzle flux by a tenth of
its error; the derivatives serve only the ideal-port constraint, whose drift correction
removes the pressure offset a wrong derivative leaves.  (The slopes of the interpolated p
in those cells instead, tried: a CO2 point's cycle needed twice the periods, the
derivatives then jumping at every cell edge.)  That is the dew line; the bubble line,
where a liquid meets the wet mixture, is carried apart (:mod:`.coolprop_bubble`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from rotorflow.errors import CaseError

from . import coolprop_bubble
from .coolprop_table import (
    _state,
    build_nodes,
    continue_vapour_side,
    dew_temperature,
    reachable_box,
    suction_state,
)
from .flows import select

# Grid of the property table: 200 x 200 nodes in (ln rho, u); builds in ~1 s.  The
# interpolation error (module docstring) is set by the cells the saturation line crosses;
# 400 x 400 halves it at four times the cost.
TABLE_NODES = 200
# the table's rows of the state (ln p, T, kappa, (dp/drho)_u, (dp/du)_rho); the bubble
# line's follow (coolprop_bubble.ROWS)
_STATE_ROWS = slice(0, 5)


@dataclass(frozen=True)
class TabulatedFluid:
    """A CoolProp fluid tabulated in (ln rho, u) over [rho_lo, rho_hi] x [u_lo, u_hi]."""

    name: str  # CoolProp name, e.g. "R134a"
    x0: float
    dx: float
    u0: float
    du: float
    nx: int
    nu: int
    # (10, nx*nu): ln p, T, kappa, dp/drho|u, dp/du|rho at the nodes; the bubble line at
    # the u nodes (the first nu entries of rows 5-9, :mod:`.coolprop_bubble`)
    table: np.ndarray = field(repr=False)
    # (nx-1, nu-1): cells whose four nodes CoolProp could evaluate
    cells: np.ndarray = field(repr=False)

    @classmethod
    def build(cls, name: str, rho_lo: float, rho_hi: float, u_lo: float, u_hi: float,
              nodes: int = TABLE_NODES) -> TabulatedFluid:
        x = np.linspace(math.log(rho_lo), math.log(rho_hi), nodes)
        ug = np.linspace(u_lo, u_hi, nodes)
        tab, dome = build_nodes(name, x, ug)
        continue_vapour_side(name, tab)
        ok = np.all(np.isfinite(tab), axis=0)
        cells = ok[:-1, :-1] & ok[1:, :-1] & ok[:-1, 1:] & ok[1:, 1:]
        bubble = coolprop_bubble.bubble_line(_state(name), ug)
        coolprop_bubble.continue_wet_side(tab, dome, x, bubble[0])
        table = np.zeros((5 + coolprop_bubble.ROWS, nodes * nodes))
        table[:5] = tab.reshape(5, -1)
        table[5:, :nodes] = bubble
        return cls(name, float(x[0]), float(x[1] - x[0]), float(ug[0]),
                   float(ug[1] - ug[0]), nodes, nodes, table, cells)

    def kernel_params(self):
        """(kind, parameters, table) of the compiled right-hand side (:mod:`.kernel`)."""
        return 2, np.array([self.x0, self.dx, self.u0, self.du, float(self.nu)]), self.table

    def state(self, rho, u):
        """p, T, kappa, (dp/drho)_u, (dp/du)_rho at rho, u (:func:`table_state`; on
        arrays the five rows in one gather, a third of the time of five)."""
        rho, u = np.asarray(rho, dtype=float), np.asarray(u, dtype=float)
        args = (self.x0, self.dx, self.u0, self.du, self.nu)
        if rho.ndim == 0 and u.ndim == 0:
            return table_state(rho, u, *args, self.table)
        k, tx, tu = table_cell(rho, u, *args, self.nx)
        rows = table_row(self.table, _STATE_ROWS, k, tx, tu, self.nu)
        return _or_liquid(rho, self.table, k, tu, self.du, self.nu, *rows)

    def props(self, rho, u):
        return self.state(rho, u)[:3]

    def dp(self, rho, u):
        return self.state(rho, u)[3:]

    def in_range(self, rho, u) -> bool:
        """Every state inside the table and in a cell CoolProp could evaluate."""
        fx = (np.log(np.asarray(rho, float)) - self.x0) / self.dx
        fu = (np.asarray(u, float) - self.u0) / self.du
        inside = (fx >= 0) & (fx <= self.nx - 1) & (fu >= 0) & (fu <= self.nu - 1)
        if not np.all(inside):
            return False
        i = np.clip(fx.astype(np.intp), 0, self.nx - 2)
        j = np.clip(fu.astype(np.intp), 0, self.nu - 2)
        return bool(np.all(self.cells[i, j]))

    def out_of_range(self, rho, u) -> str:
        """Which way states outside :meth:`in_range` left the table (for the message)."""
        fx = (np.log(np.asarray(rho, float)) - self.x0) / self.dx
        fu = (np.asarray(u, float) - self.u0) / self.du
        side = ("hotter than its hottest state (leakage heating the gas faster than the "
                "discharge carries the heat away?)" if np.any(fu > self.nu - 1) else
                "colder than its coldest state" if np.any(fu < 0) else
                "denser than its densest state" if np.any(fx > self.nx - 1) else
                "thinner than its thinnest state" if np.any(fx < 0) else
                "in a cell CoolProp could not evaluate")
        return f"{self.name} {side}"

    def u_from_rho_p(self, rho, p):
        """u at (rho, p) (starting states of the chambers: a guess, so the flash's value
        rather than the table's inverse, which differs by the interpolation error)."""
        return self._upd("DmassP_INPUTS", rho, p).umass()

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

    def _start(self, p, T, q=None, h=None):
        """The state at p and T; on the saturation line, where (p, T) does not fix it, at
        p and the quality q or the enthalpy h."""
        if q is not None:
            return self._upd("PQ_INPUTS", p, q)
        if h is not None:
            return self._upd("HmassP_INPUTS", h, p)
        try:
            return self._upd("PT_INPUTS", p, T)
        except ValueError as exc:
            raise CaseError(f"CoolProp {self.name} at {p / 1e5:.4g} bar, {T:.2f} K: {exc} "
                            "(on the saturation line give the quality)") from None

    def state_pT(self, p: float, T: float, q: float | None = None, h: float | None = None):
        """rho, u, h at (p, T); with q (quality) or h given, at (p, q) or (p, h): a
        two-phase plenum, where T is the saturation temperature and fixes nothing."""
        st = self._start(p, T, q, h)
        return st.rhomass(), st.umass(), st.hmass()

    def T_ph(self, p, h):
        return self._upd("HmassP_INPUTS", h, p).T()

    def T_hottest(self, p) -> float:
        """The hottest temperature at p whose state the table holds (its highest u)."""
        return self._upd("PUmass_INPUTS", p, self.u0 + self.du * (self.nu - 1)).T()

    def quality_ph(self, p, h) -> float | None:
        """The vapour's mass fraction at (p, h): 1 superheated, 0 subcooled, None above
        the critical pressure (no phases to tell apart)."""
        import CoolProp.CoolProp as CP

        st = self._upd("HmassP_INPUTS", h, p)
        if st.phase() == CP.iphase_twophase:
            return float(st.Q())
        if p >= st.p_critical():
            return None
        return 1.0 if st.T() >= st.T_critical() or st.rhomass() < st.rhomass_critical() \
            else 0.0

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
        # (the geometry's bracketed root, not scipy's brentq: importing scipy.optimize
        # took ~1 s of a real-fluid `simulate`'s ~10 s on a slow machine, for this alone)
        from rotorflow.geometry.scalar import root

        m = np.atleast_1d(m)
        U = np.atleast_1d(U)
        V = np.broadcast_to(V, m.shape)  # (a liquid's share differs per state)
        m2 = np.empty_like(m)
        for i in range(m.size):
            mi, Ui, Vi = m.flat[i], U.flat[i], float(V.flat[i])

            def f(mm, mi=mi, Ui=Ui, Vi=Vi):
                uu = (Ui + (mm - mi) * h_in) / mm
                return self._upd("DmassUmass_INPUTS", mm / Vi, uu).p() - p2

            lo, hi = _bracket(f, mi)
            m2.flat[i] = root(f, lo, hi, xtol=1e-15 * mi)
        return m2, U + (m2 - m) * h_in

    def work_isentropic(self, p1, T1, p2, q: float | None = None):
        """h(p2, s1) - h1 from (p1, T1), or from (p1, quality q) for a wet suction."""
        st = self._start(p1, T1, q)
        h1, s1 = st.hmass(), st.smass()
        return self._upd("PSmass_INPUTS", p2, s1).hmass() - h1

    def work_isothermal(self, p1, T1, p2, q: float | None = None):
        """(h2 - h1) - T1 (s2 - s1) at T1 from p1 to p2; from (p1, quality q) for a wet
        suction.  None where the isotherm reaches the saturation line on the way (T1 below
        the critical temperature and p2 at or above the dew pressure at T1; a wet suction
        always): the reversible isothermal path then condenses the vapour, and the
        efficiency against it compares a compressor with a condenser (R134a at 3 bar /
        285 K -> 9 bar: 0.27).  A supercritical isotherm (CoolProp air, CO2 sucked above
        304 K) never does, nor one that starts above the critical pressure (CO2 from 80
        bar at 300 K: dense, but no phase change on the way)."""
        st = self._start(p1, T1, q)
        h1, s1, T1 = st.hmass(), st.smass(), st.T()
        if q is not None:
            return None
        if T1 < st.T_critical() and p1 < st.p_critical() \
                and p2 >= self._upd("QT_INPUTS", 1.0, T1).p():
            return None
        st = self._upd("PT_INPUTS", p2, T1)
        return (st.hmass() - h1) - T1 * (st.smass() - s1)


def _bracket(f, m, tries=60):
    """lo, hi about m with f(lo) < 0 <= f(hi), f rising.  Doubling the mass of a wet
    chamber under a liquid-dense plenum can step past the liquid's density, where CoolProp
    refuses the state (beyond the melting line): such a trial is halved back towards the
    last mass that fell short, since the root lies below any mass CoolProp cannot hold."""
    lo, hi = m, 2.0 * m
    for _ in range(tries):
        try:
            high = f(hi) >= 0
        except ValueError:
            hi = 0.5 * (lo + hi)
            continue
        if high:
            return lo, hi
        lo, hi = hi, 2.0 * hi
    raise ValueError(f"no mass from {m:.6g} kg fills the chamber to the plenum's pressure")


def table_state(rho, u, x0, dx, u0, du, nu, table):
    """p, T, kappa, (dp/drho)_u, (dp/du)_rho at arrays or scalars rho, u: the liquid's
    law denser than the bubble line (:mod:`.coolprop_bubble`), else the table bilinearly
    (the nodes' pressure derivatives interpolated too)."""
    k, tx, tu = table_cell(rho, u, x0, dx, u0, du, nu, table.shape[1] // nu)
    return _or_liquid(rho, table, k, tu, du, nu, table_row(table, 0, k, tx, tu, nu),
                      table_row(table, 1, k, tx, tu, nu), table_row(table, 2, k, tx, tu, nu),
                      table_row(table, 3, k, tx, tu, nu), table_row(table, 4, k, tx, tu, nu))


def _or_liquid(rho, table, k, tu, du, nu, lnp, T, kappa, pr, pu):
    """The table's state (ln p, T, kappa, (dp/drho)_u, (dp/du)_rho) in the cells k, or the
    liquid's where rho is denser than the bubble line: (p, T, kappa, pr, pu)."""
    rb, pl, Tl, kl, prl, pul = coolprop_bubble.liquid_state(table, k % nu, tu, rho, du)
    liquid = rho >= rb
    return (select(liquid, pl, np.exp(lnp)), select(liquid, Tl, T),
            select(liquid, kl, kappa), select(liquid, prl, pr), select(liquid, pul, pu))


def table_cell(rho, u, x0, dx, u0, du, nu, nx):
    """The table's cell (index of its first node) and the position in it at rho, u
    (arrays or scalars: the compiled right-hand side calls it per slot, :mod:`.compiled`)."""
    fx = (np.log(rho) - x0) / dx
    fu = (u - u0) / du
    # truncate, then clip: a NaN state lands in the first cell (never out of the table)
    i = np.minimum(np.maximum(np.intp(fx), 0), nx - 2)
    j = np.minimum(np.maximum(np.intp(fu), 0), nu - 2)
    return i * nu + j, fx - i, fu - j


def table_row(table, r, k, tx, tu, nu):
    """Row r of the table interpolated bilinearly in the cells k at (tx, tu)."""
    c00 = table[r, k]
    c10 = table[r, k + nu]
    a = c00 + tu * (table[r, k + 1] - c00)
    b = c10 + tu * (table[r, k + nu + 1] - c10)
    return a + tx * (b - a)


@functools.lru_cache(maxsize=16)
def tabulated(name, ps, pd, Ts, Tw, To, vr, qs=None, nodes=TABLE_NODES):
    """CoolProp's ``name`` tabulated over the states reachable from suction (ps, Ts, or
    quality qs for a wet suction), discharge pressure pd, wall and oil temperatures Tw, To
    and volume ratio vr (the range: :func:`checked_box`)."""
    fluid = TabulatedFluid.build(name, *checked_box(name, ps, pd, Ts, Tw, To, vr, qs),
                                 nodes=nodes)
    rho_s, u_s = suction_state(name, ps, Ts, qs)[:2]
    if not fluid.in_range(np.array([rho_s]), np.array([u_s])):
        # the pseudo-pure blends (R410A, R404A, R507A): CoolProp has no (rho, u) flash
        # inside their dome, so a wet suction has no table cells
        raise CaseError(f"CoolProp's {name} cannot be evaluated by (density, energy) at the "
                        f"suction state (its two-phase flash fails for pseudo-pure blends): "
                        f"give a superheated suction")
    return fluid


def checked_box(name, ps, pd, Ts, Tw, To, vr, qs=None):
    """The range of :func:`.coolprop_table.reachable_box` for this point, once the point
    passes the refusals (CaseError): a suction off the saturation temperature its quality
    implies, outside the equation of state, inside the dome, squeezed past the equation.
    (A performance map builds its shared table from its corners' ranges through here, so
    that they are refused as a single point is: it called reachable_box directly, and a
    suction pressure range reaching into the dome ended in a traceback.)"""
    if qs is not None:
        Tsat = suction_state(name, ps, Ts, qs)[4]
        if abs(Ts - Tsat) > SATURATION_T_TOLERANCE_K:
            raise CaseError(
                f"T_suction_K = {Ts:g} is not the saturation temperature of {name} at "
                f"{ps / 1e5:g} bar ({Tsat:.2f} K) that suction_quality = {qs:g} implies")
    else:
        _refuse_outside_the_equation(name, ps, pd, Ts)
        Tsat = dew_temperature(name, ps)
        if Tsat is not None and Ts <= Tsat + SATURATION_T_TOLERANCE_K:
            state = _below_dew(name, ps, Ts, Tsat)
            raise CaseError(
                f"suction of {name} at {ps / 1e5:g} bar and T_suction_K = {Ts:g} is {state}: "
                f"the saturation temperature there is {Tsat:.2f} K; a dry suction needs "
                f"T_suction_K above it, a wet one suction_quality in (0, 1] "
                f"(1: saturated vapour)")
    if qs is None:
        _refuse_squeezed_past_the_equation(name, ps, Ts, vr)
    try:
        return reachable_box(name, ps, pd, Ts, qs, Tw, To, vr)
    except ValueError as exc:
        raise CaseError(f"CoolProp {name} cannot evaluate the states this operating point "
                        f"reaches ({_suction_named(name, ps, Ts, qs)}, volume_ratio {vr:g}): "
                        f"{exc}") from None


def _refuse_outside_the_equation(name, ps, pd, Ts) -> None:
    """A suction temperature or a pressure beyond the range of CoolProp's equation of
    state for ``name`` is refused (CoolProp extrapolates there without a word)."""
    st = _state(name)
    if Ts < st.Tmin():
        # (below the triple point: a solid, which the dew-point check below called
        # "subcooled liquid" (R134a at 60 K), hiding a Celsius slip)
        raise CaseError(f"T_suction_K = {Ts:g} is below the range of CoolProp's equation of "
                        f"state for {name} ({st.Tmin():.2f} K): was it given in Celsius?")
    if Ts > st.Tmax():
        raise CaseError(f"T_suction_K = {Ts:g} is above the range of CoolProp's equation of "
                        f"state for {name} ({st.Tmax():.2f} K)")
    if max(ps, pd) > st.pmax():
        raise CaseError(f"a pressure of {max(ps, pd) / 1e5:g} bar is above the range of "
                        f"CoolProp's equation of state for {name} ({st.pmax() / 1e5:g} bar)")


def _suction_named(name, ps, Ts, qs) -> str:
    """The suction state in words, with its density against the critical one (a pressure
    in kPa written as bar makes R134a's suction a liquid of ~1300 kg/m3)."""
    try:
        rho = suction_state(name, ps, Ts, qs)[0]
    except ValueError:
        return f"suction {ps / 1e5:g} bar, {Ts:g} K"
    rho_c = _state(name).rhomass_critical()
    dense = f", {rho / rho_c:.1f} times the critical density" if rho > rho_c else ""
    return f"suction {ps / 1e5:g} bar, {Ts:g} K: {rho:.4g} kg/m3{dense}"


def _refuse_squeezed_past_the_equation(name, ps, Ts, vr) -> None:
    """A built-in volume ratio that squeezes a dense (dry) suction past the range of
    CoolProp's equation of state along its isentrope is refused."""
    import CoolProp.CoolProp as CP

    st = _state(name)
    st.update(CP.PT_INPUTS, ps, Ts)
    rho, s = st.rhomass(), st.smass()
    try:
        st.update(CP.DmassSmass_INPUTS, vr * rho, s)
        p_end = st.p()
    except ValueError:
        return  # (a flash that fails is no evidence: the table's own range check follows)
    if p_end > st.pmax():
        raise CaseError(f"volume_ratio {vr:g} squeezes the suction of {name} "
                        f"({rho:.4g} kg/m3) to {p_end / 1e5:.4g} bar along its isentrope, "
                        f"beyond CoolProp's range ({st.pmax() / 1e5:g} bar): a dense suction "
                        f"needs a volume ratio near 1")


def _below_dew(name, p, T, T_dew) -> str:
    """What a state at or below the dew temperature is: saturated, inside a blend's
    glide (between its bubble and dew points) or subcooled liquid."""
    import CoolProp.CoolProp as CP

    if T >= T_dew - SATURATION_T_TOLERANCE_K:
        return "saturated"
    st = _state(name)
    st.update(CP.PQ_INPUTS, p, 0.0)
    if T > st.T() + SATURATION_T_TOLERANCE_K:
        return f"inside its glide (bubble point {st.T():.2f} K)"
    return "subcooled liquid"


# A wet suction's T_suction_K must be the saturation temperature at p_suction within this:
# 0.1 K allows the figure rounded to one decimal; a larger difference is another state.
# A dry suction must lie this far above it: closer, (p, T) barely fixes the state (the
# flash is singular on the saturation line), and saturated vapour is suction_quality = 1.
SATURATION_T_TOLERANCE_K = 0.1
