"""End-to-end CAN tests against the real SIL over its socketcand transport
(docs/can.md): acceptance 1 (enable, speed within 1 %, parameter write and
read-back, command timeout) and 3 (a flood of malformed frames at full rate).
"""

from __future__ import annotations

import json
import random
import re
import select
import socket
import subprocess
import threading
import time
from pathlib import Path

import can
import pytest

from conftest import REAL_SIL
from fluxdrive import params
from fluxdrive.can import Drive, DriveError, Protocol

pytestmark = [
    pytest.mark.real_sil,
    pytest.mark.skipif(not REAL_SIL.is_file(), reason=f"fluxdrive-sil not built ({REAL_SIL})"),
]

NODE = 2
SPEED = 300.0  # rpm: below the voltage limit of the Rubino machine on 310 V


@pytest.fixture
def sil(tmp_path: Path):
    """A realtime SIL commanded over socketcand on a free port; always killed."""
    sc = tmp_path / "can.json"
    sc.write_text(json.dumps({
        "name": "can e2e", "duration": 120.0, "machine": {"preset": "rubino2020_spm"},
        "mechanics": {"mode": "free"}, "controller": {"law": "foc", "mode": "speed"},
    }))
    proc = subprocess.Popen([str(REAL_SIL), str(sc), "--can", "socketcand:0", "--realtime",
                             "--node", str(NODE)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([proc.stderr], [], [], 20.0)
        assert ready, "the SIL did not start"
        line = proc.stderr.readline()
        m = re.search(r"127\.0\.0\.1:(\d+)", line)
        assert m, f"unexpected SIL output: {line!r}"
        yield proc, int(m.group(1))
    finally:
        proc.terminate()
        try:
            out, err = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
        print(err)


def reach_speed(drv: Drive, rpm: float, timeout: float = 15.0) -> list[float]:
    """Waits for |speed - rpm| < 1 % and returns 0.3 s of speeds after that."""
    drv.wait_for(lambda v: abs(v["speed_rpm"] - rpm) < 0.01 * rpm and v["state"] == 2, timeout)
    speeds, t_end = [], time.monotonic() + 0.3
    while time.monotonic() < t_end:
        speeds.append(drv.read_telemetry(timeout=2.0)["speed_rpm"])
    return speeds


def test_enable_speed_param_and_timeout(sil):
    proc, port = sil
    status: list[tuple[float, dict]] = []
    with Drive("vcan0", "socketcand", node=NODE, port=port, reply_timeout=3.0) as drv:
        proto = drv.proto
        drv.notifier.add_listener(lambda m: (d := proto.decode(m)) and d[0] == "STATUS"
                                  and status.append((m.timestamp, d[1])))
        assert drv.status(timeout=5.0)["state_name"] == "idle"
        drv.heartbeat(0.05)
        drv.set_mode("speed")
        assert drv.enable().value == 1.0
        assert drv.set_speed(SPEED).value == pytest.approx(SPEED, abs=0.01)
        speeds = reach_speed(drv, SPEED)
        print(f"speed over 0.3 s: {min(speeds):.2f} .. {max(speeds):.2f} rpm")
        assert len(speeds) >= 5
        assert all(abs(s - SPEED) < 0.01 * SPEED for s in speeds)

        # parameter write, acknowledged with the value read back, then read
        assert drv.get_param("speed_bw") == pytest.approx(60.0)
        assert drv.set_param("speed_bw", 40.0) == pytest.approx(40.0)
        assert drv.get_param("speed_bw") == pytest.approx(40.0)
        # out of range: rejected, naming the signal; the reference stays
        with pytest.raises(Exception) as exc:
            drv.set_speed(5000.0)
        assert exc.value.reply.signal == "cmd_speed_rpm" and exc.value.reply.value == pytest.approx(SPEED)
        # a non-finite value: refused naming the parameter and its value in
        # force (issue 22, point 7: it was answered for parameter 0, "no reply")
        # (an inf is refused by cantools' encoder before it is sent)
        with pytest.raises(DriveError, match=r"i_trip.*out_of_range \(param_value\)") as exc:
            drv.set_param("i_trip", float("nan"))
        assert exc.value.reply.param == "i_trip"
        assert exc.value.reply.value == pytest.approx(drv.get_param("i_trip"))
        # a shorter timeout for the test (protocol parameters)
        assert drv.set_param("can_timeout_ms", 300) == 300
        assert drv.set_param("can_ramp_ms", 100) == 100

        # silence: the last frame is acknowledged at t_last (simulated time)
        drv.heartbeat(None)
        time.sleep(0.1)
        t_last = drv.set_speed(SPEED).timestamp
        drv.wait_for(lambda v: v["state"] == 3, timeout=5.0)
        time.sleep(0.05)
        ramp = next(t for t, s in status if t >= t_last and s["timeout_ramp"] == 1)
        fault = next((t, s) for t, s in status if t >= t_last and s["state"] == 3)
        print(f"timeout ramp at +{ramp - t_last:.4f} s, gates off at +{fault[0] - t_last:.4f} s")
        assert ramp - t_last == pytest.approx(0.300, abs=0.001)
        # the fault request is taken by the next ISR; STATUS reports it at the
        # next slow period (1 ms)
        assert 0.400 - 1e-6 <= fault[0] - t_last <= 0.4015
        assert int(fault[1]["faults"]) == 1 << 7  # DRIVE_FAULT_CMD_TIMEOUT
        v = drv.read_telemetry(timeout=2.0)
        assert abs(v["i_a"]) + abs(v["i_b"]) + abs(v["i_c"]) < 0.05  # gates off
    assert proc.poll() is None, "the SIL ended"


def flood_frames(proto: Protocol, rng: random.Random, n: int):
    """(frame, expected reply or None): random garbage and known messages
    with wrong lengths, out-of-range and valid values, in send order."""
    host_ids = {proto.frame_id(m) for m in ("CMD_STATE", "CMD_TORQUE", "CMD_SPEED", "CMD_CURRENT",
                                           "CMD_FLUX", "PARAM_REQ", "HOST_HB", "CMD_PROC")}
    out = []
    for _ in range(n):
        k = rng.random()
        if k < 0.45:  # random standard id (never one of ours), dlc, payload
            fid = rng.choice([i for i in range(0x800) if i not in host_ids]) if rng.random() < 0.5 else \
                rng.choice(sorted(host_ids)) - NODE + rng.choice([0, 1, 3, 15])
            if fid in host_ids:
                fid ^= 0x400
            dlc = rng.randint(0, 8)
            out.append((can.Message(arbitration_id=fid, is_extended_id=False,
                                    data=bytes(rng.getrandbits(8) for _ in range(dlc))), None))
        elif k < 0.5:  # random extended id
            dlc = rng.randint(0, 8)
            out.append((can.Message(arbitration_id=rng.getrandbits(29), is_extended_id=True,
                                    data=bytes(rng.getrandbits(8) for _ in range(dlc))), None))
        elif k < 0.65:  # one of ours with a wrong length
            name = rng.choice(["CMD_STATE", "CMD_TORQUE", "CMD_SPEED", "CMD_CURRENT", "CMD_FLUX",
                               "PARAM_REQ", "HOST_HB"])
            dlc = rng.choice([d for d in range(9) if d != proto.message(name).length])
            msg = can.Message(arbitration_id=proto.frame_id(name), is_extended_id=False,
                              data=bytes(rng.getrandbits(8) for _ in range(dlc)))
            out.append((msg, None if name == "HOST_HB" else (name, "bad_dlc", "none")))
        elif k < 0.8:  # out of range
            if rng.random() < 0.5:
                rpm = rng.choice([-1, 1]) * rng.uniform(1300.0, 190000.0)
                out.append((proto.encode("CMD_SPEED", cmd_speed_rpm=rpm), ("CMD_SPEED", "out_of_range", "cmd_speed_rpm")))
            else:
                keep = params.keep()  # 255: outside every mode and law
                msg = proto.encode("CMD_STATE", strict=False, enable=keep, clear_fault=0,
                                   mode=rng.randint(len(params.mode_ids()), keep - 1), law=keep)
                out.append((msg, ("CMD_STATE", "out_of_range", "mode")))
        else:  # valid and harmless
            c = rng.randrange(3)
            if c == 0:
                out.append((proto.encode("PARAM_REQ", param_op=0, param_id=31, param_value=0.0), ("PARAM_REQ", "ok", "none")))
            elif c == 1:
                out.append((proto.encode("CMD_SPEED", cmd_speed_rpm=SPEED), ("CMD_SPEED", "ok", "none")))
            else:
                out.append((proto.encode("HOST_HB", host_hb_count=rng.getrandbits(8)), None))
    return out


def garbage_client(port: int, rng: random.Random) -> int:
    """A socketcand client sending garbage: bytes, long lines, malformed sends."""
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    try:
        assert s.recv(64) == b"< hi >"
        s.sendall(b"< open vcan0 >")
        assert s.recv(64) == b"< ok >"
        s.sendall(b"< rawmode >")
        assert s.recv(64) == b"< ok >"
        chunks = [bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 300))) for _ in range(200)]
        chunks += [b"<" * 500, b"< send 12 >", b"< send 123 9 1 2 3 4 5 6 7 8 9 >", b"< send zzz 1 1 >",
                   b"< send 123 2 1 >", b"< send 800 0 >", b"< frame 123 >", b"< " + b"x" * 5000 + b" >",
                   b"< send 1FFFFFFFF 0 >", b">>>>", b"< send 123 1 100 >"]
        for c in chunks:
            s.sendall(c)
        return len(chunks)
    finally:
        s.close()


def test_flood_of_malformed_frames(sil):
    proc, port = sil
    rng = random.Random(20240603)
    with Drive("vcan0", "socketcand", node=NODE, port=port, reply_timeout=3.0) as drv:
        proto = drv.proto
        replies = []
        lock = threading.Lock()

        def on_frame(m: can.Message) -> None:
            r = proto.reply(m)
            if r is not None:
                with lock:
                    replies.append(r)

        drv.heartbeat(0.05)
        drv.set_mode("speed")
        drv.enable()
        drv.set_speed(SPEED)
        reach_speed(drv, SPEED)
        garbage_client(port, rng)
        frames = flood_frames(proto, rng, 5000)
        expected = [e for _, e in frames if e is not None]
        drv.heartbeat(None)  # one sender thread: the flood's own valid frames keep the drive alive
        time.sleep(0.1)
        drv.notifier.add_listener(on_frame)
        t0 = time.monotonic()
        for msg, _ in frames:
            drv.bus.send(msg)
        t_send = time.monotonic() - t0
        drv.heartbeat(0.05)
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline:
            with lock:
                if len(replies) >= len(expected):
                    break
            time.sleep(0.05)
        time.sleep(0.2)
        with lock:
            got = [(r.req, r.result, r.signal) for r in replies]
        counts = {k: sum(1 for e in expected if e[1] == k) for k in ("ok", "bad_dlc", "out_of_range")}
        print(f"flood: {len(frames)} frames sent in {t_send:.2f} s, {len(expected)} answerable "
              f"{counts}, {len(got)} replies")
        assert got == expected  # every answerable frame answered, in order, naming the signal
        # still controlling, no fault
        speeds = reach_speed(drv, SPEED, timeout=5.0)
        print(f"after the flood: {min(speeds):.2f} .. {max(speeds):.2f} rpm")
        assert all(abs(s - SPEED) < 0.01 * SPEED for s in speeds)
        st = drv.status()
        assert st["state_name"] == "run" and st["faults"] == 0
        assert drv.get_param("speed_bw") == pytest.approx(60.0)
    assert proc.poll() is None, "the SIL ended"


@pytest.fixture
def sil_sensorless(tmp_path: Path):
    """The Table 5.1 motor on the IVD + Kalman filter position, a brake of
    0.05 N m from 3 s (simulated, real time), over socketcand."""
    sc = tmp_path / "can_kf.json"
    base = json.loads((Path(__file__).resolve().parents[2] / "sil" / "scenarios" /
                       "fabbri_speed.json").read_text())
    base.update({"name": "can e2e sensorless", "duration": 60.0, "references": {},
                 "log": {"decimation": 1000}})
    base["controller"]["pos_source"] = "ivd+kf"
    base["mechanics"]["load_torque"] = [{"type": "step", "t": 3.0, "value": LOAD}]
    sc.write_text(json.dumps(base))
    proc = subprocess.Popen([str(REAL_SIL), str(sc), "--can", "socketcand:0", "--realtime",
                             "--node", str(NODE)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([proc.stderr], [], [], 20.0)
        assert ready, "the SIL did not start"
        m = re.search(r"127\.0\.0\.1:(\d+)", proc.stderr.readline())
        assert m
        yield proc, int(m.group(1))
    finally:
        proc.terminate()
        try:
            proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


LOAD = 0.05  # N m: the brake of the sensorless test


def test_sensorless_load_torque_over_can(sil_sensorless):
    """Issue 12: the Kalman filter's load-torque estimate travels in
    TM_POSITION; its parameters (ids beyond the protocol's 64..95) are read
    and written over CAN; the drive holds 300 rpm sensorless under the
    brake and the estimate settles on the scenario's load within 15 %."""
    proc, port = sil_sensorless
    with Drive("vcan0", "socketcand", node=NODE, port=port, reply_timeout=3.0) as drv:
        assert drv.status(timeout=5.0)["state_name"] == "idle"
        drv.heartbeat(0.05)
        assert drv.get_param("kf_q_load") == pytest.approx(1e-6)
        assert drv.set_param("kf_q_load", 2e-6) == pytest.approx(2e-6)
        assert drv.get_param("pos_source") == params.pos_source_ids()["ivd+kf"]
        drv.set_mode("speed")
        drv.enable()
        drv.set_speed(300.0)
        # wall-clock bounds generous: the realtime SIL falls behind the
        # clock when the CI's other tests share the cores (the brake acts
        # at 3 s of simulated time, whatever the wall clock says)
        reach_speed(drv, 300.0, timeout=60.0)
        drv.wait_for(lambda v: v.get("load_torque_est", 0.0) > 0.5 * LOAD, timeout=60.0)
        # the speed's recovery from the brake takes simulated time, which a
        # loaded machine stretches (the realtime SIL at a fraction of the
        # clock): wait until the filter's speed is back near the reference
        # (a drive that never recovers times out here), then measure over a
        # window: its mean must hold within 1 %
        drv.wait_for(lambda v: abs(v.get("speed_rpm", 0.0) - 300.0) < 0.01 * 300.0, timeout=60.0)
        est, spd = [], []
        t_end = time.monotonic() + 1.0
        while time.monotonic() < t_end:
            v = drv.read_telemetry(timeout=2.0)
            est.append(v["load_torque_est"])
            spd.append(v["speed_rpm"])  # the filter's speed: its spread is Table 5.2's
            assert v["state"] == 2 and v["pos_err"] < 0.1
        print(f"load estimate {min(est):.4f} .. {max(est):.4f} N m for {LOAD} N m, "
              f"speed {min(spd):.1f} .. {max(spd):.1f} rpm")
        assert len(est) >= 5
        assert abs(sum(est) / len(est) - LOAD) < 0.15 * LOAD
        assert abs(sum(spd) / len(spd) - 300.0) < 0.01 * 300.0
    assert proc.poll() is None, "the SIL ended"


def test_half_open_connections_time_out(sil):
    """Issue 13, defect 9: four idle connections that never complete the
    socketcand handshake take every slot; they are dropped after the
    handshake timeout (2 s, hal/sil/can_socketcand.h) and a real client gets
    in."""
    proc, port = sil
    idle = [socket.create_connection(("127.0.0.1", port), timeout=5.0) for _ in range(4)]
    try:
        time.sleep(0.3)
        # every slot is held: a fifth connection is closed at once
        extra = socket.create_connection(("127.0.0.1", port), timeout=5.0)
        extra.settimeout(2.0)
        try:
            assert extra.recv(64) == b""  # closed without a greeting
        finally:
            extra.close()
        time.sleep(2.5)  # past the handshake timeout
        with Drive("vcan0", "socketcand", node=NODE, port=port, reply_timeout=3.0) as drv:
            assert drv.status(timeout=5.0)["state_name"] == "idle"
            assert drv.get_param("speed_bw") == pytest.approx(60.0)
        for s in idle:  # the server closed them: the greeting, then the end
            s.settimeout(2.0)
            got = b""
            while True:
                chunk = s.recv(64)
                if not chunk:
                    break
                got += chunk
            assert got == b"< hi >"
    finally:
        for s in idle:
            s.close()
    assert proc.poll() is None, "the SIL ended"
