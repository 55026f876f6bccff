"""The RLS of a, b (`ivd+kf+rls`, Fabbri 2022 (4.51)-(4.57), Fig. 4.4) from
+-50 % starts on every star-point preset and on drawn star-point machines
(issue 23 point 5; docs/dfc.md, "RLS and the loop of Fig. 4.4").

The rotor is driven by the dynamometer (`mechanics.mode: imposed`, ramp to
100 and 300 rpm from 0.12 to 0.15 s; at most 0.6 of the rated speed: the
e-bike preset, rated 200 rpm, at 120 rpm for 300 - from 140 rpm it trips
lost_control on this ramp with ivd+kf as well, open), torque reference 0,
start angles spread over the turn, one noise seed per case; the machine of
the issue (p = +0.35) among them. A -50 % start of a takes b +50 %, or
0.45 |a| where that breaks Theorem 1's |b/a| < 1/2 for the configured
start (refused by the drive's check). Measured on the full-rate log against the plant's a, b of (3.7)
(plant_aniso_ab, sil/plant/plant_star.c):
  * the start is outside the band (the test starts where it says);
  * a and b enter the 5 % band (the issue) and stay in it, within 1 s of
    the ramp's start (the issue's limit for Figs. 5.11-5.12,
    fabbri2022_kf.PAPER_KF.rls_time), and not at once (> 0: the start is
    outside);
  * the last 0.3 s mean of each within the band, both sides;
  * the health flag `rls_ok` is 0 before the RLS's first update and 1 at
    the end.
Non-convergence forced: the rotor held still (no excitation: the RLS never
updates) and a machine of p = 0.01 (b below what the covariance floor
resolves): `rls_ok` stays 0.

Fixed seeds 1, 2, 3 of `fluxdrive machines draw --kind star` in CI, from the
+50 % start only (both on the presets and the issue's machine); more seeds
with FLUXDRIVE_RLS_SEEDS="4 5 6", both starts on drawn machines with
FLUXDRIVE_RLS_FULL=1. Prints the table docs/results-fabbri2022.md quotes
(`pytest -s`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import machines as mach
from fluxdrive.fabbri2022_kf import PAPER_KF, sigma_of
from fluxdrive.paper_report import run

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")

RPM = math.pi / 30.0
BAND = 0.05  # issue 23 point 5
T_STEP = 0.15  # s: the imposed speed reaches its value
T_RAMP = 0.12  # s: it starts (the alignment has ended): the times count from here
DURATION = 1.2  # s: the 1 s bound from the ramp's start, and the last 0.3 s
OFF = 0.5  # the +-50 % starts
# rls_p_min scaled to the declared noise (at least the default 1e-9): the
# floor gain k = p_min / (p_min + sigma^2) sets both the RLS's time constant
# (1 / k updates) and b's spread, about sqrt(k / 2) sigma; k = 0.01 keeps
# three of those within half the band on the noisiest drawn machine (seed 2:
# sigma / |b| = 0.083) and the time constant at 100 updates (19 ms). With
# 1e-9 at 0.06 V (k = 1.2e-4) the estimate keeps the start's transient for
# seconds (docs/dfc.md, tuning notes)
P_MIN_RATIO = 0.01
SEEDS = [1, 2, 3]
ISSUE = {"preset": "fabbri2022_t51", "pole_pairs": 4, "rs": 1.2, "ld": 1.35e-3, "lq": 0.65e-3}
# the star-point presets (sil/runner/presets.c): ld, lq, star_m0, star_m2 and
# rated speed [rpm]
PRESETS = {
    "fabbri2022_t51": (394e-6, 475e-6, 20e-6, -48.54e-6, 1500.0),
    "fabbri2022_fig33": (421.5e-6 * 1.15, 421.5e-6 * 0.85, 20.7e-6,
                         0.15 * 421.5e-6 - 0.5 * 103.3e-6, 1500.0),
    "fabbri2022_ebike": (103e-6, 149e-6, 6e-6, -21.42e-6, 200.0),
}


def plant_ab(ld: float, lq: float, m0: float, m2: float) -> tuple[float, float]:
    """(3.7) as the plant computes it (plant_aniso_ab)."""
    l0, l2 = 0.5 * (ld + lq) + m0, (ld - lq) - 2.0 * m2
    g0, g2 = l0 - m0, 0.5 * l2 + m2
    k = (l2 - m2) / (3.0 * (g0 * g0 - g2 * g2))
    return g0 * k, g2 * k


def machines() -> list[tuple[str, dict, dict, float, float]]:
    """(label, machine section, other sections, rated rpm, noise [V])."""
    out = [(n, {"preset": n}, {}, v[4], 0.002) for n, v in PRESETS.items()]
    # the machine of the issue: p = +0.35, 4 pole pairs, the rest Table 5.1's
    out.append(("issue 23 (p +0.350)", dict(ISSUE), {}, 1500.0, 0.002))
    extra = [int(s) for s in os.environ.get("FLUXDRIVE_RLS_SEEDS", "").split()]
    for seed in SEEDS + extra:
        d = mach.draw("star", seed)
        sec = {k: v for k, v in d.sections.items() if k != "machine"}
        out.append((f"star seed {seed} (p {d.rated['star_p']:+.3f})", dict(d.sections["machine"]),
                    sec, d.rated["n_rpm"], d.rated["star_noise"]))
    return out


def true_ab(m: dict) -> tuple[float, float]:
    ld, lq, m0, m2, _ = PRESETS.get(m.get("preset"), (0, 0, 0, 0, 0))
    m0, m2 = m.get("star_m0", m0), m.get("star_m2", m2)
    ld, lq = m.get("ld", ld), m.get("lq", lq)
    return plant_ab(ld, lq, m0, m2)


def scenario(m: dict, sec: dict, noise: float, rpm: float, fa: float, fb: float, theta0: float,
             seed: int, duration: float = DURATION) -> tuple[dict, float, float]:
    sc = json.loads((REPO_ROOT / "sil" / "scenarios" / "fabbri_speed.json").read_text())
    sc.update({k: v for k, v in sec.items()})
    a0, b0 = true_ab(m)
    sc["name"] = "RLS of a, b from a +-50 % start (issue 23 point 5)"
    sc["machine"] = m
    sc["duration"] = duration
    sc["sensors"] = {**sc["sensors"], "star_noise": noise, "seed": seed}
    sc["mechanics"] = {**sc.get("mechanics", {}), "mode": "imposed", "theta0": theta0,
                       "speed": [{"type": "ramp", "t0": 0.12, "t1": T_STEP, "value": rpm * RPM}]}
    sc["mechanics"].pop("speed0", None)
    sigma = max(sigma_of(noise), 5e-5)
    ctl = {**sc["controller"], "law": "foc", "mode": "torque", "pos_source": "ivd+kf+rls",
           "dfc_iter": 1, "align_time": 0.1, "dfc_sigma": sigma,
           "dfc_a": a0 * fa, "dfc_b": b0 * fb, "rls_w_min": 20.0,
           "rls_p_min": max(1e-9, P_MIN_RATIO * sigma * sigma)}
    ctl.setdefault("align_current", 1.0)
    sc["controller"] = ctl
    sc["references"] = {"torque": {"terms": [{"type": "const", "value": 0.0}]}}
    return sc, a0, b0


def measure(lg, a0: float, b0: float) -> dict:
    t, a, b = lg["t"], lg["rls_a"] / a0 - 1.0, lg["rls_b"] / b0 - 1.0
    bad = (np.abs(a) > BAND) | (np.abs(b) > BAND)
    t_in = float(t[np.nonzero(bad)[0][-1]] - T_RAMP) if bad.any() else 0.0
    if bad[-1]:
        t_in = math.inf
    m = t >= t[-1] - 0.3
    ok = lg["rls_ok"]
    first_ok = float(t[np.argmax(ok > 0.5)]) if (ok > 0.5).any() else math.inf
    # the angle's error, the polarity aside (on 2 theta, halved), last 0.3 s
    e2 = np.angle(np.exp(2j * (lg["theta_e_est"][m] - lg["theta_e"][m]))) / 2.0
    return {"t_in": t_in, "a_end": float(np.mean(a[m])), "b_end": float(np.mean(b[m])),
            "ang_sd": float(np.degrees(np.std(e2))),
            "a_start": float(a[0]), "b_start": float(b[0]), "ok_end": float(ok[-1]),
            "first_ok": first_ok, "faults": [], "ok_before": float(np.max(ok[t < 0.1]))}


def cases() -> list[tuple]:
    out = []
    ms = machines()
    k = 0
    full = os.environ.get("FLUXDRIVE_RLS_FULL", "") == "1"
    for label, m, sec, n_rated, noise in ms:
        for rpm in (100.0, 300.0):
            r = min(rpm, 0.6 * n_rated)
            a0, b0 = true_ab(m)
            starts = 2 if (full or not label.startswith("star seed")) else 1
            # a -50 %, b +50 %: b held at 0.45 |a| where 1.5 |b| breaks Theorem 1's
            # |b/a| < 1/2 for the configured start (dfc_check refuses it)
            fb2 = min(1 + OFF, 0.45 * (1 - OFF) * abs(a0 / b0))
            for fa, fb in ((1 + OFF, 1 - OFF), (1 - OFF, fb2))[:starts]:
                theta0 = 2.0 * math.pi * ((0.37 * k) % 1.0)  # over the whole turn
                out.append((label, m, sec, noise, r, fa, fb, theta0, k + 1))
                k += 1
    return out


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> list[tuple]:
    out = tmp_path_factory.mktemp("rls")

    def one(c):
        label, m, sec, noise, rpm, fa, fb, theta0, seed = c
        sc, a0, b0 = scenario(m, sec, noise, rpm, fa, fb, theta0, seed)
        r = run(REAL_SIL, sc, out, f"rls_{seed}")
        res = measure(r.log, a0, b0)
        res["faults"] = r.summary.get("faults_seen", [])
        return c, a0, b0, res

    with ThreadPoolExecutor(2) as ex:
        rows = list(ex.map(one, cases()))
    print("\n| machine | speed | start a, b | into the 5 % band (from the ramp's start) | "
          "a, b: last 0.3 s | rls_ok from | angle error sD |")
    print("|---|---|---|---|---|---|---|")
    for c, a0, b0, res in rows:
        print(f"| {c[0]} | {c[4]:.0f} rpm | {c[5] - 1:+.0%}, {c[6] - 1:+.0%} | "
              f"{res['t_in']:.3f} s | {res['a_end']:+.2%}, {res['b_end']:+.2%} | "
              f"{res['first_ok']:.2f} s | {res['ang_sd']:.2f} deg |")
    return rows


def test_rls_enters_band_and_stays(results):
    for c, a0, b0, res in results:
        lab = (c[0], c[4], c[5], c[6])
        assert res["faults"] == [], lab
        assert abs(res["a_start"] - (c[5] - 1)) < 1e-3 and abs(res["b_start"] - (c[6] - 1)) < 1e-3
        assert 0.0 < res["t_in"] < PAPER_KF.rls_time, (lab, res)
        assert -BAND < res["a_end"] < BAND and -BAND < res["b_end"] < BAND, (lab, res)


def test_rls_ok_flag_on_convergence(results):
    """0 before the RLS's first update (alignment, standstill), 1 at the end
    of every converging case."""
    for c, a0, b0, res in results:
        assert res["ok_before"] == 0.0, c[0]
        assert res["ok_end"] == 1.0, (c[0], c[4], res)
        assert res["first_ok"] > T_STEP - 0.05, (c[0], res)


@pytest.mark.parametrize("case", ["standstill", "p_small"])
def test_rls_ok_flag_without_convergence(case, tmp_path):
    """The RLS cannot converge: held still (no update: the estimates stay
    50 % off), or p = 0.002 on the Fig. 3.3 motor (b = 0.002 a: the floor
    rls_p_min leaves b a spread beyond the band: sqrt(2 p_min) > 0.05 b).
    rls_ok never 1; the same machine at p = 0.35 (or turning at 300 rpm)
    sets it (the flag is not simply off)."""
    m = {"preset": "fabbri2022_fig33", "star_p": 0.002 if case == "p_small" else 0.35}
    g0 = 421.5e-6  # Fig. 3.3's L0 - M0 (presets.c): ld, lq = g0 (1 +- p)
    l2 = 103.3e-6
    p = m["star_p"]
    m2 = p * g0 - 0.5 * l2
    a0, b0 = plant_ab(g0 * (1 + p), g0 * (1 - p), 20.7e-6, m2)
    rpm = 0.0 if case == "standstill" else 300.0
    sc, _, _ = scenario(m, {}, 0.002, max(rpm, 1e-9), 1 + OFF, 1 - OFF, 1.0, 7, duration=1.0)
    sc["controller"].update({"dfc_a": a0 * (1 + OFF), "dfc_b": b0 * (1 - OFF)})
    if case == "standstill":
        sc["mechanics"]["speed"] = [{"type": "const", "value": 0.0}]
    r = run(REAL_SIL, sc, tmp_path, f"rls_{case}")
    lg = r.log
    print(f"\n{case}: p {p}, rls_ok max {lg['rls_ok'].max():.0f}, a, b at the end "
          f"{lg['rls_a'][-1] / a0 - 1:+.2%}, {lg['rls_b'][-1] / b0 - 1:+.2%}")
    assert r.summary.get("faults_seen", []) == []
    assert lg["rls_ok"].max() == 0.0
    sc2 = json.loads(json.dumps(sc))
    if case == "p_small":
        sc2["machine"]["star_p"] = 0.35
        a1, b1 = plant_ab(g0 * 1.35, g0 * 0.65, 20.7e-6, 0.35 * g0 - 0.5 * l2)
    else:
        a1, b1 = a0, b0
        sc2["mechanics"]["speed"] = [{"type": "ramp", "t0": 0.12, "t1": T_STEP,
                                      "value": 300.0 * RPM}]
    sc2["controller"].update({"dfc_a": a1 * (1 + OFF), "dfc_b": b1 * (1 - OFF)})
    lg2 = run(REAL_SIL, sc2, tmp_path, f"rls_{case}_ref").log
    assert lg2["rls_ok"][-1] == 1.0
