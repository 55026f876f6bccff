"""Torque and power capability of a flux-map machine vs speed, under the
current limit |i| <= i_max and the voltage limit |v| <= v_max with the
steady-state voltage v_d = Rs i_d - w lambda_q(i), v_q = Rs i_q + w
lambda_d(i) on the map's bicubic interpolant. `fluxdrive capability
SCENARIO` uses it when the scenario's machine is a flux map.

v_max is the drive's: v_margin times the linear range of the duty range it
applies, (d_max - d_min) v_dc / sqrt(3) (firmware/app/drive.c drive_derive,
modulation_v_max: the board's duty_min / duty_max, narrowed by the DFC
window with a star-point position source), see `v_max_of`.

The solve is 1-D along the limits, not over a grid of currents: along each
ray of current angle theta the torque grows with the amplitude, so the best
current on the ray is the largest admissible amplitude r(theta) (the
current limit, the voltage limit found by bisection, or the map's edge);
T(r(theta), theta) is swept densely over theta and its maximum refined by
zooming on it (four passes of 65 rays, each 32x narrower): the optimum is
the current/voltage corner, a point of the voltage limit curve (MTPV) or
the MTPA at i_max. The MTPV is found, not imposed."""

from __future__ import annotations

import numpy as np

from .model import FluxMap

# star-point position sources: gated (POS_CAP_GATED, firmware/app/pos_sources.c)
GATED_SOURCES = ("dfc", "dfc_inv", "ivd", "dfc+kf", "ivd+kf", "ekf", "ivd+kf+rls")


def v_max_of(cfg: dict) -> tuple[float, str]:
    """The drive's voltage limit [V, phase peak] from `fluxdrive-sil
    SCENARIO --print-config`, as drive_derive computes it: the board's duty
    range (narrowed by dfc_window_range for a gated position source), its
    linear range (d_max - d_min) v_dc / sqrt(3), times v_margin; and a line
    saying so."""
    c, b = cfg["controller"], cfg.get("board", {})
    lo, hi = float(b.get("duty_min", 0.0)), float(b.get("duty_max", 1.0))
    how = f"board duty {lo:g} .. {hi:g}"
    if c.get("pos_source") in GATED_SOURCES:
        t0, tw = c["dfc_t0"] / cfg["ts"], c["dfc_tw"] / cfg["ts"]
        lo, hi = max(lo, 0.5 - t0), min(hi, 1.0 - t0 - tw)  # dfc_window_range
        how += f", DFC window -> {lo:.4f} .. {hi:.4f}"
    v = c["v_margin"] * max(hi - lo, 0.0) * cfg["v_dc"] / np.sqrt(3.0)
    return float(v), (f"v_max {v:.2f} V = v_margin {c['v_margin']:g} x ({hi:.4f} - {lo:.4f}) x "
                      f"v_dc {cfg['v_dc']:g} / sqrt(3) ({how})")


def _ray_limit(m: FluxMap, i_max: float, theta: np.ndarray) -> np.ndarray:
    """The largest amplitude on each ray inside both |i| <= i_max and the grid."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.full(theta.shape, float(i_max))
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(c < 0, np.minimum(r, m.i_d[0] / np.where(c < 0, c, -1.0)), r)
        r = np.where(c > 0, np.minimum(r, m.i_d[-1] / np.where(c > 0, c, 1.0)), r)
        r = np.where(s > 0, np.minimum(r, m.i_q[-1] / np.where(s > 0, s, 1.0)), r)
    return np.maximum(r, 0.0)


def _volt(m: FluxMap, rs: float, w: float, i_d, i_q):
    ld, lq = m.flux_smooth(i_d, i_q)
    return np.hypot(rs * i_d - w * lq, rs * i_q + w * ld)


def _best_on_rays(m: FluxMap, rs: float, w: float, v_max: float, i_max: float,
                  theta: np.ndarray, n_r: int = 64, n_bis: int = 36):
    """Per ray: the largest admissible amplitude r (the last admissible of
    n_r samples, then bisection on the voltage limit), its torque (-inf where
    nothing but zero is admissible) and the binding limit (0 current,
    1 voltage, 2 map edge)."""
    theta = np.atleast_1d(np.asarray(theta, float))
    c, s = np.cos(theta), np.sin(theta)
    r_edge = _ray_limit(m, i_max, theta)
    frac = np.linspace(0.0, 1.0, n_r)
    R = r_edge[:, None] * frac[None, :]
    ok = _volt(m, rs, w, R * c[:, None], R * s[:, None]) <= v_max
    any_ok = ok[:, 1:].any(axis=1)
    k = np.where(any_ok, n_r - 1 - np.argmax(ok[:, ::-1], axis=1), 0)  # last admissible sample
    lo = r_edge * frac[k]
    hi = r_edge * frac[np.minimum(k + 1, n_r - 1)]
    full = k == n_r - 1
    for _ in range(n_bis):
        mid = 0.5 * (lo + hi)
        good = _volt(m, rs, w, mid * c, mid * s) <= v_max
        lo, hi = np.where(good, mid, lo), np.where(good, hi, mid)
    r = np.where(full, r_edge, lo)
    t = m.torque_smooth(r * c, r * s)
    t = np.where(any_ok, t, -np.inf)
    which = np.where(~full, 1, np.where(r_edge >= i_max * (1 - 1e-12), 0, 2))
    return r, t, which


def map_capability(m: FluxMap, rs: float, i_max: float, v_dc: float, v_margin: float,
                   torque_max: float, speeds: np.ndarray, n: int = 721,
                   duty: tuple[float, float] = (0.0, 1.0), v_max: float | None = None):
    """Per mechanical speed [rad/s]: torque, i_d, i_q and the binding limit
    ("current", "voltage", "current+voltage" at their corner, "map edge",
    "torque"). The voltage limit is v_max if given, else v_margin (duty[1] -
    duty[0]) v_dc / sqrt(3)."""
    if v_max is None:
        v_max = v_margin * (duty[1] - duty[0]) * v_dc / np.sqrt(3.0)
    th = np.linspace(0.0, np.pi, n)
    names = {0: "current", 1: "voltage", 2: "map edge"}
    out = []
    for ws in np.asarray(speeds, float):
        w = ws * m.pole_pairs
        r, t, which = _best_on_rays(m, rs, w, v_max, i_max, th)
        if not np.any(np.isfinite(t)):
            out.append((0.0, 0.0, 0.0, "voltage"))
            continue
        k = int(np.argmax(t))
        x, rr, tt, wh = th[k:k + 1], r[k:k + 1], t[k:k + 1], which[k:k + 1]
        h = th[1] - th[0]
        for _ in range(4):  # zoom on T(r(theta), theta) around its best: 32x per pass
            sub = np.clip(x[0] + np.linspace(-h, h, 65), 0.0, np.pi)
            r2, t2, w2 = _best_on_rays(m, rs, w, v_max, i_max, sub)
            j = int(np.argmax(t2))
            if t2[j] >= tt[0]:
                x, rr, tt, wh = sub[j:j + 1], r2[j:j + 1], t2[j:j + 1], w2[j:j + 1]
            h /= 32.0
        i_d, i_q = float(rr[0] * np.cos(x[0])), float(rr[0] * np.sin(x[0]))
        lim = names[int(wh[0])]
        if lim == "voltage" and np.hypot(i_d, i_q) >= i_max * (1 - 1e-4):
            lim = "current+voltage"
        elif lim == "current" and _volt(m, rs, w, i_d, i_q) >= v_max * (1 - 1e-4):
            lim = "current+voltage"
        t_best = float(tt[0])
        if t_best > torque_max:
            i_d, i_q = _least_current_for(m, rs, w, v_max, i_max, torque_max, th)
            out.append((float(torque_max), i_d, i_q, "torque"))
            continue
        out.append((t_best, i_d, i_q, lim))
    return out


def _least_current_for(m, rs, w, v_max, i_max, torque, th):
    """The admissible current of the least amplitude giving `torque` (ray by
    ray: bisection on the amplitude below the ray's limit)."""
    r, t, _ = _best_on_rays(m, rs, w, v_max, i_max, th)
    ok = t >= torque
    th, hi = th[ok], r[ok]
    lo = np.zeros_like(hi)
    c, s = np.cos(th), np.sin(th)
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        big = m.torque_smooth(mid * c, mid * s) >= torque
        lo, hi = np.where(big, lo, mid), np.where(big, mid, hi)
    k = int(np.argmin(hi))
    return float(hi[k] * c[k]), float(hi[k] * s[k])
