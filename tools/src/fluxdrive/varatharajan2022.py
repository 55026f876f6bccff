"""Varatharajan, Pellegrino, Armando 2022 (decoupled DFVC of saturated
synchronous machines, online MTPA / MTPV) reproduced in SIL.

`fluxdrive varatharajan2022` runs the law `dfvc_decoupled` on the SyR preset
`syr_1k1` (its flux map) through the paper's experiments, fits and measures
them on the full-rate logs (the plant's true values), draws the figures and
writes the tables of docs/results-varatharajan2022.md. The same functions
back the acceptance tests (tests/python/test_varatharajan2022.py), which
take every limit from the paper or the issue, never from the drive.

Experiments (scenario bases in sil/scenarios/varatharajan_*.json):
  bandwidth   Figs. 10-11: small steps of lambda* and i_tau* at 3 speeds x
              3 loads, Omega = 2 pi 100 and 2 pi 200, gains (a, b) and
              (a', b'), at 5 kHz (the paper's) and 16 kHz
  robustness  Fig. 14: current-model map error in d from -30 % to +30 %
              every 0.5 s, -25 % in q, 300 rpm, rated torque, Omega = 2 pi 150
  speed step  Fig. 12: 0 -> 2625 rpm at no load, online references
  sine torque Fig. 13: 25 Hz sinusoidal torque at 750 rpm, online references
  machines    the speed step on the interior-PM and map-file presets
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
import functools
import json
from pathlib import Path
import tempfile

import numpy as np

from .fluxmap import blob as blobmod
from .paper_report import Run, paper_paths, replace_table, run, stacked_axes
from .fluxmap.model import FluxMap

RPM = np.pi / 30.0
TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Paper:
    """What the paper and the issue state (A. Varatharajan, G. Pellegrino,
    E. Armando, "Direct Flux Vector Control of Synchronous Motor Drives:
    Accurate Decoupled Control with Online Adaptive MTPA and MTPV
    Evaluation", IEEE TIE 69(2), 2022)."""

    fs: float = 5000.0  # section VI: dSPACE at 5 kHz
    i_rated: float = 2.3  # Table I [A rms]
    torque_rated: float = 7.1  # Table I [N m]
    speed_rated_rpm: float = 1500.0
    pole_pairs: int = 2
    g: float = TWO_PI * 5.0  # observer gain
    k_a: float = 60.0
    omegas: tuple = (TWO_PI * 100.0, TWO_PI * 200.0)  # Figs. 10, 11
    omega_robust: float = TWO_PI * 150.0  # Fig. 14
    # Fig. 10: b'/b = 1.59 -> poles at 2 pi 256 and 2 pi 62 for Omega = 2 pi 100
    sota_ratio: float = 1.59
    sota_poles_hz: tuple = (256.0, 62.0)
    # Fig. 14 at t > 3 s: b/b' = 3 (poles 817, 82 Hz), b/b_hat = 1.5 (354, 95 Hz)
    robust_ratio_sota: float = 3.0
    robust_ratio_prop: float = 1.5
    # section III.C: at i_d = 3 A, i_q = 6 A (SyR frame) a' = 4, a = 6
    a_point_syr: tuple = (3.0, 6.0)
    a_sota: float = 4.0
    a_prop: float = 6.0
    speed_step_rpm: float = 2625.0  # Fig. 12 (1.75 p.u.)
    sine_hz: float = 25.0  # Fig. 13
    sine_rpm: float = 750.0
    # acceptance bounds of the issue
    bw_tol: float = 0.10
    mtpa_tol: float = 0.02
    mtpv_tol: float = 0.05

    @property
    def i_max(self) -> float:  # 1.5 sqrt(2) I_n: the 50 % overload
        return 1.5 * np.sqrt(2.0) * self.i_rated


PAPER = Paper()


# ------------------------------------------------------------- the model
@dataclass
class MapTables:
    fm: FluxMap
    mtpa_t: np.ndarray  # torque axis of the MTPA table [N m]
    mtpa_id: np.ndarray
    mtpa_iq: np.ndarray
    mtpa_flux: np.ndarray
    mtpv_flux: np.ndarray  # flux axis of the MTPV table [Vs]
    mtpv_torque: np.ndarray

    def mtpa_current(self, t):
        t = np.abs(np.asarray(t, float))
        return np.hypot(np.interp(t, self.mtpa_t, self.mtpa_id), np.interp(t, self.mtpa_t, self.mtpa_iq))

    def mtpa_flux_of(self, t):
        return np.interp(np.abs(np.asarray(t, float)), self.mtpa_t, self.mtpa_flux)

    def mtpa_torque_at(self, i_amp: float) -> float:
        amps = np.hypot(self.mtpa_id, self.mtpa_iq)
        return float(np.interp(i_amp, amps, self.mtpa_t))

    def mtpv(self, flux):
        return np.interp(np.asarray(flux, float), self.mtpv_flux, self.mtpv_torque)


def tables_of_blob(path: Path) -> MapTables:
    b = blobmod.read(path)
    fm = FluxMap(b["i_d"], b["i_q"], b["psi_d"].astype(float), b["psi_q"].astype(float),
                 int(b["pole_pairs"]))
    n = len(b["mtpa_flux"])
    return MapTables(fm, np.linspace(0.0, float(b["mtpa_t_max"]), n), b["mtpa_id"].astype(float),
                     b["mtpa_iq"].astype(float), b["mtpa_flux"].astype(float),
                     np.linspace(0.0, float(b["mtpv_flux_max"]), len(b["mtpv_torque"])),
                     b["mtpv_torque"].astype(float))


def tables_of_preset(root: Path, preset: str) -> MapTables:
    """The blob the SIL loads for a preset (a .npz goes through `map convert`)."""
    files = {"syr_1k1": "maps/syr_1k1.fdmap", "ipm_sat": "maps/ipm_sat.fdmap",
             "pmasyr_file": "maps/pmasyr_file.npz"}
    p = root / files[preset]
    if p.suffix == ".fdmap":
        return tables_of_blob(p)
    from .fluxmap import io as fio
    fm = fio.load(p)
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "m.fdmap"
        out.write_bytes(blobmod.to_bytes(fm))
        return tables_of_blob(out)


def sfo_gains(fm: FluxMap, i_d, i_q, lam_d, lam_q, scale=(1.0, 1.0)):
    """(a, b) of (22) and (a', b') of (17) in the fluxdrive frame (the C
    core's firmware/core/model/sfo_model.h, in double), from the map at i
    and the flux lambda; scale: the current-model error (rows of the map)."""
    i_d, i_q, lam_d, lam_q = (np.asarray(x, float) for x in (i_d, i_q, lam_d, lam_q))
    sd, sq = scale
    ldd, ldq, lqd, lqq = fm.inductance(i_d, i_q)
    ldd, ldq, lqd, lqq = sd * ldd, sd * ldq, sq * lqd, sq * lqq
    l2 = lam_d ** 2 + lam_q ** 2
    lx = 0.5 * (ldq + lqd)
    det = ldd * lqq - lx * lx
    s2 = 2 * lam_d * lam_q / l2
    c2 = (lam_d ** 2 - lam_q ** 2) / l2
    a = (0.5 * (ldd - lqq) * s2 - lx * c2) / det
    # i^a = J i - L^-1 J lambda, b = lambda^T J i^a / lambda^2
    jl_d, jl_q = -lam_q, lam_d
    det2 = ldd * lqq - ldq * lqd
    ia_d = -i_q - (lqq * jl_d - ldq * jl_q) / det2
    ia_q = i_d - (ldd * jl_q - lqd * jl_d) / det2
    b = (lam_q * ia_d - lam_d * ia_q) / l2
    # (17) with the apparent inductances of (3), PM on +d
    pd, pq = fm.flux(i_d, i_q)
    lm = fm.pm_flux() * sd
    la_d = np.where(np.abs(i_d) > 0.05, (sd * pd - lm) / np.where(i_d == 0, 1, i_d), ldd)
    la_q = np.where(np.abs(i_q) > 0.05, sq * pq / np.where(i_q == 0, 1, i_q), lqq)
    lam = np.sqrt(l2)
    cd, sn = lam_d / lam, lam_q / lam
    k = (la_d - la_q) / (la_d * la_q)
    a_s = sn * cd * k
    b_s = (cd * cd - sn * sn) * k + cd * lm / (lam * la_d)
    return a, b, a_s, b_s


def sota_poles(r: float, omega: float) -> tuple:
    """Poles of s^2 + 2 r Omega s + r Omega^2 (tau loop with b/b_hat = r) [rad/s]."""
    disc = complex(r * r - r) ** 0.5
    return (omega * (-r + disc), omega * (-r - disc))


# ------------------------------------------------------------- running
def base(root: Path, name: str) -> dict:
    return json.loads((root / "sil" / "scenarios" / f"varatharajan_{name}.json").read_text())


# ------------------------------------------------------------- step fits
def step_model(t, omega: float, r: float):
    """Unit-step response of r (2 Omega s + Omega^2) / (s^2 + 2 r Omega s + r Omega^2):
    the loop of (26)-(28) with b/b_hat = r (r = 1: the double pole at -Omega)."""
    t = np.maximum(np.asarray(t, float), 0.0)
    if abs(r - 1.0) < 1e-6:
        return 1.0 - np.exp(-omega * t) * (1.0 - omega * t)
    p1, p2 = sota_poles(r, omega)
    y = np.ones_like(t, dtype=complex)
    for p, q in ((p1, p2), (p2, p1)):
        y += r * 2 * omega * (p + omega / 2) / (p * (p - q)) * np.exp(p * t)
    return y.real


def _golden(f, lo, hi, n=30):
    g = (np.sqrt(5) - 1) / 2
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(n):
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return 0.5 * (a + b)


@dataclass
class StepFit:
    omega: float  # fitted bandwidth (r = 1) [rad/s]
    r: float  # fitted loop-gain ratio b/b_hat at the design Omega
    delay: float  # fitted dead time [s]
    rms: float  # residual of the Omega fit, of the unit step
    gain: float  # the step the response settles to / the reference's step
    omega_ref: float  # bandwidth fitted with the final value held at the reference


def fit_step(t, y, ref, t_step: float, omega_design: float, window: float = 8.0) -> StepFit:
    """Fits the true response y to the reference step (both full rate),
    normalised by the reference's step with the pre-step offset removed:
    the loop's model (Omega with r = 1; r with Omega = design; a dead time
    each) plus the observer's slow mode 1 - e^{-g t}, their weights by least
    squares; gain is where the two settle against the reference (the
    static error, which the observer's and the map's accuracy set, not the
    loop); omega_ref is the loop model alone held at the reference."""
    t = np.asarray(t, float)
    k0 = int(np.searchsorted(t, t_step))
    ks = k0 + int(np.argmax(np.abs(np.diff(ref[k0:k0 + 400])) > 0)) + 1  # the step in the log
    r0 = float(np.mean(ref[ks - 20:ks - 1]))
    r1 = float(np.mean(ref[ks + 5:ks + 25]))
    y0 = float(np.mean(y[ks - 20:ks - 1]))
    te = t[ks - 1]
    m = (t >= te) & (t <= te + window / omega_design)
    tt, z = t[m] - te, (y[m] - y0) / (r1 - r0)

    # the observer's own mode: after a change of operating point its
    # estimate (the current model weighs g / omega) settles with 1/g, which
    # the true i_tau shows as a slow tail on top of the loop's response
    tail = np.where(tt > 0.0, -np.expm1(-PAPER.g * tt), 0.0)

    def sse(w, r, d, free=True):
        mdl = step_model(tt - d, w, r)
        if not free:
            return float(np.mean((mdl - z) ** 2)), 1.0
        a = np.stack([mdl, tail], axis=1)
        (k, c), *_ = np.linalg.lstsq(a, z, rcond=None)
        return float(np.mean((a @ np.array([k, c]) - z) ** 2)), float(k + c * tail[-1])

    ts = float(t[1] - t[0])

    def best_of(param, lo, hi, free):
        best = None
        for d in np.linspace(0.0, 3.0 * ts, 7):
            f = (lambda x: sse(x, 1.0, d, free)[0]) if param == "w" else \
                (lambda x: sse(omega_design, x, d, free)[0])
            x = _golden(f, lo, hi)
            e, k = sse(x, 1.0, d, free) if param == "w" else sse(omega_design, x, d, free)
            if best is None or e < best[0]:
                best = (e, x, d, k)
        return best

    e_w, w_fit, d_fit, k_fit = best_of("w", 0.3 * omega_design, 3.0 * omega_design, True)
    r_fit = best_of("r", 0.2, 5.0, True)[1]
    w_ref = best_of("w", 0.3 * omega_design, 3.0 * omega_design, False)[1]
    return StepFit(w_fit, r_fit, d_fit, float(np.sqrt(e_w)), k_fit, w_ref)


# ------------------------------------------------------------- experiments
SPEEDS_RPM = (300.0, 750.0, 1200.0)
# The small steps: 5 % of the operating flux, and 5 % of the rated torque
# but at most 20 % of the operating torque (light load: 0.14 N m). At 2 %
# of the rated torque (0.05 A of i_tau, ten steps of the current ADC) the
# fits' residual was 2 to 3 times larger and the 5 kHz i_tau fits
# scattered to -12 %; at 5 % the same points fit at -3 .. -5 %; a 5 % step
# at light load is half the operating torque (b doubles along it: +12 %).
STEP = 0.05
GAIN_LBL = {0: "(a, b)", 1: "(a', b')"}
LOADS = ("light", "rated", "limit")


def load_points(tab: MapTables) -> dict:
    """Torque of each load: light (10 % of rated), MTPA at rated current
    (sqrt(2) 2.3 A), at the current limit (98.4 % of 1.5 sqrt(2) 2.3 A, so
    that the negative steps stay inside it)."""
    return {"light": 0.1 * PAPER.torque_rated,
            "rated": tab.mtpa_torque_at(np.sqrt(2.0) * PAPER.i_rated),
            "limit": tab.mtpa_torque_at(0.984 * PAPER.i_max)}


@dataclass
class BwPoint:
    fs: float
    omega: float
    gains: int
    speed_rpm: float
    load: str
    torque: float
    flux: StepFit
    itau: StepFit
    b_ratio_pred: float  # b / b_hat at the point (b from the true map and state)
    cross: StepFit  # i_tau through the flux step (decoupling)


def bandwidth_point(sil, root, out, tab, fs, omega, gains, speed, load) -> BwPoint:
    sc = copy.deepcopy(base(root, "bandwidth"))
    t_op = load_points(tab)[load]
    flux = float(tab.mtpa_flux_of(t_op))
    sign = -1.0 if load == "limit" else 1.0
    dt = min(STEP * PAPER.torque_rated, 0.2 * t_op)  # small against the operating point too
    c = sc["controller"]
    c["dfvc_decoupled_bw"] = omega
    c["dfvc_decoupled_gains"] = gains
    sc["inverter"]["pwm_frequency"] = fs
    sc["mechanics"]["speed"]["terms"][0]["value"] = speed
    # ramps to the operating point (a step of the flux from zero at speed
    # overshoots into the current trip), then the small steps
    sc["references"]["torque"] = [{"type": "ramp", "t0": 0.1, "t1": 0.2, "value": t_op},
                                  {"type": "step", "t": 0.4, "value": sign * dt}]
    sc["references"]["flux"] = [{"type": "const", "value": 0.2},
                                {"type": "ramp", "t0": 0.02, "t1": 0.1, "value": flux - 0.2},
                                {"type": "step", "t": 0.3, "value": sign * STEP * flux}]
    name = f"bw_{int(fs)}_{int(round(omega / TWO_PI))}_{gains}_{int(speed)}_{load}"
    r = run(sil, sc, out, name)
    lg = r.log
    if r.summary["faults_seen"]:
        raise RuntimeError(f"{name}: faults {r.summary['faults_seen']}")
    f_fit = fit_step(lg["t"], lg["flux"], lg["flux_ref"], 0.3, omega)
    i_fit = fit_step(lg["t"], lg["i_qs"], lg["i_qs_ref"], 0.4, omega)
    # decoupling: i_tau through the flux step (its reference moves by -2 %
    # with 1/lambda*); a wrong a shows as a bump the i_tau model cannot fit
    x_fit = fit_step(lg["t"], lg["i_qs"], lg["i_qs_ref"], 0.3, omega)
    # b / b_hat at the point, before the i_tau step
    m = (lg["t"] > 0.38) & (lg["t"] < 0.4)
    lam_d = lg["flux"][m] * np.cos(lg["delta"][m])
    lam_q = lg["flux"][m] * np.sin(lg["delta"][m])
    _, b_true, _, _ = sfo_gains(tab.fm, lg["i_d"][m], lg["i_q"][m], lam_d, lam_q)
    ratio = float(np.mean(b_true) / np.mean(lg["gain_b"][m]))
    return BwPoint(fs, omega, gains, speed, load, t_op, f_fit, i_fit, ratio, x_fit)


def bandwidth_map(sil, root, out, tab, fss=(5000.0, 16000.0)) -> list:
    pts = []
    for fs in fss:
        for omega in PAPER.omegas:
            for gains in (0, 1):
                for speed in SPEEDS_RPM:
                    for load in LOADS:
                        pts.append(bandwidth_point(sil, root, out, tab, fs, omega, gains, speed, load))
    return pts


@dataclass
class RobustSeg:
    gains: int
    fs: float
    scale_d: float
    torque_mean: float
    torque_std: float  # ripple (rms about the mean) [N m]
    torque_pp: float
    b_ratio: float  # b (true map, true state) / b_hat (the drive's)
    poles_hz: tuple


def robustness(sil, root, out, tab, fs: float, gains: int) -> tuple[Run, list]:
    sc = copy.deepcopy(base(root, "robustness"))
    sc["controller"]["dfvc_decoupled_gains"] = gains
    sc["inverter"]["pwm_frequency"] = fs
    r = run(sil, sc, out, f"robust_{int(fs)}_{gains}")
    lg = r.log
    segs = []
    for k in range(7):
        t0 = 0.5 + 0.5 * k + 0.15
        m = (lg["t"] >= t0) & (lg["t"] < t0 + 0.3)
        tq = lg["torque"][m]
        lam_d = lg["flux"][m] * np.cos(lg["delta"][m])
        lam_q = lg["flux"][m] * np.sin(lg["delta"][m])
        _, b_true, _, _ = sfo_gains(tab.fm, lg["i_d"][m], lg["i_q"][m], lam_d, lam_q)
        ratio = float(np.mean(b_true) / np.mean(lg["gain_b"][m]))
        p = sota_poles(ratio, PAPER.omega_robust)
        segs.append(RobustSeg(gains, fs, round(1.3 - 0.1 * k, 2), float(tq.mean()), float(tq.std()),
                              float(tq.max() - tq.min()), ratio,
                              tuple(abs(x.real) / TWO_PI for x in p)))
    return r, segs


@dataclass
class SpeedStep:
    preset: str
    run: Run
    t_fw: float  # flux weakening begins: the true flux leaves its plateau [s]
    mtpa_err: float  # largest |i| / i_MTPA(T) - 1 on MTPA (true values)
    mtpa_n: int
    t_mtpv: float  # the MTPV limit binds [s] (-1: never)
    mtpv_err: float  # largest |T_max / (k_T f_T(lambda)) - 1| at steady MTPV points
    mtpv_n: int
    final_rpm: float


def speed_step(sil, root, out, preset: str = "syr_1k1", overrides: dict | None = None,
               name: str = "speed_step", speed_rpm: float | None = None,
               duration: float | None = None) -> SpeedStep:
    sc = copy.deepcopy(base(root, "speed_step"))
    for k, v in (overrides or {}).items():
        sect, key = k.split(".", 1)
        if sect == "machine":
            sc["machine"] = {key: v}
        else:
            sc.setdefault(sect, {})[key] = v
    if speed_rpm is not None:
        sc["references"]["speed"]["terms"][0]["value"] = speed_rpm
    if duration is not None:
        sc["duration"] = duration
    tab = tables_of_preset(root, preset)
    r = run(sil, sc, out, name)
    lg = r.log
    t = lg["t"]
    k_t = sc["controller"].get("k_t", 0.9)
    t0 = sc["references"]["speed"]["terms"][0]["t"]
    # MTPA phase: from 20 ms after the step (the flux built) until the
    # voltage applied reaches 97 % of the k_v share of the linear range
    # (flux weakening begins; the voltage from the logged duties)
    k1 = int(np.searchsorted(t, t0 + 0.02))
    v_a = lg["v_dc"] * (2 * lg["duty_a"] - lg["duty_b"] - lg["duty_c"]) / 3.0
    v_b = lg["v_dc"] * (lg["duty_b"] - lg["duty_c"]) / np.sqrt(3.0)
    k_v = sc["controller"].get("k_v", 0.9)
    fw = np.nonzero((t > t[k1]) & (np.hypot(v_a, v_b) > 0.97 * k_v * lg["v_dc"] / np.sqrt(3.0)))[0]
    k_fw = int(fw[0]) if len(fw) else len(t)
    seg = slice(k1, k_fw)
    iamp = np.hypot(lg["i_d"][seg], lg["i_q"][seg])
    tab_i = tab.mtpa_current(lg["torque"][seg])
    mtpa_err = float(np.max(np.abs(iamp / tab_i - 1.0))) if k_fw > k1 else float("nan")
    # MTPV: where the drive's limit is its MTPV limit and the flux is steady
    # (slow: |d lambda/dt| < 1 %/s of lambda): T_max of (34) against k_T f_T
    bind = (np.abs(lg["torque_max"] - lg["torque_mtpv"]) < 1e-4) & \
           (lg["torque_ref"] >= lg["torque_max"] - 1e-4) & (t > t[k_fw - 1] if k_fw < len(t) else False)
    dflux = np.gradient(lg["flux"], t)
    steady = bind & (np.abs(dflux) < 0.5 * lg["flux"])
    idx = np.nonzero(steady)[0]
    if len(idx):
        ft = k_t * tab.mtpv(lg["flux"][idx])
        err = lg["torque_mtpv"][idx] / ft - 1.0
        mtpv_err, t_mtpv = float(np.max(np.abs(err))), float(t[idx[0]])
    else:
        mtpv_err, t_mtpv = float("nan"), -1.0
    return SpeedStep(preset, r, float(t[k_fw]) if k_fw < len(t) else -1.0, mtpa_err, k_fw - k1,
                     t_mtpv, mtpv_err, len(idx), r.summary["final_speed_rpm"])


@dataclass
class SineTorque:
    run: Run
    flux_err: float  # largest |flux_mtpa (adapted, the drive's) / f_lambda(T) - 1|, last periods
    iamp_err: float  # largest |i| / i_MTPA(T) - 1 (true values)
    flux_err_rms: float
    iamp_err_rms: float
    true_flux_err: float  # largest |true flux / f_lambda(T) - 1|


def sine_torque(sil, root, out, tab, fs: float) -> SineTorque:
    return _sine_of(sil, base(root, "sine_torque"), out, tab, fs, f"sine_{int(fs)}")


def a_comparison(tab: MapTables) -> list:
    """(a', a, b', b) at the paper's point i_d = 3, i_q = 6 A (SyR frame:
    i_d(fd) = -i_q(SyR), i_q(fd) = i_d(SyR)) and on this map's MTPA at the
    rated and limit currents."""
    rows = []
    pts = [("paper's point (3, 6) A SyR", -PAPER.a_point_syr[1], PAPER.a_point_syr[0])]
    for lbl, amp in (("MTPA at rated current", np.sqrt(2) * PAPER.i_rated),
                     ("MTPA at the current limit", PAPER.i_max)):
        t = tab.mtpa_torque_at(amp)
        pts.append((lbl, float(np.interp(t, tab.mtpa_t, tab.mtpa_id)),
                    float(np.interp(t, tab.mtpa_t, tab.mtpa_iq))))
    for lbl, i_d, i_q in pts:
        ld, lq = tab.fm.flux(i_d, i_q)
        a, b, a_s, b_s = sfo_gains(tab.fm, i_d, i_q, ld, lq)
        rows.append((lbl, i_d, i_q, float(a_s), float(a), float(b_s), float(b)))
    return rows


@dataclass
class MtpvPoint:
    k_t: float
    speed_rpm: float
    torque: float  # true torque, steady [N m]
    t_max: float  # the drive's T_max of (34), steady [N m]
    kt_ft: float  # k_T f_T(lambda) from the offline MTPV table at the true flux [N m]
    ratio: float  # t_max / kt_ft
    parabola: float  # 2 / (1 + k_T): where (34) settles on a parabolic torque peak


def mtpv_steady(sil, root, out, tab, k_t: float, speed_rpm: float = PAPER.speed_step_rpm,
                preset: str = "syr_1k1") -> MtpvPoint:
    """Steady operation on the MTPV limit: the speed imposed, T* far above
    what the flux allows; (34) against the offline table. (34) extrapolates
    the torque linearly in the load angle up to the MTPV angle: on a
    concave peak T = f_T (1 - c x^2) the tangent reaches f_T (1 + c x^2), so
    at the fixed point T = T_max = k_T (2 f_T - T): T_max / (k_T f_T) =
    2 / (1 + k_T), 5.3 % above for k_T = 0.9."""
    sc = copy.deepcopy(base(root, "speed_step"))
    sc["name"] = f"steady MTPV limit at {speed_rpm:.0f} rpm, k_T = {k_t}"
    # the rotor brought up to speed by the dynamometer (a start at speed
    # trips the encoder plausibility while its PLL locks)
    sc["mechanics"] = {"mode": "imposed", "speed": {"unit": "rpm", "terms": [
        {"type": "ramp", "t0": 0.05, "t1": 0.45, "value": speed_rpm}]}}
    sc["controller"].update(mode="torque", k_t=k_t)
    if preset != "syr_1k1":
        sc["machine"] = {"preset": preset}
        p = OTHER_MACHINES[preset]
        sc["controller"].update(i_max=p["controller.i_max"], flux_min=p["controller.flux_min"],
                                speed_trip=1.25 * speed_rpm * RPM, speed_max=1.15 * speed_rpm * RPM,
                                v_dc_max=800.0, v_dc_min=50.0)
    sc["duration"] = 1.0
    sc["references"] = {"torque": [{"type": "ramp", "t0": 0.1, "t1": 0.3,
                                    "value": 3.0 * tab.mtpa_torque_at(1e9)}]}
    r = run(sil, sc, out, f"mtpv_{preset}_{int(speed_rpm)}_{k_t:g}")
    lg = r.log
    m = lg["t"] >= 0.7
    kt_ft = k_t * tab.mtpv(lg["flux"][m])
    if r.summary["faults_seen"]:
        raise RuntimeError(f"steady MTPV {preset} {speed_rpm} rpm: {r.summary['faults_seen']}")
    return MtpvPoint(k_t, speed_rpm, float(lg["torque"][m].mean()), float(lg["torque_mtpv"][m].mean()),
                     float(kt_ft.mean()), float(np.mean(lg["torque_mtpv"][m] / kt_ft)), 2.0 / (1.0 + k_t))


def sine_variant(sil, root, out, tab, fs: float, k_a: float, mean: float, amp: float) -> SineTorque:
    sc = copy.deepcopy(base(root, "sine_torque"))
    sc["controller"]["k_a"] = k_a
    sc["references"]["torque"] = [{"type": "step", "t": 0.1, "value": mean},
                                  {"type": "sine", "amplitude": amp, "freq": PAPER.sine_hz, "t0": 0.2}]
    return _sine_of(sil, sc, out / "variants", tab, fs, f"sine_{int(fs)}_{k_a:g}_{mean:g}_{amp:g}")


def _sine_of(sil, sc, out, tab, fs, name) -> SineTorque:
    sc = copy.deepcopy(sc)
    sc["inverter"]["pwm_frequency"] = fs
    r = run(sil, sc, out, name)
    lg = r.log
    m = lg["t"] >= sc["duration"] - 4.0 / PAPER.sine_hz
    tq = lg["torque"][m]
    ferr = lg["flux_mtpa"][m] / tab.mtpa_flux_of(tq) - 1.0
    terr = lg["flux"][m] / tab.mtpa_flux_of(tq) - 1.0
    ierr = np.hypot(lg["i_d"][m], lg["i_q"][m]) / tab.mtpa_current(tq) - 1.0
    return SineTorque(r, float(np.max(np.abs(ferr))), float(np.max(np.abs(ierr))),
                      float(np.sqrt(np.mean(ferr ** 2))), float(np.sqrt(np.mean(ierr ** 2))),
                      float(np.max(np.abs(terr))))


# Per-machine parameters of the speed step on the other presets (docs):
# the current limit 1.5 sqrt(2) I_n where the map covers it, flux_min below
# the PM flux, the target 1.75 x the base speed at the preset's DC link.
OTHER_MACHINES = {
    "ipm_sat": {"controller.i_max": 21.2, "controller.flux_min": 0.02, "speed_rpm": 6000.0,
                "duration": 2.0},
    "pmasyr_file": {"controller.i_max": 10.0, "controller.flux_min": 0.1, "speed_rpm": 2900.0,
                    "duration": 3.0},
}


def other_machine(sil, root, out, preset: str) -> SpeedStep:
    p = OTHER_MACHINES[preset]
    w = p["speed_rpm"] * RPM
    ov = {"machine.preset": preset, "controller.i_max": p["controller.i_max"],
          "controller.flux_min": p["controller.flux_min"], "controller.speed_max": 1.15 * w,
          "controller.speed_trip": 1.25 * w, "controller.v_dc_max": 800.0,
          "controller.v_dc_min": 50.0}
    return speed_step(sil, root, out, preset, ov, name=f"speed_step_{preset}",
                      speed_rpm=p["speed_rpm"], duration=p["duration"])


# ------------------------------------------------------------- all of it
class Results:
    """The experiments, each run on first use and kept: a test (or a
    mutant's run of one test) pays only for what it reads."""

    def __init__(self, sil, root, out, fss=(5000.0, 16000.0)):
        self.sil, self.root, self.out, self.fss = sil, root, out, fss
        self.tab = tables_of_preset(root, "syr_1k1")

    @functools.cached_property
    def bw(self) -> list:
        return bandwidth_map(self.sil, self.root, self.out / "bandwidth", self.tab, self.fss)

    @functools.cached_property
    def robust(self) -> dict:  # (fs, gains) -> (Run, [RobustSeg])
        return {(fs, g): robustness(self.sil, self.root, self.out / "robustness", self.tab, fs, g)
                for fs in self.fss for g in (0, 1)}

    @functools.cached_property
    def step(self) -> SpeedStep:
        return speed_step(self.sil, self.root, self.out / "speed_step")

    @functools.cached_property
    def mtpv(self) -> list:  # [MtpvPoint], the k_T sweep on syr_1k1
        return [mtpv_steady(self.sil, self.root, self.out / "mtpv", self.tab, k)
                for k in (0.8, 0.9, 0.95)]

    @functools.cached_property
    def sine(self) -> dict:  # fs -> SineTorque (the scenario)
        return {fs: sine_torque(self.sil, self.root, self.out / "sine", self.tab, fs)
                for fs in self.fss}

    @functools.cached_property
    def sine_var(self) -> list:  # [(k_a, mean, amp, SineTorque)] at 5 kHz
        return [(k, m, a, sine_variant(self.sil, self.root, self.out / "sine", self.tab, 5000.0,
                                       k, m, a)) for k, m, a in SINE_VARIANTS]

    @functools.cached_property
    def others(self) -> dict:  # preset -> SpeedStep
        return {p: other_machine(self.sil, self.root, self.out / "machines", p)
                for p in OTHER_MACHINES}

    @functools.cached_property
    def a_rows(self) -> list:
        return a_comparison(self.tab)


SINE_VARIANTS = ((60.0, 5.0, 2.0), (120.0, 5.0, 2.0), (240.0, 5.0, 2.0), (60.0, 4.0, 3.0),
                 (240.0, 4.0, 3.0))


def run_all(sil, root, out, fss=(5000.0, 16000.0)) -> Results:
    return Results(sil, root, out, fss)


def _hz(w):
    return w / TWO_PI


def _poles(r: float, omega: float) -> str:
    p1, p2 = sota_poles(r, omega)
    if abs(p1.imag) > 1e-9:
        return f"{_hz(abs(p1)):.0f} Hz, complex (zeta {-p1.real / abs(p1):.2f})"
    return f"{_hz(-p1.real):.0f} / {_hz(-p2.real):.0f} Hz"


def report(res: Results) -> str:
    P = PAPER
    L = []
    s = res.step
    L += ["| experiment | paper | fluxdrive |", "|---|---|---|"]
    for fs in sorted({p.fs for p in res.bw}):
        q = [p for p in res.bw if p.gains == 0 and p.fs == fs]
        fl = [p.flux.omega / p.omega for p in q]
        it = [p.itau.omega / p.omega for p in q]
        L.append(f"| bandwidth map at {fs / 1000:g} kHz, (a, b): fitted bandwidth / Omega over "
                 f"{len(q)} steps of each loop (3 speeds x 3 loads x 2 Omega) | uniform "
                 f"(Figs. 10b, 11b) | flux {min(fl):.3f} .. {max(fl):.3f}, i_tau {min(it):.3f} .. "
                 f"{max(it):.3f} (bound 0.9 .. 1.1) |")
    for fs in sorted({p.fs for p in res.bw}):
        for om in P.omegas:
            rs = [p.itau.r for p in res.bw if p.gains == 1 and p.fs == fs and p.omega == om
                  and p.load != "light"]
            pr = [p.b_ratio_pred for p in res.bw if p.gains == 1 and p.fs == fs and p.omega == om
                  and p.load != "light"]
            paper = (f"b'/b = 1.59: {P.sota_poles_hz[0]:.0f} / {P.sota_poles_hz[1]:.0f} Hz"
                     if om == P.omegas[0] else "1.59: 512 / 124 Hz")
            L.append(f"| (a', b') at {fs / 1000:g} kHz, Omega = 2 pi {_hz(om):.0f}, rated and "
                     f"limit loads: fitted b/b_hat | {paper} | {min(rs):.2f} .. {max(rs):.2f} "
                     f"(map: {min(pr):.2f} .. {max(pr):.2f}); poles at r = {np.mean(rs):.2f}: "
                     f"{_poles(float(np.mean(rs)), om)} |")
    a0 = res.a_rows[0]
    L.append(f"| cross-coupling gain at i_d = 3, i_q = 6 A (SyR frame) | a' = {P.a_sota:g}, "
             f"a = {P.a_prop:g} 1/H | a' = {a0[3]:.2f}, a = {a0[4]:.2f}; b' = {a0[5]:.1f}, "
             f"b = {a0[6]:.1f} 1/H (this map) |")
    for fs in sorted({k[0] for k in res.robust}):
        segs0, segs1 = res.robust[(fs, 0)][1], res.robust[(fs, 1)][1]
        faults = res.robust[(fs, 0)][0].summary["faults_seen"] + \
            res.robust[(fs, 1)][0].summary["faults_seen"]
        L.append(f"| robustness at {fs / 1000:g} kHz (Fig. 14): lambda_d^i 1.3 -> 0.7, "
                 f"lambda_q^i 1.25; b/b_hat at 0.7 | (a', b') 3 (817 / 82 Hz), (a, b) 1.5 "
                 f"(354 / 95 Hz) | (a', b') {segs1[-1].b_ratio:.2f} .. {segs1[0].b_ratio:.2f}, "
                 f"(a, b) {segs0[-1].b_ratio:.2f} .. {segs0[0].b_ratio:.2f} (1.3 -> 0.7); "
                 f"faults: {', '.join(faults) or 'none'} |")
    L.append(f"| speed step 0 -> {P.speed_step_rpm:.0f} rpm, no load: MTPA current vs the "
             f"offline table | coincident | {100 * s.mtpa_err:.2f} % worst over {s.mtpa_n} "
             f"samples (bound 2 %); flux weakening from {s.t_fw:.3f} s |")
    L.append(f"| ... MTPV limit (34) binding in the run | from 0.45 s, \"coherent\" | from "
             f"{s.t_mtpv:.2f} s; T_max / (k_T f_T) within {100 * s.mtpv_err:.1f} % while "
             f"accelerating |")
    for m in res.mtpv:
        L.append(f"| steady MTPV, {m.speed_rpm:.0f} rpm, k_T = {m.k_t:g}: T_max (34) / (k_T f_T) "
                 f"| \"coherent\" | {m.ratio:.4f} (parabolic peak: {m.parabola:.4f}); bound 1.05 |")
    for fs, st in sorted(res.sine.items()):
        L.append(f"| 25 Hz torque 3..7 N m at 750 rpm, k_A = 60, {fs / 1000:g} kHz: adapted flux, "
                 f"current vs the MTPA table | coincident (Fig. 13) | flux {100 * st.flux_err:.1f} %, "
                 f"current {100 * st.iamp_err:.2f} % worst (bound 2 %) |")
    for p, o in res.others.items():
        L.append(f"| speed step on {p} ({OTHER_MACHINES[p]['speed_rpm']:.0f} rpm): MTPA current, "
                 f"faults | | {100 * o.mtpa_err:.2f} % over {o.mtpa_n} samples, flux weakening from "
                 f"{o.t_fw:.3f} s, MTPV "
                 f"{'binding from %.2f s' % o.t_mtpv if o.t_mtpv >= 0 else 'not reached'}, final "
                 f"{o.final_rpm:.0f} rpm, faults: {', '.join(o.run.summary['faults_seen']) or 'none'} |")
    L += ["", "### Bandwidth map", "",
          "Fitted bandwidth / Omega of each loop; where the i_tau response settles against the "
          "reference (the step = 1); for (a', b') the fitted b/b_hat beside the map's; the "
          "residual of i_tau through the flux step (decoupling).", "",
          "| f_s | Omega / 2 pi | gains | speed rpm | load | T N m | flux | i_tau | i_tau settles | "
          "i_tau: r fit | b/b_hat of the map | i_tau through the flux step (residual) |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for p in res.bw:
        L.append(f"| {p.fs / 1000:g} kHz | {_hz(p.omega):.0f} Hz | {GAIN_LBL[p.gains]} "
                 f"| {p.speed_rpm:.0f} | {p.load} | {p.torque:.2f} | {p.flux.omega / p.omega:.3f} | "
                 f"{p.itau.omega / p.omega:.3f} | {p.itau.gain:.3f} | {p.itau.r:.2f} | "
                 f"{p.b_ratio_pred:.2f} | {p.cross.rms:.3f} |")
    L += ["", "### Robustness (Fig. 14): per 0.5 s segment", "",
          "| f_s | gains | lambda_d^i / lambda_d | torque mean N m | ripple rms N m | ripple p-p N m | "
          "b / b_hat | tau-loop poles |", "|---|---|---|---|---|---|---|---|"]
    for (fs, g), (_, segs) in sorted(res.robust.items()):
        for sg in segs:
            L.append(f"| {fs / 1000:g} kHz | {GAIN_LBL[g]} | {sg.scale_d:.1f} | "
                     f"{sg.torque_mean:.3f} | {sg.torque_std:.4f} | {sg.torque_pp:.4f} | "
                     f"{sg.b_ratio:.2f} | {_poles(sg.b_ratio, P.omega_robust)} |")
    L += ["", "### Online MTPA at 25 Hz: k_A and the torque swing (5 kHz)", "",
          "| k_A | T* N m | adapted flux vs table | true flux vs table | current vs table |",
          "|---|---|---|---|---|"]
    for k, m, a, st in res.sine_var:
        L.append(f"| {k:g} | {m - a:g} .. {m + a:g} | {100 * st.flux_err:.1f} % | "
                 f"{100 * st.true_flux_err:.1f} % | {100 * st.iamp_err:.2f} % |")
    L += ["", "### Gains of the stator-flux frame on this map (1/H)", "",
          "| point | i_d A | i_q A | a' (17) | a (22) | b' (17) | b (22) |", "|---|---|---|---|---|---|---|"]
    for lbl, i_d, i_q, a_s, a, b_s, b in res.a_rows:
        L.append(f"| {lbl} | {i_d:.2f} | {i_q:.2f} | {a_s:.2f} | {a:.2f} | {b_s:.1f} | {b:.1f} |")
    return "\n".join(L)


def _finish(plt, fig, ax, path):
    for a in ax:
        a.grid(True, alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_bandwidth(res: Results, path: Path) -> None:
    plt, fig, ax = stacked_axes(2, "Varatharajan 2022 Figs. 10-11: fitted bandwidth / design, 9 points each")
    for k, (lbl, key) in enumerate((("flux loop", "flux"), ("i_tau loop", "itau"))):
        for g, mk in ((0, "o"), (1, "x")):
            for fs, col in ((5000.0, "C0"), (16000.0, "C1")):
                for om, ms in ((PAPER.omegas[0], 6), (PAPER.omegas[1], 9)):
                    pts = [p for p in res.bw if p.gains == g and p.fs == fs and p.omega == om]
                    if not pts:
                        continue
                    y = [getattr(p, key).omega / p.omega for p in pts]
                    ax[k].plot(range(len(pts)), y, mk, color=col, ms=ms,
                               label=f"{GAIN_LBL[g]} "
                                     f"{fs / 1000:g} kHz {_hz(om):.0f} Hz")
        ax[k].axhspan(0.9, 1.1, color="g", alpha=0.1)
        ax[k].set_ylabel(lbl)
    ax[1].set_xticks(range(9), [f"{s:.0f} {ld}" for s in SPEEDS_RPM for ld in LOADS], fontsize=7)
    _finish(plt, fig, ax, path)


def plot_speed_step(step: SpeedStep, tab: MapTables, path: Path) -> None:
    lg = step.run.log
    t = lg["t"]
    plt, fig, ax = stacked_axes(4, "Varatharajan 2022 Fig. 12: speed step 0 -> 2625 rpm, online MTPA / MTPV")
    ax[0].plot(t, lg["speed"] / RPM, label="speed (rpm)")
    ax[1].plot(t, lg["torque"], label="torque")
    ax[1].plot(t, lg["torque_max"], "--", label="limit in force")
    ax[1].plot(t, lg["torque_mtpv"], ":", label="T_max (34)")
    ax[1].plot(t, 0.9 * tab.mtpv(lg["flux"]), "k:", lw=0.8, label="k_T f_T (table)")
    ax[1].set_ylim(0, 14)
    ax[2].plot(t, np.hypot(lg["i_d"], lg["i_q"]), label="|i|")
    ax[2].plot(t, tab.mtpa_current(lg["torque"]), "--", label="MTPA table at the torque")
    ax[3].plot(t, lg["flux"], label="flux")
    ax[3].plot(t, lg["flux_mtpa"], "--", label="adapted MTPA flux (32)")
    ax[3].set_xlabel("s")
    _finish(plt, fig, ax, path)


def plot_sine(st: SineTorque, tab: MapTables, path: Path) -> None:
    lg = st.run.log
    t = lg["t"]
    m = t >= t[-1] - 0.12
    plt, fig, ax = stacked_axes(3, "Varatharajan 2022 Fig. 13: 25 Hz torque at 750 rpm, online MTPA (k_A = 60)")
    ax[0].plot(t[m], lg["torque"][m], label="torque")
    ax[0].plot(t[m], lg["torque_ref"][m], "--", label="reference")
    ax[1].plot(t[m], lg["flux_mtpa"][m], label="adapted flux (32)")
    ax[1].plot(t[m], tab.mtpa_flux_of(lg["torque"][m]), "--", label="MTPA table at the torque")
    ax[2].plot(t[m], np.hypot(lg["i_d"][m], lg["i_q"][m]), label="|i|")
    ax[2].plot(t[m], tab.mtpa_current(lg["torque"][m]), "--", label="MTPA table at the torque")
    ax[2].set_xlabel("s")
    _finish(plt, fig, ax, path)


def plot_robustness(res: Results, path: Path) -> None:
    plt, fig, ax = stacked_axes(2, "Varatharajan 2022 Fig. 14: map error in d 1.3 -> 0.7 (q 1.25), 300 rpm, 5 kHz")
    for k, g in enumerate((1, 0)):
        lg = res.robust[(5000.0, g)][0].log
        ax[k].plot(lg["t"], lg["torque"], lw=0.6, label=f"torque, {GAIN_LBL[g]}")
        ax[k].set_ylim(5.8, 7.4)
    ax[1].set_xlabel("s")
    _finish(plt, fig, ax, path)


def main_varatharajan(args) -> int:
    root, sil, out, figs = paper_paths(args, "varatharajan2022")
    res = run_all(sil, root, out)
    plot_bandwidth(res, figs / "varatharajan2022_bandwidth.png")
    plot_speed_step(res.step, res.tab, figs / "varatharajan2022_speed_step.png")
    plot_sine(res.sine[5000.0], res.tab, figs / "varatharajan2022_sine.png")
    plot_robustness(res, figs / "varatharajan2022_robustness.png")
    table = report(res)
    print(table)
    if args.doc and replace_table(Path(args.doc), "varatharajan2022", table):
        print(f"updated {args.doc}")
    return 0


def linear_machine(sil, root, out) -> Run:
    """The same law on a linear machine model (the SPM of Rubino 2020, no
    map): observer (24) with Ld, Lq, lambda_m as current model, online
    references; 10 N m at 100 rpm (below the voltage limit)."""
    sc = {"name": "decoupled DFVC on the linear SPM rubino2020_spm, 10 N m at 100 rpm",
          "duration": 0.4, "machine": {"preset": "rubino2020_spm"},
          "inverter": {"model": "average", "dead_time": 0},
          "mechanics": {"mode": "imposed", "speed": {"unit": "rpm", "terms": [
              {"type": "const", "value": 100}]}},
          "sensors": {"encoder_cpr": 0},
          "controller": {"law": "dfvc_decoupled", "mode": "torque", "dfvc_decoupled_refs": 1,
                         "flux_min": 0.1},
          "references": {"torque": [{"type": "step", "t": 0.1, "value": 10.0}]},
          "board": {"preset": "ideal"}}
    return run(sil, sc, out, "linear_spm")
