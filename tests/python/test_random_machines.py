"""Acceptance tests on random machines (issue 23, point 19; docs/machines.md).

Machines drawn by `fluxdrive.machines` (seeded: the same seed gives the same
machine everywhere); fixed seeds per CI run, more with FLUXDRIVE_SEEDS="4 5 6"
or `pytest --seed 4 --seed 5`. Each test prints the machine's parameters and
the measured figures, so that a failure is reproduced from its seed
(`fluxdrive machines draw --kind KIND --seed N`).

(a) Closed-loop torque tracking in the SIL, speed imposed at 30 % of rated:
    torque steps 0.2 -> 0.6 -> -0.2 T_n. Limits from the law and the machine:
    FOC's current loop is first order at current_bw (the PI zero cancels the
    pole L/R_s: kp = wc L, ki = wc R_s), 5 % settling 3/wc; plus the sampling
    and PWM delay (2 periods) and, when the step asks more than the voltage
    headroom, the slew L |di| / (v_s - |v| at the operating point). Bounds:
    settle within 1.5 times that sum, and not faster than 0.6 * 3/wc (a loop
    faster than designed: a gain off). The DB-DFVC (Rubino 2020) is a
    deadbeat: the step settles within 6 periods (the paper's 1-2 samples,
    plus the observer and the two-period delay) plus 1.5 times the slew.
    Steady state (mean of the last 10 ms before the next step): within 3 % of
    the reference, both signs.
(b) MTPA and MTPV tables of the map tool (`fluxdrive map check`:
    fluxmap.luts.tables on the gridded map) against the analytic model itself
    (no grid): the largest torque at the current limit by a dense sweep of
    the current angle (40001 angles), and the largest torque at a flux
    amplitude by a dense sweep of the load angle with the model's exact
    current-from-flux: within 0.5 %.
(c) IVD convergence against Theorem 1 (Fabbri 2022) on drawn star-point
    machines (test_ivd_convergence_theorem1).
(d) Sensorless start and speed control (Fabbri 2022) on drawn star-point
    machines, dfc+kf and ivd+kf, a free rotor from three seeded start angles
    over the electrical turn: no fault, the polarity right, and after the
    machine's settling time (the reference's ramp or J dw / T_max, plus
    4 / speed_bw) the speed's mean, spread and the angle's mean error
    within the fabbri2022 acceptance (test_sensorless_start_and_speed).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from conftest import REAL_SIL
from fluxdrive import machines as mach
from fluxdrive.fluxmap import io as mapio
from fluxdrive.fluxmap.luts import tables

TS = 1.0 / 16000.0
SEEDS = [1, 2, 3]
T_STEPS = (0.05, 0.10)  # s: 0.2 -> 0.6 T_n at the first, -> -0.2 T_n at the second
DURATION = 0.15
SPEED_PU = 0.3
TOL_STEADY = 0.03
TOL_MAP = 0.005

real_sil = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")


def seeds(config) -> list[int]:
    extra = [int(s) for s in os.environ.get("FLUXDRIVE_SEEDS", "").split()]
    extra += list(config.getoption("--seed") or [])
    return extra or SEEDS


def _scenario(d: mach.Drawn, law: str) -> dict:
    s = json.loads(json.dumps(d.sections))
    t_n = d.rated["t_n"]
    w_m = SPEED_PU * d.rated["n_rpm"] * mach.RPM
    s["controller"].update({"law": law, "mode": "torque"})
    s["mechanics"].update({"mode": "imposed", "speed": w_m})
    s["inverter"] = {"model": "average", "dead_time": 1e-6}
    s.update({"name": f"random {d.kind} seed {d.seed} {law}", "duration": DURATION,
              "references": {"torque": [{"type": "const", "value": 0.2 * t_n},
                                        {"type": "step", "t": T_STEPS[0], "value": 0.4 * t_n},
                                        {"type": "step", "t": T_STEPS[1], "value": -0.8 * t_n}]},
              "log": {"decimation": 1}})
    return s


def _run(tmp, name: str, sc: dict):
    p = tmp / f"{name}.json"
    p.write_text(json.dumps(sc))
    r = subprocess.run([str(REAL_SIL), str(p), "--log", str(p.with_suffix(".npy")), "--summary",
                        str(p.with_suffix(".s.json"))], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, f"{name}: the SIL refused or failed: {r.stderr.strip()}"
    return json.loads(p.with_suffix(".s.json").read_text()), np.load(p.with_suffix(".npy"))


def _linear_point(d: mach.Drawn, t_ref: float):
    """i_d, i_q (MTPA) and the voltage amplitude at torque t_ref, speed imposed."""
    m = d.sections["machine"]
    ld, lq = m.get("ld", m.get("ls")), m.get("lq", m.get("ls"))
    lam, p, rs = m["lambda_m"], m["pole_pairs"], m["rs"]
    amps = np.linspace(0.0, 1.2 * d.rated["i_n"], 4001)
    pts = [mach._mtpa_linear(ld, lq, lam, a) for a in amps]
    tor = np.array([1.5 * p * (lam * iq + (ld - lq) * id_ * iq) for id_, iq in pts])
    a = float(np.interp(abs(t_ref), tor, amps))
    i_d, i_q = mach._mtpa_linear(ld, lq, lam, a)
    i_q = math.copysign(i_q, t_ref)
    w_e = SPEED_PU * d.rated["w_e"]
    v = math.hypot(rs * i_d - w_e * lq * i_q, rs * i_q + w_e * (lam + ld * i_d))
    return i_d, i_q, v


def _step_figures(d: mach.Drawn, law: str, lg: np.ndarray) -> list[dict]:
    t, tor, ref = lg["t"], lg["torque"], lg["torque_ref"]
    t_n = d.rated["t_n"]
    m = d.sections["machine"]
    lq = m.get("lq", m.get("ls"))
    wc = d.sections["controller"]["current_bw"]
    refs = (0.2 * t_n, 0.6 * t_n, -0.2 * t_n)
    out = []
    for k, ts in enumerate(T_STEPS):
        k0 = int(np.argmax((t >= ts - 0.5e-3) & (np.abs(ref - refs[k + 1]) < 1e-6 * t_n)))
        k1 = int(np.searchsorted(t, T_STEPS[k + 1] if k + 1 < len(T_STEPS) else t[-1]))
        step = refs[k + 1] - refs[k]
        out_band = np.nonzero(np.abs(tor[k0:k1] - refs[k + 1]) > 0.05 * abs(step))[0]
        n_settle = int(out_band[-1]) + 1 if len(out_band) else 0
        tail = (t >= t[k1 - 1] - 0.01) & (t <= t[k1 - 1])
        steady = float(np.mean(tor[tail]))
        id0, iq0, _ = _linear_point(d, refs[k])
        id1, iq1, v1 = _linear_point(d, refs[k + 1])
        head = max(d.rated["v_s"] - v1, 1e-9)
        slew = lq * math.hypot(id1 - id0, iq1 - iq0) / head
        if law == "foc":
            lo, hi = 0.6 * 3.0 / wc, 1.5 * (3.0 / wc + 2 * TS + slew)
        else:
            lo, hi = TS, 6 * TS + 1.5 * slew
        out.append({"step": f"{refs[k] / t_n:+.1f} -> {refs[k + 1] / t_n:+.1f} T_n",
                    "settle_s": n_settle * TS, "lo_s": lo, "hi_s": hi, "slew_s": slew,
                    "steady": steady, "ref": refs[k + 1],
                    "err": (steady - refs[k + 1]) / abs(refs[k + 1])})
    return out


def _tracking(tmp, kind: str, law: str, seed_list: list[int]):
    drawn = [mach.draw(kind, s) for s in seed_list]

    def one(d):
        s, lg = _run(tmp, f"{kind}_{d.seed}_{law}", _scenario(d, law))
        return s, _step_figures(d, law, lg)

    with ThreadPoolExecutor(max_workers=2) as ex:
        got = list(ex.map(one, drawn))
    bad = []
    for d, (s, figs) in zip(drawn, got):
        print(d.params_line())
        print(f"  {law}: tau_e {d.rated.get('tau_e', 0) * 1e3:.2f} ms, current_bw "
              f"{d.sections['controller']['current_bw']:g} rad/s, faults {s['faults_seen']}")
        if s["faults_seen"]:
            bad.append(f"{d.kind} seed {d.seed} {law}: faults {s['faults_seen']}")
        for f in figs:
            print(f"  {f['step']}: settled in {f['settle_s'] * 1e3:.3f} ms (bounds "
                  f"{f['lo_s'] * 1e3:.3f} .. {f['hi_s'] * 1e3:.3f} ms, slew "
                  f"{f['slew_s'] * 1e3:.3f} ms); steady {f['steady']:.5g} N m vs "
                  f"{f['ref']:.5g} ({f['err']:+.2%})")
            if not f["lo_s"] <= f["settle_s"] <= f["hi_s"]:
                bad.append(f"{d.kind} seed {d.seed} {law} {f['step']}: settled in "
                           f"{f['settle_s'] * 1e3:.3f} ms, outside {f['lo_s'] * 1e3:.3f} .. "
                           f"{f['hi_s'] * 1e3:.3f} ms")
            if abs(f["err"]) > TOL_STEADY:
                bad.append(f"{d.kind} seed {d.seed} {law} {f['step']}: steady error "
                           f"{f['err']:+.2%} beyond {TOL_STEADY:.0%}")
    assert not bad, "\n".join(bad)


def test_draw_is_reproducible_and_in_range():
    for kind in mach.KINDS:
        for s in SEEDS:
            a, b = mach.draw(kind, s), mach.draw(kind, s)
            assert a.sections == b.sections and a.rated == b.rated
            r = a.rated
            assert r["w_e"] / (2 * math.pi) <= mach.F_PWM / 20.0
            c = a.sections["controller"]
            assert c["i_trip"] >= c["i_max"] and c["speed_trip"] >= c["speed_max"]
            if kind == "star":
                assert 0.1 <= abs(r["star_p"]) <= 0.45
    # different seeds: different machines
    assert mach.draw("spm", 1).sections != mach.draw("spm", 2).sections


@real_sil
@pytest.mark.parametrize("kind,law", [("spm", "foc"), ("spm", "db_dfvc"), ("ipm", "foc")])
def test_torque_tracking(tmp_path, request, kind, law):
    _tracking(tmp_path, kind, law, seeds(request.config))


def _mtpv_exact(d: mach.Drawn, flux: float, half: float, n: int = 40001):
    """The largest torque at stator flux amplitude `flux` over the load angle
    from the model's exact current-from-flux (SyR frame: psi_d(syr) =
    psi_q(fd), psi_q(syr) = -psi_d(fd)): (torque, its current amplitude,
    whether it lies inside a grid of +-half A: the true MTPV on the map)."""
    p = d.sections["machine"]["pole_pairs"]
    delta = np.linspace(0.0, math.pi, n)
    pd_fd, pq_fd = flux * np.cos(delta), flux * np.sin(delta)
    id_s, iq_s = d.model.current(pq_fd, -pd_fd)
    id_fd, iq_fd = -iq_s, id_s
    tq = 1.5 * p * (pd_fd * iq_fd - pq_fd * id_fd)
    k = int(np.argmax(tq))
    return (float(tq[k]), float(math.hypot(id_fd[k], iq_fd[k])),
            bool(abs(id_fd[k]) <= half and 0.0 <= iq_fd[k] <= half))


@pytest.mark.parametrize("kind", ["syr_map", "pmsyr_map"])
def test_map_tables_against_the_model(tmp_path, request, kind):
    bad = []
    for s in seeds(request.config):
        d = mach.draw(kind, s)
        path = mach.write_map(d, tmp_path)
        m = mapio.load(str(path))
        t = tables(m)
        p = d.sections["machine"]["pole_pairs"]
        print(d.params_line())
        for frac in (0.5, 1.0):
            a = frac * d.rated["i_n"]
            got = float(np.interp(a, t.amp, t.amp_t))
            ref = mach.mtpa_torque_exact(d.model, p, a)
            e = got / ref - 1.0
            print(f"  MTPA at {a:.4g} A: table {got:.6g} N m, model {ref:.6g} N m ({e:+.3%})")
            if abs(e) > TOL_MAP:
                bad.append(f"{kind} seed {s}: MTPA at {a:.4g} A {e:+.3%}")
        # the table's own currents give its torque on the model (its MTPA
        # current for 80 % of the table's range)
        k = int(0.8 * (len(t.mtpa_id) - 1))
        tt = k / (len(t.mtpa_id) - 1) * t.mtpa_t_max
        pd_, pq_ = d.model.flux(t.mtpa_iq[k], -t.mtpa_id[k])  # fluxdrive -> SyR currents
        t_model = 1.5 * p * (pd_ * -t.mtpa_id[k] - pq_ * t.mtpa_iq[k])
        e = t_model / tt - 1.0
        print(f"  MTPA table entry {k}: ({t.mtpa_id[k]:.4g}, {t.mtpa_iq[k]:.4g}) A for {tt:.6g} "
              f"N m, model {t_model:.6g} N m ({e:+.3%})")
        if abs(e) > TOL_MAP:
            bad.append(f"{kind} seed {s}: MTPA table entry {k} {e:+.3%}")
        # MTPV: on the drawn grid (1.5 i_n) the true MTPV of these machines
        # mostly lies beyond the map and the table is the map-edge limit
        # (issue 23 point 15, open: docs/machines.md); so the same model
        # gridded out to 1.25 times the MTPV current at a third of the rated
        # flux, and the table at its own flux nodes where the true MTPV is on
        # that map (the two largest)
        psi_n = mach.REF_FLUX_PER_C * d.rated["c"]
        half2 = max(d.grid[0], 1.25 * _mtpv_exact(d, psi_n / 3.0, 0.0)[1])
        t2 = tables(mapio.load(str(mach.write_map(d, tmp_path, half=half2, n=61))))
        ll = np.linspace(0.0, t2.mtpv_flux_max, len(t2.mtpv_torque))
        on = [j for j in range(1, len(ll)) if _mtpv_exact(d, ll[j], half2)[2]]
        print(f"  MTPV on a +-{half2:.4g} A map up to {ll[on[-1]] if on else 0.0:.4g} Vs of "
              f"{t2.mtpv_flux_max:.4g} Vs ({len(on)} of {len(ll) - 1} table nodes)")
        if len(on) < 2:
            bad.append(f"{kind} seed {s}: the MTPV lies on the map at {len(on)} table nodes")
        for j in on[-2:]:
            ref = _mtpv_exact(d, ll[j], half2)[0]
            e = t2.mtpv_torque[j] / ref - 1.0
            print(f"  MTPV at {ll[j]:.4g} Vs: table {t2.mtpv_torque[j]:.6g} N m, model {ref:.6g} "
                  f"N m ({e:+.3%})")
            if abs(e) > TOL_MAP:
                bad.append(f"{kind} seed {s}: MTPV at {ll[j]:.4g} Vs {e:+.3%}")
    assert not bad, "\n".join(bad)


@real_sil
@pytest.mark.parametrize("kind", ["syr_map", "pmsyr_map", "star"])
def test_sil_accepts_the_drawn_machines(tmp_path, request, kind):
    """The drawn sections run: the drive enables, no fault, in a short FOC run
    on the encoder (the star machines' sensorless start is point 1's)."""
    bad = []
    for s in seeds(request.config):
        d = mach.draw(kind, s)
        if d.model is not None:
            mach.write_map(d, tmp_path)
        sc = json.loads(json.dumps(d.sections))
        sc["controller"].update({"law": "foc", "mode": "torque"})
        sc["mechanics"].update({"mode": "imposed", "speed": SPEED_PU * d.rated["n_rpm"] * mach.RPM})
        sc.update({"name": f"random {kind} {s}", "duration": 0.04,
                   "references": {"torque": 0.5 * d.rated["t_n"]}, "log": {"decimation": 16}})
        summ, lg = _run(tmp_path, f"{kind}_{s}", sc)
        tail = lg["t"] > 0.03
        got = float(np.mean(lg["torque"][tail]))
        print(d.params_line())
        print(f"  FOC 0.5 T_n: {got:.5g} N m vs {0.5 * d.rated['t_n']:.5g}, faults "
              f"{summ['faults_seen']}")
        if summ["faults_seen"] or abs(got / (0.5 * d.rated["t_n"]) - 1.0) > TOL_STEADY:
            bad.append(f"{kind} seed {s}: torque {got:.5g} N m, faults {summ['faults_seen']}")
    assert not bad, "\n".join(bad)


@real_sil
def test_ivd_convergence_theorem1(tmp_path, request):
    """(c) IVD convergence vs Theorem 1 (Fabbri 2022) on drawn star-point
    machines, as test_fabbri2022.test_theorem1_convergence_per_iteration on
    Fig. 3.3's: the dynamometer at 50 rpm, no current, 8 iterations logged,
    no star noise (16-bit ADC). D_0 (3.13) within 3 %, each iteration
    contracts |tan D_k| <= 2|p| |tan D_k-1| plus the floor the signals' own
    error leaves, and follows the sequence (3.81) within 10 % plus that floor
    (fabbri2022.SIGNAL_ERR / (1 - 2|p|))."""
    from fluxdrive import fabbri2022 as fb
    from conftest import REPO_ROOT

    drawn = [mach.draw("star", s) for s in seeds(request.config)]

    def one(d):
        sc = fb.base(REPO_ROOT, "dyno")
        sc["name"] = f"Theorem 1 on random star seed {d.seed}"
        sc["machine"] = dict(d.sections["machine"])
        sc["controller"].update({k: v for k, v in d.sections["controller"].items()
                                 if k in ("i_max", "i_trip", "torque_max", "speed_max",
                                          "speed_trip", "v_dc_max", "v_dc_min")})
        sc["controller"].update({"dfc_iter": 8, "align_current": 0.2 * d.rated["i_n"]})
        sc["dc_link"] = d.sections["dc_link"]
        sc["mechanics"]["speed"] = fb.speed_const(50.0)
        sc["sensors"].update({**d.sections["sensors"], "adc_bits": 16, "star_noise": 0.0})
        sc["duration"] = 0.2
        r = fb._run(REAL_SIL, sc, tmp_path, f"conv_{d.seed}")
        return np.array([np.max(np.abs(fb.err2(r, k, 0.05)[1])) for k in range(9)])

    with ThreadPoolExecutor(max_workers=2) as ex:
        got = list(ex.map(one, drawn))
    bad = []
    for d, m in zip(drawn, got):
        p = d.rated["star_p"]
        th = fb.ivd_theory(p, 8)
        fl = fb.SIGNAL_ERR / (1.0 - 2.0 * abs(p))
        print(d.params_line())
        print(f"  p {p:+.3f}: max |2theta error| per iteration [mrad] measured "
              + " ".join(f"{x * 1e3:.1f}" for x in m) + "; Theorem 1 (3.81) "
              + " ".join(f"{x * 1e3:.1f}" for x in th) + f"; floor {fl * 1e3:.1f}")
        if abs(m[0] / th[0] - 1.0) >= 0.03:
            bad.append(f"star seed {d.seed}: D_0 {m[0]:.4f} vs (3.13) {th[0]:.4f}")
        for k in range(1, 5):
            if not np.tan(m[k]) <= 2.0 * abs(p) * np.tan(m[k - 1]) + fl:
                bad.append(f"star seed {d.seed}: iteration {k} does not contract")
            if not abs(m[k] - th[k]) <= 0.1 * th[k] + fl:
                bad.append(f"star seed {d.seed}: iteration {k} {m[k]:.4f} vs (3.81) {th[k]:.4f}")
    assert not bad, "\n".join(bad)


# (d) Sensorless start and speed control (Fabbri 2022) on drawn star-point
# machines: free rotor at a start angle, alignment, speed step.
SL_SOURCES = ("dfc+kf", "ivd+kf")  # FLUXDRIVE_SL_SOURCES="dfc ivd" runs others (docs/machines.md)
RUN_STATE = 2  # DRIVE_STATE_RUN in the log's state column
SL_ALIGN = 0.1  # s: align_time (the polarity from the motion it causes)
SL_STEP = 0.15  # s: the speed step, after the alignment
SL_SPEED_PU = 0.3
SL_WINDOW = 0.25  # s measured after the settling time
SL_STARTS = 3  # start angles per machine: one in each third of the electrical turn
STAR_ADC_BITS, STAR_FS = 12, 13.0  # the star channel the runs set (sensors.star_full_scale)
# the fabbri2022 acceptance of the thesis's speed control
# (test_fabbri2022.test_closed_loop_on_the_ivd_position): mean speed within
# 0.5 %, spread within 1 % of the reference, the angle's mean error within 1
# degree. On a drawn machine the filtered angle's own error (the method's,
# now in R_k: (3.13), Theorem 1) is what moves the speed; where it moves it
# beyond these, the machine is outside the source's band (docs/machines.md).
SL_TOL_MEAN, SL_TOL_SD, SL_TOL_ANGLE = 0.005, 0.01, 1.0


def _sl_settle(d: mach.Drawn, c: dict) -> float:
    """The time from the step to a settled speed, from the machine: the
    reference's ramp at accel_max or, if the torque cannot follow it, the
    acceleration at torque_max less friction (J dw / T), plus the speed
    loop's 2 % settling at speed_bw (4 / speed_bw)."""
    w = SL_SPEED_PU * d.rated["n_rpm"] * mach.RPM
    m = d.sections["mechanics"]
    acc = min(c.get("accel_max", 125.66371), (c["torque_max"] - m["b"] * w) / m["j"])
    return w / acc + 4.0 / c.get("speed_bw", 60.0)


def _sl_scenario(d: mach.Drawn, src: str, th0e: float, noise_seed: int) -> dict:
    s = json.loads(json.dumps(d.sections))
    # sigma_v of each DFC signal (docs/dfc.md): sqrt(4/3) s / v_dc for a star
    # channel of noise s, the 12-bit channel's quantisation (LSB / sqrt 12) in s
    q = STAR_FS / 2 ** STAR_ADC_BITS / math.sqrt(12.0)
    s_v = math.hypot(d.rated["star_noise"], q)
    sig = math.sqrt(4.0 / 3.0) * s_v / d.rated["v_dc"]
    s["controller"].update({"law": "foc", "mode": "speed", "pos_source": src, "dfc_sigma": sig,
                            "align_time": SL_ALIGN})
    p = s["machine"]["pole_pairs"]
    s["mechanics"].update({"mode": "free", "theta0": th0e / p})
    s["sensors"].update({"encoder_cpr": 65536, "i_noise": 0.005, "star_full_scale": STAR_FS,
                         "star_tau": 2e-7, "seed": noise_seed})
    n_ref = SL_SPEED_PU * d.rated["n_rpm"]
    dur = SL_STEP + _sl_settle(d, s["controller"]) + SL_WINDOW
    s.update({"name": f"random star seed {d.seed} {src} from {th0e:.3f} rad", "duration": dur,
              "references": {"speed": {"unit": "rpm",
                                       "terms": [{"type": "step", "t": SL_STEP, "value": n_ref}]}},
              "log": {"decimation": 1}})
    return s


def _sl_starts(seed: int) -> list[float]:
    """Start angles (electrical) over the whole turn, seeded: one drawn in
    each third."""
    g = np.random.default_rng([int(seed), 19])
    return [float((k + g.uniform()) * 2.0 * math.pi / SL_STARTS) for k in range(SL_STARTS)]


def _sl_figures(d: mach.Drawn, sc: dict, summ: dict, lg: np.ndarray) -> dict:
    t = lg["t"]
    t0 = SL_STEP + _sl_settle(d, sc["controller"])
    tail = t >= t0
    w_ref = SL_SPEED_PU * d.rated["n_rpm"] * mach.RPM
    w = lg["speed"][tail]
    err = np.degrees(np.angle(np.exp(1j * (lg["theta_e_est"] - lg["theta_e"]))))
    # the polarity: from 2 ms into the run (the alignment's decision) until a
    # fault if any, the estimate stays on the magnet's branch (the other is
    # 180 degrees off)
    run_ = lg["state"] == RUN_STATE
    after = run_ & (t >= t[np.argmax(run_)] + 0.002)
    return {"faults": summ["faults_seen"], "t0": t0, "mean": float(np.mean(w) / w_ref - 1.0),
            "sd": float(np.std(w) / w_ref), "ang_mean": float(np.mean(err[tail])),
            "ang_sd": float(np.std(err[tail])),
            "ang_max": float(np.max(np.abs(err[after]))) if after.any() else 180.0}


@real_sil
def test_sensorless_start_and_speed(tmp_path, request):
    """(d) Sensorless start and speed control (Fabbri 2022 chapters 3-5) on
    drawn star-point machines, each source SL_SOURCES, free rotor from
    SL_STARTS seeded start angles over the electrical turn (each with its
    own noise seed): alignment, then a step to 0.3 x rated speed. No fault;
    the polarity right (the angle within 90 degrees of the plant's from the
    alignment's end on: the wrong branch is 180 off); after the machine's
    settling time (_sl_settle) the speed's mean and spread and the angle's
    mean error within the fabbri2022 acceptance (SL_TOL_*)."""
    sources = os.environ.get("FLUXDRIVE_SL_SOURCES", "").split() or SL_SOURCES
    cases = [(mach.draw("star", s), src, k, th) for s in seeds(request.config)
             for src in sources for k, th in enumerate(_sl_starts(s))]

    def one(c):
        d, src, k, th = c
        sc = _sl_scenario(d, src, th, 100 * d.seed + k)
        summ, lg = _run(tmp_path, f"sl_{d.seed}_{src.replace('+', '_')}_{k}", sc)
        return _sl_figures(d, sc, summ, lg)

    with ThreadPoolExecutor(max_workers=2) as ex:
        got = list(ex.map(one, cases))
    bad, last = [], None
    for (d, src, k, th), f in zip(cases, got):
        if d.seed != last:
            last = d.seed
            print(d.params_line())
            print(f"  settled from {f['t0']:.3f} s (step at {SL_STEP} s), "
                  f"{SL_SPEED_PU * d.rated['n_rpm']:.1f} rpm")
        print(f"  {src:7s} from {th:.2f} rad: speed {f['mean']:+.3%} sd {f['sd']:.3%}; angle "
              f"{f['ang_mean']:+.2f} sd {f['ang_sd']:.2f} max {f['ang_max']:.1f} deg; faults "
              f"{f['faults']}")
        why = []
        if f["faults"]:
            why.append(f"faults {f['faults']}")
        if not f["ang_max"] < 90.0:
            why.append(f"angle {f['ang_max']:.1f} deg off after the alignment (polarity)")
        if not abs(f["mean"]) <= SL_TOL_MEAN:
            why.append(f"mean speed {f['mean']:+.3%} beyond {SL_TOL_MEAN:.1%}")
        if not f["sd"] <= SL_TOL_SD:
            why.append(f"speed sd {f['sd']:.3%} beyond {SL_TOL_SD:.0%}")
        if not abs(f["ang_mean"]) <= SL_TOL_ANGLE:
            why.append(f"angle mean {f['ang_mean']:+.2f} deg beyond {SL_TOL_ANGLE} deg")
        if why:
            bad.append(f"star seed {d.seed} {src} from {th:.2f} rad: " + "; ".join(why))
    assert not bad, "\n".join(bad)
