"""Acceptance of the sensorless drive on the star point (Fabbri 2022 chapters
4-5.1, issue "Sensorless speed control: Kalman filter, EKF and RLS"), on the
full-rate logs of the SIL runs that `fluxdrive fabbri2022` reports
(docs/results-fabbri2022.md).

Limits come from the thesis or the issue (fluxdrive.fabbri2022_kf.PAPER_KF)
or the scenario (the plant's load, the preset's a and b of (3.7)), never from
what the drive prints; speed errors are taken against the reference, angles
and load torque against the plant.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import fabbri2022_kf as kf

P = kf.PAPER_KF

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")


@pytest.fixture(scope="module")
def res(tmp_path_factory) -> kf.ResultsKF:
    return kf.ResultsKF(REAL_SIL, REPO_ROOT, tmp_path_factory.mktemp("fabbri2022_kf"))


def test_noise_calibration(res):
    """The star noise reproduces the thesis's spread: the IVD's raw position
    error has half the DFC's at 100 rpm (interpolated; the grid brackets
    it, and the ratio grows with the noise)."""
    ratios = [i / d for _, d, i in res.cal[1]]
    assert all(b > a for a, b in zip(ratios, ratios[1:]))
    assert kf.NOISE_GRID[0] < res.noise < kf.NOISE_GRID[-1]


def test_table52_headline_and_no_fault(res):
    """Acceptance 1: every source holds the speed (no fault, the mean speed
    error within 0.5 % of the reference both ways), and IVD+KF's speed
    spread is at most half of DFC+KF's at both speeds (R_k = sigma^2); the
    filters use their R: 5 sigma^2 smooths DFC+KF at 500 rpm."""
    assert len(res.table) == 2 * (3 + 3 * 2)
    for r in res.table:
        assert r.faults == [], (r.source, r.rpm)
        assert abs(r.mean) < 0.005 * r.rpm, (r.source, r.rpm, r.mean)
        assert r.sd > 0.0
        # the angle the laws run on has no offset against the plant's (1
        # degree: the issue-11 bound of the Full IVD)
        assert abs(r.pos_mean) < 1.0, (r.source, r.rpm, r.pos_mean)
    for rpm, _ in P.table52_sd:
        dk, ik = res.sd("dfc+kf", rpm), res.sd("ivd+kf", rpm)
        assert ik.sd <= P.headline_ratio * dk.sd, (rpm, ik.sd, dk.sd)
        # the filter's position is better than the raw IVD's
        assert ik.pos_sd < res.sd("ivd", rpm).pos_sd
    assert res.sd("dfc+kf", 500.0, 5.0).sd < res.sd("dfc+kf", 500.0, 1.0).sd


def test_table52_headline_band_over_noise(tmp_path):
    """Issue 23, point 7: the headline IVD+KF sD <= 1/2 DFC+KF's rests on the
    calibrated star noise (0.0368 V, an assumption: the thesis prints
    none). At 500 rpm, R_k = 5 sigma^2 (the thesis's own 0.66 there), three
    noise seeds: it holds at the calibrated level for every seed, and not at
    0.06 V, where the doc (`fluxdrive fabbri2022 --noise-sweep`) says the
    band has ended; no fault at either. A drive that makes IVD+KF better
    beyond the band fails the second half: the doc's band is then stale."""
    rows = kf.noise_sweep(REAL_SIL, REPO_ROOT, tmp_path, noises=kf.SWEEP_CI, rpms=(500.0,),
                          r_scales=(5.0,))
    print(kf.sweep_report(rows, cal=kf.SWEEP_CI[0]))
    assert len(rows) == len(kf.SWEEP_CI) * len(kf.SWEEP_SEEDS)
    for r in rows:
        assert r.faults == [], (r.noise, r.seed, r.faults)
        if r.noise == kf.SWEEP_CI[0]:
            assert r.ratio <= P.headline_ratio, (r.noise, r.seed, r.ratio)
        else:
            assert r.ratio > P.headline_ratio, (r.noise, r.seed, r.ratio)


def test_rls_converges_from_30_percent(res):
    """Acceptance 2: a and b, started 30 % off, within 5 % of (3.7)'s values
    in under 1 s from the speed step at 500 rpm, and they stay there; the
    speed loop holds throughout; the faster RLS settles sooner and is
    noisier."""
    slow, fast = res.rls
    for r in res.rls:
        assert r.faults == []
        # started 30 % off (a up, b down), ended within the band, stayed there
        assert r.a[0] / r.a_true == pytest.approx(1 + P.rls_off, abs=1e-3)
        assert r.b[0] / r.b_true == pytest.approx(1 - P.rls_off, abs=1e-3)
        assert r.t_in < P.rls_time, (r.label, r.t_in)
        assert abs(r.a_mean / r.a_true - 1) < P.rls_tol and abs(r.b_mean / r.b_true - 1) < P.rls_tol
        assert abs(r.speed_mean - P.rls_rpm) < 0.005 * P.rls_rpm
    assert fast.t_in < slow.t_in
    assert fast.b_sd > slow.b_sd


def test_load_torque_estimate(res):
    """Acceptance 3: the load estimate behaves as the filter's own
    equations say it must (fabbri2022_kf.kf_load_response: the
    steady-state Kalman filter of (4.46)-(4.49) with the run's Q and R): the
    brake step settles on the plant's load (within 3 %) with the predicted
    90 % rise time (within 20 %: the estimate is noisy), IVD+KF the
    smoother (Fig. 5.13); the 10 Hz load comes through with the predicted
    gain (within 5 %) and delay (within 1 ms), and the raised Q_33 tracks
    it (gain within 5 % of 1)."""
    step_dfc, step_ivd, sine, sine_q = res.loads
    for r in (step_dfc, step_ivd):
        assert r.faults == []
        assert abs(r.err_mean) < 0.03 * P.brake, r.label
        assert abs(r.lag / r.pred_lag - 1.0) < 0.2, (r.label, r.lag, r.pred_lag)
    assert step_ivd.err_sd < step_dfc.err_sd
    for r in (sine, sine_q):
        assert r.faults == []
        assert abs(r.gain / r.pred_gain - 1.0) < 0.05, (r.label, r.gain, r.pred_gain)
        assert abs(r.lag - r.pred_lag) < 1e-3, (r.label, r.lag, r.pred_lag)
    assert abs(sine_q.gain - 1.0) < 0.05


def test_ebike_sensorless(res):
    """Acceptance 4: the Table 5.4 motor runs on IVD (4 iterations) + KF in
    speed control: no fault, speed within 1 % of the reference, angle
    within 2 degrees of the plant's."""
    e = res.ebike
    assert e.faults == []
    assert abs(e.speed_mean - e.rpm) < 0.01 * e.rpm
    assert abs(e.pos_mean) < 2.0 and e.pos_sd < 2.0


def test_laws_on_ivd_kf(res):
    """Acceptance 5: the decoupled DFVC and DB-DFVC in speed control at
    500 rpm on the IVD+KF position (36 V link) answer the brake steps with
    torque steps: no fault, the settled torque within 2 % of load and
    friction (the scenario's), the speed dip within 25 % (+ 3 rpm) of the
    encoder run's and back within 0.5 % in at most twice its time. On 24 V
    the window's halved voltage range is too small for the second step: the
    star-point runs trip with the PLL as with the filter, the encoder (no
    window) does not - the cause is the window, not the filter."""
    for law, _, _ in kf.LAW_CASES_KF:
        st, enc = res.law(law, "ivd+kf", 36.0), res.law(law, "encoder", 36.0)
        assert st.faults == [] and enc.faults == [], law
        assert res.law(law, "ivd", 36.0).faults == [], law
        for got, ld in zip(st.torque, st.load):
            assert abs(got / ld - 1.0) < 0.02, (law, got, ld)
        for d, de, b, be in zip(st.dip, enc.dip, st.recover, enc.recover):
            assert d < 1.25 * de + 3.0, (law, d, de)
            assert b < 2.0 * be, (law, b, be)
        assert res.law(law, "encoder", 24.0).faults == []
        assert "lost_control" in res.law(law, "ivd", 24.0).faults
        assert "lost_control" in res.law(law, "ivd+kf", 24.0).faults


@pytest.mark.parametrize("keys, field, why", [
    ({"pos_source": "ivd+kf+rls", "rls_p_min": 1e-3, "rls_p_max": 1e-5}, "controller.rls_p_min",
     "rls_p_min <= rls_p_max"),
    ({"pos_source": "ivd+kf", "kf_q_omega": -1.0}, "controller.kf_q_omega", "must be in"),
    ({"pos_source": "ekf", "dfc_sigma": 0.0}, "controller.dfc_sigma", "must be in"),
    ({"pos_source": "dfc+kf", "kf_r_sys": -1.0}, "controller.kf_r_sys", "must be in"),
    ({"pos_source": "ivd+kf+"}, "controller.pos_source", "ivd+kf+rls"),
])
def test_bad_filter_settings_are_refused(tmp_path, keys, field, why):
    """Bad input: the SIL refuses the scenario, naming the field (exit 2)."""
    import json
    import subprocess
    sc = json.loads((REPO_ROOT / "sil" / "scenarios" / "fabbri_speed.json").read_text())
    sc["controller"].update(keys)
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(sc))
    r = subprocess.run([str(REAL_SIL), str(p), "--print-config"], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2 and f"{field}: " in r.stderr and why in r.stderr, r.stderr
