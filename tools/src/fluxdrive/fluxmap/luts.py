"""The reference tables of Varatharajan et al. 2022 from a map (fluxdrive
frame), computed on the map's bicubic (Catmull-Rom) interpolant
(FluxMap.flux_smooth: an optimum of a bilinear surface sits on cell
edges):

* MTPA (maximum torque per ampere): for each current amplitude A the
  current angle of the largest torque (dense sweep of i_q >= 0, then a
  golden-section refinement), giving T(A) and i(A); tabulated at uniform
  torque from 0 to mtpa_t_max = the MTPA torque at the largest amplitude
  inside the grid: i_d, i_q and the flux amplitude |lambda| ((29): the
  MTPA flux vs torque);
* MTPV: the largest torque at a stator flux amplitude not above lambda,
  over the grid's currents (dense sampling), tabulated at uniform flux from
  0 to mtpv_flux_max = the largest flux amplitude on the grid (f_T of
  (31), without k_T);
* the voltage limit (30) lambda_max = k_v v_dc / (sqrt(3) omega) is a
  formula, not a table.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import FluxMap

N_LUT = 64


@dataclass
class Tables:
    mtpa_t_max: float
    mtpa_id: np.ndarray
    mtpa_iq: np.ndarray
    mtpa_flux: np.ndarray
    mtpv_flux_max: float
    mtpv_torque: np.ndarray
    # the MTPA trajectory by amplitude (plots, checks)
    amp: np.ndarray
    amp_id: np.ndarray
    amp_iq: np.ndarray
    amp_t: np.ndarray
    # the MTPV trajectory (plots): the current of the largest torque at each flux
    mtpv_id: np.ndarray | None = None
    mtpv_iq: np.ndarray | None = None
    # the MTPA at the grid's i_d edge with the torque still rising beyond it:
    # (amplitude, relative slope per rad, edge i_d), else None (validate.check_tables)
    edge: tuple | None = None
    # per MTPV row: True where the largest torque at that flux sits on the
    # grid's edge (the map-edge limit; the true MTPV lies outside the grid)
    mtpv_edge: np.ndarray | None = None


def _best_angles(m: FluxMap, amp: np.ndarray,
                 th_min: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Angle theta (i = a (cos, sin), sin >= 0) of the largest torque at each
    amplitude over theta >= th_min (the angles inside the grid's i_d):
    a dense sweep, then golden-section refinement (vectorised)."""
    if th_min is None:
        th_min = np.zeros_like(amp)
    th = np.linspace(0.0, np.pi, 721)
    A, TH = np.meshgrid(amp, th, indexing="ij")
    t = np.where(TH >= th_min[:, None], m.torque_smooth(A * np.cos(TH), A * np.sin(TH)), -np.inf)
    k = np.argmax(t, axis=1)
    lo = np.maximum(th[np.maximum(k - 1, 0)], th_min)
    hi = np.maximum(th[np.minimum(k + 1, len(th) - 1)], th_min)
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    for _ in range(40):
        x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
        first = (m.torque_smooth(amp * np.cos(x1), amp * np.sin(x1))
                 > m.torque_smooth(amp * np.cos(x2), amp * np.sin(x2)))
        hi = np.where(first, x2, hi)
        lo = np.where(first, lo, x1)
    x = 0.5 * (lo + hi)
    return x, m.torque_smooth(amp * np.cos(x), amp * np.sin(x))


def mtpa_amp_max(m: FluxMap) -> float:
    """The largest amplitude whose quarter circle i_d <= 0, i_q >= 0 lies in
    the grid (the MTPA of a machine with the PM on +d and L_q >= L_d; a
    grid of i_d <= 0 only is enough; 0 when the grid has no i_d <= 0)."""
    return float(max(0.0, min(-m.i_d[0], m.i_q[-1]))) if m.i_d[-1] >= -1e-9 * m.did else 0.0


def _edge(m: FluxMap, amp, ang, th_min, tor):
    """Where the optimum sits on the i_d edge (th_min > 0) with the torque
    still rising beyond it by more than EDGE_SLOPE per rad: the worst
    (amplitude, relative slope, edge i_d), else None."""
    from .validate import EDGE_SLOPE

    h = 1e-3
    on = (th_min > 0) & (ang - th_min < np.pi / 720) & (tor > 0)
    if not np.any(on):
        return None
    a, t0 = amp[on], th_min[on]
    g0 = m.torque_smooth(a * np.cos(t0), a * np.sin(t0))
    g1 = m.torque_smooth(a * np.cos(t0 + h), a * np.sin(t0 + h))
    rise = (g0 - g1) / h / np.maximum(np.abs(g0), 1e-300)  # towards smaller theta (larger i_d)
    k = int(np.argmax(rise))
    return (float(a[k]), float(rise[k]), float(m.i_d[-1])) if rise[k] > EDGE_SLOPE else None


def tables(m: FluxMap, n: int = N_LUT) -> Tables:
    key = ("tables", n)
    if key not in m.cache:
        m.cache[key] = _tables(m, n)
    return m.cache[key]


def _tables(m: FluxMap, n: int) -> Tables:
    amax = mtpa_amp_max(m)
    amp = np.linspace(0.0, amax, 161)
    with np.errstate(divide="ignore", invalid="ignore"):
        th_min = np.arccos(np.clip(np.where(amp > 0, m.i_d[-1] / amp, 1.0), -1.0, 1.0))
    ang, tor = _best_angles(m, amp, th_min)
    ang[0], tor[0] = ang[1], 0.0
    edge = _edge(m, amp, ang, th_min, tor)
    tor = np.maximum.accumulate(tor)
    ad, aq = amp * np.cos(ang), amp * np.sin(ang)
    t_max = float(tor[-1])
    tt = np.linspace(0.0, t_max, n)
    # the amplitude for each torque (T(A) increasing), then its current
    a_t = np.interp(tt, tor, amp)
    th_t = np.interp(a_t, amp, ang)
    m_id, m_iq = a_t * np.cos(th_t), a_t * np.sin(th_t)
    pd, pq = m.flux_smooth(m_id, m_iq)
    m_flux = np.maximum.accumulate(np.hypot(pd, pq))
    # MTPV: the largest torque over the load angle at each flux amplitude
    # (currents by Newton on the interpolant, inside the grid only), then
    # the largest at flux <= lambda (monotone)
    l_max = float(np.hypot(m.psi_d, m.psi_q).max())
    ll = np.linspace(0.0, l_max, n)
    delta = np.linspace(0.0, np.pi, 361)
    L, Dl = np.meshgrid(ll, delta, indexing="ij")
    ld, lq = L * np.cos(Dl), L * np.sin(Dl)
    i_d, i_q = current_smooth(m, ld, lq)
    inside = ((i_d >= m.i_d[0]) & (i_d <= m.i_d[-1]) & (i_q >= 0.0) & (i_q <= m.i_q[-1])
              & np.isfinite(i_d) & np.isfinite(i_q))
    tq = np.where(inside, 1.5 * m.pole_pairs * (ld * i_q - lq * i_d), 0.0)
    t_row, v_id, v_iq, v_edge = _refine_mtpv(m, ll, delta, tq, inside, i_d, i_q)
    tv = np.maximum.accumulate(np.maximum(t_row, 0.0))
    return Tables(t_max, m_id, m_iq, m_flux, l_max, tv, amp, ad, aq, tor, v_id, v_iq, edge,
                  v_edge)


def _inside(m: FluxMap, i_d, i_q):
    return ((i_d >= m.i_d[0]) & (i_d <= m.i_d[-1]) & (i_q >= 0.0) & (i_q <= m.i_q[-1])
            & np.isfinite(i_d) & np.isfinite(i_q))


def _refine_mtpv(m: FluxMap, ll, delta, tq, inside, i_d, i_q):
    """The MTPV rows refined from the load-angle samples: where a neighbour
    of the best sample lies outside the grid, the grid's edge along the load
    angle by bisection; then golden section on the torque over the bracket
    (clipped to the edge). A row whose optimum is that edge is the map-edge
    limit, not the MTPV (the torque still grows beyond the grid): flagged.
    Returns the torque, i_d, i_q and the flag per row."""
    n, nd = tq.shape
    rows = np.arange(n)
    b = tq.argmax(axis=1)
    t0 = tq[rows, b]
    g_d, g_q = np.nan_to_num(i_d[rows, b]), np.nan_to_num(i_q[rows, b])
    ok_row = (t0 > 0) & inside[rows, b]
    l2, gd2, gq2 = np.tile(ll, 2), np.tile(g_d, 2), np.tile(g_q, 2)

    def at(dl, lam=ll, gd=g_d, gq=g_q):
        """Currents and torque at load angle dl on each row's flux circle;
        -inf outside the grid (Newton warm-started at gd, gq)."""
        fd, fq = lam * np.cos(dl), lam * np.sin(dl)
        cd, cq = current_smooth(m, fd, fq, iters=4, guess=(gd, gq))
        t = np.where(_inside(m, cd, cq), 1.5 * m.pole_pairs * (fd * cq - fq * cd), -np.inf)
        return t, cd, cq

    # the bracket's ends: the neighbour sample, or the grid's edge by bisection
    j = np.concatenate([b - 1, b + 1])
    inb = (j >= 0) & (j < nd)
    jc = np.clip(j, 0, nd - 1)
    out = ~inb | ~inside[np.tile(rows, 2), jc]
    step = np.concatenate([-np.ones(n), np.ones(n)]) * (delta[1] - delta[0])
    lo = np.tile(delta[b], 2)
    hi = np.clip(np.where(inb, delta[jc], lo + step), 0.0, np.pi)
    for _ in range(24):  # lo inside, hi outside
        mid = 0.5 * (lo + hi)
        good = np.isfinite(at(mid, l2, gd2, gq2)[0])
        lo, hi = np.where(good, mid, lo), np.where(good, hi, mid)
    e = np.where(out, lo, hi)
    a, c, a_edge, c_edge = e[:n], e[n:], out[:n], out[n:]
    ends = [(a.copy(), a_edge), (c.copy(), c_edge)]
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    for _ in range(30):
        x1, x2 = c - g * (c - a), a + g * (c - a)
        f = at(np.concatenate([x1, x2]), l2, gd2, gq2)[0]
        first = f[:n] > f[n:]
        c, a = np.where(first, x2, c), np.where(first, a, x1)
    tol = 1e-6
    for e, flag in ends:  # the edge itself if it is better (the torque rising to it)
        te = at(e)[0]
        x = 0.5 * (a + c)
        tx = at(x)[0]
        use = flag & (te >= tx)
        a, c = np.where(use, e, a), np.where(use, e, c)
    x = 0.5 * (a + c)
    t, cd, cq = at(x)
    better = ok_row & np.isfinite(t) & (t >= t0)
    t = np.where(better, t, np.where(ok_row, t0, tq.max(axis=1)))
    cd, cq = np.where(better, cd, g_d), np.where(better, cq, g_q)
    on_edge = better & ((a_edge & (np.abs(x - ends[0][0]) < tol))
                        | (c_edge & (np.abs(x - ends[1][0]) < tol)))
    on_edge |= ok_row & ~better & (a_edge | c_edge)
    return t, cd, cq, on_edge


def edge_ranges(t: Tables) -> list[tuple[float, float]]:
    """The flux ranges [Vs] where the MTPV table is the map-edge limit."""
    if t.mtpv_edge is None or not np.any(t.mtpv_edge):
        return []
    ll = np.linspace(0.0, t.mtpv_flux_max, len(t.mtpv_torque))
    out, start = [], None
    for k, e in enumerate(t.mtpv_edge):
        if e and start is None:
            start = k
        if start is not None and (not e or k == len(ll) - 1):
            out.append((float(ll[start]), float(ll[k if e else k - 1])))
            start = None
    return out


def mtpv_label(t: Tables) -> str:
    """Which the MTPV table is: the MTPV, or where the map's edge limits it."""
    r = edge_ranges(t)
    if not r:
        return "the MTPV inside the grid at every flux"
    return ("the map-edge limit (the true MTPV lies outside the grid) at flux "
            + ", ".join(f"{a:.3f} .. {b:.3f} Vs" for a, b in r) + "; the MTPV elsewhere")


def current_smooth(m: FluxMap, ld, lq, iters: int = 16, guess=None):
    """i(lambda) on the bicubic interpolant: Newton from the zero-current
    linearisation (or from guess = (i_d, i_q)), Jacobian by central
    differences (vectorised)."""
    h = 1e-4 * max(m.did, m.diq)
    if guess is None:
        l0 = m.inductance(0.0, 0.0)
        f0 = m.flux_smooth(0.0, 0.0)
        det0 = l0[0] * l0[3] - l0[1] * l0[2]
        rd, rq = ld - f0[0], lq - f0[1]
        i_d = (l0[3] * rd - l0[1] * rq) / det0
        i_q = (l0[0] * rq - l0[2] * rd) / det0
    else:
        i_d, i_q = (np.array(np.broadcast_to(x, np.shape(ld)), float) for x in guess)
    for _ in range(iters):
        i_d = np.clip(i_d, 2 * m.i_d[0], 2 * m.i_d[-1])
        i_q = np.clip(i_q, 2 * m.i_q[0], 2 * m.i_q[-1])
        fd, fq = m.flux_smooth(i_d, i_q)
        a = m.flux_smooth(i_d + h, i_q)
        b = m.flux_smooth(i_d - h, i_q)
        c = m.flux_smooth(i_d, i_q + h)
        e = m.flux_smooth(i_d, i_q - h)
        jdd, jqd = (a[0] - b[0]) / (2 * h), (a[1] - b[1]) / (2 * h)
        jdq, jqq = (c[0] - e[0]) / (2 * h), (c[1] - e[1]) / (2 * h)
        det = jdd * jqq - jdq * jqd
        rd, rq = ld - fd, lq - fq
        with np.errstate(divide="ignore", invalid="ignore"):
            i_d = i_d + (jqq * rd - jdq * rq) / det
            i_q = i_q + (jdd * rq - jqd * rd) / det
        i_d = np.where(np.isfinite(i_d), i_d, 0.0)  # a singular step: start again from 0
        i_q = np.where(np.isfinite(i_q), i_q, 0.0)
    fd, fq = m.flux_smooth(i_d, i_q)
    bad = np.hypot(fd - ld, fq - lq) > 1e-6 * (1.0 + np.hypot(ld, lq))
    return np.where(bad, np.nan, i_d), np.where(bad, np.nan, i_q)


def lambda_max(k_v: float, v_dc: float, omega: float) -> float:
    """Varatharajan (30): the largest stator flux at electrical speed omega."""
    return k_v * v_dc / (np.sqrt(3.0) * abs(omega))
