"""Issue 23, point 17: the decoupled DFVC's stationary (DC) alpha-beta
current at light load (docs/faults.md, "Still open").

The run: the Table 5.1 motor in speed control at 500 rpm on the encoder,
36 V link, 0.5 us dead time, switching inverter model, no load but the
friction (the encoder run of `fluxdrive fabbri2022`'s law cases,
fluxdrive.fabbri2022_kf.law_step_run without its brake steps). Measured on
the full-rate log against the plant's phase currents, over whole electrical
revolutions of the plant's angle from 0.6 s (the ramp ends by 0.5 s).

Bound: 3 % of i_max (0.085 A on the preset's 2.83 A): a healthy machine in
steady rotation carries no stationary current (FOC on the same run: the
reference, asserted below the same bound), and 3 % of i_max is a twentieth
of the 0.75 A found and below the phase check's 0.05 i_max of mean current.
The decoupled DFVC fails it (0.74 A): strict xfail until the defect is
fixed, so that the fix turns this file red until the mark is removed.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import fabbri2022_kf as kf
from fluxdrive.paper_report import run

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")

V_DC = 36.0
DEAD_TIME = 5e-7
T_FROM = 0.6  # s
I_MAX = 2.0 * np.sqrt(2.0)  # the preset's i_rated * sqrt 2 (sil/runner/presets.c)
BOUND = 0.03 * I_MAX


def scenario(law: str) -> dict:
    sc = kf.speed_sc(REPO_ROOT, "encoder", 500.0, 0.002)
    sc["name"] = f"{law}, Table 5.1 motor, 500 rpm, light load, {V_DC:g} V"
    sc["machine"] = {"preset": "fabbri2022_t51"}
    sc["controller"]["law"] = law
    sc["controller"]["align_time"] = 0.0
    sc["controller"]["v_dc_max"] = 1.5 * V_DC
    sc["dc_link"] = {"voltage": V_DC}
    sc["sensors"]["v_full_scale"] = 2.0 * V_DC
    sc["sensors"]["star_full_scale"] = 13.0 * V_DC / kf.V_DC
    sc["inverter"].update({"model": "switching", "dead_time": DEAD_TIME})
    sc["duration"] = 1.1
    return sc


def stationary_current(lg) -> tuple[int, float]:
    """(whole electrical revolutions, |mean alpha-beta current| over them [A])"""
    m = lg["t"] >= T_FROM
    u = np.unwrap(lg["theta_e"][m])
    n = int(np.floor(abs(u[-1] - u[0]) / (2.0 * np.pi)))
    k = np.abs(u - u[0]) < n * 2.0 * np.pi
    ia, ib, ic = (lg[c][m][k] for c in ("i_a", "i_b", "i_c"))
    alpha = (2.0 * ia - ib - ic) / 3.0
    beta = (ib - ic) / np.sqrt(3.0)
    return n, float(np.hypot(np.mean(alpha), np.mean(beta)))


@pytest.fixture(scope="module")
def dc(tmp_path_factory):
    out = tmp_path_factory.mktemp("dfvc_dc")
    res = {}
    for law in ("foc", "dfvc_decoupled"):
        r = run(REAL_SIL, scenario(law), out, law)
        assert r.summary.get("faults_seen", []) == [], (law, r.summary.get("faults_seen"))
        res[law] = stationary_current(r.log)
        print(f"{law}: {res[law][0]} revolutions, stationary current {res[law][1]:.4f} A "
              f"(bound {BOUND:.4f} A)")
    return res


def test_foc_reference_has_no_stationary_current(dc):
    n, i_dc = dc["foc"]
    assert n >= 30
    assert i_dc < BOUND


@pytest.mark.xfail(strict=True, reason="issue 23 point 17: decoupled DFVC carries ~0.75 A of "
                   "stationary current here (docs/faults.md, Still open)")
def test_decoupled_dfvc_has_no_stationary_current(dc):
    n, i_dc = dc["dfvc_decoupled"]
    assert n >= 30
    assert i_dc < BOUND
