"""The C codec (firmware/app/can_codec.c, drive_params.c, can_proto.c) and
the DBC (firmware/app/can/fluxdrive.dbc) agree: every message and signal has
the same identifier, length, layout, scale, offset, range and value tables,
and frames round-trip C -> cantools and cantools -> C.

Run by CTest (can/dbc_agreement) with FD_CAN_CODEC_TOOL set to the helper.
"""

from __future__ import annotations

import os
import random
import struct
import subprocess
from pathlib import Path

import cantools
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
DBC = REPO / "firmware" / "app" / "can" / "fluxdrive.dbc"
TOOL = os.environ.get("FD_CAN_CODEC_TOOL")

pytestmark = pytest.mark.skipif(not TOOL, reason="FD_CAN_CODEC_TOOL not set (run through CTest)")


def run(mode: str, lines: list[str] | None = None) -> list[str]:
    out = subprocess.run([TOOL, mode], input="\n".join(lines or []) + "\n", capture_output=True,
                         text=True, check=True, timeout=60)
    return out.stdout.splitlines()


@pytest.fixture(scope="module")
def db():
    return cantools.database.load_file(str(DBC), strict=True)


@pytest.fixture(scope="module")
def tables():
    msgs, sigs, results, params, pparams = {}, {}, {}, {}, set()
    for line in run("describe"):
        f = line.split()
        if f[0] == "MSG":
            msgs[f[1]] = (int(f[2]), int(f[3]), f[4] == "1")
        elif f[0] == "SIG":
            sigs[(f[1], f[2])] = dict(start=int(f[3]), length=int(f[4]), signed=f[5] == "1",
                                      is_float=f[6] == "1", scale=float(f[7]), offset=float(f[8]),
                                      min=float(f[9]), max=float(f[10]), raw_min=int(f[11]),
                                      raw_max=int(f[12]), code=int(f[13]))
        elif f[0] == "RESULT":
            results[int(f[1])] = f[2]
        elif f[0] == "PARAM":
            params[int(f[1])] = f[2]
        elif f[0] == "PPARAM":
            pparams.add(int(f[1]))
    return msgs, sigs, results, params, pparams


def raw_range(s) -> tuple[int, int]:
    """The raw integers that the DBC range allows."""
    return round((s.minimum - s.offset) / s.scale), round((s.maximum - s.offset) / s.scale)


def test_messages_and_layout_agree(db, tables):
    msgs, sigs, _, _, _ = tables
    assert [m.name for m in db.messages] == list(msgs), "messages and their order"
    for m in db.messages:
        base, dlc, to_drive = msgs[m.name]
        assert (m.frame_id, m.length) == (base, dlc), m.name
        assert to_drive == (m.senders == ["HOST"]), m.name
        assert not m.is_extended_frame and m.frame_id + 15 <= 0x7FF
        c_names = [k[1] for k in sigs if k[0] == m.name]
        assert [s.name for s in m.signals] == c_names, f"{m.name}: signals and their order"
        for s in m.signals:
            c = sigs[(m.name, s.name)]
            where = f"{m.name}.{s.name}"
            assert s.byte_order == "little_endian", where
            assert (s.start, s.length, s.is_float) == (c["start"], c["length"], c["is_float"]), where
            if not s.is_float:
                assert s.is_signed == c["signed"], where
                assert np.float32(s.scale) == np.float32(c["scale"]), where
                assert np.float32(s.offset) == np.float32(c["offset"]), where
                assert np.float32(s.minimum) == np.float32(c["min"]), where
                assert np.float32(s.maximum) == np.float32(c["max"]), where
                assert raw_range(s) == (c["raw_min"], c["raw_max"]), where
    # identifiers of all nodes never collide
    ids = [m.frame_id + n for m in db.messages for n in range(16)]
    assert len(ids) == len(set(ids))


def test_value_tables_agree(db, tables):
    msgs, sigs, results, params, pparams = tables
    reply = db.get_message_by_name("REPLY")
    # reply_signal: code k names the k-th signal (C enum order == DBC order)
    sig_choices = {int(k): str(v) for k, v in reply.get_signal_by_name("reply_signal").choices.items()}
    c_codes = {c["code"]: name for (msg, name), c in sigs.items()}
    assert sig_choices[0] == "none"
    for code, name in sig_choices.items():
        if code:
            assert c_codes[code] == name
    # every host signal can be named in an error
    host = {name for (msg, name) in sigs if msgs[msg][2] and msg != "HOST_HB"}
    assert host <= set(sig_choices.values())
    res_choices = {int(k): str(v) for k, v in reply.get_signal_by_name("reply_result").choices.items()}
    assert res_choices == results
    req_choices = {int(k): str(v) for k, v in reply.get_signal_by_name("reply_req").choices.items()}
    assert req_choices == {i: m for i, m in enumerate(msgs) if msgs[m][2] and m != "HOST_HB"}
    par_choices = {int(k): str(v) for k, v in reply.get_signal_by_name("reply_param").choices.items()}
    proto = range(64, 96)  # the protocol's ids (can_proto.h), the drive's around them
    assert not set(params) & set(proto), "drive parameter ids in the protocol's range 64..95"
    assert {k: v for k, v in par_choices.items() if k not in proto} == params
    assert {k for k in par_choices if k in proto} == pparams


def random_raws(s, rng: random.Random, n: int) -> list[int]:
    if s.is_float:
        return []
    lo = -(1 << (s.length - 1)) if s.is_signed else 0
    hi = (1 << (s.length - 1)) - 1 if s.is_signed else (1 << s.length) - 1
    rmin, rmax = raw_range(s)
    edges = [lo, hi, max(lo, rmin), min(hi, rmax), max(lo, rmin - 1), min(hi, rmax + 1), 0]
    return edges + [rng.randint(lo, hi) for _ in range(n)]


def test_cantools_to_c(db):
    """Frames encoded by cantools (raw and float values) decode identically in C."""
    rng = random.Random(4)
    lines, expect = [], []
    for m in db.messages:
        for k in range(40):
            raws = {}
            for s in m.signals:
                if s.is_float:
                    v = struct.unpack("<f", struct.pack("<f", rng.uniform(-1e6, 1e6)))[0]
                    raws[s.name] = [0.0, 1.5, -2.25e-7, 3.0e38, v][k % 5] if k < 10 else v
                else:
                    cands = random_raws(s, rng, 1)
                    raws[s.name] = cands[k] if k < 7 else cands[-1]
            data = m.encode(raws, scaling=False, strict=False)
            lines.append(f"{m.name} {data.hex().upper()}")
            expect.append((m, raws))
    out = run("unpack", lines)
    assert len(out) == len(expect)
    for line, (m, raws) in zip(out, expect):
        f = line.split()
        got = {f[i]: (int(f[i + 1]), float(f[i + 2]), f[i + 3] == "1") for i in range(0, len(f), 4)}
        assert list(got) == [s.name for s in m.signals]
        for s in m.signals:
            raw_c, phys_c, in_c = got[s.name]
            if s.is_float:
                assert phys_c == pytest.approx(raws[s.name], rel=1e-7), s.name
                continue
            assert raw_c == raws[s.name], f"{m.name}.{s.name}"
            phys = raws[s.name] * s.scale + s.offset
            assert phys_c == pytest.approx(phys, rel=2e-7, abs=abs(s.scale) * 1e-3), f"{m.name}.{s.name}"
            rmin, rmax = raw_range(s)
            assert in_c == (rmin <= raws[s.name] <= rmax), f"{m.name}.{s.name} range at raw {raws[s.name]}"


def test_c_to_cantools(db):
    """Frames packed by C from physical values decode identically in cantools."""
    rng = random.Random(5)
    lines, expect = [], []
    for m in db.messages:
        for k in range(40):
            phys = {}
            for s in m.signals:
                if s.is_float:
                    phys[s.name] = float(np.float32(rng.uniform(-1e4, 1e4)))
                    continue
                lo, hi = raw_range(s)
                # raw values float32 carries exactly (|raw| < 2^22), plus the extremes
                lo2, hi2 = max(lo, -(1 << 22)), min(hi, 1 << 22)
                raw = [lo2, hi2, 0][k] if k < 3 else rng.randint(lo2, hi2)
                phys[s.name] = raw * s.scale + s.offset
            lines.append(m.name + " " + " ".join(f"{n}={v!r}" for n, v in phys.items()))
            expect.append((m, phys))
        # saturation: beyond what the field holds
        over = {s.name: (1e12 if not s.is_float else 1.0) for s in m.signals}
        lines.append(m.name + " " + " ".join(f"{n}={v!r}" for n, v in over.items()))
        expect.append((m, None))
    out = run("pack", lines)
    assert len(out) == len(expect)
    for hexdata, (m, phys) in zip(out, expect):
        data = bytes.fromhex(hexdata)
        assert len(data) == m.length
        dec = m.decode(data, scaling=True, decode_choices=False)
        raw = m.decode(data, scaling=False, decode_choices=False)
        for s in m.signals:
            if phys is None:  # saturated to the largest raw value
                if not s.is_float:
                    top = (1 << (s.length - 1)) - 1 if s.is_signed else (1 << s.length) - 1
                    assert raw[s.name] == top, f"{m.name}.{s.name} saturation"
                continue
            if s.is_float:
                assert dec[s.name] == pytest.approx(phys[s.name], rel=1e-7)
            else:
                assert raw[s.name] == round((phys[s.name] - s.offset) / s.scale), f"{m.name}.{s.name}"
        if phys is not None:
            assert data == m.encode(phys, scaling=True, strict=False), m.name
