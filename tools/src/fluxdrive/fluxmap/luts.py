"""The reference tables of Varatharajan et al. 2022 from a map (fluxdrive
frame), computed on the map's bilinear interpolant (the lookups the core
makes, so that table and core agree):

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


def _best_angle(m: FluxMap, a: float) -> tuple[float, float]:
    """Angle theta (i = a (cos, sin), sin >= 0) of the largest torque."""
    th = np.linspace(0.0, np.pi, 721)
    t = m.torque(a * np.cos(th), a * np.sin(th))
    k = int(np.argmax(t))
    lo, hi = th[max(k - 1, 0)], th[min(k + 1, len(th) - 1)]
    g = 0.5 * (np.sqrt(5.0) - 1.0)
    for _ in range(40):
        x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
        if m.torque(a * np.cos(x1), a * np.sin(x1)) > m.torque(a * np.cos(x2), a * np.sin(x2)):
            hi = x2
        else:
            lo = x1
    x = 0.5 * (lo + hi)
    return x, float(m.torque(a * np.cos(x), a * np.sin(x)))


def mtpa_amp_max(m: FluxMap) -> float:
    """The largest amplitude whose half circle i_q >= 0 lies in the grid."""
    return float(min(-m.i_d[0], m.i_d[-1], m.i_q[-1]))


def tables(m: FluxMap, n: int = N_LUT) -> Tables:
    amax = mtpa_amp_max(m)
    amp = np.linspace(0.0, amax, 161)
    ang = np.zeros_like(amp)
    tor = np.zeros_like(amp)
    for k, a in enumerate(amp[1:], 1):
        ang[k], tor[k] = _best_angle(m, a)
    ang[0] = ang[1]
    tor = np.maximum.accumulate(tor)
    ad, aq = amp * np.cos(ang), amp * np.sin(ang)
    t_max = float(tor[-1])
    tt = np.linspace(0.0, t_max, n)
    # the amplitude for each torque (T(A) increasing), then its current
    a_t = np.interp(tt, tor, amp)
    th_t = np.interp(a_t, amp, ang)
    m_id, m_iq = a_t * np.cos(th_t), a_t * np.sin(th_t)
    pd, pq = m.flux(m_id, m_iq)
    m_flux = np.maximum.accumulate(np.hypot(pd, pq))
    # MTPV: largest torque at flux amplitude <= lambda
    D, Q = np.meshgrid(np.linspace(m.i_d[0], m.i_d[-1], 401), np.linspace(0.0, m.i_q[-1], 201))
    fd, fq = m.flux(D, Q)
    lam = np.hypot(fd, fq).ravel()
    tq = (1.5 * m.pole_pairs * (fd * Q - fq * D)).ravel()
    l_max = float(np.hypot(m.psi_d, m.psi_q).max())
    ll = np.linspace(0.0, l_max, n)
    order = np.argsort(lam)
    best = np.maximum.accumulate(np.maximum(tq[order], 0.0))
    idx = np.searchsorted(lam[order], ll, side="right") - 1
    tv = np.where(idx >= 0, best[np.clip(idx, 0, None)], 0.0)
    tv = np.maximum.accumulate(tv)
    return Tables(t_max, m_id, m_iq, m_flux, l_max, tv, amp, ad, aq, tor)


def lambda_max(k_v: float, v_dc: float, omega: float) -> float:
    """Varatharajan (30): the largest stator flux at electrical speed omega."""
    return k_v * v_dc / (np.sqrt(3.0) * abs(omega))
