"""The flow network of one lobe period, segment by segment, built from the declared paths.

Nodes: 0 the suction plenum, 1..n_act the active slots (slot k is node k+1), n_act+1 the
discharge plenum.  Every declared leakage path (:class:`.paths.PathLaw`, the table's
:class:`~rotorflow.geometry.table.LeakagePath` with its settings) becomes flows:

- a path to the chamber d periods older (or younger) joins every pair of slots d apart,
  the younger slot first (ia), the older second (ib).  A slot below 0 is a chamber not
  yet born, whose space is open to suction; one past the last a chamber already
  discharged.  The flow area is the path's area factor times its column read at the
  source slot, averaged with its mirror column read at the target slot where both slots
  exist (the two chambers' views of one sealing line);
- a path to a plenum joins every active slot to it (ia the slot, ib the plenum).

Flows come in the order of the declarations, a path's links youngest first; a run of
consecutive plenum paths goes chamber by chamber (each chamber's plenum paths together).
Then the ports: nozzle ports as flows through the port areas, ideal ports as constraints.

State layout: per slot m and U (and with oil its mass and enthalpy), then the
accumulators: ACC_M_SUC .. ACC_Q, one gross leakage per report key of the paths, and
the oil's (:class:`AccColumns`).  Where the leakage carries oil (:mod:`.oil`), each
segment also maps the leakage flows' oil into the slots' oil states and the oil's
accumulators (Segment.oil).  The accumulators are part of the integrated state, so
their number enters the step control: a new report key is a change of every result.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from . import flows, oil
from .chamber import ROW_AREA_HP, ROW_AREA_LP, ChamberGeometry
from .rarefied import RarefiedLaw

# Accumulator columns that every machine has (offsets after the slot states)
ACC_M_SUC, ACC_H_SUC, ACC_M_DIS, ACC_H_DIS, ACC_W, ACC_Q = range(6)


@dataclass(frozen=True)
class AccColumns:
    """Accumulator columns: the fixed six, the gross leakage per report key (in the order
    the paths first name them), then the oil's mass and enthalpy in and out, and, where
    the leakage carries oil (``oil_leaks``), the gross oil leakage per report key."""

    leak_keys: tuple[str, ...]
    oil_leaks: bool = False
    vapour: bool = False  # a volatile liquid's vapour in, out and evaporated (.humid)

    def leak(self, key: str) -> int:
        return ACC_Q + 1 + self.leak_keys.index(key)

    def oil_leak(self, key: str) -> int:
        if not self.oil_leaks:
            raise KeyError(f"no oil leakage accumulators (leakage of gas only): {key!r}")
        return self.oil_m_in + 4 + self.leak_keys.index(key)

    @property
    def oil_m_in(self) -> int:
        return ACC_Q + 1 + len(self.leak_keys)

    @property
    def oil_h_in(self) -> int:
        return self.oil_m_in + 1

    @property
    def oil_m_out(self) -> int:
        return self.oil_m_in + 2

    @property
    def oil_h_out(self) -> int:
        return self.oil_m_in + 3

    @property
    def vap_in(self) -> int:
        return self.oil_m_in + 4 + (len(self.leak_keys) if self.oil_leaks else 0)

    @property
    def vap_out(self) -> int:
        return self.vap_in + 1

    @property
    def evaporated(self) -> int:
        return self.vap_in + 2

    @property
    def size(self) -> int:
        return self.vap_in + (3 if self.vapour else 0)

    @classmethod
    def of(cls, laws, oil_leaks: bool = False, vapour: bool = False) -> AccColumns:
        return cls(tuple(dict.fromkeys(law.path.report_key for law in laws)), oil_leaks,
                   vapour)


@dataclass(frozen=True)
class FlowGroup:
    """Leakage flows of one segment that flow by one law: the model and its constants."""

    model: str
    flows: slice | np.ndarray  # columns of the segment's flows
    zeta: float = 0.0  # fanno
    x_choke: float = 0.0  # fanno
    correlation: object = None  # cfd-calibrated
    k_factor: float = 0.0  # cfd-calibrated: 24 L mu / h^2
    drag: slice | np.ndarray | None = None  # flows whose walls drag (the fit's wall term)
    drag_in_group: slice | np.ndarray | None = None  # the same, within the group
    rarefied: RarefiedLaw | None = None  # rarefied


@dataclass(frozen=True)
class Segment:
    """Part of a lobe period between two events; the topology is constant inside.

    Flow f goes from node ia[f] to node ib[f] through area = area @ geometry, where the
    geometry vector is ChamberGeometry.evaluate's ``lin`` raveled (rows: the port areas,
    then the paths' columns, over the active slots).  The matrices mm, me, mg map mass
    flows, enthalpy flows and |mass flows| straight into dy/dtheta (slot balances and
    accumulators); mx, mxe do the same for the ideal-port flows.
    """

    index: int
    start: float
    end: float
    events: tuple  # (kind, slot) applied at ``start``, in order
    n_act: int  # active slots 0..n_act-1
    k_sc: int  # slots 0..k_sc-1 open to suction
    k_do: int  # slots k_do..n_act-1 open to discharge
    kP: np.ndarray = field(repr=False)  # k * period for the active slots
    ia: np.ndarray = field(repr=False)
    ib: np.ndarray = field(repr=False)
    n_leak: int  # flows 0..n_leak-1 are leakage, the rest nozzle ports
    names: tuple = field(repr=False)  # per flow: the path's name, or the port's
    groups: tuple = field(repr=False)  # FlowGroups of the leakage flows
    area: np.ndarray = field(repr=False)  # (n_flows, rows*n_act)
    cou: slice | np.ndarray = field(repr=False)  # flows with a Couette term
    cou_older: slice | np.ndarray = field(repr=False)  # their older node (ib)
    cou_gap: np.ndarray = field(repr=False)  # their gaps
    link_len: np.ndarray = field(repr=False)  # (n_cou, rows*n_act): their line lengths
    walls: bool  # moving walls drive some flow here (it may run against the pressure)
    mm: np.ndarray = field(repr=False)  # (n_flows, n_state)
    me: np.ndarray = field(repr=False)
    mg: np.ndarray = field(repr=False)
    ideal: np.ndarray = field(repr=False)  # slots held at a plenum pressure
    ideal_p: np.ndarray = field(repr=False)  # their plenum pressure
    ideal_h: np.ndarray = field(repr=False)  # and plenum enthalpy
    ideal_is_dis: np.ndarray = field(repr=False)  # True where the plenum is discharge
    mx: np.ndarray = field(repr=False)  # (n_ideal, n_state)
    mxe: np.ndarray = field(repr=False)
    dis_port: np.ndarray = field(repr=False)  # flows that are nozzle discharge ports
    oil: object = field(default=None, repr=False)  # oil.OilMaps where the leakage carries oil


@dataclass(frozen=True)
class _Link:
    """One flow of a leakage path: nodes, the (row, slot) views of its area, the law."""

    ia: int
    ib: int
    views: tuple
    law: int


@dataclass(frozen=True)
class _Frame:
    """What every segment of one model shares."""

    n: int  # slots
    nv: int  # state variables per slot
    period: float
    n_rows: int  # rows of the geometry's ``lin``
    w: float  # 1 / omega: d/dtheta = w d/dt
    laws: tuple
    acc: AccColumns
    ports: object
    suc: object
    dis: object

    @property
    def n_state(self) -> int:
        return self.nv * self.n + self.acc.size


def segments(geo: ChamberGeometry, laws, acc: AccColumns, nv: int, n: int, ports, suc, dis):
    """The segments of one lobe period (see Segment)."""
    P, t0 = geo.period, geo.birth
    frame = _Frame(n, nv, P, geo.rows, 1.0 / geo.omega_outer, laws, acc, ports, suc, dis)
    tol = 1e-10 * P
    events = [(t0, 0, "birth", 0)]
    order = {"birth": 0, "death": 1, "close": 2, "open": 3}
    for kind, age in (("close", geo.suction_close), ("open", geo.discharge_open),
                      ("death", geo.death)):
        k = int(math.floor((age - t0 + tol) / P))
        if 0 <= k < n:
            th = max(age - k * P, t0)
            events.append((th, order[kind], kind, k))
    events.sort()
    marks = sorted({e[0] for e in events} | {t0 + P})
    index = 0
    for a, b in zip(marks[:-1], marks[1:], strict=True):
        evs = tuple((kind, k) for th, _, kind, k in events if abs(th - a) <= tol)
        if b - a <= tol and not evs:
            continue
        mid = 0.5 * (a + b)
        ages = mid + P * np.arange(n)
        n_act = int(np.sum(ages <= geo.death))
        k_sc = int(np.sum(ages[:n_act] < geo.suction_close))
        k_do = int(np.sum(ages[:n_act] < geo.discharge_open))
        links = leak_links(laws, n_act, geo)
        yield _topology(frame, (index, a, max(a, b), evs), n_act, k_sc, k_do, links)
        index += 1


def leak_links(laws, na: int, geo: ChamberGeometry) -> list[_Link]:
    """The leakage flows of a segment with ``na`` active slots, in flow order."""
    def node(k):  # a slot below 0 is suction's space, one past the last discharge's
        return min(max(k + 1, 0), na + 1)

    links = []
    live = [i for i, law in enumerate(laws) if law.model != "none"]
    for to_chamber, run in itertools.groupby(live, key=lambda i: laws[i].path.to_chamber):
        run = list(run)
        if not to_chamber:  # chamber by chamber, each chamber's plenum paths together
            for k in range(na):
                for i in run:
                    plenum = 0 if laws[i].path.target == "suction" else na + 1
                    links.append(_Link(k + 1, plenum, ((geo.row(laws[i].path.column), k),), i))
            continue
        for i in run:
            path = laws[i].path
            d = abs(path.target)
            rows = [geo.row(c) if c is not None else None for c in (path.column, path.mirror)]
            young, old = rows if path.target > 0 else rows[::-1]
            for j in range(-d, na):  # slot j (younger) to slot j + d (older)
                if j < 0 and j + d >= na:
                    continue
                views = tuple((r, k) for r, k in ((young, j), (old, j + d))
                              if r is not None and 0 <= k < na)
                if views:
                    links.append(_Link(node(j), node(j + d), views, i))
    return links


def _topology(fr: _Frame, span, na, k_sc, k_do, links) -> Segment:
    """Flow paths and their maps into dy/dtheta for one segment (see Segment);
    ``span``: the segment's index, start, end and events."""
    ncol = fr.n_rows * na
    laws = [fr.laws[ln.law] for ln in links]
    ia, ib = [ln.ia for ln in links], [ln.ib for ln in links]
    names = [law.path.name for law in laws]
    rows, cou, link_len = [], [], []
    for f, (ln, law) in enumerate(zip(links, laws, strict=True)):
        lengths = np.zeros(ncol)  # the path's column, its views averaged
        for row, k in ln.views:
            lengths[row * na + k] = 1.0 / len(ln.views)
        r = np.zeros(ncol)
        for row, k in ln.views:
            r[row * na + k] = law.area_factor / len(ln.views)
        rows.append(r)
        if law.couette:
            cou.append(f)
            link_len.append(lengths)
    dis_port, ideal = [], []
    if fr.ports.model == "nozzle":
        for k in range(na):
            for node, row, open_ in ((0, ROW_AREA_LP, k < k_sc),
                                     (na + 1, ROW_AREA_HP, k >= k_do)):
                if open_:
                    r = np.zeros(ncol)
                    r[row * na + k] = fr.ports.coefficient
                    if node == na + 1:
                        dis_port.append(len(ia))
                    ia.append(k + 1)
                    ib.append(node)
                    rows.append(r)
                    names.append("discharge port" if node == na + 1 else "suction port")
    else:
        ideal = list(range(k_sc)) + list(range(k_do, na))
    mm, me, mg = _flow_maps(fr, na, ia, ib, laws)
    is_dis = np.array([k >= k_do for k in ideal], dtype=bool)
    mx, mxe = _ideal_maps(fr, na, ideal, is_dis)
    nf = len(ia)
    groups = _groups(links, fr.laws)
    return Segment(
        *span, na, k_sc, k_do, fr.period * np.arange(na),
        np.array(ia, dtype=np.intp), np.array(ib, dtype=np.intp), len(links), tuple(names),
        groups, np.array(rows).reshape(nf, ncol) if nf else np.zeros((0, ncol)),
        _index(cou), _index([ib[f] for f in cou]), np.array([laws[f].gap_m for f in cou]),
        np.array(link_len).reshape(len(cou), ncol),
        bool(cou) or any(g.drag is not None for g in groups),
        mm, me, mg, np.array(ideal, dtype=np.intp), np.where(is_dis, fr.dis.p, fr.suc.p),
        np.where(is_dis, fr.dis.h, fr.suc.h), is_dis, mx, mxe,
        np.array(dis_port, dtype=np.intp),
        oil.leak_maps(fr, na, ia[:len(links)], ib[:len(links)], laws) if fr.acc.oil_leaks
        else None)


def _node_maps(fr: _Frame, na, node_a, node_b):
    """Rows of dy for a unit mass flow and for a unit enthalpy flow from node_a to node_b
    (arrays of nodes: one row each)."""
    acc0, n, w = fr.nv * fr.n, fr.n, fr.w
    nf = len(node_a)
    rm, re = np.zeros((nf, fr.n_state)), np.zeros((nf, fr.n_state))
    rows = np.arange(nf)
    for nodes, sgn in ((np.asarray(node_a, dtype=np.intp), -1.0),
                       (np.asarray(node_b, dtype=np.intp), 1.0)):
        suc, dis = nodes == 0, nodes == na + 1
        col_m = np.where(suc, acc0 + ACC_M_SUC, np.where(dis, acc0 + ACC_M_DIS, nodes - 1))
        col_e = np.where(suc, acc0 + ACC_H_SUC, np.where(dis, acc0 + ACC_H_DIS, n + nodes - 1))
        wgt = np.where(suc, -sgn * w, sgn * w)  # the suction's sums count what leaves it
        np.add.at(rm, (rows, col_m), wgt)
        np.add.at(re, (rows, col_e), wgt)
    return rm, re


def _flow_maps(fr: _Frame, na, ia, ib, leak_laws):
    """mm, me, mg of Segment: mass, enthalpy and |mass| flows into dy/dtheta."""
    mm, me = _node_maps(fr, na, ia, ib)
    mg = np.zeros_like(mm)
    for f, law in enumerate(leak_laws):  # gross leakage, per report key
        mg[f, fr.nv * fr.n + fr.acc.leak(law.path.report_key)] = fr.w
    return mm, me, mg


def _ideal_maps(fr: _Frame, na, ideal, is_dis):
    """mx, mxe of Segment: the ideal ports' mass and enthalpy flows into dy/dtheta."""
    plen = np.where(is_dis, na + 1, 0).astype(np.intp)
    return _node_maps(fr, na, plen, np.asarray(ideal, dtype=np.intp) + 1)


def _groups(links, laws) -> tuple[FlowGroup, ...]:
    """The leakage flows grouped by the law they flow by (in order of first flow)."""
    keys = {}
    for f, ln in enumerate(links):
        law = laws[ln.law]
        if law.model == "fanno":
            key = ("fanno", law.zeta)
        elif law.model == "cfd-calibrated":
            key = ("cfd-calibrated", id(law.correlation), law.k_factor)
        elif law.model == "rarefied":
            key = ("rarefied", law.path.measure != "length")  # (orifices apart)
        else:
            key = (law.model,)
        keys.setdefault(key, []).append(f)
    groups = []
    for key, fs in keys.items():
        law = laws[links[fs[0]].law]
        if key[0] == "fanno":
            groups.append(FlowGroup("fanno", _index(fs), law.zeta,
                                    flows.fanno_choke_ratio(law.zeta)))
        elif key[0] == "cfd-calibrated":
            drag = [f for f in fs if laws[links[f].law].drag_in_fit]
            groups.append(FlowGroup(
                "cfd-calibrated", _index(fs), correlation=law.correlation,
                k_factor=law.k_factor, drag=_index(drag) if drag else None,
                drag_in_group=_index([fs.index(f) for f in drag]) if drag else None))
        elif key[0] == "rarefied":
            groups.append(FlowGroup("rarefied", _index(fs), rarefied=RarefiedLaw.of_flows(
                [laws[links[f].law] for f in fs], key[1])))
        else:
            groups.append(FlowGroup(key[0], _index(fs)))
    return tuple(groups)


def _index(items) -> slice | np.ndarray:
    """Column selection of ``items``: a slice where they are consecutive (a view, and the
    arithmetic of a plain slice), else an index array."""
    items = list(items)
    if items and items == list(range(items[0], items[0] + len(items))):
        return slice(items[0], items[0] + len(items))
    return np.array(items, dtype=np.intp)
