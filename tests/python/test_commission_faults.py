"""Issue 25, safety: a fault during any identification procedure ends in the
safe state. For every procedure the drive has (offset, rs, ldq, poles, enc,
flux, mech on the Rubino 2020 machine; fmap on syr_1k1; star on the Fabbri
2022 T5.1 machine), a trip is injected while the procedure runs
(`inject.trip_at` / `trip_cause`, the main loop posting the fault as a
protection or the CAN timeout would), each procedure with another cause.
Asserted on the full-rate log and the summary, limits from the drive's
contract (docs/faults.md: the gates off, or the active short, from the
period after the fault; nothing modulates after it):

  * the procedure was running at the trip (its record starts before it) and
    ends at it: status `aborted` or `failed`; a procedure that modulated
    stops modulating within one main-loop period plus 2 PWM periods of the
    trip (the record's end is noted at the runner's next main-loop pass);
  * from one main-loop period plus 2 PWM periods after the trip to the end of
    the run, no period modulates (gates 0 or 2) and the drive's state is
    fault with the injected cause latched;
  * the phase currents die out: below 5 % of i_max 20 ms after the trip.

Break on purpose: a procedure whose abort is ignored keeps modulating and
fails the gates check (docs/commissioning.md, "Safety").
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")

TS = 62.5e-6  # s, the PWM period
MAIN = 1e-3  # s, the main loop's period (the injection is the main loop's)
STATE_FAULT = 3
# procedure: (base scenario, cause, trip time [s] inside the procedure)
CASES = {
    "offset": ("rubino", "overcurrent", 0.005),
    "rs": ("rubino", "cmd_timeout", 0.25),
    "ldq": ("rubino", "gate_driver", 0.25),
    "poles": ("rubino", "hw_overcurrent", 0.25),
    "enc": ("rubino", "position", 0.25),
    "flux": ("rubino", "overspeed", 0.25),
    "mech": ("rubino", "current_sensor", 0.25),
    "fmap": ("syr", "overvoltage", 0.25),
    "star": ("star", "watchdog", 0.25),
}


def scenario(base: str, proc: str, cause: str, t_trip: float) -> dict:
    if base == "star":
        sc = json.loads((REPO_ROOT / "sil/scenarios/fabbri_speed.json").read_text())
        sc["controller"] = {**sc["controller"], "law": "foc", "mode": "torque",
                            "pos_source": "dfc", "align_time": 0.1}
        sc["mechanics"] = {**sc.get("mechanics", {}), "mode": "free"}
    elif base == "syr":
        sc = {"machine": {"preset": "syr_1k1"}, "mechanics": {"mode": "free"},
              "inverter": {"model": "average", "dead_time": 1e-6},
              "controller": {"law": "foc", "mode": "torque", "id_fmap_dwell": 0.012}}
    else:
        sc = json.loads((REPO_ROOT / "sil/scenarios/default.json").read_text())
        sc["mechanics"] = {"mode": "free", "b": 0.002}
        sc["controller"] = {"law": "foc", "mode": "current"}
    for k in ("references", "log"):
        sc.pop(k, None)
    sc["name"] = f"{cause} during {proc}"
    sc["duration"] = t_trip + 0.05
    sc["commission"] = [{"proc": proc}]
    sc["inject"] = {"trip_at": t_trip, "trip_cause": cause}
    return sc


@pytest.mark.parametrize("proc", sorted(CASES))
def test_fault_during_procedure_ends_in_the_safe_state(proc: str, tmp_path: Path) -> None:
    base, cause, t_trip = CASES[proc]
    sc = scenario(base, proc, cause, t_trip)
    p = tmp_path / "sc.json"
    p.write_text(json.dumps(sc))
    out, log = tmp_path / "sum.json", tmp_path / "log.npy"
    r = subprocess.run([str(REAL_SIL), str(p), "--summary", str(out), "--log", str(log),
                        "--decimate", "1"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    s = json.loads(out.read_text())
    rec = next(c for c in s["commission"] if c["proc"] == proc)
    lg = np.load(log)
    t = lg["t"]
    i_max = s["i_max"]
    late = t >= t_trip + MAIN + 2 * TS
    i_mag = np.sqrt((lg["i_a"] ** 2 + lg["i_b"] ** 2 + lg["i_c"] ** 2) / 1.5)
    mod_before = bool(np.any(lg["gates"][(t > rec["t0"]) & (t < t_trip)] == 1))
    print(f"{proc}: {cause} at {t_trip} s: procedure {rec['status']} {rec['fault']} at "
          f"{rec['t1']:.5f} s, modulating before {mod_before}, gates after "
          f"{sorted(set(int(g) for g in lg['gates'][late]))}, state "
          f"{sorted(set(int(x) for x in lg['state'][late]))}, |i| 20 ms after "
          f"{float(np.max(i_mag[t >= t_trip + 0.02])) / i_max:.4f} i_max")
    assert rec["t0"] < t_trip, "the procedure had not started at the trip"
    assert rec["status"] in ("aborted", "failed"), rec
    # the record's end is noted by the runner at its next main-loop pass
    assert t_trip <= rec["t1"] <= t_trip + 2 * MAIN + 2 * TS
    if mod_before:
        t_off = float(t[(t >= t_trip) & (lg["gates"] != 1)][0])
        print(f"  gates off {1e3 * (t_off - t_trip):.3f} ms after the trip")
        assert t_off <= t_trip + MAIN + 2 * TS
    assert cause in rec["fault"] or cause in s.get("faults", []), (rec, s.get("faults"))
    assert np.all(lg["gates"][late] != 1), "modulating after the fault"
    assert np.all(lg["state"][late] == STATE_FAULT)
    assert float(np.max(i_mag[t >= t_trip + 0.02])) <= 0.05 * i_max
