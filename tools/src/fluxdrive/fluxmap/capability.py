"""Torque and power capability of a flux-map machine vs speed, under the
current limit |i| <= i_max and the voltage limit |v| <= v_margin v_dc /
sqrt(3) with the steady-state voltage v_d = Rs i_d - w lambda_q(i), v_q =
Rs i_q + w lambda_d(i) on the map's bicubic interpolant; the largest
motoring torque over a dense grid of currents in the half disc (the MTPV
limit is where the voltage-limited optimum stops growing with current: it
is found, not imposed). `fluxdrive capability SCENARIO` uses it when the
scenario's machine is a flux map."""

from __future__ import annotations

import numpy as np

from .model import FluxMap


def map_capability(m: FluxMap, rs: float, i_max: float, v_dc: float, v_margin: float,
                   torque_max: float, speeds: np.ndarray, n: int = 241):
    """Per mechanical speed [rad/s]: torque, i_d, i_q and the binding limit."""
    g = np.linspace(0.0, np.pi, n)
    r = np.linspace(0.0, i_max, n // 2)
    R, G = np.meshgrid(r, g, indexing="ij")
    i_d, i_q = (R * np.cos(G)).ravel(), (R * np.sin(G)).ravel()
    inside = (i_d >= m.i_d[0]) & (i_d <= m.i_d[-1]) & (i_q <= m.i_q[-1])
    i_d, i_q = i_d[inside], i_q[inside]
    ld, lq = m.flux_smooth(i_d, i_q)
    t = 1.5 * m.pole_pairs * (ld * i_q - lq * i_d)
    v_max = v_margin * v_dc / np.sqrt(3.0)
    out = []
    for ws in np.asarray(speeds, float):
        w = ws * m.pole_pairs
        v = np.hypot(rs * i_d - w * lq, rs * i_q + w * ld)
        ok = v <= v_max
        if not np.any(ok):
            out.append((0.0, 0.0, 0.0, "voltage"))
            continue
        tt = np.where(ok, np.minimum(t, torque_max), -np.inf)
        k = int(np.argmax(tt - 1e-9 * np.hypot(i_d, i_q)))
        amp = np.hypot(i_d[k], i_q[k])
        lim = ("torque" if t[k] >= torque_max else "current" if amp >= 0.999 * i_max
               else "voltage")
        out.append((float(tt[k]), float(i_d[k]), float(i_q[k]), lim))
    return out
