"""A small Python API to one fluxdrive over CAN (python-can).

Example (SIL: ``fluxdrive-sil sil/scenarios/can_demo.json --can socketcand:29536 --realtime``)::

    from fluxdrive.can import Drive

    with Drive("vcan0", "socketcand", node=1, port=29536) as drv:
        drv.set_mode("speed")
        drv.enable()
        drv.set_speed(600.0)                      # rpm, acknowledged
        drv.wait_for(lambda v: abs(v["speed_rpm"] - 600) < 6, timeout=5)
        print(drv.read_telemetry())               # {"speed_rpm": ..., "torque_est": ...}
        drv.set_param("speed_bw", 40.0)           # written, read back
        drv.disable()
        drv.identify("offset")                    # CMD_PROC: an identification, drive disabled
        print(drv.wait_proc("offset").results)    # TM_PROC: its eight results

Every command waits for the drive's REPLY and raises :class:`DriveError`
(naming the rejected signal) unless it is ``ok``. The drive stops on its
own (command timeout) when nothing arrives for ``can_timeout_ms`` while it
runs: send commands or call :meth:`Drive.heartbeat` to keep it alive.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import can

from fluxdrive import params
from fluxdrive.can.protocol import Protocol, Reply
from fluxdrive.errors import FluxdriveError

#: TM_PROC.proc_status: the procedure's end (it is no longer running)
PROC_ENDED = ("done", "failed", "aborted", "refused")
TELEMETRY = ("TM_SPEED", "TM_TORQUE", "TM_PHASE", "TM_DQ", "TM_FLUX", "TM_POSITION")  # TM_CPU: 100 ms, ask for it
# names and numbers from the firmware's tables (fluxdrive params)
MODES = params.mode_ids()
LAWS = params.law_ids()
KEEP_ENABLE = KEEP_MODE = KEEP_LAW = params.keep()


@dataclass
class ProcStatus:
    """The procedure telemetry (TM_PROC) as collected by the host."""

    proc: str  # procedure name (cmd_proc's value table), "none" before the first
    status: str  # idle, running, done, failed, aborted, refused
    phase: int  # the procedure's own phase or point counter
    results: list[float | None]  # PROC_RESULTS values; None: not received since the status changed
    since: float  # local monotonic time the (proc, status) pair was first seen

    @property
    def ended(self) -> bool:
        return self.status in PROC_ENDED

    @property
    def complete(self) -> bool:
        """Every result received since the status last changed."""
        return all(r is not None for r in self.results)


class DriveError(FluxdriveError):
    """The drive rejected a request (``reply.result``, ``reply.signal``) or did not answer."""

    def __init__(self, message: str, reply: Reply | None = None) -> None:
        super().__init__(message, exit_code=1)
        self.reply = reply


def open_bus(channel: str = "vcan0", interface: str = "socketcand", host: str = "127.0.0.1",
             port: int = 29536, **kwargs: Any) -> can.BusABC:
    """A python-can bus; host and port are used by the socketcand interface only."""
    if interface == "socketcand":
        # python-can warns on every frame split across TCP reads: not a problem
        logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)
        kwargs.setdefault("tcp_tune", True)
        return can.Bus(channel=channel, interface=interface, host=host, port=port, **kwargs)
    return can.Bus(channel=channel, interface=interface, **kwargs)


class Drive:
    """One drive (node) on a CAN bus."""

    def __init__(self, channel: str = "vcan0", interface: str = "socketcand", node: int = 1, *,
                 host: str = "127.0.0.1", port: int = 29536, bus: can.BusABC | None = None,
                 reply_timeout: float = 1.0, retries: int = 0) -> None:
        self.proto = Protocol(node)
        self.bus = bus if bus is not None else open_bus(channel, interface, host, port)
        self._own_bus = bus is None
        self.reply_timeout = reply_timeout
        self.retries = retries  # resends after a reply_timeout without an answer
        self._replies: queue.Queue[Reply] = queue.Queue()
        self._cond = threading.Condition()
        self._values: dict[str, float] = {}
        self._stamp: dict[str, float] = {}  # message name -> arrival (local clock)
        self._frame_time: dict[str, float] = {}  # message name -> frame timestamp
        self._req_lock = threading.Lock()
        self._hb_task: can.broadcastmanager.CyclicSendTaskABC | None = None
        self._hb_count = 0
        self.procs = {v: k for k, v in self.proto.proc_names.items()}  # name -> cmd_proc
        n_res = self.proto.proc_results
        self._proc = ProcStatus("none", "idle", 0, [None] * n_res, time.monotonic())
        self.notifier = can.Notifier(self.bus, [self._on_frame], timeout=0.02)

    # --------------------------------------------------------- plumbing
    def _on_frame(self, frame: can.Message) -> None:
        d = self.proto.decode(frame)
        if d is None:
            return
        name, sigs = d
        if name == "REPLY":
            r = self.proto.reply(frame)
            if r is not None:
                self._replies.put(r)
            return
        with self._cond:
            if name == "TM_PROC":
                self._on_proc(sigs)
            self._values.update({k: float(v) for k, v in sigs.items()})
            self._stamp[name] = time.monotonic()
            self._frame_time[name] = float(frame.timestamp)
            self._cond.notify_all()

    def _on_proc(self, sigs: dict[str, Any]) -> None:
        """TM_PROC: one result per frame; the results restart when the
        procedure or its status changes (so a complete set is the end's)."""
        pid, st = int(sigs["proc_id"]), int(sigs["proc_status"])
        proc = self.proto.proc_names.get(pid, "none")
        status = self.proto.proc_status_names.get(st, str(st))
        p = self._proc
        if (proc, status) != (p.proc, p.status):
            p = self._proc = ProcStatus(proc, status, 0, [None] * len(p.results), time.monotonic())
        p.phase = int(sigs["proc_phase"])
        k = int(sigs["proc_index"])
        if 0 <= k < len(p.results):
            p.results[k] = float(sigs["proc_result"])

    def request(self, message: str, check: bool = True, **signals: Any) -> Reply:
        """Sends a CMD_* or PARAM_REQ frame and returns the drive's REPLY.

        With `retries` > 0 the frame is sent again when no reply came within
        `reply_timeout` (a lost request or a lost reply: every request of the
        protocol sets a value, so a repeat is harmless)."""
        frame = self.proto.encode(message, **signals)
        param = signals.get("param_id")
        with self._req_lock:
            while not self._replies.empty():  # stale answers
                self._replies.get_nowait()
            r = None
            for _ in range(self.retries + 1):
                self.bus.send(frame)
                deadline = time.monotonic() + self.reply_timeout
                while r is None:
                    left = deadline - time.monotonic()
                    try:
                        got = self._replies.get(timeout=max(left, 0.0))
                    except queue.Empty:
                        break
                    if got.req == message and (param is None or got.param in (param, self.proto.param_names.get(param))):
                        r = got
                if r is not None:
                    break
            if r is None:
                raise DriveError(f"no reply to {message} from node {self.proto.node} "
                                 f"within {self.reply_timeout} s ({self.retries + 1} tries)")
        if check and not r.ok:
            what = f" ({r.signal})" if r.signal != "none" else ""
            name = f" {r.param}" if param is not None else ""
            raise DriveError(f"{message}{name} rejected: {r.result}{what}", r)
        return r

    # --------------------------------------------------------- commands
    def enable(self) -> Reply:
        return self.request("CMD_STATE", enable=1, clear_fault=0, mode=KEEP_MODE, law=KEEP_LAW)

    def disable(self) -> Reply:
        return self.request("CMD_STATE", enable=0, clear_fault=0, mode=KEEP_MODE, law=KEEP_LAW)

    def clear_fault(self) -> Reply:
        return self.request("CMD_STATE", enable=KEEP_ENABLE, clear_fault=1, mode=KEEP_MODE, law=KEEP_LAW)

    def set_mode(self, mode: str) -> Reply:
        return self.request("CMD_STATE", enable=KEEP_ENABLE, clear_fault=0, mode=MODES[mode], law=KEEP_LAW)

    def set_law(self, law: str) -> Reply:
        return self.request("CMD_STATE", enable=KEEP_ENABLE, clear_fault=0, mode=KEEP_MODE, law=LAWS[law])

    def set_torque(self, torque: float) -> Reply:
        """Torque reference [N m]."""
        return self.request("CMD_TORQUE", cmd_torque=torque)

    def set_speed(self, rpm: float) -> Reply:
        """Speed reference [rpm]."""
        return self.request("CMD_SPEED", cmd_speed_rpm=rpm)

    def set_current(self, i_d: float, i_q: float) -> Reply:
        return self.request("CMD_CURRENT", cmd_id=i_d, cmd_iq=i_q)

    def set_flux(self, flux: float) -> Reply:
        """Stator flux reference [Vs], 0 = automatic."""
        return self.request("CMD_FLUX", cmd_flux=flux)

    def identify(self, name: str) -> Reply:
        """CMD_PROC: runs identification procedure `name` (the drive
        disabled: the offsets, then it, then the gates off); "stop" stops the
        one running. Raises DriveError when refused (unavailable: not an
        identification; not_while_running: the drive is enabled)."""
        try:
            pid = self.procs[name]
        except KeyError:
            raise DriveError(f"unknown procedure {name!r}; known: {', '.join(self.procs)}") from None
        return self.request("CMD_PROC", cmd_proc=pid)

    def stop_identify(self) -> Reply:
        return self.identify("stop")

    def proc_status(self) -> ProcStatus:
        """The procedure telemetry (TM_PROC) as received so far (a copy)."""
        with self._cond:
            p = self._proc
            return replace(p, results=list(p.results))

    def wait_proc(self, name: str, timeout: float = 60.0, after: float | None = None,
                  progress: Callable[[ProcStatus], None] | None = None) -> ProcStatus:
        """Waits until procedure `name` has ended (a status change seen after
        `after`, default now) and all its results of that end have arrived.
        `progress` is called with each new status (at most every 0.1 s)."""
        t0 = time.monotonic() if after is None else after
        deadline = time.monotonic() + timeout
        last = None
        while True:
            with self._cond:
                self._cond.wait(timeout=0.1)
                p = self._proc
                done = p.proc == name and p.ended and p.since >= t0 and p.complete
                snap = replace(p, results=list(p.results))
            if progress is not None and snap.proc == name and (snap.status, snap.phase) != last \
                    and (snap.since >= t0 or not snap.ended):
                last = (snap.status, snap.phase)
                progress(snap)
            if done:
                return snap
            if time.monotonic() > deadline:
                raise DriveError(f"procedure {name} did not end within {timeout} s "
                                 f"(last: {snap.proc} {snap.status}, phase {snap.phase})")

    def get_param(self, name: str | int) -> float:
        pid = self.proto.param_id(name)
        return self.request("PARAM_REQ", param_op=0, param_id=pid, param_value=0.0).value

    def set_param(self, name: str | int, value: float) -> float:
        """Writes a parameter; returns the value read back in the acknowledge."""
        pid = self.proto.param_id(name)
        return self.request("PARAM_REQ", param_op=1, param_id=pid, param_value=float(value)).value

    def heartbeat(self, period: float | None = 0.1) -> None:
        """Sends HOST_HB every `period` s (None or 0: stop), keeping the command timeout away."""
        if self._hb_task is not None:
            self._hb_task.stop()
            self._hb_task = None
        if period:
            self._hb_task = self.bus.send_periodic(self.proto.encode("HOST_HB", host_hb_count=0), period)

    # -------------------------------------------------------- telemetry
    def values(self) -> dict[str, float]:
        """The latest value of every signal received so far."""
        with self._cond:
            return dict(self._values)

    def frame_time(self, message: str) -> float | None:
        """Timestamp of the latest frame of `message` (the SIL: simulated time)."""
        with self._cond:
            return self._frame_time.get(message)

    def read_telemetry(self, timeout: float = 1.0, messages: tuple[str, ...] = TELEMETRY) -> dict[str, float]:
        """Waits for a fresh frame of each telemetry message; returns all latest values."""
        t0 = time.monotonic()
        with self._cond:
            ok = self._cond.wait_for(lambda: all(self._stamp.get(m, -1.0) >= t0 for m in messages), timeout)
            if not ok:
                missing = [m for m in messages if self._stamp.get(m, -1.0) < t0]
                raise DriveError(f"no telemetry ({', '.join(missing)}) within {timeout} s")
            return dict(self._values)

    def status(self, timeout: float = 1.0) -> dict[str, Any]:
        """The latest STATUS, decoded (state and law by name)."""
        v = self.read_telemetry(timeout, ("STATUS",))
        st = {k: v[k] for k in ("state", "ctrl_mode", "ctrl_law", "faults", "v_dc", "timeout_ramp",
                                "cmd_enabled", "err_count")}
        st["state_name"] = params.state_names().get(int(st["state"]), str(st["state"]))
        st["fault_names"] = params.fault_names(int(st["faults"]))
        return st

    def wait_for(self, predicate: Callable[[dict[str, float]], bool], timeout: float = 5.0) -> dict[str, float]:
        """Waits until predicate(latest values) holds; returns the values."""
        with self._cond:
            def check() -> bool:
                try:
                    return bool(predicate(self._values))
                except KeyError:
                    return False
            if not self._cond.wait_for(check, timeout):
                raise DriveError(f"condition not met within {timeout} s (values: {self._values})")
            return dict(self._values)

    # ------------------------------------------------------------ close
    def close(self) -> None:
        self.heartbeat(None)
        self.notifier.stop()
        if self._own_bus:
            self.bus.shutdown()

    def __enter__(self) -> "Drive":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
