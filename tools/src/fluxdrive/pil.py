"""Processor-in-the-loop replay on QEMU ``mps2-an386`` (docs/pil.md).

Per scenario and control law:

1. ``fluxdrive-sil SCENARIO --record-isr rec.bin`` records every ISR's inputs
   and the host build's outputs (sil/runner/isr_stream.h).
2. The PIL image (pil/, Cortex-M4F, the board's fd_core/fd_app objects)
   replays the whole stream in QEMU; its outputs are compared with the
   host's: duties within ``DUTY_TOL``, gate state, fault bits and drive
   state identical.
3. The first ``isrs`` ISRs (0: all of them) are replayed again with
   ``-singlestep -d exec,nochain``: every executed instruction is one trace
   line, streamed through a FIFO and counted per ISR (from drive_isr's entry
   to the first line back in its caller pil_step, callees included) and per
   function, and priced with the Cortex-M4 model (cm4_cycles).
4. With ``--procs`` the ISRs are also grouped by the procedure the host's
   drive had in force (the stream's ``host_proc``: offsets, identification
   procedures, alignment ...), each group reported and checked like a law.

Without ``--elf`` / ``$FLUXDRIVE_PIL_ELF`` and ``--sil`` / ``$FLUXDRIVE_SIL``
the default image and runner of the repo are used, and built first when
they are missing (presets ``cortex-m4f`` and ``host-release``). Every path
handed to QEMU and the runner is absolute.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fluxdrive import cm4_cycles, params, sil
from fluxdrive.signals import pil_out
from fluxdrive.errors import FluxdriveError

ENV_ELF = "FLUXDRIVE_PIL_ELF"
ELF_RELPATH = Path("build/cortex-m4f/pil/fluxdrive-pil.elf")
#: How the default image and runner are built when missing (run in the repo root).
ELF_BUILD = (["cmake", "--preset", "cortex-m4f"],
             ["cmake", "--build", "build/cortex-m4f", "--target", "fluxdrive-pil.elf"])
SIL_BUILD = (["cmake", "--preset", "host-release"],
             ["cmake", "--build", "--preset", "host-release", "--target", "fluxdrive-sil"])
ELF_HINT = "build it with: " + " && ".join(" ".join(a) for a in ELF_BUILD)
CROSS_CC = "arm-none-eabi-gcc"
QEMU = "qemu-system-arm"

#: Absolute tolerance on the duties (0..1). Both builds are IEEE-754 binary32
#: without contraction (-std=c11 implies -ffp-contract=off on both) and
#: agree bit for bit except where a math library differs. The ISR path now
#: uses the core's own trig (math/fast_trig.h) and VSQRT, and the measured
#: deviation is 0; the tolerance stays for a CORDIC binding of fd_sincosf/
#: fd_atan2f and compiler differences. With libm trig (glibc vs newlib, 1-2
#: ulp apart) the duties differed by up to a few 1e-6 through the laws'
#: gains (deadbeat: ~L/Ts) with the applied voltage forced (docs/pil.md).
#: 2e-5 = ~170 ulp of 1.0 = 6 mV on 310 V.
DUTY_TOL = 2e-5

BUDGET_CYCLES = 10625  # 170 MHz / 16 kHz
SYSCLK_HZ = 170_000_000


def budget_cycles(pwm_hz: float) -> int:
    """Cycles per ISR at the scenario's PWM frequency (``inverter.pwm_frequency``,
    16 kHz by default): 10625 at 16 kHz, 5312 at 32 kHz."""
    return int(SYSCLK_HZ / pwm_hz)
RUN = 2  # DRIVE_STATE_RUN

HEADER = np.dtype(
    [
        ("magic", "<u4"),
        ("version", "<u4"),
        ("header_size", "<u4"),
        ("config_size", "<u4"),
        ("caps_size", "<u4"),
        ("in_size", "<u4"),
        ("out_size", "<u4"),
        ("count", "<u4"),
        ("flags", "<u4"),
    ]
)
MAGIC, VERSION, FORCE_APPLIED = 0x52534946, 6, 1
#: header flags: the replay's RAM state from / to pil_snap.bin (isr_stream.h)
SNAP_LOAD, SNAP_SAVE = 2, 4
# the output record's fields, named after the signals they carry
# (sil/runner/isr_stream.h ISR_STREAM_OUT_FIELDS, `fluxdrive signals`)
OUT = np.dtype(pil_out())
DUTIES = ("duty_a", "duty_b", "duty_c")
IN_SIZE = 240
#: Byte offset of isr_stream_in_t.host_proc (isr_stream.h asserts it): the
#: procedure the host's drive had in force after the ISR (proc_id_t; the
#: table's length, PROC_NONE, for none).
HOST_PROC_AT = 188
HOST_PHASE_AT = 192  # isr_stream_in_t.host_phase: its phase (the procedure telemetry's)

#: Blocks of the per-function share: the first pattern that a function name
#: starts with (or equals) names its block.
BLOCKS = [
    # the procedures (proc.h: offsets, alignment, held start, identification;
    # FD_COLD, in flash on the board): each row's static functions
    # (proc_<name>.c) and the identification's estimators (core/estimation/
    # ident_*); enc_ and flux_ named exactly (the encoder source, the flux
    # observer share the prefixes)
    ("procedures (proc_*.c rows, ident_*)",
     ("proc_", "ident_", "offset_", "align_", "hold_", "rs_", "ldq_", "fmap_", "poles_",
      "star_", "mech_", "enc_step", "enc_init", "enc_publish", "enc_target", "flux_step",
      "flux_init", "flux_publish", "flux_acc", "flux_lambda", "pulse", "pulse_periods",
      "zero_current")),
    # protect_: the protections, owned parts of the drive (firmware/app/protect)
    ("drive (ISR body, commands, protections, offsets)", ("drive_", "protect_",
                                                          "hal_pwm_centred")),
    ("speed loop (speed_ctrl, every slow_div ISRs)", ("speed_ctrl_",)),
    ("position source (encoder, star point, PLL)", ("enc_", "pdfc_", "nearest_branch",
                                                    "pos_source", "pos_encoder_", "pos_star_",
                                                    "pos_method_", "angle_pll_", "trk_",
                                                    "meas_r", "rls_step")),
    ("Kalman filter (kf_mech_predict, kf_mech_update: (4.46)-(4.49))",
     ("kf_mech_predict", "kf_mech_update", "kf_mech_reset", "kf_mech_r_speed")),
    ("EKF update (kf_mech_update_ekf: (4.35)-(4.41))", ("kf_mech_update_ekf",)),
    ("RLS of a, b (rls_ab_update: (4.51)-(4.57))", ("rls_ab_",)),
    ("DFC signals (dfc_signals_: (2.101), sequentiality)", ("dfc_signals_",)),
    ("IVD iteration (dfc_ivd_step, (3.76)/(3.100))", ("dfc_ivd_step",)),
    ("DFC / IVD angle (dfc_vector2, dfc_window)", ("dfc_",)),
    ("CORDIC atan2 (math/cordic_q31, software Q31)", ("fd_cordic_",)),
    ("control-law dispatch (ctrl, law tables)", ("ctrl_", "dfvc_law_", "db_step", "pi_step",
                                                 "foc_step")),
    ("DFVC step", ("dfvc_step", "dfvc_reset")),
    ("flux observer", ("flux_observer_", "flux_obs_")),
    ("current predictor", ("current_predictor_",)),
    ("SPM discrete model", ("spm_discrete_",)),
    ("DFVC references (MTPA/FW/MTPV)", ("dfvc_refs_",)),
    ("DB-DFVC law", ("dfvc_deadbeat_",)),
    ("PI-DFVC law", ("dfvc_pi_",)),
    ("decoupled DFVC step (dfvc_decoupled)", ("dfvc_decoupled_step", "dfvc_decoupled_reset", "dfvc_decoupled_law_",
                                        "dfvc_decoupled_map", "dfvc_decoupled_model_at")),
    ("decoupled DFVC references (dfvc_decoupled_refs)", ("dfvc_decoupled_refs_",)),
    ("decoupled DFVC regulators (dfvc_decoupled_pi)", ("dfvc_decoupled_pi_",)),
    ("stator-flux-frame model (sfo_model)", ("sfo_",)),
    ("flux map lookups (flux_map)", ("flux_map_", "flux_jac")),
    ("PI controllers (pi_ctrl)", ("pi_ctrl_",)),
    ("FOC current control", ("current_ctrl_", "pmsm_")),
    ("modulation", ("modulation_",)),
    ("dead-time compensation", ("deadtime_comp_",)),
    ("frames (Clarke/Park, wrap)", ("frames_",)),
    ("machine model", ("machine_", "mtpa_at")),
    ("core trig fd_sincosf/fd_atan2f (math/fast_trig)", ("fd_",)),
    (
        "libm sinf/cosf (newlib)",
        ("sinf", "cosf", "__kernel_sinf", "__kernel_cosf", "__ieee754_rem_pio2f",
         "__kernel_rem_pio2f"),
    ),
    ("libm atan2f/asinf (newlib)", ("atan2f", "atanf", "__ieee754_atan2f", "asinf",
                                    "__ieee754_asinf")),
    ("libm sqrtf/powf (newlib)", ("sqrtf", "__ieee754_sqrtf", "powf", "__ieee754_powf")),
    ("libm classify/min/max/floor (newlib)", ("__fpclassifyf", "fmaxf", "fminf", "floorf",
                                              "fabsf", "scalbnf", "copysignf")),
    ("libc memset/memcpy", ("memset", "memcpy")),
    # roundf: the replay HAL's timer model (hal_pattern.h) rounds the edges;
    # called by hal_pwm_write only (cm4_cycles.stand_ins checks the image)
    ("PIL replay HAL (stands in for the register HAL)", ("hal_", "roundf")),
]


def block_of(func: str) -> str:
    for name, pats in BLOCKS:
        for p in pats:
            if func == p or (p.endswith("_") and func.startswith(p)):
                return name
    return "other: " + (func or "?")


# ------------------------------------------------------------------ files
def host_procs(body: np.ndarray, at: int = HOST_PROC_AT) -> np.ndarray:
    """Per record, the host's procedure after the ISR (isr_stream_in_t.host_proc;
    ``at`` = HOST_PHASE_AT: its phase)."""
    raw = np.frombuffer(body["in"].tobytes(), np.uint8).reshape(len(body), IN_SIZE)
    return raw[:, at:at + 4].copy().view("<u4").ravel()


def sample_windows(host_proc: np.ndarray, host_phase: np.ndarray, names: list[str],
                   w: int) -> list[tuple[int, int]]:
    """The ISRs --sample W traces, as merged windows [a, b): of every run of
    a procedure (proc_isrs' attribution) its first and last W ISRs and W
    around each change of its phase (where its fits and hand-overs run)."""
    n = len(host_proc)
    owner = np.full(n, -1)
    before = len(names)
    for j in range(n):
        after = int(host_proc[j])
        p = before if before < len(names) else after
        owner[j] = p if p < len(names) else -1
        before = after
    win = []
    j = 0
    while j < n:
        if owner[j] < 0:
            j += 1
            continue
        k = j
        while k + 1 < n and owner[k + 1] == owner[j]:
            k += 1
        win += [(j, j + w), (k + 1 - w, k + 1)]
        for i in range(j + 1, k + 1):
            if host_phase[i] != host_phase[i - 1]:
                win.append((i - w // 2, i + w - w // 2))
        j = k + 1
    out: list[list[int]] = []
    for a, b in sorted((max(a, 0), min(b, n)) for a, b in win):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def read_record(path: Path) -> tuple[bytes, np.ndarray, np.ndarray]:
    """(header+config bytes, input records as raw bytes rows, host outputs)."""
    data = path.read_bytes()
    if len(data) < HEADER.itemsize:
        raise FluxdriveError(f"{path}: too short for an ISR record", exit_code=1)
    h = np.frombuffer(data, HEADER, count=1)[0]
    if int(h["magic"]) != MAGIC or int(h["version"]) != VERSION:
        raise FluxdriveError(f"{path}: not an isr_stream v{VERSION} file", exit_code=1)
    if int(h["in_size"]) != IN_SIZE or int(h["out_size"]) != OUT.itemsize:
        raise FluxdriveError(f"{path}: record layout differs from this tool's", exit_code=1)
    start = int(h["header_size"]) + int(h["config_size"]) + int(h["caps_size"])
    n = int(h["count"])
    rec = np.dtype([("in", f"V{IN_SIZE}"), ("out", OUT)])
    body = np.frombuffer(data, rec, count=n, offset=start)
    return data[:start], body, body["out"]


def write_pil_input(path: Path, head: bytes, body: np.ndarray, n: int, force: bool,
                    start: int = 0, snap: int = 0) -> None:
    """pil_in.bin of records [start, n); ``snap``: SNAP_LOAD | SNAP_SAVE."""
    h = np.frombuffer(head, HEADER, count=1).copy()
    h["count"] = n - start
    h["flags"] = (FORCE_APPLIED if force else 0) | snap
    with open(path, "wb") as f:
        f.write(h.tobytes())
        f.write(head[HEADER.itemsize:])
        f.write(body[start:n].tobytes())


# ------------------------------------------------------------------- qemu
def qemu_argv(elf: Path, trace: Path | None) -> list[str]:
    argv = [
        QEMU, "-M", "mps2-an386", "-nographic", "-monitor", "none", "-serial", "none",
        "-semihosting-config", "enable=on,target=native", "-kernel", str(elf),
    ]
    if trace is not None:
        # -singlestep: one instruction per translation block; -d exec logs
        # every TB execution, nochain keeps chained TBs from skipping the log.
        argv += ["-singlestep", "-d", "exec,nochain", "-D", str(trace)]
    return argv


def run_qemu(elf: Path, workdir: Path, timeout: float) -> np.ndarray:
    workdir, elf = workdir.resolve(), elf.resolve()
    out = workdir / "pil_out.bin"
    out.unlink(missing_ok=True)
    try:
        r = subprocess.run(qemu_argv(elf, None), cwd=workdir, capture_output=True,
                           text=True, timeout=timeout, check=False)
    except FileNotFoundError:
        raise FluxdriveError(f"{QEMU} not found", hint="apt-get install qemu-system-arm") from None
    except subprocess.TimeoutExpired:
        raise FluxdriveError(f"PIL replay timed out after {timeout:.0f} s", exit_code=1) from None
    if r.returncode != 0:
        raise FluxdriveError(
            f"PIL image failed (exit {r.returncode}): {(r.stdout + r.stderr).strip()}", exit_code=1
        )
    return np.fromfile(out, OUT)


@dataclass
class TraceResult:
    counts: list[int] = field(default_factory=list)  # per ISR, in order
    funcs: list[dict[str, int]] = field(default_factory=list)  # per ISR
    cycles: list[int] = field(default_factory=list)  # per ISR: model cycles (cm4_cycles)
    func_cycles: list[dict[str, int]] = field(default_factory=list)  # per ISR
    #: per ISR: function -> [calls, instructions from its entry to its return, callees included]
    calls: list[dict[str, list[int]]] = field(default_factory=list)
    unknown_pcs: set[bytes] = field(default_factory=set)  # executed PCs not in the listing


ISR_FUNC, ISR_CALLER = "drive_isr", "pil_step"


def _entries(tab: dict) -> set[bytes]:
    """The first PC of each function of a trace table (its entry)."""
    first: dict[str, int] = {}
    for k, e in tab.items():
        a = int(k, 16)
        if e[4] not in first or a < first[e[4]]:
            first[e[4]] = a
    return {b"%08x" % a for a in first.values()}


def _book(stack: list, n: int, calls: dict, until=None) -> None:
    """Pops the call stack down to the frame of ``until`` (all of it when
    None), booking each popped call's inclusive instructions."""
    while stack and stack[-1][0] is not until:
        f, n_in = stack.pop()
        c = calls.setdefault(f, [0, 0])
        c[0] += 1
        c[1] += n - n_in


def _parse_trace(stream, res: TraceResult, tab: dict) -> None:
    """Stream parser: line = 'Trace 0: HOSTPTR [cs_base/pc/flags/cflags] SYMBOL'.

    ``tab`` (cm4_cycles.trace_table of the traced ELF) maps the printed PC
    to (seq cycles, jump cycles, fall-through PC, taken penalty, function).
    An ISR runs from drive_isr's first line after a line in pil_step to
    the next line in pil_step. Per line: one dict lookup; the instruction
    costs its seq cycles when it is its predecessor's fall-through, else its
    jump cycles plus the predecessor's taken-branch penalty. Counts and
    cycles are running totals; per-function shares are booked when the
    function changes (calls and returns), not per line. Calls: a change of
    function at the new function's first PC is a call (pushed), any other
    change a return to a caller on the stack (the frames above it popped,
    each booked with its instructions from entry to return); a change into
    a function not on the stack at another PC (a branch into its body)
    counts as a call too."""
    in_isr = False
    prev = ""  # function of the previous line
    nxt = b""  # fall-through PC of the previous instruction
    pen = 0  # its penalty when the next PC is not nxt (taken branch)
    n = cyc = 0  # running instructions / cycles over the whole trace
    n0 = c0 = fn0 = fc0 = 0  # at the ISR's entry / the current function's entry
    cur_n: dict[str, int] = {}
    cur_c: dict[str, int] = {}
    entries = _entries(tab)
    stack: list = []
    cur_calls: dict[str, list[int]] = {}
    for line in stream:
        j = line.rfind(b"] ")
        if j < 0:
            continue
        k = line[j - 26:j - 18]  # [cs_base/PC/flags/cflags]: each field 8 hex digits
        try:
            sc, jc, f_next, p, fn = tab[k]
        except KeyError:
            sc, jc, f_next, p, fn = tab[k] = _unknown_pc(line, j, k, res)
        if k != nxt:
            cyc += pen
            sc = jc
        if fn is not prev:
            if in_isr:
                cur_n[prev] = cur_n.get(prev, 0) + n - fn0
                cur_c[prev] = cur_c.get(prev, 0) + cyc - fc0
                if fn == ISR_CALLER:
                    in_isr = False
                    _book(stack, n, cur_calls)
                    res.counts.append(n - n0)
                    res.cycles.append(cyc - c0)
                    res.funcs.append(cur_n)
                    res.func_cycles.append(cur_c)
                    res.calls.append(cur_calls)
                elif k in entries or not any(f is fn for f, _ in stack):
                    stack.append((fn, n))  # a call (or a branch into a function's body)
                else:
                    _book(stack, n, cur_calls, fn)
            elif fn == ISR_FUNC and prev == ISR_CALLER:
                in_isr = True
                n0, c0, cur_n, cur_c = n, cyc, {}, {}
                stack, cur_calls = [(fn, n)], {}
            fn0, fc0, prev = n, cyc, fn
        n += 1
        cyc += sc
        nxt, pen = f_next, p


def _unknown_pc(line: bytes, j: int, k: bytes, res: TraceResult) -> tuple:
    """A PC the disassembly does not list: 1 cycle, function from QEMU's
    symbol; reported (fluxdrive pil fails on it)."""
    if line[j - 36:j - 35] != b"[":
        raise FluxdriveError(f"unexpected QEMU trace line: {line[:120]!r}", exit_code=1)
    res.unknown_pcs.add(k)
    return (1, 1, b"", 0, sys.intern(line[j + 2:-1].decode(errors="replace")))


def run_qemu_trace(elf: Path, workdir: Path, timeout: float,
                   tab: dict | None = None) -> tuple[TraceResult, np.ndarray]:
    """Traced replay; ``tab``: cm4_cycles.trace_table of ``elf`` (built when None)."""
    workdir, elf = workdir.resolve(), elf.resolve()  # QEMU's -D path is taken from its cwd
    if tab is None:
        tab = cm4_cycles.trace_table(cm4_cycles.load_program(elf))
    fifo = workdir / "trace.fifo"
    fifo.unlink(missing_ok=True)
    os.mkfifo(fifo)
    out = workdir / "pil_out.bin"
    out.unlink(missing_ok=True)
    res = TraceResult()
    proc = subprocess.Popen(qemu_argv(elf, fifo), cwd=workdir, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT)
    err: list[BaseException] = []

    def reader() -> None:
        try:
            with open(fifo, "rb", buffering=1 << 22) as f:
                _parse_trace(f, res, tab)
        except BaseException as exc:  # pragma: no cover - reported below
            err.append(exc)

    t = threading.Thread(target=reader, daemon=True)
    t.start()
    try:
        msg, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise FluxdriveError(f"traced PIL replay timed out after {timeout:.0f} s",
                             exit_code=1) from None
    finally:
        t.join(timeout=60)
        fifo.unlink(missing_ok=True)
    if proc.returncode != 0:
        raise FluxdriveError(f"traced PIL image failed (exit {proc.returncode}): "
                             f"{msg.decode(errors='replace').strip()}", exit_code=1)
    if err:
        raise FluxdriveError(f"trace parser failed: {err[0]}", exit_code=1)
    if res.unknown_pcs:
        raise FluxdriveError(f"{len(res.unknown_pcs)} executed PCs are not in the disassembly of "
                             f"{elf} (e.g. {sorted(res.unknown_pcs)[0].decode()}): the cycle "
                             "model cannot price them", exit_code=1)
    return res, np.fromfile(out, OUT)


# ------------------------------------------------------------- comparison
@dataclass
class Agreement:
    isrs: int
    max_duty_dev: float
    max_dev_isr: int
    duty_bad: int
    gates_bad: int
    faults_bad: int
    state_bad: int

    @property
    def ok(self) -> bool:
        return self.duty_bad == 0 and self.gates_bad == 0 and self.faults_bad == 0 and \
            self.state_bad == 0


def compare(host: np.ndarray, pil: np.ndarray) -> Agreement:
    if len(pil) != len(host):
        raise FluxdriveError(f"PIL wrote {len(pil)} ISR outputs, expected {len(host)}",
                             exit_code=1)
    def duty(x: np.ndarray) -> np.ndarray:
        return np.stack([x[d].astype(np.float64) for d in DUTIES], axis=-1).reshape(-1, 3)

    dev = np.abs(duty(host) - duty(pil)).max(axis=1)
    dev = np.where(np.isnan(dev), np.inf, dev) if len(dev) else dev
    k = int(np.argmax(dev)) if len(dev) else 0
    return Agreement(
        isrs=len(host),
        max_duty_dev=float(dev[k]) if len(dev) else 0.0,
        max_dev_isr=k,
        duty_bad=int((dev > DUTY_TOL).sum()),
        gates_bad=int(((host["gates"] ^ pil["gates"]) & 1).sum()),
        faults_bad=int((host["faults"] != pil["faults"]).sum()),
        state_bad=int((host["state"] != pil["state"]).sum()),
    )


# ---------------------------------------------------------------- counting
@dataclass
class Counts:
    isrs: int  # ISRs running the law (state RUN before and after)
    mean: float
    worst: int
    worst_isr: int
    blocks: dict[str, float]  # mean instructions per ISR per block
    funcs: dict[str, float]
    # Estimated Cortex-M4 cycles (cm4_cycles model) over the same ISRs
    cycles_mean: float = 0.0
    cycles_worst: int = 0
    cycles_worst_isr: int = 0
    block_cycles: dict[str, float] = field(default_factory=dict)  # mean per ISR
    func_cycles: dict[str, float] = field(default_factory=dict)
    #: function -> (calls per ISR, instructions per call, callees included)
    calls: dict[str, tuple[float, float]] = field(default_factory=dict)
    #: the image's replay-HAL functions the board replaces (cm4_cycles.stand_ins)
    stand_ins: frozenset = frozenset(cm4_cycles.BOARD_HAL)
    #: per law ISR: (cycles, cycles in the software trigonometry the board binds to
    #: its CORDIC (cm4_cycles.BOARD_TRIG, leaves), {function: calls} of it)
    trig_isr: list = field(default_factory=list)

    @property
    def cpi(self) -> float:
        return self.cycles_mean / self.mean if self.mean else 0.0

    def stand_in_cycles(self) -> float:
        """Mean cycles per ISR in the PIL replay HAL (the board runs its own)."""
        return sum(v for f, v in self.func_cycles.items() if f in self.stand_ins)


def _mean_by(run: list[int], per_isr: list[dict[str, int]]) -> tuple[dict, dict]:
    funcs: dict[str, int] = {}
    for j in run:
        for f, v in per_isr[j].items():
            funcs[f] = funcs.get(f, 0) + v
    blocks: dict[str, float] = {}
    for f, v in funcs.items():
        b = block_of(f)
        blocks[b] = blocks.get(b, 0.0) + v / len(run)
    return blocks, {f: v / len(run) for f, v in funcs.items()}


def law_isrs(tr: TraceResult, host: np.ndarray) -> list[int]:
    """The traced ISRs that ran the control law (state RUN before and after)."""
    n = min(len(tr.counts), len(host))
    st = host["state"][:n]
    return [j for j in range(1, n) if st[j] == RUN and st[j - 1] == RUN
            and tr.counts[j] is not None]


def proc_isrs(tr: TraceResult, host_proc: np.ndarray, names: list[str]) -> dict[str, list[int]]:
    """The traced ISRs per procedure, in the order the procedures first ran:
    an ISR belongs to the procedure in force before it (its step ran, and
    its end and the next one's start when it ended), or, when none was,
    to the one in force after it (the ISR that took the request and began
    the first). ``host_proc``: per ISR, the host's procedure after it
    (isr_stream_in_t.host_proc); ``names``: the table's, by id."""
    n = min(len(tr.counts), len(host_proc))
    out: dict[str, list[int]] = {}
    before = len(names)  # PROC_NONE: none after drive_init
    for j in range(n):
        after = int(host_proc[j])
        p = before if before < len(names) else after
        if p < len(names) and tr.counts[j] is not None:  # None: not traced (--sample)
            out.setdefault(names[p], []).append(j)
        before = after
    return out


def law_counts(tr: TraceResult, host: np.ndarray,
               stand_ins: frozenset = frozenset(cm4_cycles.BOARD_HAL),
               run: list[int] | None = None) -> Counts:
    """Counts over ``run`` (default: the law ISRs, law_isrs)."""
    n = min(len(tr.counts), len(host))
    if run is None:
        run = law_isrs(tr, host)
    if not run:
        raise FluxdriveError("no ISR ran the control law in the traced window "
                             "(raise --isrs beyond the offset calibration)", exit_code=1)
    c = np.array([tr.counts[j] for j in run])
    blocks, funcs = _mean_by(run, tr.funcs)
    w = int(np.argmax(c))
    out = Counts(len(run), float(c.mean()), int(c[w]), run[w], blocks, funcs,
                 stand_ins=frozenset(stand_ins))
    if len(tr.cycles) >= n:
        y = np.array([tr.cycles[j] for j in run])
        wy = int(np.argmax(y))
        out.cycles_mean, out.cycles_worst, out.cycles_worst_isr = float(y.mean()), int(y[wy]), \
            run[wy]
        out.block_cycles, out.func_cycles = _mean_by(run, tr.func_cycles)
        if len(tr.calls) >= n:
            out.trig_isr = [
                (tr.cycles[j], sum(tr.func_cycles[j].get(f, 0) for f in cm4_cycles.BOARD_TRIG),
                 {f: tr.calls[j][f][0] for f in cm4_cycles.BOARD_TRIG if f in tr.calls[j]})
                for j in run]
    if len(tr.calls) >= n:
        tot: dict[str, list[int]] = {}
        for j in run:
            for f, (k, v) in tr.calls[j].items():
                t = tot.setdefault(f, [0, 0])
                t[0] += k
                t[1] += v
        out.calls = {f: (k / len(run), v / k) for f, (k, v) in tot.items() if k}
    return out


# ------------------------------------------------------------------- run
@dataclass
class PilRun:
    scenario: str
    law: str
    agreement: Agreement
    counts: Counts
    trace_exact: bool  # traced replay's outputs == untraced replay's
    budget: int = BUDGET_CYCLES  # cycles per ISR at the scenario's PWM frequency
    proc: str | None = None  # the procedure whose ISRs these are (--procs), None: the law's
    traced: int | None = None  # ISRs traced in --sample's windows (None: a prefix, --isrs)


def build_default(root: Path, steps: tuple[list[str], ...], what: str) -> None:
    """Build a missing default artefact in the repo root, saying so."""
    for argv in steps:
        print(f"fluxdrive pil: {what} missing, building it: {' '.join(argv)}  (in {root})",
              flush=True)
        try:
            r = subprocess.run(argv, cwd=root, check=False)
        except FileNotFoundError:
            raise FluxdriveError(f"cannot build the {what}: {argv[0]} not found",
                                 hint="apt-get install cmake ninja-build") from None
        if r.returncode != 0:
            raise FluxdriveError(f"building the {what} failed (exit {r.returncode}): "
                                 f"{' '.join(argv)}", exit_code=1)


def locate_elf(explicit: str | None, build: bool = True) -> Path:
    """--elf, else $FLUXDRIVE_PIL_ELF (both authoritative: never built), else
    the repo's build/cortex-m4f image, built first when missing."""
    if explicit:
        p = Path(explicit)
    elif os.environ.get(ENV_ELF):
        p = Path(os.environ[ENV_ELF])
    else:
        root = sil.find_repo_root()
        if root is None:
            raise FluxdriveError("cannot find the repo root; pass --elf", hint=ELF_HINT)
        p = root / ELF_RELPATH
        if not p.exists() and build:
            if shutil.which(CROSS_CC) is None:
                raise FluxdriveError(
                    f"PIL image not found: {p}; building it needs {CROSS_CC}, not found",
                    hint="apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi "
                         "(or pass --elf)")
            build_default(root, ELF_BUILD, "PIL image")
    if not p.is_file():
        raise FluxdriveError(f"PIL image not found: {p}", hint=ELF_HINT)
    return p.resolve()


def locate_runner(explicit: str | None, build: bool = True) -> Path:
    """--sil, else $FLUXDRIVE_SIL (both authoritative: never built), else the
    repo's build/host-release runner, built first when missing."""
    if not explicit and not os.environ.get(sil.ENV_SIL) and build:
        root = sil.find_repo_root()
        if root is not None and not (root / sil.SIL_RELPATH).exists():
            build_default(root, SIL_BUILD, "SIL runner")
    return sil.locate_sil(explicit)


def scenario_pwm_hz(src: Path) -> float:
    """The scenario's ``inverter.pwm_frequency`` (16 kHz when not given)."""
    try:
        sc = json.loads(src.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise FluxdriveError(f"{src}: {exc}") from None
    return float((sc.get("inverter") or {}).get("pwm_frequency", 16000.0))


def scenario_with_law(src: Path, law: str | None, dst: Path) -> str:
    try:
        sc = json.loads(src.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise FluxdriveError(f"{src}: {exc}") from None
    ctrl = sc.setdefault("controller", {})
    if law is not None:
        ctrl["law"] = law
    dst.write_text(json.dumps(sc, indent=2) + "\n", encoding="utf-8")
    return str(ctrl.get("law", "foc"))


def trace_windows(elf: Path, workdir: Path, head: bytes, body: np.ndarray, force: bool,
                  timeout: float, tab: dict | None, windows: list[tuple[int, int]],
                  untraced: np.ndarray) -> tuple[TraceResult, bool]:
    """Traces the ISRs of ``windows`` only: the records before each window
    replayed untraced up to it (from the previous window's state), its state
    saved (pil_snap.bin), the window traced from that state. The per-ISR
    lists have an entry per record, None where not traced; True when every
    window's outputs equal the untraced replay's."""
    n = len(body)
    tr = TraceResult(counts=[None] * n, funcs=[None] * n, cycles=[None] * n,
                     func_cycles=[None] * n, calls=[None] * n)
    exact, pos = True, 0
    (workdir / "pil_snap.bin").unlink(missing_ok=True)
    for a, b in windows:
        if a > pos:  # the gap, untraced, from the state at pos to the state at a
            write_pil_input(workdir / "pil_in.bin", head, body, a, force, pos,
                            SNAP_SAVE | (SNAP_LOAD if pos else 0))
            run_qemu(elf, workdir, timeout)
        write_pil_input(workdir / "pil_in.bin", head, body, b, force, a,
                        SNAP_SAVE | (SNAP_LOAD if a else 0))
        w, out = run_qemu_trace(elf, workdir, timeout, tab)
        if len(w.counts) != b - a:
            raise FluxdriveError(f"trace shows {len(w.counts)} ISRs, replayed {b - a}",
                                 exit_code=1)
        exact &= out.tobytes() == untraced[a:b].tobytes()
        for name in ("counts", "funcs", "cycles", "func_cycles", "calls"):
            getattr(tr, name)[a:b] = getattr(w, name)
        tr.unknown_pcs |= w.unknown_pcs
        pos = b
    return tr, exact


def run_one(runner: Path, elf: Path, scenario: Path, law: str | None, isrs: int,
            workdir: Path, force: bool, timeout: float, tab: dict | None = None,
            stand_ins: frozenset = frozenset(cm4_cycles.BOARD_HAL),
            procs: bool = False, sample: int = 0) -> list[PilRun]:
    """One scenario and law; ``isrs`` ISRs traced (0: all). The law's run,
    and with ``procs`` one per procedure that ran (proc_isrs); without
    ``procs`` or with law ISRs traced, the law's first."""
    workdir = workdir.resolve()  # QEMU runs in it and gets the FIFO's path
    workdir.mkdir(parents=True, exist_ok=True)
    scen = workdir / "scenario.json"
    law_name = scenario_with_law(scenario, law, scen)
    rec = workdir / "rec.bin"
    rec.unlink(missing_ok=True)
    r = sil.run_sil([str(runner), str(scen), "--record-isr", str(rec)])
    if not r.ok:
        sil.relay_stderr(r)
        raise FluxdriveError(f"SIL runner failed (exit {r.returncode})", exit_code=1)
    head, body, host = read_record(rec)

    write_pil_input(workdir / "pil_in.bin", head, body, len(body), force)
    pil_out = run_qemu(elf, workdir, timeout)
    agreement = compare(host, pil_out)

    names = list(params.proc_ids())
    traced = None
    if sample > 0:
        windows = sample_windows(host_procs(body), host_procs(body, HOST_PHASE_AT), names,
                                 sample)
        if not windows:
            raise FluxdriveError("--sample: no procedure ran in this scenario", exit_code=1)
        tr, exact = trace_windows(elf, workdir, head, body, force, timeout, tab, windows,
                                  pil_out)
        traced = sum(b - a for a, b in windows)
    else:
        n = len(body) if isrs <= 0 else min(isrs, len(body))
        write_pil_input(workdir / "pil_in.bin", head, body, n, force)
        tr, traced_out = run_qemu_trace(elf, workdir, timeout, tab)
        if len(tr.counts) != n:
            raise FluxdriveError(f"trace shows {len(tr.counts)} ISRs, replayed {n}", exit_code=1)
        exact = traced_out.tobytes() == pil_out[:n].tobytes()
    budget = budget_cycles(scenario_pwm_hz(scen))
    runs = []
    if not procs or law_isrs(tr, host):
        runs.append(PilRun(scenario.stem, law_name, agreement, law_counts(tr, host, stand_ins),
                           exact, budget, traced=traced))
    if procs:
        groups = proc_isrs(tr, host_procs(body), names)
        if not groups and not runs:
            raise FluxdriveError("no ISR ran the law or a procedure in the traced window",
                                 exit_code=1)
        for name, js in groups.items():
            runs.append(PilRun(scenario.stem, law_name, agreement,
                               law_counts(tr, host, stand_ins, js), exact, budget, name,
                               traced))
    return runs


# ---------------------------------------------------------------- report
def _pct(cycles: float, budget: int = BUDGET_CYCLES) -> str:
    return f"{100 * cycles / budget:.0f} %"


def board_estimate(c: Counts, board: cm4_cycles.BoardBound) -> tuple[float, float]:
    """(typical, worst) cycles on the board: the PIL's drive_isr cycles with
    its replay HAL replaced by the board HAL, plus the ISR wrapper and the
    exception (typical with the PIL mean, worst with the PIL worst)."""
    base = -c.stand_in_cycles()
    t, w = board.typical, board.worst
    return (c.cycles_mean + base + t.hal_cycles + t.wrapper_cycles,
            c.cycles_worst + base + w.hal_cycles + w.wrapper_cycles)


def board_estimate_cordic(c: Counts, board: cm4_cycles.BoardBound) -> tuple[float, float] | None:
    """board_estimate with, besides the HAL, the core's software trigonometry
    replaced by the board's CORDIC bindings (cordic_bind.c; cycles per call
    from `fluxdrive cycles-board`), ISR by ISR: (typical: the mean, worst:
    the largest). None without the per-ISR calls."""
    if not c.trig_isr:
        return None
    hw = {p.name: p.cycles for p in board.trig}
    y = [cy - sw + sum(k * hw.get(f, 0) for f, k in calls.items())
         for cy, sw, calls in c.trig_isr]
    base = -c.stand_in_cycles()
    t, w = board.typical, board.worst
    return (sum(y) / len(y) + base + t.hal_cycles + t.wrapper_cycles,
            max(y) + base + w.hal_cycles + w.wrapper_cycles)


def trig_on_cordic(c: Counts, board: cm4_cycles.BoardBound) -> float | None:
    """Instructions per ISR with the core's software trigonometry
    (fd_sincosf, fd_atan2f, the Q31 CORDIC: what cordic_bind.c binds to the
    STM32G4's CORDIC co-processor) replaced by the board's bindings, per
    call as traced; the rest as the PIL counts it (its replay HAL included).
    None without the per-call counts (--functions)."""
    if not c.calls:
        return None
    trig = {p.name: p.insns for p in board.trig}
    sw = sum(k * v for f, (k, v) in c.calls.items() if f in trig)
    hw = sum(c.calls[f][0] * n for f, n in trig.items() if f in c.calls)
    return c.mean - sw + hw


def traced_text(isrs: int, total: int, sampled: int | None = None) -> str:
    if sampled is not None:
        return f"{sampled} of {total} ISRs traced: --sample's windows"
    if isrs <= 0 or isrs >= total:
        return f"all {total} ISRs traced"
    return f"first {isrs} of {total} ISRs traced"


def format_report(runs: list[PilRun], isrs: int, cpi: float | None = None,
                  board: cm4_cycles.BoardBound | None = None, functions: bool = False) -> str:
    lines = []
    for r in runs:
        a, c = r.agreement, r.counts
        bud = r.budget  # this run's: the scenario's PWM frequency
        lines.append(f"== {r.scenario} / {r.law}" + (f" / procedure {r.proc}" if r.proc else ""))
        lines.append(
            f"agreement over {a.isrs} ISRs: max |duty dev| {a.max_duty_dev:.3g} at ISR "
            f"{a.max_dev_isr} (tolerance {DUTY_TOL:g}), {a.duty_bad} duty / {a.gates_bad} gate / "
            f"{a.faults_bad} fault / {a.state_bad} state mismatches -> "
            f"{'OK' if a.ok else 'FAIL'}"
        )
        lines.append(
            f"instructions per ISR over {c.isrs} {'ISRs of the procedure' if r.proc else 'law ISRs'}"
            f" ({traced_text(isrs, a.isrs, r.traced)}): mean "
            f"{c.mean:.0f}, worst {c.worst} (ISR {c.worst_isr}); traced outputs identical to "
            f"untraced: {r.trace_exact}"
        )
        lines.append(
            f"estimated cycles (Cortex-M4 model, docs/pil.md): mean {c.cycles_mean:.0f}, worst "
            f"{c.cycles_worst} (ISR {c.cycles_worst_isr}); {c.cpi:.2f} cycles/instruction; "
            f"{_pct(c.cycles_mean, bud)} mean / {_pct(c.cycles_worst, bud)} worst of {bud}"
            + (f" (legacy {cpi:g} cycles/instruction: {_pct(c.worst * cpi, bud)} worst)"
               if cpi else "")
        )
        if board is not None:
            bt, bw = board_estimate(c, board)
            lines.append(
                f"board estimate (PIL - replay HAL {c.stand_in_cycles():.0f} + board HAL + ISR "
                f"wrapper and exception, `fluxdrive cycles-board`): typical {bt:.0f} "
                f"({_pct(bt, bud)}), worst {bw:.0f} ({_pct(bw, bud)})"
            )
            bc = board_estimate_cordic(c, board)
            if bc is not None:
                lines.append(
                    f"board estimate with the core's trigonometry on the board's CORDIC "
                    f"co-processor (cordic_bind.c, per call, ISR by ISR): typical {bc[0]:.0f} "
                    f"({_pct(bc[0], bud)}), worst {bc[1]:.0f} ({_pct(bc[1], bud)})"
                )
            tc = trig_on_cordic(c, board)
            if tc is not None:
                lines.append(
                    f"instructions per ISR with the core's trigonometry on the board's CORDIC "
                    f"co-processor (cordic_bind.c, per call as traced): mean {tc:.0f}"
                )
        lines.append("  instr/ISR  share  cycles/ISR  cyc/instr  block")
        for b, v in sorted(c.blocks.items(), key=lambda kv: -kv[1]):
            y = c.block_cycles.get(b, 0.0)
            cpi_b = y / v if v else 0.0
            lines.append(f"  {v:8.1f}  {100 * v / c.mean:5.1f} %  {y:9.1f}  {cpi_b:8.2f}   {b}")
        if functions:
            lines.append("  instr/ISR  share  cycles/ISR  cyc/instr  function")
            for f, v in sorted(c.funcs.items(), key=lambda kv: -kv[1]):
                y = c.func_cycles.get(f, 0.0)
                cpi_f = y / v if v else 0.0
                lines.append(f"  {v:8.1f}  {100 * v / c.mean:5.1f} %  {y:9.1f}  {cpi_f:8.2f}   "
                             f"{f or '?'}")
            lines.append("  calls/ISR  instr/call (callees included)  function")
            for f, (k, v) in sorted(c.calls.items(), key=lambda kv: -kv[1][0] * kv[1][1]):
                lines.append(f"  {k:9.2f}  {v:10.1f}                     {f or '?'}")
    return "\n".join(lines)


SECTION = "### The laws on the encoder (PIL, QEMU mps2-an386)"


def format_markdown(runs: list[PilRun], isrs: int, cpi: float | None, build: str,
                    board: cm4_cycles.BoardBound | None = None) -> str:
    out = [SECTION, ""]
    window = ("every ISR of each run traced" if isrs <= 0
              else f"within the first {isrs} ISRs of each scenario")
    out.append(
        f"Measured by `fluxdrive pil` (docs/pil.md): the ISR inputs of a SIL run replayed on "
        f"the Cortex-M4F image in QEMU 7.2 `mps2-an386` (`{build}`), executed instructions "
        f"counted exactly from the `-singlestep -d exec,nochain` trace, from `drive_isr` "
        f"entry to its return, callees included, over the ISRs that ran the control law "
        f"({window}). The cycles are an **estimate**: every traced instruction priced with the Cortex-M4 cycle model of docs/pil.md "
        f"(TRM instruction timings, zero wait states, taken branches from the traced PC "
        f"sequence, P = {cm4_cycles.P}), against the cycles per ISR at 170 MHz and the "
        f"scenario's PWM frequency ({BUDGET_CYCLES} at 16 kHz). Not included: the board's ISR wrapper, exception entry/exit "
        f"and register HAL (`fluxdrive cycles-board`{', below' if board else ''})."
    )
    out.append("")
    legacy = f" worst x {cpi:g} (legacy) |" if cpi else ""
    out.append("| scenario | law | law ISRs | instructions mean | instructions worst | "
               "cycles mean | cycles worst | cycles/instr | budget mean | budget worst |"
               f"{legacy} duties max dev (full run) | ISRs compared |")
    out.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|" if cpi else "")
               + "---:|---:|")
    for r in runs:
        c, a = r.counts, r.agreement
        out.append(
            f"| {r.scenario} | {_law_label(r)} | {c.isrs} | {c.mean:.0f} | {c.worst} | "
            f"{c.cycles_mean:.0f} | {c.cycles_worst} | {c.cpi:.2f} | "
            f"{_pct(c.cycles_mean, r.budget)} | {_pct(c.cycles_worst, r.budget)} |"
            + (f" {_pct(c.worst * cpi, r.budget)} |" if cpi else "")
            + f" {a.max_duty_dev:.2g}{'' if a.ok else ' (FAIL)'} | {a.isrs} |"
        )
    out.append("")
    if board is not None:
        t, w = board.typical, board.worst
        out.append(
            f"Board ISR path outside `drive_isr` (`fluxdrive cycles-board`, same model plus "
            f"exception entry/exit with lazy FP stacking and bus wait states): wrapper "
            f"{t.wrapper_cycles} cycles typical (two entries: the first ADC end, the "
            f"period) / {w.wrapper_cycles} worst (a third, spurious entry, overrun "
            f"bookkeeping, ART misses); board HAL called by "
            f"`drive_isr` {t.hal_cycles} / {w.hal_cycles} (replaces the PIL's replay HAL). "
            f"Board estimate = PIL cycles - replay HAL + board HAL + wrapper; with the "
            f"CORDIC: also the core's software trigonometry replaced by the board's "
            f"co-processor bindings, ISR by ISR:"
        )
        out.append("")
        out.append("| scenario | law | board typical (PIL mean) | board worst (PIL worst) | "
                   "with the CORDIC: typical | worst |")
        out.append("|---|---|---:|---:|---:|---:|")
        for r in runs:
            bt, bw = board_estimate(r.counts, board)
            bc = board_estimate_cordic(r.counts, board)
            cc = (f"{bc[0]:.0f} ({_pct(bc[0], r.budget)}) | {bc[1]:.0f} "
                  f"({_pct(bc[1], r.budget)})" if bc is not None else "- | -")
            out.append(f"| {r.scenario} | {_law_label(r)} | {bt:.0f} ({_pct(bt, r.budget)}) | "
                       f"{bw:.0f} ({_pct(bw, r.budget)}) | {cc} |")
        out.append("")
    out.append("Share of the mean per block (instructions per ISR, % of the mean; estimated "
               "cycles per ISR):")
    out.append("")
    for r in runs:
        c = r.counts
        out.append(f"* {r.scenario} / {_law_label(r)}: " + "; ".join(
            f"{b} {v:.0f} ({100 * v / c.mean:.0f} %, {c.block_cycles.get(b, 0.0):.0f} cyc)"
            for b, v in sorted(c.blocks.items(), key=lambda kv: -kv[1]) if v >= 0.5))
    out.append("")
    return "\n".join(out)


def update_markdown(path: Path, section: str) -> None:
    """Replace our section (from its heading to the next '## ' or '### '
    heading) or append it; other sections are left as they are."""
    text = path.read_text(encoding="utf-8") if path.exists() else "# Benchmarks\n\n"
    lines = text.splitlines(keepends=True)
    start = next((i for i, ln in enumerate(lines) if ln.rstrip() == SECTION), None)
    if start is None:
        if not text.endswith("\n"):
            text += "\n"
        new = text + ("\n" if not text.endswith("\n\n") else "") + section
    else:
        end = next((i for i in range(start + 1, len(lines))
                    if lines[i].startswith("## ") or lines[i].startswith("### ")), len(lines))
        tail = "".join(lines[end:])
        new = "".join(lines[:start]) + section + ("\n" + tail if tail else "")
    path.write_text(new, encoding="utf-8")


def tools_available() -> None:
    if shutil.which(QEMU) is None:
        raise FluxdriveError(f"{QEMU} not found", hint="apt-get install qemu-system-arm")


LAWS = tuple(params.law_ids())


def main(args) -> int:
    """``fluxdrive pil``: see the module docstring."""
    import time

    tools_available()
    scenarios = []
    for s in args.scenario:
        p = Path(s)
        if not p.is_file():
            raise FluxdriveError(f"scenario not found: {p}")
        scenarios.append(p.resolve())
    laws: list[str | None] = [None]
    if args.law:
        laws = [x.strip() for x in args.law.split(",") if x.strip()]
        bad = [x for x in laws if x not in LAWS]
        if bad:
            raise FluxdriveError(f"unknown law {bad[0]!r}; use {', '.join(LAWS)}")
    try:
        guards = parse_proc_limits(getattr(args, "proc_limit", None))
    except ValueError as exc:
        raise FluxdriveError(str(exc)) from None
    runner = locate_runner(args.sil)
    elf = locate_elf(args.elf)
    # absolute: QEMU runs with its working directory in here
    out_dir = (Path(args.out) if args.out else Path("out") / "pil").resolve()
    prog = cm4_cycles.load_program(elf)
    if prog.unclassified():
        print(f"warning: instructions outside the cycle model (1 cycle assumed): "
              f"{prog.unclassified()}")
    tab = cm4_cycles.trace_table(prog)
    hal = cm4_cycles.stand_ins(prog)
    board = None
    if args.board_elf:
        bp = Path(args.board_elf)
        if not bp.is_file():
            raise FluxdriveError(f"board image not found: {bp}",
                                 hint="cmake --preset stm32g474 && cmake --build --preset "
                                      "stm32g474")
        board = cm4_cycles.bound_board(cm4_cycles.load_program(bp), str(bp))
        print(cm4_cycles.format_board(board), flush=True)
    cpi = getattr(args, "cpi", None)
    runs: list[PilRun] = []
    for sc in scenarios:
        for law in laws:
            t0 = time.monotonic()
            wd = out_dir / f"{sc.stem}-{law or 'scenario'}"
            rr = run_one(runner, elf, sc, law, args.isrs, wd, not args.free_running,
                         args.timeout, dict(tab), hal, getattr(args, "procs", False),
                         getattr(args, "sample", 0) or 0)
            runs += rr
            print(format_report(rr, args.isrs, cpi, board, args.functions), flush=True)
            print(f"  ({time.monotonic() - t0:.1f} s, files in {wd})", flush=True)
    build = "MinSizeRel -Os, -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard"
    if getattr(args, "procs", False):
        print(format_proc_table(runs, board))
    md = format_markdown(runs, args.isrs, cpi, build, board)
    if args.markdown:
        update_markdown(Path(args.markdown), md)
        print(f"markdown: {args.markdown} (section '{SECTION.lstrip('# ')}')")
    plain = [r for r in runs if r.proc not in guards]
    rc = check_runs(plain, args.check_worst, getattr(args, "check_cycles", None),
                    getattr(args, "check_mean", None), getattr(args, "check_call", None),
                    getattr(args, "check_worst_all", None))
    rc |= check_board(plain, getattr(args, "check_board", None), board)
    for name, (mean, worst, pct) in guards.items():
        mine = [r for r in runs if r.proc == name]
        if not mine:
            print(f"FAIL: --proc-limit {name}: the procedure did not run in the traced window")
            rc = 1
        rc |= check_runs(mine, None, None, mean, None, worst)
        rc |= check_board(mine, pct, board)
    lim = getattr(args, "check_mean_cordic", None)
    if lim:
        for r in runs:
            tc = trig_on_cordic(r.counts, board) if board is not None else None
            ok = tc is not None and tc < lim
            got = "not measured (needs --board-elf and --functions)" if tc is None else \
                f"{tc:.0f} instructions"
            print(f"{'check' if ok else 'FAIL'}: {_name(r)}: mean with the trigonometry "
                  f"on the CORDIC co-processor {got}, limit {lim}")
            rc |= 0 if ok else 1
    return rc


def check_board(runs: list[PilRun], lim: float | None,
                board: cm4_cycles.BoardBound | None) -> int:
    """--check-board: each run's board worst case with the trigonometry on
    the CORDIC at most ``lim`` % of its budget. Prints; 1 on failure."""
    rc = 0
    if not lim:
        return rc
    for r in runs:
        bc = board_estimate_cordic(r.counts, board) if board is not None else None
        ok = bc is not None and bc[1] <= lim / 100.0 * r.budget
        got = "not measured (needs --board-elf)" if bc is None else \
            f"{bc[1]:.0f} estimated cycles = {100 * bc[1] / r.budget:.1f} % of {r.budget}"
        print(f"{'check' if ok else 'FAIL'}: {_name(r)}: board worst case with the "
              f"trigonometry on the CORDIC co-processor {got}, limit {lim:g} %")
        rc |= 0 if ok else 1
    return rc


def parse_proc_limits(items: list[str] | None) -> dict[str, tuple[int, int, float]]:
    """--proc-limit PROC=MEAN,WORST,PCT items as {PROC: (MEAN, WORST, PCT)}:
    that procedure's ISRs checked against these (mean and worst instructions,
    board worst % of the budget) in place of --check-mean, --check-worst-all
    and --check-board. ValueError names a bad one."""
    out = {}
    for it in items or []:
        name, sep, rest = it.partition("=")
        try:
            m, w, p = (float(x) for x in rest.split(","))
        except ValueError:
            m = w = p = -1.0
        if not sep or not name or min(m, w, p) <= 0:
            raise ValueError(f"--proc-limit {it!r}: expected PROC=MEAN,WORST,PCT, each > 0")
        out[name] = (int(m), int(w), p)
    return out


def _law_label(r: PilRun) -> str:
    """The law, or for a procedure's ISRs (--procs) the procedure."""
    return f"{r.law}, procedure {r.proc}" if r.proc else r.law


def _name(r: PilRun) -> str:
    return f"{r.scenario}/{r.law}" + (f"/{r.proc}" if r.proc else "")


def format_proc_table(runs: list[PilRun], board: cm4_cycles.BoardBound | None) -> str:
    """The procedures' ISR cost (--procs): per procedure and scenario, its
    ISRs, instructions mean and worst, estimated cycles worst, and the
    board worst case (the CORDIC estimate, as --check-board) in % of the
    budget."""
    lines = ["procedure ISR cost (PIL; board worst: estimated cycles, trigonometry on the "
             "CORDIC, % of the budget)",
             f"  {'procedure':10s} {'scenario':24s} {'ISRs':>7s} {'mean':>6s} {'worst':>6s} "
             f"{'cyc worst':>9s} {'board worst':>11s}"]
    for r in runs:
        if not r.proc:
            continue
        c = r.counts
        bc = board_estimate_cordic(c, board) if board is not None else None
        bw = f"{100 * bc[1] / r.budget:10.1f}%" if bc is not None else f"{'-':>11s}"
        lines.append(f"  {r.proc:10s} {r.scenario:24s} {c.isrs:7d} {c.mean:6.0f} {c.worst:6d} "
                     f"{c.cycles_worst:9d} {bw}")
    return "\n".join(lines)


def parse_call_limits(items: list[str] | None) -> dict[str, float]:
    """FUNC=N items of --check-call as {FUNC: N}; ValueError names a bad one."""
    out = {}
    for it in items or []:
        f, sep, n = it.partition("=")
        try:
            lim = float(n)
        except ValueError:
            lim = -1.0
        if not sep or not f or lim <= 0:
            raise ValueError(f"--check-call {it!r}: expected FUNC=N with N > 0")
        out[f] = lim
    return out


def check_runs(runs: list[PilRun], worst_instr: int | None, worst_pct: float | None,
               mean_instr: int | None = None, call_limits: list[str] | None = None,
               worst_all: int | None = None) -> int:
    """Agreement and exact trace for every run; with limits, the DB-DFVC
    worst case: fewer than ``worst_instr`` instructions and at most
    ``worst_pct`` % of the cycle budget (estimated); every run's mean below
    ``mean_instr`` and worst case below ``worst_all`` (every law); each
    FUNC of ``call_limits`` (FUNC=N) at most N instructions per call,
    callees included. Prints; 1 on failure."""
    rc = 0
    limits = parse_call_limits(call_limits)
    for r in runs:
        name = f"{r.scenario}/{r.law}" + (f"/{r.proc}" if r.proc else "")
        for f, lim in limits.items():
            k, v = r.counts.calls.get(f, (0.0, float("inf")))
            ok = k > 0 and v <= lim
            print(f"{'check' if ok else 'FAIL'}: {name}: {f} {v:.1f} instructions per call "
                  f"({k:.2f} calls per ISR), limit {lim:g}")
            rc |= 0 if ok else 1
        if not r.agreement.ok:
            print(f"FAIL: {name}: PIL outputs disagree with the host build")
            rc = 1
        if not r.trace_exact:
            print(f"FAIL: {name}: traced replay differs from the untraced one")
            rc = 1
        if mean_instr:
            ok = r.counts.mean < mean_instr
            print(f"{'check' if ok else 'FAIL'}: {name}: mean {r.counts.mean:.0f} instructions, "
                  f"limit {mean_instr}")
            rc |= 0 if ok else 1
        if worst_all:
            ok = r.counts.worst < worst_all
            print(f"{'check' if ok else 'FAIL'}: {name}: worst case {r.counts.worst} instructions "
                  f"(ISR {r.counts.worst_isr}), limit {worst_all}")
            rc |= 0 if ok else 1
        if r.law != "db_dfvc" or r.proc:
            continue
        c = r.counts
        if worst_instr:
            ok = c.worst < worst_instr
            print(f"{'check' if ok else 'FAIL'}: {name}: worst case {c.worst} instructions "
                  f"(ISR {c.worst_isr}), limit {worst_instr}")
            rc |= 0 if ok else 1
        if worst_pct:
            lim = worst_pct / 100.0 * r.budget
            ok = c.cycles_worst <= lim
            pct = 100 * c.cycles_worst / r.budget
            print(f"{'check' if ok else 'FAIL'}: {name}: worst case {c.cycles_worst} estimated "
                  f"cycles (ISR {c.cycles_worst_isr}) = {pct:.1f} % of {r.budget}, "
                  f"limit {worst_pct:g} % ({lim:.0f})")
            rc |= 0 if ok else 1
    return rc
