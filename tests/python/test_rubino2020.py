"""Acceptance of the deadbeat DFVC issue: Rubino et al. 2020 reproduced in SIL.

Runs every sil/scenarios/rubino_*.json once (switching-level inverter with
1 us dead time, 12-bit ADC, 4096-count encoder) through fluxdrive-sil,
logging every sample (`--decimate 1`), and asserts the paper's figures.
`fluxdrive rubino2020` prints the same numbers as a table
(docs/results-rubino2020.md).

Every limit comes from the paper (`rb.PAPER`, Table I and section IV) and
the plant's true machine and DC link, never from what the drive prints: the
capability the flux-weakening tests compare with is that of the plant's
machine under i_max = 2.5 sqrt(2) A, v_s,max = v_dc / sqrt(3) and
delta_max = 80 deg. Each bound states its source next to it.

FLUXDRIVE_RUBINO_SCENARIOS=DIR runs the suite on the rubino_*.json of DIR
instead (deliberate breaks: scripts/rubino-breaks.py).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import rubino2020 as rb

P = rb.PAPER
SCENARIO_DIR = Path(os.environ.get("FLUXDRIVE_RUBINO_SCENARIOS") or REPO_ROOT / "sil" / "scenarios")

# ---------------------------------------------------------------- tolerances
# The ADC resolves 2 x 17.7 A over 12 bits: 8.6 mA a step. The current bound
# allows 4 steps (35 mA, 1 % of i_max): quantisation plus the extremes of the
# 3 mA rms current noise over ~45 000 samples (4.5 sigma = 14 mA).
I_TOL = 0.01
# One encoder count is 360 deg * 21 / 4096 = 1.85 electrical degrees: the
# resolution of the rotor angle the drive works with.
ENC_COUNT_DEG = 360.0 * P.pole_pairs / 4096
# Settling band of the small step: 5 % of it (0.05 N m), above the residual
# switching ripple (0.014 N m rms at 10 N m, 100 rpm).
STEP_BAND = 0.05
# Band of the deadbeat claim (n_ref): 2 % of the reference.
REF_BAND = 0.02
# The 1 kHz PI loop's time constant in samples: tau = 1/(2 pi 1 kHz) = 2.55 Ts.
TAU_PI = 1.0 / (2 * np.pi * P.pi_bw_hz * P.ts)


class _Lazy(Mapping):
    """The runs (or metrics) of the nine scenarios, keyed as rb.SCENARIOS,
    each computed on first use and kept for the module: a test runs only
    the scenarios it reads (the whole module runs all nine, once each;
    scripts/mutation_check.py runs single tests)."""

    def __init__(self, make):
        self._make, self._done = make, {}

    def __getitem__(self, key):
        if key not in rb.SCENARIOS:
            raise KeyError(key)
        if key not in self._done:
            self._done[key] = self._make(key)
        return self._done[key]

    def __iter__(self):
        return iter(rb.SCENARIOS)

    def __len__(self):
        return len(rb.SCENARIOS)

    def complete(self) -> bool:
        return len(self._done) == len(rb.SCENARIOS)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    if not REAL_SIL.is_file():
        pytest.skip(f"fluxdrive-sil not built ({REAL_SIL})")
    out = tmp_path_factory.mktemp("rubino")
    runs = _Lazy(lambda key: rb.run(REAL_SIL, SCENARIO_DIR / rb.SCENARIOS[key], out))
    met = _Lazy(lambda key: rb.metrics(key, runs[key]))
    yield runs, met
    if met.complete():
        print("\n" + rb.report(dict(met)))


def test_plant_is_the_paper_machine(results):
    """The capability is computed from the plant's machine: it must be the
    Table I machine, on the paper's DC link (section IV.A: about 310 V)."""
    runs, _ = results
    for key, r in runs.items():
        m = rb.plant_machine(r.config)
        assert (m.pole_pairs, m.rs, m.ld, m.lq, m.lambda_m) == pytest.approx(
            (P.pole_pairs, P.rs, P.ls, P.ls, P.lambda_m)), key
        assert r.config["v_dc"] == pytest.approx(P.v_dc), key
        assert r.config["ts"] == pytest.approx(P.ts), key
        # every sample logged
        assert np.median(np.diff(r.log["t"])) == pytest.approx(P.ts), key


def test_torque_step_deadbeat(results):
    """Fig. 21: the DB-DFVC meets the 10 -> 11 N m target in one sampling
    period. Counted from the first ISR that sees the step (k): the voltage
    computed at k acts over [k+1, k+2), so the target can be met at k+2."""
    _, met = results
    db = met["step_db"]
    f1, f2, f3 = db.frac
    # nothing moves before the new voltage acts (band: the settling band)
    assert abs(f1) <= STEP_BAND, db
    # one beat gives what v_dc/sqrt(3) allows over one period (model from the
    # paper's machine, frac_vlim), to within the settling band, and no more
    # than the step plus the band
    assert min(1.0, db.frac_vlim) - STEP_BAND <= f2 <= 1.0 + STEP_BAND, db
    # the next beat completes it
    assert 1.0 - STEP_BAND <= f3 <= 1.0 + STEP_BAND, db
    # torque and i_qs within 2 % of their references at k+2
    assert db.n_ref <= 2, db
    # transient over at k+3 (around the response's own final value; against
    # the reference: test_step_settles_on_the_reference)
    assert db.n_final <= 3, db


def test_torque_step_pi(results):
    """Fig. 22: the PI-DFVC (1 kHz, feed-forward) needs eleven sampling
    periods; ours counts from the ISR that sees the step, one more (12).
    Band: +-4 samples, 1.5 time constants of the 1 kHz loop (tau = 2.55 Ts)."""
    _, met = results
    db, pi = met["step_db"], met["step_pi"]
    lo, hi = P.pi_step_samples + 1 - 1.5 * TAU_PI, P.pi_step_samples + 1 + 1.5 * TAU_PI
    assert lo <= pi.n_final <= hi, (pi, lo, hi)
    assert pi.n_final >= 3 * db.n_final, (db, pi)
    # and behind the deadbeat at k+2
    assert pi.frac[1] < db.frac[1], (db, pi)


def test_step_settles_on_the_reference(results):
    """Settling against the torque reference, not the measured final value:
    within 5 % of the step (0.05 N m) from k+3 on (DB, Fig. 21: one period),
    from sample 12 + 4 on (PI, Fig. 22); the reversal (Fig. 13: "zero
    steady-state error") within the same 0.05 N m."""
    _, met = results
    db, pi, rv = met["step_db"], met["step_pi"], met["reversal"]
    failures = []
    if db.n_settle > 3:
        failures.append(f"DB settles at k+{db.n_settle} (static error {db.static_err:+.3f} N m)")
    if pi.n_settle > P.pi_step_samples + 1 + 1.5 * TAU_PI:
        failures.append(f"PI settles at k+{pi.n_settle} (static error {pi.static_err:+.3f} N m)")
    if abs(rv.static_err) > STEP_BAND * abs(db.step):
        failures.append(f"reversal static error {rv.static_err:+.3f} N m")
    assert not failures, failures


def test_torque_step_deadbeat_32khz(tmp_path):
    """The Fig. 21 step with the PWM and ISR at 32 kHz (issue 24), counted
    in samples of the 31.25 us period. One period of v_dc/sqrt(3) now gives
    about 0.4 of the 1 N m step (model frac_vlim), so the paper's "one
    sampling period" becomes: the first beat takes what the voltage allows,
    and the target is met as soon as the voltage-limited rise of the
    paper's machine can (n_rise_vlim periods, model from the true state at
    k+1), with the 16 kHz test's bands and no overshoot beyond them."""
    if not REAL_SIL.is_file():
        pytest.skip(f"fluxdrive-sil not built ({REAL_SIL})")
    path = SCENARIO_DIR / rb.SCENARIO_32K
    if not path.is_file():
        path = REPO_ROOT / "sil" / "scenarios" / rb.SCENARIO_32K
    r = rb.run(REAL_SIL, path, tmp_path)
    assert r.config["ts"] == pytest.approx(rb.TS_32K)
    assert np.median(np.diff(r.log["t"])) == pytest.approx(rb.TS_32K)
    assert not r.summary.get("faults_seen"), r.summary.get("faults_seen")
    db = rb.step_metrics(r.log, 0.1, v_dc=float(r.config["v_dc"]), ts=rb.TS_32K)
    f1, f2, _ = db.frac
    assert abs(f1) <= STEP_BAND, db
    assert min(1.0, db.frac_vlim) - STEP_BAND <= f2 <= 1.0 + STEP_BAND, db
    # voltage-limited: more than one period is needed (else this case would
    # not test the limit), and the drive needs no more than the model
    assert db.n_rise_vlim > 2, db
    assert db.n_ref <= db.n_rise_vlim, db
    assert db.n_settle <= db.n_rise_vlim and db.n_final <= db.n_rise_vlim, db
    assert db.overshoot_step <= STEP_BAND, db
    assert abs(db.static_err) <= STEP_BAND * abs(db.step), db


def test_torque_reversal(results):
    """Figs. 12-13: -20 -> +20 N m at 100 rpm in the shortest possible rise
    time, no overshoot, flux amplitude unchanged."""
    _, met = results
    rv = met["reversal"]
    # shortest rise: the model's minimum-time path at constant flux amplitude
    # with |v| <= v_dc/sqrt(3) (n_rise_vlim); -1 sample for the model's
    # Euler step, +10 % for the dead time (1 us of 62.5 us, 5 V of the
    # ~135 V left over the back-EMF)
    assert rv.n_rise_vlim - 1 <= rv.n_rise <= 1.1 * rv.n_rise_vlim, rv
    # and stays within 2 % of the reference after that
    assert rv.n_ref <= 1.1 * rv.n_rise_vlim, rv
    # no overshoot beyond the 2 % band
    assert rv.overshoot <= REF_BAND, rv
    # flux unchanged: within 2 % (a 2 % flux error is a 2 % torque error)
    assert rv.flux_dev <= REF_BAND, rv


def test_fw_current_limit(results):
    """Fig. 14: the current limit (25), i_max = 2.5 sqrt(2) A (Table I),
    holds at every sample, and the drive uses it where the capability is
    current-limited (between base speed and MTPV entry, 50 rpm clear)."""
    _, met = results
    fw = met["fw"]
    assert fw.current_max <= P.i_max * (1 + I_TOL), (fw.current_max, P.i_max)
    assert fw.current_lim_min >= P.i_max * (1 - I_TOL), (fw.current_lim_min, P.i_max)
    assert not fw.faults


def test_fw_load_angle_limit(results):
    """Fig. 14: delta_max = 80 deg holds in MTPV and is reached there.
    Mean over 8 ms: within one encoder count (1.85 deg) of 80 deg above
    the MTPV entry (+50 rpm). Every sample: below 80 deg + 2 counts (one
    count of angle error, one of noise: with an ideal encoder the 3 mA rms
    current noise gives 0.46 deg rms, 4 sigma = 1.84 deg)."""
    _, met = results
    fw = met["fw"]
    assert fw.delta_max_deg <= P.delta_max_deg + 2 * ENC_COUNT_DEG, fw.delta_max_deg
    assert fw.delta_mtpv_min_deg >= P.delta_max_deg - ENC_COUNT_DEG, fw.delta_mtpv_min_deg
    assert fw.delta_mtpv_max_deg <= P.delta_max_deg + ENC_COUNT_DEG, fw.delta_mtpv_max_deg


# Torque against the true capability: at most 2 % above (1 % current
# resolution, as I_TOL, + 1 % for the torque's static error, 0.7 % measured
# at 20 N m), at least 97 % (1 % current resolution + 1.6 % of the voltage
# that the 1 us dead time takes from a 62.5 us period).
CAP_HI, CAP_LO = 1.02, 0.97


def test_fw_torque_not_above_capability(results):
    """Fig. 14: the torque never exceeds what the machine allows under the
    paper's limits; flux-weakening ratio 1:5; constant power in MTPV."""
    runs, met = results
    fw = met["fw"]
    assert fw.top_ratio <= CAP_HI, (fw.top_ratio, fw.top_ratio_rpm)
    # flux-weakening ratio: the paper's 1:5 (Fig. 14) is the model's 1:4.52
    # within its one significant figure; the SIL within 5 % of the model
    # (flux ripple 0.8 % rms at 1200 rpm, base-speed flux read off a ramp)
    assert abs(fw.fw_ratio / fw.fw_ratio_model - 1.0) <= 0.05, (fw.fw_ratio, fw.fw_ratio_model)
    assert abs(fw.fw_ratio_model / P.fw_ratio - 1.0) <= 0.10, fw.fw_ratio_model
    # at least the paper's 600 W (the model has no iron or mechanical losses)
    assert fw.power_top >= P.fw_power_w, fw.power_top
    # constant power in the MTPV region: within 5 % between 700 and 1195 rpm
    log = runs["fw"].log
    rpm = log["speed"] / rb.RPM
    k = np.ones(128) / 128  # 8 ms
    p = np.convolve(log["torque"], k, mode="same") * log["speed"]
    hi = (rpm > 700) & (rpm < 1195)
    assert np.min(p[hi]) >= 0.95 * np.median(p[hi])


def test_fw_torque_reaches_capability(results):
    """Fig. 14: maximum torque at every speed, to within 3 % of the
    capability under v_s,max = v_dc/sqrt(3) (section III, (23))."""
    _, met = results
    fw = met["fw"]
    assert fw.worst_ratio >= CAP_LO, (fw.worst_ratio, fw.worst_ratio_rpm)
    assert fw.power_top >= CAP_LO * fw.power_top_model, (fw.power_top, fw.power_top_model)


def test_detuning_stable_with_power_loss(results):
    """Figs. 19-20: L_s x1.2 and lambda_m x0.8 stay stable and lose power
    in MTPV: "near to 17 %" (600 W -> 500 W, Fig. 19; lambda_m: "similar").
    The watts are read off a figure: +-25 W each gives 8 % to 26 %."""
    runs, met = results
    fw = met["fw"]
    p0, p1 = P.detuned_power_w
    lo, hi = (p0 - p1 - 50) / (p0 + 25), (p0 - p1 + 50) / (p0 - 25)
    for key in ("fw_ls120", "fw_lm080"):
        d = met[key]
        assert not d.faults, (key, d.faults)
        # the current limit holds on the true current (the ADC is not detuned)
        assert d.current_max <= P.i_max * (1 + I_TOL), (key, d.current_max)
        # the load angle stays below the limit (Fig. 19: 55 deg)
        assert d.delta_max_deg <= P.delta_max_deg + 2 * ENC_COUNT_DEG, (key, d.delta_max_deg)
        loss = 1.0 - d.power_top / fw.power_top
        assert lo <= loss <= hi, (key, loss, lo, hi)
        # and it keeps producing motoring torque all the way to 1200 rpm
        log = runs[key].log
        top = log["speed"] > 1100 * rb.RPM
        assert np.min(log["torque"][top]) > 0.5 * d.power_top / (P.speed_max_rpm * rb.RPM)


def test_torque_bandwidth_1500hz(results):
    """Figs. 23-24: DB follows 0.5 N m at 1.5 kHz; reference, prediction and
    observation one period apart (lag 2 samples: computation delay + one
    beat); the PI-DFVC does not follow."""
    _, met = results
    db, pi = met["bw_db"], met["bw_pi"]
    # +-10 %: 0.05 N m of the 0.5 N m amplitude; +-0.05 sample: the
    # resolution of the sine fit on a rippled signal
    assert 0.9 <= db.ratio <= 1.1, db
    assert 1.95 <= db.lag <= 2.05, db
    assert not (0.9 <= pi.ratio <= 1.1 and 1.95 <= pi.lag <= 2.05), pi


def test_speed_control_0_to_1200(results):
    """Fig. 18: 0 -> 1200 rpm, acceleration limited at 1200 rpm/s, no
    overshoot."""
    _, met = results
    sp = met["speed"]
    assert not sp.faults
    # no overshoot: 1 % (12 rpm), the band t_reach uses
    assert sp.overshoot <= 0.01, sp
    # the acceleration limit, over 50 ms: +5 % (the 1 kHz ramp starts with a
    # 1.2 rpm step, 2 % of 50 ms at 1200 rpm/s, and the PI catches up)
    assert sp.accel_max <= 1.05 * P.accel_rpm_s, sp
    # within 1 % of 1200 rpm: not before the ramp allows (5 ms: the speed
    # loop's lead), at most 0.1 s after it ("about 1 s", Fig. 18)
    assert sp.t_reach_min - 0.005 <= sp.t_reach <= sp.t_reach_min + 0.1, sp


def test_flux_weakening_ramp_full_voltage(tmp_path):
    """The ramp of Fig. 14 with the paper's v_s,max = v_dc/sqrt(3) in (23)
    (v_margin 1): no voltage headroom is left for the q_s deadbeat (33).
    With (23) evaluated at i_qs(tau) only, a lagging i_qs raised the flux
    reference and the drive lost torque control from ~280 rpm without a
    fault (load angle -169 deg, 5.65 A). (23) at the limited i_qs* restores
    i_qs through Rs (dfvc_refs.h): bounded, motoring, limits held."""
    if not REAL_SIL.is_file():
        pytest.skip(f"fluxdrive-sil not built ({REAL_SIL})")
    sc = json.loads((REPO_ROOT / "sil" / "scenarios" / rb.SCENARIOS["fw"]).read_text())
    sc["controller"]["v_margin"] = 1.0
    path = tmp_path / "rubino_fw_ramp_margin1.json"
    path.write_text(json.dumps(sc))
    r = rb.run(REAL_SIL, path, tmp_path)
    fw = rb.ramp_metrics(r)
    assert not fw.faults
    # the paper's limits (Table I, section IV.B.3), as test_fw_current_limit
    # and test_fw_load_angle_limit; not the drive's printed configuration
    assert fw.delta_max_deg <= P.delta_max_deg + 2 * ENC_COUNT_DEG, fw.delta_max_deg
    assert fw.current_max <= P.i_max * (1 + I_TOL), (fw.current_max, P.i_max)
    # zero headroom: i_qs lags i_qs* by (unmodelled voltage) / Rs at the
    # flux-weakening knee (about 10 % of torque near 300 rpm), not more
    assert fw.worst_ratio >= 0.85, (fw.worst_ratio, fw.worst_ratio_rpm)
    assert fw.power_top >= 700.0, fw.power_top
