"""Issue 13 item 4: CAN frame loss and delay injected in the SIL's socketcand
transport (scenario inject.can, docs/scenarios.md; hal/sil/can_link.h),
against the real SIL in real time (docs/faults.md, "CAN and timing").

* Moderate loss and delay, below the command timeout: the drive rides
  through (references arrive through the host's retries, the heartbeat keeps
  it enabled, no fault).
* Loss or delay beyond can_timeout_ms: the cmd_timeout ramp starts
  can_timeout_ms after the last frame that got through and the fault follows
  can_ramp_ms later (docs/can.md, "Command timeout").
"""

from __future__ import annotations

import json
import math
import re
import select
import subprocess
import threading
import time
from pathlib import Path

import pytest

from conftest import REAL_SIL
from fluxdrive.can import Drive, DriveError

pytestmark = [
    pytest.mark.real_sil,
    pytest.mark.skipif(not REAL_SIL.is_file(), reason=f"fluxdrive-sil not built ({REAL_SIL})"),
]

NODE = 3
SLOW = 1e-3  # main-loop period: the transport is polled, the protocol runs, at this rate [s]


class Sil:
    """A realtime SIL over socketcand on a free port with inject.can."""

    def __init__(self, tmp_path: Path, can_faults: dict) -> None:
        sc = tmp_path / "can_faults.json"
        sc.write_text(json.dumps({
            "name": "can faults", "duration": 60.0, "machine": {"preset": "rubino2020_spm"},
            "mechanics": {"mode": "free"}, "controller": {"law": "foc", "mode": "speed"},
            "inject": {"can": can_faults},
        }))
        self.proc = subprocess.Popen([str(REAL_SIL), str(sc), "--can", "socketcand:0", "--realtime",
                                      "--node", str(NODE)], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        ready, _, _ = select.select([self.proc.stderr], [], [], 20.0)
        assert ready, "the SIL did not start"
        m = re.search(r"127\.0\.0\.1:(\d+)", self.proc.stderr.readline())
        assert m
        self.port = int(m.group(1))
        self.err = ""

    def stop(self) -> str:
        """Ends the run; returns its stderr (the CAN and link counters)."""
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            _, self.err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, self.err = self.proc.communicate()
        return self.err


@pytest.fixture
def make_sil(tmp_path: Path):
    sils: list[Sil] = []

    def make(can_faults: dict) -> Sil:
        s = Sil(tmp_path, can_faults)
        sils.append(s)
        return s

    yield make
    for s in sils:
        print(s.stop())


def link_counters(err: str) -> tuple[int, int, int, int]:
    m = re.search(r"CAN link \(inject\.can\): rx (\d+) of (\d+) frames lost, \d+ delayed; "
                  r"tx (\d+) of (\d+) lost", err)
    assert m, err
    return tuple(int(g) for g in m.groups())  # type: ignore[return-value]


def binomial_bounds(n: int, p: float, sds: float = 5.0) -> tuple[float, float]:
    s = math.sqrt(n * p * (1.0 - p))
    return n * p - sds * s, n * p + sds * s


LOSS, DELAY, JITTER = 0.2, 0.02, 0.01  # each direction


def test_moderate_loss_and_delay_ridden_through(make_sil):
    """20 % loss, 20 ms + up to 10 ms latency each way; can_timeout_ms 500.
    The heartbeat (every 50 ms) times out only if 10 in a row are lost
    (0.2^10 = 1e-7); a request or its reply is lost with 1 - 0.8^2 = 36 %:
    the host sends it again (Drive(retries=)), which is safe because every
    request sets a value."""
    sil = make_sil({"seed": 11, "rx": {"loss": LOSS, "delay": DELAY, "jitter": JITTER},
                    "tx": {"loss": LOSS, "delay": DELAY, "jitter": JITTER}})
    status: list[tuple[float, dict]] = []
    tm: list[float] = []
    rtt_max = 2 * (DELAY + JITTER) + 2 * SLOW
    with Drive("vcan0", "socketcand", node=NODE, port=sil.port, reply_timeout=rtt_max + 0.1,
               retries=8) as drv:
        proto = drv.proto

        def on_frame(m):
            d = proto.decode(m)
            if d and d[0] == "STATUS":
                status.append((m.timestamp, d[1]))
            elif d and d[0] == "TM_SPEED":
                tm.append(m.timestamp)

        drv.notifier.add_listener(on_frame)
        drv.heartbeat(0.05)
        assert drv.get_param("can_timeout_ms") == 500
        drv.set_mode("speed")
        assert drv.enable().value == 1.0
        assert drv.set_speed(300.0).value == pytest.approx(300.0, abs=0.01)
        v = drv.wait_for(lambda v: abs(v["speed_rpm"] - 300.0) < 3.0 and v["state"] == 2, timeout=15.0)
        # round trips of single tries: both latencies, never more than both
        # with their jitter (plus a poll each way); lost ones counted
        drv.retries = 0
        rtts, lost = [], 0
        t_a = status[-1][0] if status else 0.0
        for _ in range(30):
            t0 = time.monotonic()
            try:
                assert drv.get_param("speed_bw") == pytest.approx(60.0)
                rtts.append(time.monotonic() - t0)
            except DriveError:
                lost += 1
        drv.retries = 8
        t_b = max(t for t, _ in status)
        final = drv.status(timeout=2.0)
    lo, hi = binomial_bounds(30, 0.8 * 0.8)
    print(f"speed {v['speed_rpm']:.1f} rpm; 30 single tries: {len(rtts)} answered (limits "
          f"{lo:.1f} .. {hi:.1f}), round trip {min(rtts) * 1e3:.1f} .. {max(rtts) * 1e3:.1f} ms "
          f"(limits {(2 * DELAY - 2 * SLOW) * 1e3:.0f} .. {(rtt_max + 0.05) * 1e3:.0f} ms)")
    assert lo <= len(rtts) <= hi
    assert min(rtts) >= 2 * DELAY - 2 * SLOW
    assert max(rtts) <= rtt_max + 0.05  # + the host's scheduling
    # enabled throughout, never a timeout ramp or a fault
    after = [s for t, s in status if t >= t_a]
    assert after and all(s["state"] == 2 and s["faults"] == 0 and s["timeout_ramp"] == 0 for s in after)
    assert final["state_name"] == "run" and final["faults"] == 0
    # the telemetry that got through: TM_SPEED every 10 ms, 80 % of it
    n = round((t_b - t_a) / 0.01)
    got = sum(1 for t in tm if t_a <= t < t_b)
    lo, hi = binomial_bounds(n, 1.0 - LOSS)
    print(f"TM_SPEED received {got} of {n} sent over {t_b - t_a:.2f} s (limits {lo:.0f} .. {hi:.0f})")
    assert lo <= got <= hi
    rx_lost, rx_n, tx_lost, tx_n = link_counters(sil.stop())
    print(f"link: rx {rx_lost} of {rx_n} lost, tx {tx_lost} of {tx_n}")
    for k, n_ in ((rx_lost, rx_n), (tx_lost, tx_n)):
        lo, hi = binomial_bounds(n_, LOSS)
        assert lo <= k <= hi


T_LOSS = 2.5  # simulated time the link fails [s]
TIMEOUT, RAMP = 0.3, 0.1  # can_timeout_ms, can_ramp_ms of the test [s]
HB = 0.05  # heartbeat period [s]


@pytest.mark.parametrize("fault", [
    {"loss": [{"type": "step", "t": T_LOSS, "value": 1}]},
    {"delay": [{"type": "step", "t": T_LOSS, "value": 0.6}]},
], ids=["total_loss", "delay_600ms"])
def test_loss_or_delay_beyond_the_timeout_trips(make_sil, fault):
    """From T_LOSS (simulated) nothing from the host reaches the drive, or
    everything 600 ms late (beyond can_timeout_ms 300 ms). The last frame
    got through in [T_LOSS - 2 HB, T_LOSS) (a heartbeat every 50 ms; two for
    the host's scheduling); the ramp starts can_timeout_ms after it, within
    one main-loop period, the fault can_ramp_ms after that (STATUS at the
    next main-loop period)."""
    sil = make_sil({"rx": fault})
    status: list[tuple[float, dict]] = []
    lock = threading.Lock()
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
        assert drv.set_param("can_ramp_ms", RAMP * 1e3) == RAMP * 1e3
        drv.set_mode("speed")
        drv.enable()
        drv.set_speed(300.0)
        t_set = drv.frame_time("STATUS") or 0.0
        assert t_set < T_LOSS - 0.5, "the set-up took too long"
        drv.wait_for(lambda v: v["state"] == 3, timeout=T_LOSS + 5.0)
        time.sleep(0.05)
    with lock:
        ramp = next(t for t, s in status if s["timeout_ramp"] == 1)
        fault_t, fault_s = next((t, s) for t, s in status if s["state"] == 3)
        early = [s for t, s in status if t < ramp]
    r_lo, r_hi = T_LOSS - 2 * HB + TIMEOUT, T_LOSS + TIMEOUT + SLOW
    print(f"{fault}: ramp at {ramp:.4f} s (limits {r_lo:.4f} .. {r_hi:.4f}), gates off "
          f"{fault_t - ramp:.4f} s later (limits {RAMP:.4f} .. {RAMP + 1.5 * SLOW:.4f}), "
          f"faults 0x{int(fault_s['faults']):x}")
    assert all(s["state"] == 2 for s in early[-5:])  # running until the ramp
    assert r_lo <= ramp <= r_hi
    assert RAMP - 1e-6 <= fault_t - ramp <= RAMP + 1.5 * SLOW
    assert int(fault_s["faults"]) == 1 << 7  # cmd_timeout only
    err = sil.stop()
    print(err.strip().splitlines()[-1])
