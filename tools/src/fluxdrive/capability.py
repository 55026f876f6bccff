"""Offline torque capability of a PM synchronous machine from its model.

For each speed, the largest steady-state motoring torque the drive may give
under three limits (Rubino 2020, section III.D-E):

* current: |i_dq| <= i_max;
* voltage: |v_dq| <= v_margin * v_dc / sqrt(3), with the steady-state
  voltage v_d = Rs i_d - w Lq i_q, v_q = Rs i_q + w (Ld i_d + lambda_m);
* load angle: the stator flux may lead the d axis by at most delta_max,
  delta = atan2(Lq i_q, Ld i_d + lambda_m) (MTPV, eq. 26).

The search runs over i_d on a fine grid; for each i_d the largest i_q that
meets all three follows in closed form (the voltage limit is a quadratic in
i_q). Torque T = 3/2 p (lambda_m i_q + (Ld - Lq) i_d i_q).
"""

from __future__ import annotations

from dataclasses import dataclass
import json
import subprocess

import numpy as np


@dataclass(frozen=True)
class Machine:
    pole_pairs: int
    rs: float
    ld: float
    lq: float
    lambda_m: float


@dataclass(frozen=True)
class Limits:
    i_max: float
    v_dc: float
    v_margin: float
    delta_max: float
    torque_max: float


@dataclass
class Capability:
    speed: np.ndarray  # mechanical [rad/s]
    torque: np.ndarray  # [N m]
    i_d: np.ndarray
    i_q: np.ndarray
    limit: list[str]  # the binding limit at each speed

    @property
    def power(self) -> np.ndarray:
        return self.torque * self.speed


def from_config(cfg: dict) -> tuple[Machine, Limits]:
    """Machine and limits from `fluxdrive-sil SCENARIO --print-config`."""
    m, c = cfg["machine"], cfg["controller"]
    machine = Machine(int(m["pole_pairs"]), m["rs"], m["ld"], m["lq"], m["lambda_m"])
    limits = Limits(c["i_max"], cfg["v_dc"], c["v_margin"], c["delta_max"], c["torque_max"])
    return machine, limits


def load_config(sil: str, scenario: str) -> dict:
    out = subprocess.run([sil, scenario, "--print-config"], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def _iq_max(m: Machine, lim: Limits, w: float, i_d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Largest i_q >= 0 per i_d, and which limit binds (0 current, 1 voltage,
    2 load angle, 3 torque); NaN where no i_q >= 0 is feasible."""
    v_max = lim.v_margin * lim.v_dc / np.sqrt(3.0)
    iq_cur = np.sqrt(np.maximum(lim.i_max**2 - i_d**2, 0.0))
    lam_d = m.ld * i_d + m.lambda_m
    # |v|^2 <= v_max^2 as a i_q^2 + b i_q + c <= 0
    a = (w * m.lq) ** 2 + m.rs**2
    b = -2.0 * m.rs * i_d * w * m.lq + 2.0 * m.rs * w * lam_d
    c = (m.rs * i_d) ** 2 + (w * lam_d) ** 2 - v_max**2
    disc = b * b - 4.0 * a * c
    iq_volt = np.where(disc >= 0.0, (-b + np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a), np.nan)
    iq_volt = np.where(iq_volt >= 0.0, iq_volt, np.nan)
    # the low root must admit i_q >= 0 too: c <= 0 (i_q = 0 feasible) or low root >= 0
    low = np.where(disc >= 0.0, (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a), np.nan)
    iq_volt = np.where((c <= 0.0) | (low <= iq_volt), iq_volt, np.nan)
    iq_delta = np.where(lam_d > 0.0, np.tan(lim.delta_max) * lam_d / m.lq, np.nan)
    # torque limit: T = 3/2 p i_q (lambda_m + (Ld - Lq) i_d)
    k = 1.5 * m.pole_pairs * (m.lambda_m + (m.ld - m.lq) * i_d)
    iq_torque = np.where(k > 0.0, lim.torque_max / np.where(k > 0.0, k, 1.0), np.inf)
    stack = np.vstack([iq_cur, iq_volt, iq_delta, iq_torque])
    iq = np.min(np.where(np.isnan(stack), -np.inf, stack), axis=0)
    iq = np.where(np.any(np.isnan(stack[:3]), axis=0), np.nan, iq)
    which = np.argmin(np.where(np.isnan(stack), np.inf, stack), axis=0)
    return iq, which


def capability(m: Machine, lim: Limits, speeds: np.ndarray, n_id: int = 4001) -> Capability:
    names = ["current", "voltage", "load angle", "torque"]
    i_d = np.linspace(-lim.i_max, 0.0, n_id)
    out_t, out_id, out_iq, out_lim = [], [], [], []
    for ws in np.asarray(speeds, dtype=float):
        w = ws * m.pole_pairs
        iq, which = _iq_max(m, lim, w, i_d)
        t = 1.5 * m.pole_pairs * (m.lambda_m + (m.ld - m.lq) * i_d) * iq
        t = np.where(np.isfinite(t), t, -np.inf)
        # among equal torques (torque-limited plateau) prefer the least current
        best = int(np.argmax(t - 1e-9 * np.abs(i_d)))
        if not np.isfinite(t[best]):
            out_t.append(0.0), out_id.append(0.0), out_iq.append(0.0), out_lim.append("none")
            continue
        out_t.append(float(t[best]))
        out_id.append(float(i_d[best]))
        out_iq.append(float(iq[best]))
        out_lim.append(names[int(which[best])])
    return Capability(np.asarray(speeds, float), np.array(out_t), np.array(out_id),
                      np.array(out_iq), out_lim)


def corner_speeds(cap: Capability, m: Machine, lim: Limits) -> dict:
    """Base speed (the voltage limit first binds at the optimum) and MTPV
    entry (the load angle first reaches delta_max), mechanical rad/s; NaN
    when never reached."""
    w = cap.speed * m.pole_pairs
    lam_d = m.ld * cap.i_d + m.lambda_m
    lam_q = m.lq * cap.i_q
    v = np.hypot(m.rs * cap.i_d - w * lam_q, m.rs * cap.i_q + w * lam_d)
    v_max = lim.v_margin * lim.v_dc / np.sqrt(3.0)
    delta = np.arctan2(lam_q, lam_d)

    def first(mask: np.ndarray) -> float:
        idx = np.flatnonzero(mask)
        return float(cap.speed[idx[0]]) if idx.size else float("nan")

    return {"base_speed": first(v >= v_max * (1.0 - 1e-3)),
            "mtpv_speed": first(delta >= lim.delta_max - np.radians(0.1))}


def _map_table(cfg: dict, rpm: np.ndarray) -> int:
    """The capability of a flux-map machine (fluxmap/capability.py)."""
    from argparse import Namespace

    from .fluxmap.cli import _load
    from .fluxmap.capability import map_capability, v_max_of

    m, c = cfg["machine"], cfg["controller"]
    fm = _load(Namespace(i_max=c["i_max"]), m["map"])  # the map's current unit against i_max
    v_max, how = v_max_of(cfg)  # the drive's voltage limit: v_margin and the board's duty range
    rows = map_capability(fm, m["rs"], c["i_max"], cfg["v_dc"], c["v_margin"], c["torque_max"],
                          rpm * np.pi / 30.0, v_max=v_max)
    print(f"flux map {m['map']} ({fm.pole_pairs} pole pairs), i_max {c['i_max']:.3f} A, "
          f"v_dc {cfg['v_dc']:g} V, v_margin {c['v_margin']:g}")
    print(how)
    print(f"{'speed rpm':>10} {'torque N m':>11} {'power W':>9} {'i_d A':>7} {'i_q A':>7}  limit")
    for r, (t, d, q, l) in zip(rpm, rows):
        print(f"{r:10.0f} {t:11.3f} {t * r * np.pi / 30:9.1f} {d:7.3f} {q:7.3f}  {l}")
    return 0


def main_capability(args) -> int:
    """`fluxdrive capability SCENARIO`: print the capability table."""
    from .sil import locate_sil

    cfg = load_config(str(locate_sil(args.sil)), args.scenario)
    rpm = np.linspace(args.min_rpm, args.max_rpm, args.points)
    if cfg["machine"].get("kind") == "flux_map":
        return _map_table(cfg, rpm)
    m, lim = from_config(cfg)
    cap = capability(m, lim, rpm * np.pi / 30.0)
    print(f"{'speed rpm':>10} {'torque N m':>11} {'power W':>9} {'i_d A':>7} {'i_q A':>7}  limit")
    for r, t, p, d, q, l in zip(rpm, cap.torque, cap.power, cap.i_d, cap.i_q, cap.limit):
        print(f"{r:10.0f} {t:11.3f} {p:9.1f} {d:7.3f} {q:7.3f}  {l}")
    c = corner_speeds(cap, m, lim)
    print(f"base speed {c['base_speed'] * 30 / np.pi:.0f} rpm, "
          f"MTPV entry {c['mtpv_speed'] * 30 / np.pi:.0f} rpm")
    return 0
