"""Fabbri 2022, chapters 4-5.1: the Kalman filter, the EKF and the RLS on the
star-point position, reproduced in SIL (`fluxdrive fabbri2022` writes these
tables beside chapter 3's; tests/python/test_fabbri2022_kf.py asserts them).

Experiments (scenario base sil/scenarios/fabbri_speed.json, Table 5.1 motor):
  noise       the star channel's noise set so that the raw position error of
              the IVD has half the spread of the DFC's at 100 rpm (section
              5.1.3: "the standard deviation of the position error [is]
              halved"): a grid of noise levels, interpolated
  table 5.2   speed control at 100 and 500 rpm, the speed error (reference
              - estimate) of encoder, DFC, DFC+KF, IVD, IVD+KF, EKF, with
              R_k = sigma_v^2 and 5 sigma_v^2
  rls         Figs. 5.11-5.12: a, b started 30 % off, 500 rpm, two RLS
              bandwidths (the covariance floor rls_p_min)
  load        Figs. 4.1 / 5.13: a brake step of 0.1 N m at 500 rpm (DFC+KF
              and IVD+KF) and a sinusoidal load at 10 Hz
  ebike       section 5.2: the chain on the Table 5.4 motor
  laws        the decoupled DFVC and DB-DFVC on the IVD+KF position
"""

from __future__ import annotations

from dataclasses import dataclass
import functools
import json
from pathlib import Path

import numpy as np

from .fabbri2022 import RPM, wrap
from .paper_report import run, stacked_axes


@dataclass(frozen=True)
class PaperKF:
    """What the thesis and the issue state."""

    # Table 5.2: speed-error standard deviation (the table prints no unit;
    # rpm assumed), R_k = sigma^2 / 5 sigma^2
    table52_sd: tuple = (
        (100.0, {"encoder": 4.89, "dfc": 24.46, "dfc+kf": (29.54, 32.01), "ivd": 8.35,
                 "ivd+kf": (10.14, 13.91), "ekf": (7.1877, 8.33)}),
        (500.0, {"encoder": 7.1, "dfc": 102.11, "dfc+kf": (31.45, 19.66), "ivd": 35.39,
                 "ivd+kf": (16.25, 12.9), "ekf": (29.05, 22.4)}),
    )
    r_scales: tuple = (1.0, 5.0)
    # the issue: IVD+KF sD at most half of DFC+KF's at both speeds
    headline_ratio: float = 0.5
    # 5.1.3: the IVD halves the position error's spread (the calibration)
    pos_ratio: float = 0.5
    # the issue: RLS from 30 % off, within 5 % in under 1 s at 500 rpm
    rls_off: float = 0.30
    rls_tol: float = 0.05
    rls_time: float = 1.0
    rls_rpm: float = 500.0
    # Fig. 5.13: a brake of 0.1 N m at 500 rpm; Fig. 4.1 (the issue): 1 N m
    # at 10 Hz, scaled to this motor's rating (0.3 N m): 0.1 N m
    brake: float = 0.1
    sine_amp: float = 0.1
    sine_hz: float = 10.0


PAPER_KF = PaperKF()
V_DC = 24.0  # the Table 5.1 motor's link [V]
SOURCES = ("encoder", "dfc", "dfc+kf", "ivd", "ivd+kf", "ekf")
KALMAN = ("dfc+kf", "ivd+kf", "ekf")
SETTLED = 0.8  # s: the speed ramp ends by 0.5 s
NOISE_GRID = (0.01, 0.02, 0.03, 0.04, 0.05, 0.06)


def sigma_of(noise: float) -> float:
    """sigma_v of each alpha-beta DFC signal (Gamma / v_dc) for a star channel
    of noise `noise` [V]: a component is the difference of two samples
    (sqrt 2), the amplitude-invariant Clarke transform keeps 2/3 of the
    variance."""
    return float(np.sqrt(2.0 * 2.0 / 3.0) * noise / V_DC)


def speed_sc(root: Path, source: str, rpm: float, noise: float, r_scale: float = 1.0,
             enc_align: bool = False, seed: int | None = None) -> dict:
    sc = json.loads((root / "sil" / "scenarios" / "fabbri_speed.json").read_text())
    sc["name"] = f"{source} at {rpm:g} rpm, R x{r_scale:g}"
    sc["description"] = (f"FOC speed control 0 -> {rpm:g} rpm of the Table 5.1 motor on the "
                         f"{source} position, star noise {noise:.4g} V, R_k x{r_scale:g} "
                         "(fluxdrive fabbri2022, chapter 4)")
    sc["sensors"]["star_noise"] = noise
    if seed is not None:
        sc["sensors"]["seed"] = seed
    # R_k as the thesis's (4.29)/(4.30) alone (kf_r_sys 0): the chapter-4
    # figures are the thesis's filter; the drive's default adds the method's
    # own angle error (docs/dfc.md, "Covariances")
    sc["controller"].update({"pos_source": source, "dfc_sigma": sigma_of(noise),
                             "kf_r_scale": r_scale, "kf_r_sys": 0.0})
    if source == "encoder" and not enc_align:
        # the plant's encoder offset is known: the table's encoder rows as
        # the thesis's (the alignment, damped and waiting for the rotor to
        # settle, is measured on its own: enc_aligned)
        sc["controller"]["align_time"] = 0.0
    sc["references"]["speed"]["terms"][0]["value"] = rpm
    return sc


@dataclass
class SpeedRun:
    source: str
    rpm: float
    r_scale: float
    faults: list
    mean: float  # speed reference - estimate [rpm]
    sd: float
    pos_mean: float  # angle - plant's angle, mean [deg electrical]
    pos_sd: float  # its std
    speed_align_end: float  # the rotor's speed when the alignment ends [rpm]
    t: np.ndarray
    speed_est: np.ndarray  # [rpm]


def speed_run(sil, root, out, source, rpm, noise, r_scale=1.0, tag="",
              enc_align: bool = False, seed: int | None = None) -> SpeedRun:
    r = run(sil, speed_sc(root, source, rpm, noise, r_scale, enc_align, seed), out,
            f"kf_{source}_{rpm:g}_{r_scale:g}{tag}")
    lg = r.log
    m = lg["t"] >= SETTLED
    e = (lg["speed_ref"][m] - lg["speed_est"][m]) / RPM
    th = np.degrees(wrap(lg["theta_e_est"][m] - lg["theta_e"][m]))
    # the state leaves the alignment (4) for the run (2): the rotor's speed then
    st = lg["state"]
    k = np.nonzero((st[:-1] == 4) & (st[1:] == 2))[0]
    w_end = float(lg["speed"][k[0] + 1] / RPM) if len(k) else float("nan")
    return SpeedRun(source, rpm, r_scale, r.summary.get("faults_seen", []), float(np.mean(e)),
                    float(np.std(e)), float(np.mean(th)), float(np.std(th)), w_end, lg["t"],
                    lg["speed_est"] / RPM)


def calibrate(sil, root, out) -> tuple[float, list]:
    """The star noise [V] at which the IVD's raw position spread is half the
    DFC's at 100 rpm; and the grid [(noise, dfc sd, ivd sd)]."""
    grid = []
    for n in NOISE_GRID:
        d = speed_run(sil, root, out, "dfc", 100.0, n, tag=f"_cal{n:g}").pos_sd
        i = speed_run(sil, root, out, "ivd", 100.0, n, tag=f"_cal{n:g}").pos_sd
        grid.append((n, d, i))
    ratio = np.array([i / d for _, d, i in grid])
    if not (ratio[0] < PAPER_KF.pos_ratio < ratio[-1]):
        raise RuntimeError(f"calibration: ratio {ratio} does not bracket {PAPER_KF.pos_ratio}")
    return float(np.interp(PAPER_KF.pos_ratio, ratio, NOISE_GRID)), grid


# Issue 23, point 7: the Table 5.2 headline (IVD+KF sD <= 1/2 DFC+KF's) over
# the star channel's noise, beside the calibrated level (the assumption the
# table rests on: the thesis prints no noise). The doc's sweep: `fluxdrive
# fabbri2022 --noise-sweep`; CI runs SWEEP_CI.
SWEEP_NOISE = (0.005, 0.02, 0.0368, 0.045, 0.06, 0.1)  # 0 V: R_k = 0 is refused (dfc_sigma)
SWEEP_SEEDS = (1, 2, 3)
SWEEP_RPM = (100.0, 500.0)
SWEEP_CI = (0.0368, 0.06)  # [V]: within the band, and beyond it


@dataclass
class SweepRow:
    noise: float  # [V]
    rpm: float
    r_scale: float
    seed: int
    dfc_kf: float  # speed error sD [rpm]
    ivd_kf: float
    faults: list

    @property
    def ratio(self) -> float:
        return self.ivd_kf / self.dfc_kf


def noise_sweep(sil, root, out, noises=SWEEP_NOISE, seeds=SWEEP_SEEDS, rpms=SWEEP_RPM,
                r_scales=PAPER_KF.r_scales) -> list[SweepRow]:
    """IVD+KF / DFC+KF speed-error sD per noise level, speed, R_k and noise
    seed (the filters' R_k = r_scale sigma_v^2 follows each level)."""
    rows = []
    for n in noises:
        for rpm in rpms:
            for rs in r_scales:
                for sd in seeds:
                    d, i = (speed_run(sil, root, out, s, rpm, n, rs, tag=f"_sw{n:g}_{sd}",
                                      seed=sd) for s in ("dfc+kf", "ivd+kf"))
                    fl = sorted(set(d.faults + i.faults))
                    rows.append(SweepRow(n, rpm, rs, sd, d.sd, i.sd, fl))
    return rows


def sweep_report(rows: list[SweepRow], cal: float | None = None) -> str:
    """Markdown: one line per noise level and speed, the ratio per R_k as
    max over the seeds (and each seed's)."""
    rss = sorted({r.r_scale for r in rows})
    L = ["| star noise [V] | speed | " + " | ".join(
        f"IVD+KF / DFC+KF, R = {rs:g} sigma^2: worst (each seed)" for rs in rss)
         + " | DFC+KF sD [rpm] (over R_k, seeds) | IVD+KF sD [rpm] (same) | faults |",
         "|---|---|" + "---|" * len(rss) + "---|---|---|"]
    for n in sorted({r.noise for r in rows}):
        for rpm in sorted({r.rpm for r in rows}):
            cells = []
            sel = [r for r in rows if r.noise == n and r.rpm == rpm]
            for rs in rss:
                q = [r.ratio for r in sel if r.r_scale == rs]
                cells.append(f"{max(q):.2f} ({', '.join(f'{x:.2f}' for x in q)})")
            tag = f"{n:g}" + (" (calibrated)" if cal is not None and abs(n - cal) < 5e-4 else "")
            fl = sorted({f for r in sel for f in r.faults})
            L.append(f"| {tag} | {rpm:g} rpm | " + " | ".join(cells) + " | "
                     + f"{min(r.dfc_kf for r in sel):.2f}..{max(r.dfc_kf for r in sel):.2f} | "
                     + f"{min(r.ivd_kf for r in sel):.2f}..{max(r.ivd_kf for r in sel):.2f} | "
                     + (", ".join(fl) or "none") + " |")
    return "\n".join(L)


@dataclass
class RlsRun:
    label: str
    p_min: float
    faults: list
    t: np.ndarray
    a: np.ndarray
    b: np.ndarray
    a_true: float  # (3.7) of the preset
    b_true: float
    t_in: float  # last instant either estimate is outside the 5 % band [s after the step]
    ls_a: float  # the signals' own a, b: least squares of the logged signals on the
    ls_b: float  # plant's true angle (the plain Clarke vector, from 1 s)
    a_mean: float  # the estimates' means from 1 s
    b_mean: float
    a_sd: float  # after settling, relative
    b_sd: float
    speed_mean: float
    speed_sd: float


RLS_STEP = 0.15  # s: the speed step of fabbri_speed.json
POLE_PAIRS_T51 = 8


def signals_ab(lg, m) -> tuple[float, float]:
    """a, b of (3.6) fitted by least squares to the logged signals (the
    plain Clarke vector of dfc_ga..gc) at the plant's true angle at their
    instant: what the signals themselves carry."""
    g = np.stack([lg["dfc_ga"][m], lg["dfc_gb"][m], lg["dfc_gc"][m]])
    al = (2 * g[0] - g[1] - g[2]) / 3.0
    be = (g[1] - g[2]) / np.sqrt(3.0)
    th = lg["theta_e"][m] + POLE_PAIRS_T51 * lg["speed"][m] * lg["dfc_t"][m]
    h = np.zeros((2 * len(al), 2))
    h[:len(al), 0], h[:len(al), 1] = -np.cos(2 * th), np.cos(4 * th)
    h[len(al):, 0], h[len(al):, 1] = np.sin(2 * th), np.sin(4 * th)
    x = np.linalg.lstsq(h, np.concatenate([al, be]), rcond=None)[0]
    return float(x[0]), float(x[1])
RLS_CASES = (("slow, smooth", 1e-10), ("fast, noisy", 3e-9))


def rls_run(sil, root, out, noise: float, label: str, p_min: float) -> RlsRun:
    a0, p = 0.05, -0.0932  # the preset fabbri2022_t51 (docs/dfc.md)
    b0 = p * a0
    sc = speed_sc(root, "ivd+kf+rls", PAPER_KF.rls_rpm, noise)
    sc["duration"] = 1.6
    sc["controller"].update({"dfc_a": a0 * (1 + PAPER_KF.rls_off),
                             "dfc_b": b0 * (1 - PAPER_KF.rls_off), "rls_p_min": p_min})
    r = run(sil, sc, out, f"kf_rls_{p_min:g}")
    lg = r.log
    t, a, b = lg["t"], lg["rls_a"], lg["rls_b"]
    bad = (np.abs(a / a0 - 1) > PAPER_KF.rls_tol) | (np.abs(b / b0 - 1) > PAPER_KF.rls_tol)
    t_in = float(t[np.nonzero(bad)[0][-1]] - RLS_STEP) if bad.any() else 0.0
    m = t >= 1.0
    sp = lg["speed"][m] / RPM
    ls_a, ls_b = signals_ab(lg, m)
    return RlsRun(label, p_min, r.summary.get("faults_seen", []), t, a, b, a0, b0, t_in, ls_a, ls_b,
                  float(np.mean(a[m])), float(np.mean(b[m])),
                  float(np.std(a[m]) / a0), float(np.std(b[m]) / abs(b0)), float(np.mean(sp)),
                  float(np.std(sp)))


@dataclass
class LoadRun:
    label: str
    source: str
    faults: list
    t: np.ndarray
    load: np.ndarray  # plant [N m]
    est: np.ndarray
    err_mean: float  # estimate - load, settled [N m]
    err_sd: float
    lag: float  # step: 90 % rise time of the 5 ms mean [s]; sine: delay at 10 Hz [s]
    gain: float  # sine: amplitude ratio; step: settled estimate / brake
    pred_lag: float  # the same from the filter's own model (kf_load_response)
    pred_gain: float


# The filter's model of the Table 5.1 motor (the preset: sil/runner/presets.c)
KF_MODEL = {"ts": 6.25e-5, "pole_pairs": 8.0, "inertia": 2e-4, "friction": 1e-5, "a": 0.05}


def kf_load_response(noise: float, q_load: float, kind: str,
                     q_omega: float = 1.0, r_scale: float = 1.0) -> tuple[float, float]:
    """What the steady-state Kalman filter (4.46)-(4.49) of the IVD sources
    makes of a load it does not know, from its own equations and the
    run's tuning (R_k = r_scale sigma_v^2 / (4 a^2), (4.30)): the estimation
    error e+(k+1) = (I - K H) F e+(k) + (I - K H) e_3 dT_l(k), so
    T_l_hat / T_l = 1 - (z - 1) [(zI - A)^-1 B]_3. kind "sine": (delay [s],
    gain) at PAPER_KF.sine_hz; "step": (90 % rise time [s], 1)."""
    m = KF_MODEL
    t = m["ts"]
    f = np.array([[1.0 - t * m["friction"] / m["inertia"], 0.0, -t * m["pole_pairs"] / m["inertia"]],
                  [t, 1.0, 0.0], [0.0, 0.0, 1.0]])
    h = np.array([[0.0, 1.0, 0.0]])
    q = np.diag([q_omega, 0.0, q_load])
    r = r_scale * sigma_of(noise) ** 2 / (4.0 * m["a"] ** 2)
    p = np.diag([900.0, 0.09, 0.09])
    for _ in range(200000):  # the Riccati recursion to its fixed point
        pm = f @ p @ f.T + q
        k = pm @ h.T / (h @ pm @ h.T + r)
        p_new = (np.eye(3) - k @ h) @ pm
        if np.max(np.abs(p_new - p)) <= 1e-12 * np.max(np.abs(p)):
            break
        p = p_new
    a = (np.eye(3) - k @ h) @ f
    b = (np.eye(3) - k @ h) @ np.array([0.0, 0.0, 1.0])
    if kind == "sine":
        z = np.exp(1j * 2 * np.pi * PAPER_KF.sine_hz * t)
        g = 1.0 - (z - 1.0) * np.linalg.solve(z * np.eye(3) - a, b)[2]
        return float(-np.angle(g) / (2 * np.pi * PAPER_KF.sine_hz)), float(abs(g))
    e = b.copy()  # the step: dT_l = 1 at k = 0
    for n in range(1, 200000):
        if 1.0 - e[2] >= 0.9:
            return n * t, 1.0
        e = a @ e
    return float("inf"), 1.0


LOAD_T = 0.8  # s: the load is applied at 500 rpm
# (5.1)'s Q_33 = 1e-6 makes the load estimate slow (kf_load_response: half
# the amplitude at 10 Hz): the 10 Hz load is also run with Q_33 raised a
# hundredfold
SINE_Q_LOAD = 1e-4


def load_run(sil, root, out, noise: float, source: str, kind: str, q_load: float = 0.0) -> LoadRun:
    sc = speed_sc(root, source, 500.0, noise)
    if q_load:
        sc["controller"]["kf_q_load"] = q_load
    sc["duration"] = 1.5
    if kind == "step":
        prof = [{"type": "step", "t": LOAD_T, "value": PAPER_KF.brake}]
    else:
        prof = [{"type": "sine", "amplitude": PAPER_KF.sine_amp, "freq": PAPER_KF.sine_hz,
                 "t0": LOAD_T}]
    sc["mechanics"]["load_torque"] = prof
    r = run(sil, sc, out, f"kf_load_{kind}_{source}_{q_load:g}")
    lg = r.log
    t, ld, est = lg["t"], lg["load_torque"], lg["load_torque_est"]
    m = t >= LOAD_T + 0.2
    err = est[m] - ld[m]
    if kind == "step":
        # the 90 % rise of the estimate's centred 5 ms mean (the raw one is noisy)
        nw = max(1, int(round(0.005 / (t[1] - t[0]))))
        sm = np.convolve(est, np.ones(nw) / nw, mode="same")
        after = np.nonzero((t >= LOAD_T) & (sm >= 0.9 * PAPER_KF.brake))[0]
        lag = float(t[after[0]] - LOAD_T) if len(after) else float("inf")
        gain = float(np.mean(est[m]) / PAPER_KF.brake)
    else:
        w = 2 * np.pi * PAPER_KF.sine_hz
        n = int((t[m][-1] - t[m][0]) * PAPER_KF.sine_hz)
        mm = m & (t < t[m][0] + n / PAPER_KF.sine_hz)
        ref = np.mean(ld[mm] * np.exp(-1j * w * t[mm]))
        got = np.mean((est[mm] - np.mean(est[mm])) * np.exp(-1j * w * t[mm]))
        gain = float(abs(got) / abs(ref))
        lag = float(-np.angle(got / ref) / w)
    q = f", Q_33 {q_load:g}" if q_load else ""
    ql = q_load or sc["controller"].get("kf_q_load", 1e-6)
    p_lag, p_gain = kf_load_response(noise, ql, kind)
    return LoadRun(f"{kind}, {source}{q}", source, r.summary.get("faults_seen", []), t, ld, est,
                   float(np.mean(err)), float(np.std(err)), lag, gain, p_lag, p_gain)


@dataclass
class EbikeRun:
    faults: list
    rpm: float
    speed_mean: float
    speed_sd: float
    pos_mean: float  # deg electrical vs the plant
    pos_sd: float


def ebike_run(sil, root, out, rpm: float = 50.0) -> EbikeRun:
    sc = json.loads((root / "sil" / "scenarios" / "fabbri_speed.json").read_text())
    sc["name"] = "e-bike motor, IVD+KF"
    sc["machine"] = {"preset": "fabbri2022_ebike"}
    sc["controller"].update({"pos_source": "ivd+kf", "dfc_iter": 4, "dfc_b": -0.1825 * 0.05,
                             "dfc_sigma": sigma_of(sc["sensors"]["star_noise"]),
                             "align_current": 5.0})
    sc["references"]["speed"]["terms"][0]["value"] = rpm
    r = run(sil, sc, out, "kf_ebike")
    lg = r.log
    m = lg["t"] >= SETTLED
    sp = lg["speed"][m] / RPM
    th = np.degrees(wrap(lg["theta_e_est"][m] - lg["theta_e"][m]))
    return EbikeRun(r.summary.get("faults_seen", []), rpm, float(np.mean(sp)), float(np.std(sp)),
                    float(np.mean(th)), float(np.std(th)))


# The laws on IVD+KF in speed control at 500 rpm, answering brake steps of
# 0.05 N m at 0.8 s and 1.1 s with torque steps: the decoupled DFVC on the
# Table 5.1 motor, DB-DFVC (which needs |L_q - L_d| <= 10 % of L_d) on the
# Fig. 3.3 inductances with p = 0.04 (L_q 8 % below L_d). On a 36 V link:
# the DFC window halves the linear voltage range (docs/dfc.md), and at 24 V
# the 0.1 N m point at 500 rpm (2.2 Ohm: 2.9 V of resistive drop beside
# 3.6 V of back-EMF) is beyond it: the laws weaken the flux and trip, the
# same with the PLL (the 24 V rows, reported). The encoder runs start
# without an alignment (the plant's encoder offset is known: a light free
# rotor swings through an encoder alignment).
LAW_CASES_KF = (("dfvc_decoupled", "fabbri2022_t51", {}),
                ("db_dfvc", "fabbri2022_fig33", {"star_p": 0.04}))
LAW_STEPS = (0.8, 1.1)  # s: brake steps of LAW_BRAKE each
LAW_BRAKE = 0.05
LAW_V = (36.0, 24.0)
FRICTION_T51 = 1e-5  # N m s/rad: the presets' plant friction (sil/runner/presets.c)


@dataclass
class LawStep:
    law: str
    machine: str
    source: str
    v_dc: float
    faults: list
    torque: tuple  # period-average plant torque, settled after each step [N m]
    load: tuple  # plant load + friction at the same time [N m]
    dip: tuple  # largest speed drop after each step [rpm] (NaN: tripped before or during)
    recover: tuple  # time back within 0.5 % of the reference [s] (NaN: likewise)
    trip: float  # first instant with a fault [s] (NaN: none)


def law_step_run(sil, root, out, noise: float, case: tuple, source: str, v_dc: float) -> LawStep:
    law, machine, star = case
    sc = speed_sc(root, source, 500.0, noise)
    sc["name"] = f"{law} on {source}, {machine}, {v_dc:g} V"
    sc["machine"] = {"preset": machine, **star}
    sc["controller"]["law"] = law
    if source == "encoder":
        sc["controller"]["align_time"] = 0.0
    sc["dc_link"] = {"voltage": v_dc}
    sc["controller"]["v_dc_max"] = 1.5 * v_dc
    sc["sensors"]["v_full_scale"] = 2.0 * v_dc  # as the presets: the trip within the ADC
    sc["sensors"]["star_full_scale"] = 13.0 * v_dc / V_DC
    sc["controller"]["dfc_sigma"] = sigma_of(noise) * V_DC / v_dc
    sc["mechanics"]["load_torque"] = [{"type": "step", "t": t, "value": LAW_BRAKE}
                                      for t in LAW_STEPS]
    sc["duration"] = LAW_STEPS[-1] + 0.3
    r = run(sil, sc, out, f"kf_law_{law}_{source}_{v_dc:g}")
    lg = r.log
    t, sp = lg["t"], lg["speed"] / RPM
    tq, ld, dip, rec = [], [], [], []
    ends = LAW_STEPS[1:] + (sc["duration"],)
    f = np.nonzero(lg["faults"] != 0)[0]
    trip = float(t[f[0]]) if len(f) else float("nan")
    for a, e in zip(LAW_STEPS, ends):
        m = (t >= a + 0.15) & (t < e)
        tq.append(float(np.mean(lg["torque_avg"][m])))
        # what the torque holds at constant speed: the load and the friction
        ld.append(float(np.mean(lg["load_torque"][m] + FRICTION_T51 * lg["speed"][m])))
        w = (t >= a) & (t < e)
        dip.append(float(500.0 - np.min(sp[w])))
        out_ = np.nonzero(w & (np.abs(sp - 500.0) > 2.5))[0]
        rec.append(float(t[out_[-1]] - a) if len(out_) else 0.0)
        if trip < e:  # not a response: the drive tripped before the window ended
            dip[-1], rec[-1] = float("nan"), float("nan")
    return LawStep(law, machine, source, v_dc, r.summary.get("faults_seen", []), tuple(tq),
                   tuple(ld), tuple(dip), tuple(rec), trip)


class ResultsKF:
    def __init__(self, sil, root, out):
        self.sil, self.root, self.out = Path(sil), Path(root), Path(out)

    @functools.cached_property
    def cal(self) -> tuple[float, list]:
        return calibrate(self.sil, self.root, self.out)

    @property
    def noise(self) -> float:
        return self.cal[0]

    @functools.cached_property
    def table(self) -> list:
        rows = []
        for rpm, _ in PAPER_KF.table52_sd:
            for src in SOURCES:
                for rs in (PAPER_KF.r_scales if src in KALMAN else (1.0,)):
                    rows.append(speed_run(self.sil, self.root, self.out, src, rpm, self.noise, rs))
        return rows

    @functools.cached_property
    def enc_aligned(self) -> SpeedRun:
        """The encoder at 100 rpm with the scenario's 0.1 s alignment."""
        return speed_run(self.sil, self.root, self.out, "encoder", 100.0, self.noise,
                         tag="_aligned", enc_align=True)

    def sd(self, src: str, rpm: float, rs: float = 1.0) -> SpeedRun:
        return next(r for r in self.table if r.source == src and r.rpm == rpm and r.r_scale == rs)

    @functools.cached_property
    def rls(self) -> list:
        return [rls_run(self.sil, self.root, self.out, self.noise, lab, pm)
                for lab, pm in RLS_CASES]

    @functools.cached_property
    def loads(self) -> list:
        return [load_run(self.sil, self.root, self.out, self.noise, s, "step")
                for s in ("dfc+kf", "ivd+kf")] + [
            load_run(self.sil, self.root, self.out, self.noise, "ivd+kf", "sine"),
            load_run(self.sil, self.root, self.out, self.noise, "ivd+kf", "sine", SINE_Q_LOAD)]

    @functools.cached_property
    def ebike(self) -> EbikeRun:
        return ebike_run(self.sil, self.root, self.out)

    @functools.cached_property
    def laws(self) -> list:
        """LawStep per case and link (36 V, 24 V): IVD+KF, IVD (PLL) and the
        encoder (no window)."""
        res = []
        for c in LAW_CASES_KF:
            for v in LAW_V:
                srcs = ("ivd+kf", "ivd", "encoder")
                res += [law_step_run(self.sil, self.root, self.out, self.noise, c, s, v)
                        for s in srcs]
        return res

    def law(self, law: str, source: str, v: float) -> LawStep:
        return next(r for r in self.laws if (r.law, r.source, r.v_dc) == (law, source, v))


def _paper(src: str, rpm: float, rs: float) -> str:
    v = dict(PAPER_KF.table52_sd)[rpm][src]
    if isinstance(v, tuple):
        v = v[PAPER_KF.r_scales.index(rs)]
    return f"{v:g}"


def report(res: ResultsKF) -> str:
    n = res.noise
    L = ["### Noise calibration (section 5.1.3: the IVD halves the position error's spread)", "",
         "Raw position error (estimate - plant) std at 100 rpm, PLL speed:", "",
         "| star noise [V] | DFC | IVD | ratio |", "|---|---|---|---|"]
    for nn, d, i in res.cal[1]:
        L.append(f"| {nn:g} | {d:.3f} deg | {i:.3f} deg | {i / d:.2f} |")
    L += ["", f"Ratio 1/2 at **{n:.4f} V** (sigma_v = {sigma_of(n):.3g} of Gamma / v_dc), "
          "used below.", "",
          "### Table 5.2 analogue: speed error (reference - estimate) in speed control", "",
          "| speed | R_k | source | faults | mean [rpm] | sD [rpm] | thesis sD | "
          "position error, mean and std |",
          "|---|---|---|---|---|---|---|---|"]
    for r in res.table:
        rk = f"{r.r_scale:g} sigma^2" if r.source in KALMAN else "-"
        L.append(f"| {r.rpm:g} rpm | {rk} | {r.source} | {', '.join(r.faults) or 'none'} | "
                 f"{r.mean:+.3f} | {r.sd:.2f} | {_paper(r.source, r.rpm, r.r_scale)} | "
                 f"{r.pos_mean:+.3f}, {r.pos_sd:.3f} deg |")
    ea = res.enc_aligned
    L += ["", "The encoder rows start without an alignment (the plant's encoder offset is "
          f"known). With the scenario's 0.1 s alignment instead, at 100 rpm: position error "
          f"{ea.pos_mean:+.1f} deg mean, speed error sD {ea.sd:.2f} rpm, faults "
          f"{', '.join(ea.faults) or 'none'}; the rotor turns at {ea.speed_align_end:+.1f} rpm "
          "when the alignment ends and the offset is taken (the alignment damps this light "
          "free rotor's swing by the encoder's speed and ends only once it has settled: "
          "`docs/dfc.md`, \"Encoder alignment\"; before that fix, issue 23 point 18, the "
          "offset was taken mid-swing, -57.5 deg)."]
    L += ["", "IVD+KF / DFC+KF sD (the issue: at most 1/2): " + ", ".join(
        f"{rpm:g} rpm R {rs:g} sigma^2: {res.sd('ivd+kf', rpm, rs).sd / res.sd('dfc+kf', rpm, rs).sd:.2f}"
        for rpm, _ in PAPER_KF.table52_sd for rs in PAPER_KF.r_scales), "",
          "### RLS of a, b (Figs. 5.11-5.12): 500 rpm, started 30 % off (a +30 %, b -30 %)", "",
          "| bandwidth | rls_p_min | faults | within 5 % after the step | a sD | b sD | "
          "a, b: mean from 1 s (3.7: 0.05, -0.00466) | the signals' own a, b | speed |",
          "|---|---|---|---|---|---|---|---|---|"]
    for r in res.rls:
        L.append(f"| {r.label} | {r.p_min:g} | {', '.join(r.faults) or 'none'} | "
                 f"{r.t_in:.3f} s | {100 * r.a_sd:.2f} % | {100 * r.b_sd:.2f} % | "
                 f"{r.a_mean:.5f}, {r.b_mean:.6f} | {r.ls_a:.5f}, {r.ls_b:.6f} | "
                 f"{r.speed_mean:.2f} +- {r.speed_sd:.2f} rpm |")
    L += ["", "The signals' own a, b: a least-squares fit of the logged signals (plain "
          "Clarke vector) on the plant's true angle, from 1 s."]
    L += ["", "### Load torque (Figs. 4.1, 5.13): 500 rpm, load from 0.8 s", "",
          "| load | source | faults | estimate - load, mean | sD | lag | gain | the filter's "
          "model: lag, gain |",
          "|---|---|---|---|---|---|---|---|"]
    for r in res.loads:
        lag = f"{1e3 * r.lag:.1f} ms" + (" (90 % rise, 5 ms mean)" if r.label.startswith("step") else
                                          f" (at {PAPER_KF.sine_hz:g} Hz)")
        if r.label.startswith("sine"):
            lag += f", amplitude {PAPER_KF.sine_amp:g} N m"
        kind = r.label.split(",")[0]
        extra = r.label[len(kind) + len(r.source) + 2:]
        L.append(f"| {kind}{extra} | {r.source} | {', '.join(r.faults) or 'none'} | "
                 f"{r.err_mean:+.4f} N m | {r.err_sd:.4f} N m | {lag} | {r.gain:.3f} | "
                 f"{1e3 * r.pred_lag:.1f} ms, {r.pred_gain:.3f} |")
    e = res.ebike
    L += ["", "### E-bike motor (Table 5.4, p = -0.1825), IVD (4 iterations) + KF, speed "
          "control", "", "| speed | faults | speed (true) | angle - plant |", "|---|---|---|---|",
          f"| {e.rpm:g} rpm | {', '.join(e.faults) or 'none'} | {e.speed_mean:.2f} +- "
          f"{e.speed_sd:.2f} rpm | {e.pos_mean:+.2f} +- {e.pos_sd:.2f} deg |",
          "", "### The other laws on the IVD+KF position: speed control at 500 rpm, brake steps",
          "", f"Brake steps of {LAW_BRAKE:g} N m at " + " and ".join(f"{t:g} s" for t in LAW_STEPS)
          + "; torque = period-average plant torque once settled (load + friction beside it); "
          "dip = largest speed drop after the step; back = time until within 0.5 % of 500 rpm "
          "(- when the drive tripped first).",
          "", "| law | machine | link | source | faults (first at) | torque (load) [N m] | dip [rpm] | "
          "back [s] |", "|---|---|---|---|---|---|---|---|"]
    for r in res.laws:
        tq = ", ".join(f"{a:.4f} ({b:.4f})" for a, b in zip(r.torque, r.load))
        fl = f"{', '.join(r.faults)} ({r.trip:.3f} s)" if r.faults else "none"
        L.append(f"| {r.law} | {r.machine} | {r.v_dc:g} V | {r.source} | {fl} | {tq} | "
                 + ", ".join("-" if np.isnan(d) else f"{d:.1f}" for d in r.dip) + " | "
                 + ", ".join("-" if np.isnan(x) else f"{x:.3f}" for x in r.recover) + " |")
    return "\n".join(L)


def plot(res: ResultsKF, path: Path) -> None:
    plt, fig, ax = stacked_axes(4, "Kalman filter, RLS and load torque on the star point "
                                "(Table 5.1 motor)")
    for src in ("dfc", "dfc+kf", "ivd+kf", "ekf"):
        r = res.sd(src, 500.0)
        ax[0].plot(r.t, r.speed_est, lw=0.5, label=src)
    ax[0].set_ylim(400, 600)
    ax[0].set_ylabel("speed est. [rpm]")
    ax[0].legend(fontsize=7, ncol=4)
    for r in res.rls:
        ax[1].plot(r.t, r.a / r.a_true, lw=0.7, label=f"a, {r.label}")
        ax[1].plot(r.t, r.b / r.b_true, lw=0.7, label=f"b, {r.label}")
    ax[1].axhspan(0.95, 1.05, color="0.9")
    ax[1].set_ylabel("RLS / (3.7)")
    ax[1].legend(fontsize=7, ncol=2)
    for k, r in enumerate(res.loads):
        a = ax[2] if k < 2 else ax[3]
        if k in (0, 2):
            a.plot(r.t, r.load, "k", lw=0.8, label="plant")
        a.plot(r.t, r.est, lw=0.5, label=r.label)
        a.set_ylabel("load [N m]")
        a.legend(fontsize=7)
    ax[-1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
