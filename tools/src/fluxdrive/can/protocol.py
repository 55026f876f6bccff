"""The fluxdrive CAN protocol, read from ``firmware/app/can/fluxdrive.dbc``
(the single source of truth: nothing here repeats its identifiers, layouts
or value tables).

The DBC gives the identifiers for node 0; on the bus, ID = base + node
(node 0..15). :class:`Protocol` binds the database to one node.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import can
import cantools
from cantools.database.can import Database, Message

from fluxdrive.errors import FluxdriveError

NODE_MAX = 15
#: messages the host sends (the drive answers CMD_* and PARAM_REQ with REPLY)
HOST_MESSAGES = ("CMD_STATE", "CMD_TORQUE", "CMD_SPEED", "CMD_CURRENT", "CMD_FLUX", "PARAM_REQ", "HOST_HB")


def dbc_path() -> Path:
    """``$FLUXDRIVE_DBC``, else the repository's ``firmware/app/can/fluxdrive.dbc``."""
    env = os.environ.get("FLUXDRIVE_DBC")
    if env:
        return Path(env)
    here = Path(__file__).resolve()
    for parent in here.parents:
        cand = parent / "firmware" / "app" / "can" / "fluxdrive.dbc"
        if cand.is_file():
            return cand
    raise FluxdriveError(
        "cannot find firmware/app/can/fluxdrive.dbc",
        hint="set FLUXDRIVE_DBC to the DBC file of the fluxdrive repository",
    )


@lru_cache(maxsize=4)
def _load(path: str) -> Database:
    return cantools.database.load_file(path, strict=True)


def load_dbc(path: str | Path | None = None) -> Database:
    return _load(str(path or dbc_path()))


def choices(db: Database, message: str, signal: str) -> dict[int, str]:
    sig = db.get_message_by_name(message).get_signal_by_name(signal)
    return {int(k): str(v) for k, v in (sig.choices or {}).items()}


@dataclass
class Reply:
    """A decoded REPLY frame."""

    req: str  # request answered, e.g. "CMD_SPEED"
    result: str  # "ok", "out_of_range", ...
    signal: str  # signal the error concerns ("none")
    param: str | int  # parameter name (PARAM_REQ) or its number
    value: float  # value in force after the request
    timestamp: float

    @property
    def ok(self) -> bool:
        return self.result == "ok"


class Protocol:
    """Encode/decode for one node (0..15)."""

    def __init__(self, node: int = 1, dbc: str | Path | None = None) -> None:
        if not 0 <= node <= NODE_MAX:
            raise FluxdriveError(f"node must be in 0..{NODE_MAX}, got {node}")
        self.node = node
        self.db = load_dbc(dbc)
        self._by_id: dict[int, Message] = {m.frame_id + node: m for m in self.db.messages}
        self.params = {v: k for k, v in choices(self.db, "REPLY", "reply_param").items()}
        self.param_names = choices(self.db, "REPLY", "reply_param")
        self.results = choices(self.db, "REPLY", "reply_result")
        self.signals = choices(self.db, "REPLY", "reply_signal")
        self.requests = choices(self.db, "REPLY", "reply_req")

    # ------------------------------------------------------------ lookup
    def message(self, name: str) -> Message:
        return self.db.get_message_by_name(name)

    def frame_id(self, name: str) -> int:
        return self.message(name).frame_id + self.node

    def param_id(self, name_or_id: str | int) -> int:
        if isinstance(name_or_id, int):
            return name_or_id
        if name_or_id.isdigit():
            return int(name_or_id)
        try:
            return self.params[name_or_id]
        except KeyError:
            raise FluxdriveError(
                f"unknown parameter {name_or_id!r}", hint="known: " + ", ".join(sorted(self.params))
            ) from None

    # ------------------------------------------------------------ encode
    def encode(self, name: str, strict: bool = True, **signals: Any) -> can.Message:
        """A frame of message `name` for this node (all signals required)."""
        msg = self.message(name)
        data = msg.encode(signals, scaling=True, strict=strict)
        return can.Message(arbitration_id=msg.frame_id + self.node, is_extended_id=False, data=data)

    # ------------------------------------------------------------ decode
    def decode(self, frame: can.Message) -> tuple[str, dict[str, Any]] | None:
        """(message name, signals) for a frame of this node, else None."""
        if frame.is_extended_id or frame.is_error_frame or frame.is_remote_frame:
            return None
        msg = self._by_id.get(frame.arbitration_id)
        if msg is None or len(frame.data) != msg.length:
            return None
        return msg.name, msg.decode(bytes(frame.data), decode_choices=False, scaling=True)

    def reply(self, frame: can.Message) -> Reply | None:
        d = self.decode(frame)
        if d is None or d[0] != "REPLY":
            return None
        s = d[1]
        p = int(s["reply_param"])
        return Reply(
            req=self.requests.get(int(s["reply_req"]), str(s["reply_req"])),
            result=self.results.get(int(s["reply_result"]), str(s["reply_result"])),
            signal=self.signals.get(int(s["reply_signal"]), str(s["reply_signal"])),
            param=self.param_names.get(p, p),
            value=float(s["reply_value"]),
            timestamp=float(frame.timestamp),
        )


def message_table_markdown(db: Database | None = None) -> str:
    """The message and signal tables of the DBC, as Markdown."""
    db = db or load_dbc()
    out = [
        "| message | ID (node 0) | DLC | from | period / trigger | signals |",
        "|---|---|---|---|---|---|",
    ]
    for m in db.messages:
        sender = ",".join(m.senders)
        sigs = ", ".join(s.name for s in m.signals)
        out.append(f"| `{m.name}` | 0x{m.frame_id:03X} | {m.length} | {sender} | {m.comment or ''} | {sigs} |")
    out += ["", "| message | signal | bits (start\\|length, LE) | type | scale | offset | range | unit | meaning |",
            "|---|---|---|---|---|---|---|---|---|"]
    for m in db.messages:
        for s in m.signals:
            typ = "float32" if s.is_float else ("int" if s.is_signed else "uint")
            rng = "" if s.is_float else f"{s.minimum:g} .. {s.maximum:g}"
            meaning = s.comment or ""
            if s.choices and s.name not in ("reply_param",):
                meaning = (meaning + " " if meaning else "") + "(" + ", ".join(
                    f"{int(k)} {v}" for k, v in s.choices.items()) + ")"
            out.append(f"| {m.name} | `{s.name}` | {s.start}\\|{s.length} | {typ} | {s.scale:g} | {s.offset:g} "
                       f"| {rng} | {s.unit or ''} | {meaning} |")
    params = choices(db, "REPLY", "reply_param")
    out += ["", "Parameters (`PARAM_REQ.param_id`, `REPLY.reply_param`): " + ", ".join(
        f"{k} `{v}`" for k, v in params.items()) + "."]
    return "\n".join(out) + "\n"
