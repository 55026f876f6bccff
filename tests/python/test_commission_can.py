"""Issue 25 point 3: the commissioning over CAN against the real SIL
(socketcand, --realtime): ``fluxdrive commission`` runs the offset
identification (CMD_PROC, TM_PROC) on a plant whose current sensors carry
known offsets (sensors.offset_error plus an injected inject.current offset),
writes the parameter file and the report with the truth; and a lost CAN link
during an identification ends in the safe state (cmd_timeout latched, gates
off, the procedure aborted), can_timeout_ms after the last frame that got
through, with no torque ramp.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from conftest import REAL_SIL
from fluxdrive.can import Drive, DriveError
from fluxdrive.commission import SilProcess, default_procs, parameter_file

pytestmark = [
    pytest.mark.real_sil,
    pytest.mark.skipif(not REAL_SIL.is_file(), reason=f"fluxdrive-sil not built ({REAL_SIL})"),
]

NODE = 3
SLOW = 1e-3  # main-loop period [s]
OFFSETS = (0.12, -0.2, 0.05)  # sensors.offset_error [A]
INJECTED_B = 0.15  # inject.current offset on channel b [A]
TRUE = (OFFSETS[0], OFFSETS[1] + INJECTED_B, OFFSETS[2])
I_FS, ADC_BITS, NOISE, SAMPLES = 20.0, 12, 0.02, 256  # full scale [A], bits, rms [A], offset_samples


def scenario(tmp_path: Path, inject_can: dict | None = None) -> Path:
    inject: dict = {"current": [{"channel": "b", "kind": "offset", "value": INJECTED_B}]}
    if inject_can:
        inject["can"] = inject_can
    sc = tmp_path / "commission.json"
    sc.write_text(json.dumps({
        "name": "commission over CAN", "duration": 60.0, "machine": {"preset": "rubino2020_spm"},
        "mechanics": {"mode": "free"}, "controller": {"law": "foc", "mode": "speed"},
        "sensors": {"offset_error": list(OFFSETS), "i_noise": NOISE, "i_full_scale": I_FS,
                    "adc_bits": ADC_BITS},
        "inject": inject,
    }))
    return sc


def test_commission_offset_over_can(tmp_path):
    """The offsets identified within half an ADC step plus 5 sigma of the
    mean of offset_samples noisy samples of the truth (both signs); the
    parameter file holds them; the report prints identified, true, error."""
    out = tmp_path / "params.json"
    r = subprocess.run([sys.executable, "-m", "fluxdrive", "commission", "offset", "--sil",
                        str(scenario(tmp_path)), "--sil-bin", str(REAL_SIL), "--node", str(NODE),
                        "--out", str(out)], capture_output=True, text=True, timeout=120)
    print(r.stdout, r.stderr)
    assert r.returncode == 0
    bound = 0.5 * 2.0 * I_FS / 2 ** ADC_BITS + 5.0 * NOISE / math.sqrt(SAMPLES)
    pf = json.loads(out.read_text())
    got = pf["identified"]["offset"]
    assert got["status"] == "done"
    for k, ch in enumerate("abc"):
        err = got[f"offset_{ch}"] - TRUE[k]
        print(f"offset_{ch}: identified {got[f'offset_{ch}']:.5f} A, true {TRUE[k]:.5f} A, "
              f"error {err * 1e3:+.2f} mA (limit +-{bound * 1e3:.2f} mA)")
        assert -bound <= err <= bound
        assert got["results"][k] == got[f"offset_{ch}"]
        # the report: identified, true and the error on the offset's line
        line = next(ln for ln in r.stdout.splitlines() if f"offset_{ch}" in ln)
        nums = [float(x) for x in re.findall(r"-?\d+\.?\d*(?:e[-+]?\d+)?", line.split("A", 1)[1])]
        assert nums[0] == pytest.approx(TRUE[k], abs=1e-6)
    # result 3: the current sum's noise (the current-sum check's floor,
    # proc_offset.c): three independent channels of NOISE rms and their
    # quantisation, within 15 % (256 samples: the estimate's own spread 4.4 %)
    lsb = 2.0 * I_FS / 2 ** ADC_BITS
    sigma = math.sqrt(3.0 * (NOISE ** 2 + lsb ** 2 / 12.0))
    print(f"current-sum noise: identified {got['results'][3]:.5f} A, expected {sigma:.5f} A")
    assert 0.85 * sigma <= got["results"][3] <= 1.15 * sigma
    assert got["results"][4:] == [0.0] * 4
    assert "[####################] 1/1 offset   done" in r.stdout  # the progress line


def test_default_order_and_parameter_file():
    """The default procedures: ORDER first, then the drive's others; the
    parameter file holds a written parameter by its table name (what
    fluxdrive-sil --params reads) and the record under "identified"."""
    assert default_procs(["mech", "x", "offset", "rs"]) == ["offset", "rs", "mech", "x"]
    pf = parameter_file([{"proc": "rs", "status": "done", "results": [0.5] + [0.0] * 7,
                          "named": {"rs": 0.5}, "written": {"rs": 0.5}, "duration": 1.0}])
    assert pf["rs"] == 0.5
    assert pf["identified"]["rs"]["rs"] == 0.5


T_LOSS = 2.5  # simulated time the link fails [s]
TIMEOUT = 0.3  # can_timeout_ms of the test [s]
HB = 0.05  # heartbeat period [s]


def test_lost_link_during_identification_ends_in_the_safe_state(tmp_path):
    """From T_LOSS nothing from the host reaches the drive while the offsets
    (offset_samples 60000: 3.75 s) are being identified: the drive latches
    cmd_timeout can_timeout_ms after the last frame that got through (in
    [T_LOSS - 2 HB, T_LOSS)), within one main-loop period, with no torque
    ramp (timeout_ramp never 1); the gates are off (state fault), the
    procedure aborted, and it stays so."""
    sil = SilProcess(REAL_SIL, scenario(tmp_path, {"rx": {"loss": [{"type": "step", "t": T_LOSS,
                                                                      "value": 1}]}}), NODE)
    status: list[tuple[float, dict]] = []
    lock = threading.Lock()
    try:
        with Drive("vcan0", "socketcand", node=NODE, port=sil.port, reply_timeout=3.0) as drv:
            proto = drv.proto

            def on_frame(m):
                d = proto.decode(m)
                if d and d[0] == "STATUS":
                    with lock:
                        status.append((m.timestamp, d[1]))

            drv.notifier.add_listener(on_frame)
            drv.heartbeat(HB)
            assert drv.set_param("can_timeout_ms", TIMEOUT * 1e3) == TIMEOUT * 1e3
            assert drv.set_param("offset_samples", 60000) == 60000
            # refused while enabled, naming the enable
            drv.enable()
            with pytest.raises(DriveError, match=r"not_while_running \(enable\)"):
                drv.identify("offset")
            drv.disable()
            with pytest.raises(DriveError, match=r"unavailable \(cmd_proc\)"):
                drv.identify("align")
            assert drv.identify("offset").value == drv.procs["offset"]
            t_set = drv.frame_time("STATUS") or 0.0
            assert t_set < T_LOSS - 0.5, "the set-up took too long"
            drv.wait_for(lambda v: v["state"] == 3, timeout=T_LOSS + 5.0)
            end = drv.wait_proc("offset", timeout=2.0, after=0.0)
            time.sleep(0.3)
            final = drv.status()
    finally:
        print(sil.stop().strip())
    with lock:
        fault_t, fault_s = next((t, s) for t, s in status if s["state"] == 3)
        before = [s for t, s in status if t < fault_t]
    lo, hi = T_LOSS - 2 * HB + TIMEOUT, T_LOSS + TIMEOUT + 1.5 * SLOW
    print(f"gates off (fault) at {fault_t:.4f} s (limits {lo:.4f} .. {hi:.4f}), "
          f"faults 0x{int(fault_s['faults']):x}, procedure {end.proc} {end.status}")
    assert before and before[-1]["state"] == 1  # identifying the offsets until then
    assert all(s["timeout_ramp"] == 0 for _, s in status)
    assert lo <= fault_t <= hi
    assert int(fault_s["faults"]) == 1 << 7  # cmd_timeout only
    assert end.proc == "offset" and end.status == "aborted"
    assert final["state_name"] == "fault" and final["faults"] == 1 << 7
