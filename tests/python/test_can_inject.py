"""Issue 22 point 10 (a): the scenario's main-loop injections apply under
--can (docs/scenarios.md, "Commanded over CAN"): `inject.trip_at` posts its
fault at the time asked and `inject.cm_scale_*` writes the controller's
map error when its profile moves, as without CAN; only the references and
the enable / disable times are the CAN client's.

The run: the Varatharajan 2022 Fig. 14 rig (`sil/scenarios/
varatharajan_robustness.json`: decoupled DFVC on the syr_1k1 map at 300 rpm
on a dynamometer, 5 kHz), commanded over socketcand: the client enables
and asks 7.1 N m; cm_scale_q steps from 1.3 to 0.7 at 0.8 s, the trip
(`control`) at 1.3 s. The same scenario without CAN (its own torque ramp)
is the reference for the effect of the map error on the true torque.
"""

from __future__ import annotations

import json
import re
import select
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive.can import Drive

pytestmark = [
    pytest.mark.real_sil,
    pytest.mark.skipif(not REAL_SIL.is_file(), reason=f"fluxdrive-sil not built ({REAL_SIL})"),
]

NODE = 4
T_STEP, T_TRIP, DURATION = 0.8, 1.3, 1.6  # [s], simulated
CM_BEFORE, CM_AFTER = 1.3, 0.7
TORQUE = 7.1  # N m, the paper's T*


def scenario(tmp_path: Path) -> Path:
    sc = json.loads((REPO_ROOT / "sil" / "scenarios" / "varatharajan_robustness.json").read_text())
    sc["duration"] = DURATION
    sc["inject"] = {"cm_scale_d": 1.25,
                    "cm_scale_q": [{"type": "const", "value": CM_BEFORE},
                                   {"type": "step", "t": T_STEP, "value": CM_AFTER - CM_BEFORE}],
                    "trip_at": T_TRIP, "trip_cause": "control"}
    sc["log"] = {"decimation": 5}
    path = tmp_path / "can_inject.json"
    path.write_text(json.dumps(sc))
    return path


def run_without_can(sc: Path, tmp_path: Path) -> tuple[dict, np.ndarray]:
    log = tmp_path / "plain.npy"
    out = subprocess.run([str(REAL_SIL), str(sc), "--log", str(log)], capture_output=True, text=True,
                         timeout=120, check=True)
    return json.loads(out.stdout), np.load(log)


def run_over_can(sc: Path, tmp_path: Path) -> tuple[dict, np.ndarray, float, float]:
    """The client enables and commands TORQUE; reads cm_scale_q back before
    the step and after it (by the STATUS frames' simulated time)."""
    log = tmp_path / "can.npy"
    proc = subprocess.Popen([str(REAL_SIL), str(sc), "--can", "socketcand:0", "--realtime",
                             "--node", str(NODE), "--log", str(log)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([proc.stderr], [], [], 20.0)
        assert ready, "the SIL did not start"
        m = re.search(r"127\.0\.0\.1:(\d+)", proc.stderr.readline())
        assert m
        with Drive("vcan0", "socketcand", node=NODE, port=int(m.group(1)), reply_timeout=3.0) as drv:
            drv.heartbeat(0.05)
            assert drv.enable().value == 1.0
            assert drv.set_torque(TORQUE).value == pytest.approx(TORQUE, abs=0.01)
            drv.status(timeout=2.0)
            assert drv.frame_time("STATUS") < T_STEP - 0.2, "the client was too slow for the test"
            cm_before = drv.get_param("cm_scale_q")
            deadline = time.monotonic() + 10.0
            while (drv.frame_time("STATUS") or 0.0) < T_STEP + 0.1 and time.monotonic() < deadline:
                time.sleep(0.01)
            cm_after = drv.get_param("cm_scale_q")
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    print(err)
    assert proc.returncode == 0, err
    return json.loads(out), np.load(log), cm_before, cm_after


def torque_means(log: np.ndarray) -> tuple[float, float]:
    """Mean true torque over the 0.3 s before the step and before the trip."""
    t = log["t"]
    before = log["torque"][(t >= T_STEP - 0.3) & (t < T_STEP)].mean()
    after = log["torque"][(t >= T_TRIP - 0.3) & (t < T_TRIP)].mean()
    return float(before), float(after)


def test_trip_at_and_cm_scale_apply_over_can(tmp_path: Path):
    sc = scenario(tmp_path)
    ref, ref_log = run_without_can(sc, tmp_path)
    res, log, cm_before, cm_after = run_over_can(sc, tmp_path)
    slow = 5 / 5000.0  # the main-loop period (slow_div 5 at 5 kHz) [s]
    # the trip: posted by the main loop at the first period at or after
    # trip_at, taken by the ISR of that period; control alone
    print(f"first fault over CAN at {res['first_fault_t']:.5f} s ({res['faults']}), without CAN at "
          f"{ref['first_fault_t']:.5f} s (asked {T_TRIP} s)")
    assert T_TRIP <= res["first_fault_t"] <= T_TRIP + slow
    assert res["faults"] == ["control"]
    # the map error: the parameter written when the profile moved ...
    print(f"cm_scale_q read over CAN: {cm_before:.3f} before {T_STEP} s, {cm_after:.3f} after")
    assert cm_before == pytest.approx(CM_BEFORE, abs=1e-6)
    assert cm_after == pytest.approx(CM_AFTER, abs=1e-6)
    # ... and its effect on the true torque, the same as without CAN
    b_can, a_can = torque_means(log)
    b_ref, a_ref = torque_means(ref_log)
    print(f"true torque (mean over 0.3 s) before / after the step: over CAN {b_can:.4f} / {a_can:.4f} "
          f"N m, without CAN {b_ref:.4f} / {a_ref:.4f} N m")
    # the error moves the torque by more than 10 % of T* (Fig. 14: tens of %)
    assert abs(a_can - b_can) > 0.1 * TORQUE
    for x, y in ((b_can, b_ref), (a_can, a_ref)):
        assert x == pytest.approx(y, abs=0.01 * TORQUE)
