"""Acceptance of the deadbeat DFVC issue: Rubino et al. 2020 reproduced in SIL.

Runs every sil/scenarios/rubino_*.json once (switching-level inverter with
1 us dead time, 12-bit ADC, encoder) through fluxdrive-sil and asserts the
paper's figures. `fluxdrive rubino2020` prints the same numbers as a table
(docs/results-rubino2020.md).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import rubino2020 as rb


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    if not REAL_SIL.is_file():
        pytest.skip(f"fluxdrive-sil not built ({REAL_SIL})")
    runs, met = rb.run_all(REAL_SIL, REPO_ROOT / "sil" / "scenarios", tmp_path_factory.mktemp("rubino"))
    print("\n" + rb.report(met))
    return runs, met


def test_torque_step_deadbeat_vs_pi(results):
    _, met = results
    db, pi = met["step_db"], met["step_pi"]
    # true torque and i_qs within 2 % of their references two samples after
    # the step: one sample of computation delay + one deadbeat beat
    assert db.n_ref <= 2, db
    assert db.overshoot <= 0.02, db
    # the PI-DFVC (1 kHz, feed-forward) settles several times slower
    assert pi.n_step >= 3 * db.n_step, (db, pi)


def test_torque_reversal(results):
    _, met = results
    rv = met["reversal"]
    assert rv.overshoot <= 0.02, rv
    assert rv.flux_dev <= 0.02, rv


def test_flux_weakening_ramp(results):
    runs, met = results
    fw = met["fw"]
    i_max = runs["fw"].config["controller"]["i_max"]
    # at least 90 % of what the current, voltage (with margin) and load-angle
    # limits allow, at every speed (capability from the machine model)
    assert fw.worst_ratio >= 0.90, fw.worst_ratio
    assert fw.delta_max_deg <= 80.0 + 2.0, fw.delta_max_deg
    # the limit holds to within the sampled-current ripple and ADC resolution
    # (full scale 17.7 A over 12 bits: 8.6 mA a step; 1 % = 35 mA)
    assert fw.current_max <= 1.01 * i_max, (fw.current_max, i_max)
    assert 4.0 <= fw.fw_ratio <= 6.0, fw.fw_ratio  # paper: about 1:5
    assert not fw.faults
    # constant power in the MTPV region: within 5 % between 700 and 1200 rpm
    log = runs["fw"].log
    rpm = log["speed"] * 30 / np.pi
    p = log["torque"] * log["speed"]
    hi = (rpm > 700) & (rpm < 1195)
    assert np.percentile(p[hi], 5) >= 0.95 * np.median(p[hi])


def test_detuning_stable_with_power_loss(results):
    runs, met = results
    fw = met["fw"]
    i_max = runs["fw"].config["controller"]["i_max"]
    for key in ("fw_ls120", "fw_lm080"):
        d = met[key]
        assert not d.faults, (key, d.faults)
        # stable: currents bounded (the controller's current estimate is
        # detuned too, so the true limit may be exceeded by the model error)
        assert d.current_max <= 1.1 * i_max, (key, d.current_max)
        loss = 1.0 - d.power_top / fw.power_top
        # MTPV torque limit underestimated -> less power (paper: about 17 %)
        assert 0.05 <= loss <= 0.35, (key, loss)
        # and it keeps producing motoring torque all the way to 1200 rpm
        log = runs[key].log
        top = log["speed"] > 1100 * np.pi / 30
        assert np.min(log["torque"][top]) > 0.5 * d.power_top / (1200 * np.pi / 30)


def test_torque_bandwidth_1500hz(results):
    _, met = results
    db, pi = met["bw_db"], met["bw_pi"]
    assert 0.9 <= db.ratio <= 1.1, db
    # two samples: computation delay + one beat; 0.05 sample is the
    # resolution of the sine fit on a rippled signal
    assert db.lag <= 2.05, db
    assert abs(pi.ratio - 1.0) > abs(db.ratio - 1.0), (db, pi)


def test_speed_control_0_to_1200(results):
    _, met = results
    sp = met["speed"]
    assert not sp.faults
    assert sp.overshoot <= 0.02, sp
    assert sp.t_reach < 1.3, sp  # 1 s of 1200 rpm/s ramp + settling


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
    i_max = r.config["controller"]["i_max"]
    assert not fw.faults
    assert fw.delta_max_deg <= 80.0 + 2.0, fw.delta_max_deg
    assert fw.current_max <= 1.01 * i_max, (fw.current_max, i_max)
    # zero headroom: i_qs lags i_qs* by (unmodelled voltage) / Rs at the
    # flux-weakening knee (about 10 % of torque near 300 rpm), not more
    assert fw.worst_ratio >= 0.85, (fw.worst_ratio, fw.worst_ratio_rpm)
    assert fw.power_top >= 700.0, fw.power_top
