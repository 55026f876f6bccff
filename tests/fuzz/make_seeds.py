#!/usr/bin/env python3
"""Writes the hand-made seeds of the fuzz corpus (docs/fuzzing.md):
CAN sessions for fuzz_can in its operation encoding (tests/fuzz/fuzz_can.c)
and two small valid flux maps for fuzz_fluxmap (the .fdmap layout of
docs/flux-maps.md). The scenario seeds are copies of sil/scenarios files.

    python3 tests/fuzz/make_seeds.py      # rewrites tests/fuzz/corpus/*/seed-*
"""
import pathlib
import struct
import zlib

ROOT = pathlib.Path(__file__).resolve().parent / "corpus"

# fuzz_can operations (op % 8): 0 frame for the node, 2 raw frame,
# 3 main-loop periods, 4 ISR periods, 5 TX blocked/unblocked, 6 long wait,
# 7 scaled parameter write. Messages of op 0: index into
# CMD_STATE, CMD_TORQUE, CMD_SPEED, CMD_CURRENT, CMD_FLUX, PARAM_REQ, HOST_HB.
STATE, TORQUE, SPEED, CURRENT, FLUX, PARAM, HB = range(7)
PROC = 0xFF  # CMD_PROC (the message byte 255; the others: byte % 7)


def frame(msg, data, dlc=None):
    d = bytes(data) + bytes(8 - len(data))
    return bytes([0, msg, 0 if dlc is None else 0x80 | dlc]) + d


def state(enable, clear=0, mode=255, law=255):
    return frame(STATE, [enable, clear, mode, law])


def i32(v):
    return struct.pack("<i", int(round(v)))


def torque(nm):
    return frame(TORQUE, i32(nm / 1e-4))


def speed(rpm):
    return frame(SPEED, i32(rpm / 0.01))


def current(i_d, i_q):
    return frame(CURRENT, i32(i_d / 1e-4) + i32(i_q / 1e-4))


def param(op, pid, value):
    return frame(PARAM, bytes([op, pid, 0, 0]) + struct.pack("<f", value))


def wait_ms(ms):  # main-loop periods (1 ms each at the default slow_div)
    out = b""
    while ms > 0:
        n = min(ms, 256)
        out += bytes([3, n - 1])
        ms -= n
    return out


CAN = {
    "seed-torque": state(1, mode=0) + wait_ms(20) + torque(1.0) + wait_ms(30)
    + frame(HB, [1]) + wait_ms(30),
    "seed-speed": state(1, mode=1) + speed(1000.0) + wait_ms(40) + frame(HB, [2])
    + wait_ms(40) + speed(-500.0) + wait_ms(20),
    "seed-current": state(0, mode=2) + current(0.0, 2.0) + state(1) + wait_ms(40)
    + current(-1.0, 3.0) + wait_ms(20),
    "seed-params": param(0, 11, 0.0) + param(1, 11, 2.0) + param(1, 12, 100.0)
    + state(1, mode=1) + speed(600.0) + wait_ms(30) + param(1, 12, 20.0)
    + param(1, 65, 30.0) + wait_ms(20) + bytes([7, 10, 3, 7, 11, 1]),
    # torque_max lowered to a tenth (20 -> 2 N m) under a 5 N m reference
    "seed-torque-lowered": state(1, mode=0) + wait_ms(20) + torque(5.0) + wait_ms(10)
    + bytes([7, 11, 7]) + wait_ms(10),
    # shown by fuzz_can's current-limit invariant: i_max halved (idle) under a 3 A current reference
    "regress-imax-lowered": state(0, mode=2) + current(0.0, 3.0) + bytes([7, 10, 1])
    + state(1) + wait_ms(30),
    # speed_max lowered to a tenth under a ramping speed reference (it must
    # come down at accel_max), heartbeats keeping the timeout off
    "seed-speed-lowered": state(1, mode=1) + speed(1000.0)
    + (wait_ms(40) + frame(HB, [0])) * 5 + bytes([7, 12, 7])
    + (wait_ms(20) + frame(HB, [1])) * 2,
    "seed-blocked": bytes([5]) + b"".join(torque(0.1 * k) for k in range(20))
    + wait_ms(60) + bytes([5]) + wait_ms(5),
    "seed-errors": frame(TORQUE, i32(1e9)) + frame(SPEED, [0], dlc=3)
    + frame(CURRENT, [0], dlc=12) + param(1, 200, 1.0) + state(7)
    + bytes([2, 0x61, 0x01, 4]) + bytes(8) + bytes([2, 0x01, 0x81, 8]) + bytes(8)
    + state(1, mode=0, law=1) + wait_ms(30) + state(0, clear=1),
    # identifications (CMD_PROC): the offsets run, stopped, run again; one
    # refused while enabled, one not an identification, one out of range;
    # the last left to the command timeout
    "seed-proc": frame(PROC, [0]) + wait_ms(5) + frame(PROC, [255]) + wait_ms(2)
    + frame(PROC, [1]) + frame(PROC, [200]) + frame(PROC, [0]) + wait_ms(10)
    + state(1, mode=0) + wait_ms(10) + frame(PROC, [0]) + state(0) + wait_ms(5)
    + bytes([7, 43, 5]) + frame(PROC, [0]) + bytes([6, 1]),  # offset_samples x 10: 160 ms
}


def fdmap(nd, nq, nl, ld, lq, lm, id0, did, iq0, diq, poles=2):
    """A linear machine's map: lambda_d = ld i_d + lm, lambda_q = lq i_q."""
    words = []
    psi_d = [ld * (id0 + j * did) + lm for k in range(nq) for j in range(nd)]
    psi_q = [lq * (iq0 + k * diq) for k in range(nq) for j in range(nd)]
    t_max = 1.0
    # MTPA (i_d = 0 for an isotropic machine), flux and MTPV rising
    mtpa_id = [0.0] * nl
    mtpa_iq = [k * 2.0 / (nl - 1) for k in range(nl)]
    mtpa_flux = [lm + 0.01 * k for k in range(nl)]
    mtpv = [0.5 * k for k in range(nl)]
    body = (struct.pack(f"<{len(psi_d)}f", *psi_d) + struct.pack(f"<{len(psi_q)}f", *psi_q)
            + struct.pack(f"<f{nl}f{nl}f{nl}f", t_max, *mtpa_id, *mtpa_iq, *mtpa_flux)
            + struct.pack(f"<f{nl}f", 0.5, *mtpv))
    size = 4 * (12 + len(body) // 4 + 1)
    head = struct.pack("<7I5f", 0x50414D46, 1, size, nd, nq, nl, 1 if lm > 0 else 0,
                       float(poles), id0, did, iq0, diq)
    blob = head + body
    del words
    return blob + struct.pack("<I", zlib.crc32(blob) & 0xFFFFFFFF)


MAPS = {
    "seed-spm-3x3.fdmap": fdmap(3, 3, 2, 0.01, 0.01, 0.1, -4.0, 2.0, -4.0, 4.0),
    "seed-syr-4x3.fdmap": fdmap(4, 3, 3, 0.005, 0.02, 0.0, -2.0, 2.0, -3.0, 3.0),
}


def main():
    for name, data in CAN.items():
        (ROOT / "fuzz_can" / name).write_bytes(data)
    for name, data in MAPS.items():
        (ROOT / "fuzz_fluxmap" / name).write_bytes(data)


if __name__ == "__main__":
    main()
