"""Cortex-M4F cycle estimate from a per-instruction-class model (docs/pil.md).

The PIL counts executed instructions exactly (QEMU ``-singlestep -d
exec,nochain``); QEMU has no timing. This module turns the executed PC
sequence into an *estimate* of Cortex-M4 core cycles with the model below,
taken from the Arm Cortex-M4 Technical Reference Manual (DDI 0439, r0p1):
table 3-1 "Cortex-M4 instruction set summary" with section 3.3.2 "Load/store
timings", and table 7-1 "FPU instruction set" (cycle counts for zero wait
state memory). Everything the model assumes is in this block; the tests
(tests/python/test_cm4_cycles.py) pin every class's cost and docs/pil.md
shows :data:`MODEL_TABLE` verbatim.

Per executed instruction the cost depends on the instruction and on how it
was reached:

* ``jump`` cost: the class cost below (the instruction did not follow its
  static predecessor, e.g. a branch target or a return address);
* ``seq`` cost: reached by falling through from the instruction before it,
  so the TRM's pairwise rules apply: a single load/store directly after a
  single load pipelines (one cycle less, unless its address uses the
  load's destination register), and a load/store whose address register
  was written by the data-processing instruction just before it stalls one
  cycle (no forwarding path to the address generation unit);
* a conditional branch (B{cond}, CBZ/CBNZ, any PC write inside an IT block)
  costs 1 and the refill ``P`` is added when the next executed PC is not
  its fall-through address (taken). Unconditional branches include ``P``.

Not modelled (so the figures are a model, not a measurement): FPU data
hazards, integer work overlapping a VDIV/VSQRT (taken as 14 cycles, the
TRM's figure, with nothing overlapped), IT folding (IT counts 1), literal
load/fetch contention, I-bus/D-bus contention on CCM SRAM (the board runs
the ISR code *and* its data from CCM SRAM), interrupts during the ISR.
Memory: zero wait states for the PIL path (board: code and drive data in
CCM SRAM, stack in SRAM1); the board wrapper's peripheral accesses get the
bus wait states of :data:`BUS_WAIT`.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

from fluxdrive.errors import FluxdriveError

# =================================================================== model
P = 2  #: pipeline refill after a taken branch; TRM: 1..3 (alignment/width of the target)
ALU = 1  #: data processing, shifts, extends, bit-field, MOV/MOVW/MOVT, CMP/TST, NOP
MUL = 1  #: MUL/MLA/MLS, long multiply (+accumulate), DSP multiplies: single cycle on M4
DIV = 12  #: SDIV/UDIV: TRM 2..12, data dependent; the upper bound is used
LOAD = 2  #: single load LDR/LDRB/LDRH/LDRSB/LDRSH/LDREX, VLDR.32
PIPELINED = 1  #: a single load/store right after a single load (no address dependency)
STORE = 1  #: STR/STRB/STRH with immediate or no offset (TRM 3.3.2: always one cycle)
STORE_REG = 2  #: STR with a register offset
VSTR = 2  #: VSTR.32 (FPU table); VLDR.64/VSTR.64: 3
DOUBLE = 3  #: LDRD/STRD: 1 + N, N = 2; never pipelined
AGU_STALL = 1  #: load/store whose address register the previous data-processing op wrote
IT_COST = 1  #: IT (TRM: 0..1, it can fold into the previous 16-bit instruction)
FP = 1  #: VADD/VSUB/VMUL/VNMUL/VABS/VNEG/VCVT/VCMP(E)/VMOV/VMRS/VMSR
FP_MAC = 3  #: VMLA/VMLS/VNMLA/VNMLS (chained) and VFMA/VFMS/VFNMA/VFNMS (fused)
FP_DIV = 14  #: VDIV.F32, VSQRT.F32

#: The model as shown in docs/pil.md and the report: (class, instructions, cycles).
MODEL_TABLE: list[tuple[str, str, str]] = [
    ("integer ALU", "MOV/MVN/ADD/SUB/ADC/RSB/AND/ORR/EOR/BIC/shifts/extends/"
     "bit-field/CMP/TST/NOP, MOVW/MOVT, SEL, SIMD add/sub", f"{ALU}"),
    ("multiply", "MUL, MLA, MLS, SMULL/UMULL, SMLAL/UMLAL, DSP multiplies", f"{MUL}"),
    ("divide", "SDIV, UDIV (TRM 2-12, data dependent)", f"{DIV} (upper bound)"),
    ("single load", "LDR/LDRB/LDRH/LDRSB/LDRSH/LDREX, VLDR.32",
     f"{LOAD}; {PIPELINED} right after a single load whose destination it does not use as address"),
    ("single store", "STR/STRB/STRH, immediate or no offset", f"{STORE}"),
    ("single store, register offset", "STR Rt, [Rn, Rm]",
     f"{STORE_REG}; {PIPELINED} right after a single load"),
    ("FP store", "VSTR.32 (VLDR/VSTR.64: 3)", f"{VSTR}; {PIPELINED} right after a single load"),
    ("double", "LDRD, STRD", f"{DOUBLE} (1+N), not pipelined"),
    ("multiple", "LDM/STM/PUSH/POP, N registers", "1+N (+P when POP/LDM loads PC)"),
    ("FP multiple", "VLDM/VSTM/VPUSH/VPOP, N 32-bit words", "1+N"),
    ("address dependency", "load/store whose base/index register the previous "
     "data-processing instruction wrote", f"+{AGU_STALL}"),
    ("branch, conditional", "B{cond}, CBZ/CBNZ, PC writes in an IT block",
     f"1 not taken, 1+P taken (P = {P})"),
    ("branch, unconditional", "B, BL, BX, BLX, MOV/ADD PC", f"1+P = {1 + P}"),
    ("load to PC", "LDR PC (veneers); TBB/TBH", f"2+P = {2 + P}"),
    ("IT", "IT, ITT, ITE, ... (conditional instructions inside still count)",
     f"{IT_COST} (no folding)"),
    ("FP arithmetic", "VADD/VSUB/VMUL/VNMUL/VABS/VNEG/VCVT/VCMP(E)/VMOV/VMRS/VMSR",
     f"{FP} (VMOV of two core registers: 2)"),
    ("FP multiply-accumulate", "VMLA/VMLS/VNMLA/VNMLS, VFMA/VFMS/VFNMA/VFNMS", f"{FP_MAC}"),
    ("FP divide, square root", "VDIV.F32, VSQRT.F32", f"{FP_DIV} (no overlap)"),
    ("system", "MRS/MSR/CPSID/CPSIE/DMB/DSB/WFI/BKPT/SVC (ISB: 1+P)", "1"),
]

#: Board (STM32G474 at 170 MHz) memory and bus assumptions for the code the PIL
#: does not run (bound_board). Extra cycles per access on top of the
#: instruction's own cost: (read, write). Writes go through the core's write
#: buffer but are charged anyway (upper side). CCM SRAM, SRAM1/2 and the
#: private peripheral bus (DWT, NVIC) are zero wait state.
BUS_WAIT: dict[str, tuple[int, int]] = {
    "CCM SRAM": (0, 0),
    "SRAM": (0, 0),
    "PPB": (0, 0),
    "AHB": (2, 1),  # AHB1 (CORDIC), AHB2 (ADC, GPIO): bus matrix + slave
    "APB": (3, 2),  # APB1/APB2 (TIM1) at PCLK = HCLK: bus matrix + AHB/APB bridge
    "flash": (0, 0),  # data read from flash: ART data cache hit (worst: FLASH_WS)
    "untracked": (0, 0),  # address not known to the walker (caller's pointers): RAM assumed
}
#: Flash latency at 170 MHz (FLASH_ACR.LATENCY = 4, clock.c). Typical: ART
#: instruction/data cache hit, 0. Worst: a miss per 8-byte line entered and
#: per literal read.
FLASH_WS = 4
#: Exception entry and exit (TRM: 12 cycles each, zero wait states) and the
#: lazy FP state preservation: the main loop runs float code, so CONTROL.FPCA
#: is set in thread mode and the ADC interrupt gets the extended frame with
#: lazy stacking (FPCCR.LSPEN = ASPEN = 1, reset default); the ISR's first FP
#: instruction stores S0-S15 + FPSCR (17 words) and the return reloads them.
EXC_ENTRY, EXC_EXIT, LAZY_FP_SAVE, LAZY_FP_RESTORE = 12, 12, 17, 17
#: CORDIC read latency (RDATA inserts AHB wait states until the result is
#: ready): PRECISION = 6 (cordic.c), four iterations per cycle.
CORDIC_LATENCY = 6
BUDGET_CYCLES = 10625  # 170 MHz / 16 kHz


def format_model_table() -> str:
    """The model as a markdown table (docs/pil.md holds this text verbatim)."""
    out = ["| class | instructions | cycles |", "|---|---|---|"]
    out += [f"| {c} | {i} | {y} |" for c, i, y in MODEL_TABLE]
    return "\n".join(out)


# ============================================================== mnemonics
_CONDS = frozenset("eq ne cs hs cc lo mi pl vs vc hi ls ge lt gt le al".split())
_B_COND = re.compile(r"^b(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le)$")
_IT = re.compile(r"^it[te]{0,3}$")

_ALU = frozenset("""
mov movs mvn mvns add adds addw adc adcs sub subs subw sbc sbcs rsb rsbs adr and ands
orr orrs eor eors bic bics orn orns lsl lsls lsr lsrs asr asrs ror rors rrx rrxs neg negs
cmp cmn tst teq ubfx sbfx bfi bfc clz rbit rev rev16 revsh uxtb uxth sxtb sxth uxtab uxtah
sxtab sxtah uxtb16 sxtb16 uxtab16 sxtab16 movw movt ssat usat ssat16 usat16 sel pkhbt pkhtb
nop cpy sadd16 sadd8 ssub16 ssub8 uadd16 uadd8 usub16 usub8 qadd qsub qdadd qdsub qadd16
qadd8 qsub16 qsub8 uqadd16 uqadd8 uqsub16 uqsub8 shadd16 shadd8 shsub16 shsub8 uhadd16
uhadd8 uhsub16 uhsub8 sasx ssax uasx usax qasx qsax shasx shsax uhasx uhsax uqasx uqsax
usad8 usada8
""".split())
_NO_DEST = frozenset("cmp cmn tst teq nop".split())
_MUL = re.compile(r"^(mul|mla|mls|[su]mull|[su]mlal|umaal|smul|smla|smmul|smmla|smmls|smuad|"
                  r"smusd|smlad|smlsd|smlald|smlsld)")
_MUL_TWO_DEST = re.compile(r"^([su]mull|[su]mlal|umaal|smlald|smlsld)")
_DIV = frozenset(("sdiv", "udiv"))
_LOAD1 = frozenset("ldr ldrb ldrh ldrsb ldrsh ldrex ldrexb ldrexh ldrt ldrbt ldrht ldrsbt "
                   "ldrsht pld pli".split())
_STORE1 = frozenset("str strb strh strex strexb strexh strt strbt strht".split())
_LDM = frozenset("ldm ldmia ldmfd ldmdb ldmea pop".split())
_STM = frozenset("stm stmia stmea stmdb stmfd push".split())
_VLDM = frozenset("vldm vldmia vldmdb vpop".split())
_VSTM = frozenset("vstm vstmia vstmdb vpush".split())
_FP1 = frozenset("vadd vsub vmul vnmul vabs vneg vcvt vcvtr vcvtb vcvtt vcmp vcmpe vmrs vmsr "
                 "vmov".split())
_FPMAC = frozenset("vmla vmls vnmla vnmls vfma vfms vfnma vfnms".split())
_FPDIV = frozenset(("vdiv", "vsqrt"))
_SYS = frozenset("mrs msr cpsid cpsie dmb dsb wfi wfe sev svc bkpt udf yield clrex".split())

_ALIAS = {"sb": "r9", "sl": "r10", "fp": "r11", "ip": "r12"}
_CORE_RE = re.compile(r"^(r1[0-5]|r\d|sp|lr|pc|sb|sl|fp|ip)$")
_LIST_ITEM = re.compile(r"^([rsd])(\d+)(?:-\1?(\d+))?$")


def _core(tok: str) -> str | None:
    t = tok.strip().rstrip("!").strip()
    if _CORE_RE.match(t):
        return _ALIAS.get(t, t)
    return None


def _split_ops(ops: str) -> list[str]:
    out, depth, cur = [], 0, []
    for ch in ops:
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            out.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    if cur and "".join(cur).strip():
        out.append("".join(cur).strip())
    return out


def _reglist(tok: str) -> list[str]:
    """'{r4, r5, pc}' / '{d8-d10}' / '{s14}' -> register names, ranges expanded."""
    regs: list[str] = []
    for item in tok.strip().strip("{}").split(","):
        item = item.strip()
        if not item:
            continue
        c = _core(item)
        if c:
            regs.append(c)
            continue
        m = _LIST_ITEM.match(item)
        if m:
            lo = int(m.group(2))
            hi = int(m.group(3)) if m.group(3) else lo
            regs += [f"{m.group(1)}{k}" for k in range(lo, hi + 1)]
        elif "-" in item:  # r4-r7 written with both prefixes
            a, b = item.split("-", 1)
            ma, mb = _LIST_ITEM.match(a.strip()), _LIST_ITEM.match(b.strip())
            if ma and mb:
                regs += [f"{ma.group(1)}{k}" for k in range(int(ma.group(2)),
                                                            int(mb.group(2)) + 1)]
    return regs


def _words(regs: Iterable[str]) -> int:
    return sum(2 if r.startswith("d") else 1 for r in regs)


def _imm(tok: str) -> int | None:
    t = tok.strip()
    if not t.startswith("#"):
        return None
    try:
        return int(t[1:], 0)
    except ValueError:
        return None


# ============================================================ instructions
@dataclass
class Insn:
    """One disassembled instruction and its class under the model."""

    addr: int
    size: int
    func: str
    mnem: str  # as printed by objdump, e.g. 'vmovgt.f32'
    ops: str  # operands without the '@' comment
    base: str = ""  # without condition / width / type suffix, e.g. 'vmov'
    cond: bool = False  # conditional: B{cond}, CBZ/CBNZ or inside an IT block
    cls: str = "unclassified"
    cost: int = 1  # cycles when not paired with its predecessor (taken penalty excluded)
    seq_cost: int = 1  # cycles when it follows its static predecessor (pair_adjust applied)
    pen: int = 0  # P when a conditional PC write; added when the next PC is not fall-through
    branch: bool = False  # may write the PC
    target: int | None = None  # direct branch target
    dests: frozenset = frozenset()  # core registers written
    dp: bool = False  # data processing writing a core register (AGU stall source)
    mem: str = ""  # 'r' load, 'w' store, '' none
    mem_words: int = 0
    addr_regs: frozenset = frozenset()
    basereg: str | None = None  # address base register ('sp' for PUSH/POP)
    offset: int | None = None  # immediate address offset (pre-index)
    post: int | None = None  # post-index immediate (writeback)
    writeback: bool = False
    single: bool = False  # single (non-double, non-multiple) load/store
    load1: bool = False  # single load that pipelines the next single load/store
    literal: bool = False  # PC-relative load

    @property
    def fall(self) -> int:
        return self.addr + self.size


def classify(ins: Insn, in_it: bool) -> Insn:
    """Fill the model fields of ``ins`` (``in_it``: inside an IT block)."""
    head = ins.mnem.lower().split(".", 1)[0]
    base = head
    if in_it and len(head) > 2 and head[-2:] in _CONDS:
        base = head[:-2]
        ins.cond = True
    elif _B_COND.match(head):
        base = "b"
        ins.cond = True
    ins.base = base
    ops = _split_ops(ins.ops)
    first = _core(ops[0]) if ops else None
    t = re.search(r"\b([0-9a-f]+) <", ins.ops)
    if t:
        ins.target = int(t.group(1), 16)

    def branch(cost_uncond: int, cost_cond: int) -> None:
        ins.branch = True
        if ins.cond:
            ins.cost, ins.pen = cost_cond, P
        else:
            ins.cost = cost_uncond

    if base in _ALU or _MUL.match(base) or base in _DIV:
        if base in _ALU:
            ins.cls, ins.cost = "integer ALU", ALU
        elif base in _DIV:
            ins.cls, ins.cost = "divide", DIV
        else:
            ins.cls, ins.cost = "multiply", MUL
        if first and base not in _NO_DEST:
            d = {first}
            if _MUL_TWO_DEST.match(base) and len(ops) > 1 and _core(ops[1]):
                d.add(_core(ops[1]))
            ins.dests = frozenset(d)
            ins.dp = True
            if first == "pc":
                ins.cls = "branch, unconditional"
                branch(1 + P, 1)
    elif _IT.match(head):
        ins.base, ins.cls, ins.cost = "it", "IT", IT_COST
    elif base in ("b", "bl", "blx", "bx", "cbz", "cbnz"):
        if base == "cbz" or base == "cbnz":
            ins.cond = True
        if base in ("bl", "blx"):
            ins.dests = frozenset({"lr"})
        ins.cls = "branch, conditional" if ins.cond else "branch, unconditional"
        branch(1 + P, 1)
    elif base in ("tbb", "tbh"):
        ins.cls, ins.mem, ins.mem_words = "load to PC", "r", 1
        branch(2 + P, 2)
    elif base in _LOAD1 or base in _STORE1 or base in ("ldrd", "strd", "vldr", "vstr"):
        _mem_single(ins, ops, base, first)
    elif base in _LDM or base in _STM or base in _VLDM or base in _VSTM:
        _mem_multiple(ins, ops, base)
    elif base in _FP1:
        ins.cls, ins.cost = "FP arithmetic", FP
        if base == "vmov":
            cores = [c for c in (_core(o) for o in ops) if c]
            if len(cores) >= 2:
                ins.cost = 2
            if first:
                lead = []
                for o in ops:
                    c = _core(o)
                    if not c:
                        break
                    lead.append(c)
                ins.dests, ins.dp = frozenset(lead), True
        elif base == "vmrs" and first:
            ins.dests, ins.dp = frozenset({first}), True
    elif base in _FPMAC:
        ins.cls, ins.cost = "FP multiply-accumulate", FP_MAC
    elif base in _FPDIV:
        ins.cls, ins.cost = "FP divide, square root", FP_DIV
    elif base in _SYS or base == "isb":
        ins.cls, ins.cost = "system", (1 + P if base == "isb" else 1)
        if base == "mrs" and first:
            ins.dests, ins.dp = frozenset({first}), True
    # else: unclassified, 1 cycle (reported by unclassified())
    return ins


def _mem_single(ins: Insn, ops: list[str], base: str, first: str | None) -> None:
    load = base.startswith("ldr") or base in ("vldr", "pld", "pli")
    ins.mem = "r" if load else "w"
    mi = next((i for i, o in enumerate(ops) if o.startswith("[")), None)
    if mi is not None:
        m = ops[mi]
        inner = m[1:m.index("]")] if "]" in m else m[1:]
        parts = _split_ops(inner)
        ins.addr_regs = frozenset(c for c in (_core(p) for p in parts) if c)
        ins.basereg = _core(parts[0]) if parts else None
        ins.offset = _imm(parts[1]) if len(parts) > 1 else 0
        reg_offset = len(parts) > 1 and _core(parts[1]) is not None
        ins.writeback = m.rstrip().endswith("!") or len(ops) > mi + 1
        if len(ops) > mi + 1:
            ins.post = _imm(ops[mi + 1])
        ins.literal = "pc" in ins.addr_regs
        if ins.literal:
            ins.addr_regs = ins.addr_regs - {"pc"}
    else:  # literal written as a label
        reg_offset, ins.literal = False, True
    rts = [c for c in (_core(o) for o in ops[: mi if mi is not None else len(ops)]) if c]
    dword = base in ("ldrd", "strd") or (base in ("vldr", "vstr") and ops and
                                         ops[0].strip().startswith("d"))
    ins.mem_words = 2 if dword else 1
    d = set(rts) if load else set()
    if ins.writeback and ins.basereg:
        d.add(ins.basereg)
    ins.dests = frozenset(x for x in d if x)
    if base in ("ldrd", "strd"):
        ins.cls, ins.cost = "double", DOUBLE
    elif base in ("vldr", "vstr"):
        if dword:
            ins.cls, ins.cost = ("single load" if load else "FP store"), 3
        elif load:
            ins.cls, ins.cost, ins.single, ins.load1 = "single load", LOAD, True, True
        else:
            ins.cls, ins.cost, ins.single = "FP store", VSTR, True
    elif load:
        ins.cls, ins.cost, ins.single = "single load", LOAD, True
        ins.load1 = base not in ("pld", "pli")
        if first == "pc":
            ins.cls = "load to PC"
            ins.load1 = ins.single = False
            ins.branch = True
            if ins.cond:
                ins.cost, ins.pen = LOAD, P
            else:
                ins.cost = LOAD + P
    else:
        if reg_offset:
            ins.cls, ins.cost = "single store, register offset", STORE_REG
        else:
            ins.cls, ins.cost = "single store", STORE
        ins.single = True


def _mem_multiple(ins: Insn, ops: list[str], base: str) -> None:
    load = base in _LDM or base in _VLDM
    ins.mem = "r" if load else "w"
    lst = next((o for o in ops if o.startswith("{")), "{}")
    regs = _reglist(lst)
    if base in ("push", "pop", "vpush", "vpop"):
        ins.addr_regs, ins.writeback = frozenset({"sp"}), True
        basereg = "sp"
    else:
        basereg = _core(ops[0]) if ops else None
        ins.addr_regs = frozenset({basereg}) if basereg else frozenset()
        ins.writeback = bool(ops) and ops[0].strip().endswith("!")
    ins.basereg = basereg
    fp = base in _VLDM or base in _VSTM
    n = _words(regs) if fp else len(regs)
    ins.mem_words = n
    ins.cls = "FP multiple" if fp else "multiple"
    ins.cost = 1 + n
    d = set(r for r in regs if not fp and r) if load else set()
    if ins.writeback and basereg:
        d.add(basereg)
    ins.dests = frozenset(d)
    if load and "pc" in regs:
        ins.branch = True
        if ins.cond:
            ins.pen = P
        else:
            ins.cost += P


def pair_adjust(prev: Insn, cur: Insn) -> int:
    """Cycles added to ``cur`` when it directly follows ``prev`` (fall-through)."""
    adj = 0
    if cur.mem and prev.dp and (cur.addr_regs & prev.dests):
        adj += AGU_STALL
    if (cur.single and prev.load1 and not prev.writeback and not prev.cond
            and not (cur.addr_regs & prev.dests) and cur.cost > PIPELINED):
        adj -= cur.cost - PIPELINED  # LOAD, STORE_REG, VSTR (2) -> PIPELINED
    return adj


# ================================================================ listings
_LINE = re.compile(r"^\s*([0-9a-f]+):\t([0-9a-f]{4}(?: [0-9a-f]{4})?|[0-9a-f]{8})\s*\t"
                   r"(\S+)\s*(.*)$")
_LABEL = re.compile(r"^([0-9a-f]+) <(.+)>:\s*$")


@dataclass
class Program:
    """A disassembled image: instructions by address, literal words, functions."""

    insns: dict[int, Insn] = field(default_factory=dict)
    words: dict[int, int] = field(default_factory=dict)  # .word data (literal pools)
    funcs: dict[str, int] = field(default_factory=dict)  # name -> entry address
    symbols: dict[str, tuple[int, int]] = field(default_factory=dict)  # data: name -> (addr, size)

    def unclassified(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for i in self.insns.values():
            if i.cls == "unclassified":
                out[i.mnem] = out.get(i.mnem, 0) + 1
        return out

    def cond_branches(self, func: str) -> list[Insn]:
        """The function's conditional branches in address order."""
        return sorted((i for i in self.insns.values() if i.func == func and i.cond and i.branch),
                      key=lambda i: i.addr)

    def callers(self) -> dict[str, set[str]]:
        """Direct calls and tail calls: function -> the functions that branch
        to its entry (indirect calls are not seen)."""
        entry = {a: f for f, a in self.funcs.items()}
        out: dict[str, set[str]] = {}
        for i in self.insns.values():
            f = entry.get(i.target) if i.branch and i.target is not None else None
            if f is not None and f != i.func:
                out.setdefault(f, set()).add(i.func)
        return out

    def ordinal(self, ins: Insn) -> int:
        """Index of a conditional branch in :meth:`cond_branches` of its function."""
        if not hasattr(self, "_ordinals"):
            by_func: dict[str, list[Insn]] = {}
            for i in sorted(self.insns.values(), key=lambda i: i.addr):
                if i.cond and i.branch:
                    by_func.setdefault(i.func, []).append(i)
            self._ordinals = {i.addr: k for lst in by_func.values() for k, i in enumerate(lst)}
        return self._ordinals.get(ins.addr, -1)


def parse_objdump(text: str) -> Program:
    """``arm-none-eabi-objdump -d`` output -> :class:`Program` (model applied)."""
    prog = Program()
    func = ""
    it_left = 0
    prev: Insn | None = None
    for raw in text.splitlines():
        m = _LABEL.match(raw)
        if m:
            func = m.group(2)
            prog.funcs.setdefault(func, int(m.group(1), 16))
            it_left, prev = 0, None
            continue
        m = _LINE.match(raw)
        if not m:
            continue
        addr, hexs, mnem, rest = int(m.group(1), 16), m.group(2), m.group(3), m.group(4)
        if mnem.startswith("."):  # .word / .short data (literal pool)
            if mnem == ".word":
                try:
                    prog.words[addr] = int(rest.split()[0], 0)
                except (ValueError, IndexError):
                    pass
            it_left, prev = 0, None
            continue
        ops = rest.split("\t@", 1)[0].split("@ ", 1)[0].strip() if "@" in rest else rest.strip()
        size = len(hexs.replace(" ", "")) // 2
        ins = classify(Insn(addr, size, func, mnem, ops), it_left > 0)
        if it_left > 0:
            it_left -= 1
        if ins.base == "it":
            it_left = len(mnem.split(".")[0]) - 1
        ins_prev = prev if prev is not None and prev.fall == addr else None
        ins.seq_cost = ins.cost + (pair_adjust(ins_prev, ins) if ins_prev else 0)
        prog.insns[addr] = ins
        prev = ins
    return prog


def find_objdump() -> str:
    for name in (os.environ.get("FLUXDRIVE_OBJDUMP"), "arm-none-eabi-objdump"):
        if name and shutil.which(name):
            return shutil.which(name) or name
    raise FluxdriveError("arm-none-eabi-objdump not found (set FLUXDRIVE_OBJDUMP)",
                         hint="apt-get install binutils-arm-none-eabi")


def load_program(elf: Path) -> Program:
    """Disassemble ``elf`` and apply the model (also reads its data symbols)."""
    objdump = find_objdump()
    r = subprocess.run([objdump, "-d", str(elf)], capture_output=True, text=True, check=False)
    if r.returncode != 0:
        raise FluxdriveError(f"objdump failed on {elf}: {r.stderr.strip()}", exit_code=1)
    prog = parse_objdump(r.stdout)
    s = subprocess.run([objdump, "-t", str(elf)], capture_output=True, text=True, check=False)
    for line in s.stdout.splitlines():
        # 20000078 l     O .bss	00000014 s_jdr
        p = line.split()
        if len(p) >= 5 and "O" in p[1:4]:
            try:
                prog.symbols[p[-1]] = (int(p[0], 16), int(p[-2], 16))
            except ValueError:
                pass
    return prog


# ========================================================= per-PC table
#: One trace-table entry: (seq cycles, jump cycles, fall-through key, taken penalty, function).
Entry = tuple


def trace_table(prog: Program) -> dict[bytes, Entry]:
    """Per-PC costs keyed like the QEMU trace prints the PC (``b'%08x'``)."""
    tab: dict[bytes, Entry] = {}
    for a, i in prog.insns.items():
        f = sys.intern(i.func)  # one object per function: the parser compares identities
        tab[b"%08x" % a] = (i.seq_cost, i.cost, b"%08x" % i.fall, i.pen, f)
    return tab


def sequence_cycles(prog: Program, pcs: list[int]) -> int:
    """Cycles of an executed PC sequence (the trace parser's rule, for tests
    and the board walker): seq cost when a PC follows its predecessor's
    fall-through, else the jump cost plus the predecessor's taken penalty."""
    total, nxt, pen = 0, None, 0
    for pc in pcs:
        i = prog.insns[pc]
        if pc == nxt:
            total += i.seq_cost
        else:
            total += i.cost + pen
        nxt, pen = i.fall, i.pen
    return total


# ============================================================ board bound
SENTINEL = 0xFFFFFFF8  # EXC_RETURN in LR (Thumb bit dropped): the walk ends at this PC


def region(addr: int) -> str:
    """STM32G474 memory map (RM0440 section 2.2) -> BUS_WAIT key."""
    if 0x10000000 <= addr < 0x10010000:
        return "CCM SRAM"
    if 0x20000000 <= addr < 0x20020000:
        return "SRAM"
    if 0x08000000 <= addr < 0x08100000:
        return "flash"
    if 0x40000000 <= addr < 0x40020000:
        return "APB"
    if 0x40020000 <= addr < 0x40030000 or 0x48000000 <= addr < 0x60000000:
        return "AHB"
    if 0xE0000000 <= addr < 0xE0100000:
        return "PPB"
    return "untracked"


#: RAM tables of peripheral register pointers: a load from one yields a
#: pointer into that bus region (adc.c: s_jdr[k] = &ADCx->JDR[rank]).
POINTER_TABLES = {"s_jdr": "AHB"}
STACK = "stack"  # value of SP and of SP-relative pointers


@dataclass(frozen=True)
class Ptr:
    """A value known only as 'points into region'."""

    region: str


@dataclass
class ExecPath:
    """One executed path: its PCs and the wait cycles of its accesses."""

    pcs: list[int] = field(default_factory=list)
    bus: int = 0  # bus and flash wait cycles
    accesses: dict[str, int] = field(default_factory=dict)  # region -> words
    flash_lines: set[int] = field(default_factory=set)

    def copy(self) -> "ExecPath":
        return ExecPath(list(self.pcs), self.bus, dict(self.accesses), set(self.flash_lines))

    def cycles(self, prog: Program) -> int:
        return sequence_cycles(prog, self.pcs) + self.bus


#: decide(conditional branch, its ordinal among its function's conditional
#: branches in address order, how often it was reached before on this path)
#: -> True taken, False not taken, None both (the longer path is kept).
Decide = Callable[[Insn, int, int], "bool | None"]


def walk(prog: Program, entry: int, decide: Decide, stop: set[int] = frozenset(),
         worst_flash: bool = False, max_steps: int = 50000,
         indirect: dict[str, int] | None = None) -> ExecPath:
    """Run the code from ``entry`` symbolically until it returns (LR holds
    :data:`SENTINEL`): the PC, constants and pointer regions in registers
    (literal loads, MOV/MOVW/MOVT/ADD/SUB immediates, writeback, PUSH/POP),
    nothing else. Calls into ``stop`` (drive_isr) return at once and are
    not counted. Conditional branches follow ``decide``; a backward one
    (a loop) must be decided. Each load/store adds :data:`BUS_WAIT` for the
    region of its address; with ``worst_flash`` code and literals in flash
    miss the ART cache (:data:`FLASH_WS` per 8-byte line entered / word).
    ``indirect`` names the target of a call through a register whose value
    the walk does not know, per calling function (a callback the code
    registered at start-up: adc.c's period body)."""
    st = _State(prog, decide, set(stop), worst_flash, max_steps, indirect or {})
    return st.run(entry, {"lr": SENTINEL, "sp": STACK}, [], {}, ExecPath())


class _State:
    def __init__(self, prog, decide, stop, worst_flash, max_steps, indirect):
        self.prog, self.decide, self.stop = prog, decide, stop
        self.worst_flash, self.steps = worst_flash, max_steps
        self.indirect = indirect

    def run(self, pc, regs, stack, visits, path):
        prog = self.prog
        while pc != SENTINEL:
            if pc in self.stop:  # excluded callee: returns to LR at once (AAPCS clobbers)
                for r in ("r0", "r1", "r2", "r3", "r12"):
                    regs.pop(r, None)
                pc = regs.pop("lr", None)
                if not isinstance(pc, int):
                    raise FluxdriveError("walk: return address unknown after an excluded call")
                continue
            ins = prog.insns.get(pc)
            if ins is None:
                raise FluxdriveError(f"walk: no instruction at 0x{pc:08x}")
            self.steps -= 1
            if self.steps < 0:
                raise FluxdriveError(f"walk: step limit reached in {ins.func} (unbounded loop?)")
            path.pcs.append(pc)
            if self.worst_flash and region(pc) == "flash" and (pc & ~7) not in path.flash_lines:
                path.flash_lines.add(pc & ~7)
                path.bus += FLASH_WS
            if ins.cond and ins.branch:
                n = visits.get(pc, 0)
                visits[pc] = n + 1
                d = self.decide(ins, prog.ordinal(ins), n)
                if d is None and ins.target is not None and ins.target <= ins.addr:
                    raise FluxdriveError(f"walk: loop at 0x{ins.addr:08x} in {ins.func} "
                                         f"needs a bound")
                if d is None:
                    r2, s2, p2 = dict(regs), list(stack), path.copy()
                    self._bus(ins, r2, p2)
                    alts = [self.run(self._taken(ins, r2, s2), r2, s2, dict(visits), p2),
                            self.run(ins.fall, regs, stack, visits, path)]
                    return max(alts, key=lambda p: p.cycles(prog))
                if d:
                    self._bus(ins, regs, path)
                    pc = self._taken(ins, regs, stack)
                else:
                    pc = ins.fall
                continue
            self._bus(ins, regs, path)
            nxt = self._effect(ins, regs, stack)
            if nxt is not None:
                pc = nxt
            elif ins.branch:
                if ins.target is None:
                    raise FluxdriveError(f"walk: indirect branch at 0x{ins.addr:08x} "
                                         f"({ins.mnem} {ins.ops})")
                pc = ins.target
            else:
                pc = ins.fall
        return path

    def _taken(self, ins, regs, stack):
        nxt = self._effect(ins, regs, stack)
        t = nxt if nxt is not None else ins.target
        if t is None:
            raise FluxdriveError(f"walk: branch target unknown at 0x{ins.addr:08x}")
        return t

    def _addr(self, ins, regs):
        if ins.literal:
            return ((ins.addr + 4) & ~3) + (ins.offset or 0)
        v = regs.get(ins.basereg or "")
        if isinstance(v, int):
            return (v + (ins.offset or 0)) & 0xFFFFFFFF
        return v

    def _bus(self, ins, regs, path):
        if not ins.mem:
            return
        a = self._addr(ins, regs)
        if ins.literal:
            reg = region(ins.addr)  # literal pool next to the code
        elif isinstance(a, int):
            reg = region(a)
        elif isinstance(a, Ptr):
            reg = a.region
        elif a == STACK:
            reg = "SRAM"
        else:
            reg = "untracked"
        words = max(1, ins.mem_words)
        path.accesses[reg] = path.accesses.get(reg, 0) + words
        r, w = BUS_WAIT[reg]
        path.bus += (r if ins.mem == "r" else w) * words
        if reg == "flash" and self.worst_flash and ins.mem == "r":
            path.bus += FLASH_WS * words

    def _effect(self, ins, regs, stack):
        """Register/stack effect of ``ins``; the next PC when it comes from
        the simulated state (returns, BX, veneers), else None."""
        prog, b = self.prog, ins.base
        ops = _split_ops(ins.ops)
        first = _core(ops[0]) if ops else None
        lst = _reglist(next((o for o in ops if o.startswith("{")), "{}"))
        if b == "push" or (b in _STM and ins.basereg == "sp" and ins.writeback):
            stack.extend(regs.get(r) for r in lst)
            return None
        if b == "pop" or (b in _LDM and ins.basereg == "sp" and ins.writeback):
            vals = [stack.pop() if stack else None for _ in lst][::-1]
            nxt = None
            for r, v in zip(lst, vals):
                if r == "pc":
                    if not isinstance(v, int):
                        raise FluxdriveError(f"walk: unknown return address at 0x{ins.addr:08x}")
                    nxt = v & ~1
                elif v is None:
                    regs.pop(r, None)
                else:
                    regs[r] = v
            return nxt
        if b in ("bl", "blx"):
            regs["lr"] = ins.fall
            if b == "blx" and ins.target is None:
                v = regs.get(first or "")
                if not isinstance(v, int):
                    v = self.indirect.get(ins.func)
                if not isinstance(v, int):
                    raise FluxdriveError(f"walk: unknown blx target at 0x{ins.addr:08x}")
                return v & ~1
            return None
        if b == "bx":
            v = regs.get(first or "")
            if not isinstance(v, int):
                raise FluxdriveError(f"walk: unknown bx target at 0x{ins.addr:08x}")
            return v & ~1
        if ins.basereg == "sp" and ins.writeback and first and (b in _LOAD1 or b in _STORE1):
            # single-register push/pop: str rt, [sp, #-4]! / ldr rt, [sp], #4
            if ins.mem == "w":
                stack.append(regs.get(first))
                return None
            v = stack.pop() if stack else None
            if first == "pc":
                if not isinstance(v, int):
                    raise FluxdriveError(f"walk: unknown return address at 0x{ins.addr:08x}")
                return v & ~1
            if v is None:
                regs.pop(first, None)
            else:
                regs[first] = v
            return None
        if ins.mem == "r" and ins.base in _LOAD1 and first:
            a = self._addr(ins, regs)
            val: object = None
            if isinstance(a, int):
                val = prog.words.get(a)
                for name, reg_ in POINTER_TABLES.items():
                    s = prog.symbols.get(name)
                    if s and s[0] <= a < s[0] + s[1]:
                        val = Ptr(reg_)
            self._writeback(ins, regs)
            if first == "pc":
                if not isinstance(val, int):
                    raise FluxdriveError(f"walk: unknown load to PC at 0x{ins.addr:08x}")
                return val & ~1
            if val is None:
                regs.pop(first, None)
            else:
                regs[first] = val
            return None
        if ins.mem:
            self._writeback(ins, regs)
            for r in ins.dests - {ins.basereg}:
                regs.pop(r, None)
            return None
        if ins.dp and first:
            v = _alu_value(b, ops, regs)
            for r in ins.dests:
                regs.pop(r, None)
            if v is not None:
                regs[first] = v
            return None
        for r in ins.dests:
            regs.pop(r, None)
        return None

    @staticmethod
    def _writeback(ins, regs):
        if not ins.writeback or not ins.basereg or ins.basereg == "sp":
            return
        v = regs.get(ins.basereg)
        if isinstance(v, int):
            if ins.base in _LDM | _STM | _VLDM | _VSTM:
                step = 4 * ins.mem_words * (-1 if "db" in ins.base else 1)
            else:
                step = ins.post if ins.post is not None else (ins.offset or 0)
            regs[ins.basereg] = (v + step) & 0xFFFFFFFF
        elif not isinstance(v, Ptr) and v != STACK:
            regs.pop(ins.basereg, None)


def _alu_value(b: str, ops: list[str], regs: dict) -> object:
    def val(o: str) -> object:
        c = _core(o)
        return regs.get(c) if c else _imm(o)

    src = [val(o) for o in ops[1:]]
    if b in ("mov", "movs", "movw", "cpy") and len(src) == 1:
        return src[0]
    if b in ("mvn", "mvns") and len(src) == 1 and isinstance(src[0], int):
        return ~src[0] & 0xFFFFFFFF
    if b == "movt" and len(src) == 1 and isinstance(src[0], int):
        old = regs.get(_core(ops[0]) or "")
        return (old & 0xFFFF) | (src[0] << 16) if isinstance(old, int) else None
    if b in ("add", "adds", "addw", "sub", "subs", "subw"):
        if len(src) == 1:  # two-operand form: Rd = Rd op imm
            src = [regs.get(_core(ops[0]) or ""), src[0]]
        if len(src) == 2 and isinstance(src[1], int):
            a = src[0]
            if isinstance(a, int):
                return (a + (src[1] if b.startswith("add") else -src[1])) & 0xFFFFFFFF
            if a == STACK or isinstance(a, Ptr):
                return a
    return None


# ------------------------------------------------------------- the board
#: Board HAL functions drive_isr calls in every ISR that runs the law (the
#: walk follows whatever they call); the PIL runs its replay stand-ins
#: (pil/hal_pil.c) instead.
BOARD_HAL = ("hal_adc_read", "hal_fault_hw_tripped", "hal_pwm_write")


def stand_ins(prog: Program) -> frozenset[str]:
    """The functions of a PIL image that the board replaces: :data:`BOARD_HAL`
    and what only they call (none today: the replay's timer model,
    hal_pattern.h, is inline)."""
    calls = prog.callers()
    out = set(f for f in BOARD_HAL if f in prog.funcs)
    grew = True
    while grew:
        grew = False
        for f, by in calls.items():
            if f not in out and by and by <= out:
                out.add(f)
                grew = True
    return frozenset(out)

#: The core's trig entry points, bound to the CORDIC on the board (cordic_bind.c).
BOARD_TRIG = ("fd_sincosf", "fd_atan2f", "fd_cordic_atan2_q31")
#: The period body the board application registers with hal_stm32g4_start
#: (boards/stm32g4/board_main.c), called by ADC1_2_IRQHandler through a
#: pointer; it tail-calls drive_isr.
BOARD_CONTROL = "board_control_isr"


@dataclass
class Part:
    name: str
    insns: int
    core: int  # model cycles at zero wait states
    bus: int = 0  # bus and flash wait cycles
    note: str = ""

    @property
    def cycles(self) -> int:
        return self.core + self.bus


@dataclass
class BoardCase:
    wrapper: list[Part]  # exceptions, ADC1_2_IRQHandler's two entries (drive_isr excluded)
    hal: list[Part]  # BOARD_HAL, as called from drive_isr

    @property
    def wrapper_cycles(self) -> int:
        return sum(p.cycles for p in self.wrapper)

    @property
    def hal_cycles(self) -> int:
        return sum(p.cycles for p in self.hal)


@dataclass
class BoardBound:
    elf: str
    typical: BoardCase
    worst: BoardCase
    trig: list[Part]  # informational: per call, longest path


def _check_branches(prog: Program, func: str, expect: tuple[str, ...]) -> None:
    got = tuple(b.mnem.split(".")[0] for b in prog.cond_branches(func))
    if got != expect:
        raise FluxdriveError(
            f"{func}: conditional branches {got}, the board bound was written for {expect}; "
            "review cm4_cycles.bound_board against the changed code", exit_code=1)


def _entry(prog: Program, name: str) -> int:
    """Where a call to ``name`` from CCM SRAM lands: its veneer when the
    linker made one (long branch to flash), else the function."""
    v = f"__{name}_veneer"
    return prog.funcs[v] if v in prog.funcs else prog.funcs[name]


def _path_part(prog: Program, name: str, p: ExecPath, note: str = "") -> Part:
    acc = ", ".join(f"{k} x{v}" for k, v in sorted(p.accesses.items())
                    if k not in ("SRAM", "CCM SRAM"))
    note = "; ".join(x for x in (note, acc and f"accesses {acc}") if x)
    return Part(name, len(p.pcs), sequence_cycles(prog, p.pcs), p.bus, note)


#: What each board HAL part includes (shown in the report).
HAL_NOTES = {
    "hal_adc_read": "t_i from a word set at init (no hal_caps call)",
    "hal_fault_hw_tripped": "flash, through a veneer",
    "hal_pwm_write": "3 x duty_to_ccr, the applied pattern",
}


def bound_board(prog: Program, elf: str = "") -> BoardBound:
    """The board's ISR path that the PIL does not run, with the same model.

    ADC1 and ADC2 share the ADC1_2 interrupt and each raises it at the end
    of its injected sequence (adc.c): a period has two entries of
    ADC1_2_IRQHandler, the first end's (notes the end and returns: no FP
    instruction, so no lazy FP stacking) and the second's, which runs the
    period (the registered board_control_isr, which tail-calls drive_isr,
    then the overrun check and the DWT statistics). Both ends before the
    first entry make it one entry; the bound counts two.

    * typical: no overrun, duties inside (0, max) (no clamp), ART cache
      hits; board-configuration branches (which signals are measured) take
      the longer side;
    * worst: the overrun bookkeeping, the longer side of every other
      branch, ART cache misses, and a third entry like the first: the
      first end's flag clear (a bus write a few instructions before the
      exception return) not yet seen by the NVIC, which pends the line
      again; that entry finds no new end and returns.

    Both: hal_caps() already initialised (drive_init called it), and
    hal_pwm_write() asked for the applied pattern (drive_write does).

    Wrapper = both entries' exception entry/exit, the period entry's lazy
    FP stacking and both ADC1_2_IRQHandler paths (with hal_tim1_clear_update,
    board_control_isr and hal_tim1_update_pending), drive_isr excluded.
    The board HAL that drive_isr calls (:data:`BOARD_HAL`) is bounded
    separately: the PIL counts its stand-ins instead."""
    need = ("ADC1_2_IRQHandler", BOARD_CONTROL, "drive_isr", "hal_caps") + BOARD_HAL
    missing = [f for f in need if f not in prog.funcs]
    if missing:
        raise FluxdriveError(f"{elf or 'image'}: not a board image (no {', '.join(missing)})",
                             exit_code=1)
    h = "ADC1_2_IRQHandler"
    # every ADC in use ended (run the period), overrun
    _check_branches(prog, h, ("beq", "cbz"))
    # channel k measured, loop over k, v_dc measured, star point measured
    _check_branches(prog, "hal_adc_read", ("beq", "bne", "beq", "cbz"))
    _check_branches(prog, "hal_caps", ("cbnz",))  # initialised
    _check_branches(prog, "hal_pwm_write", ("beq",))  # applied == NULL
    _check_branches(prog, "duty_to_ccr", ("ble",))  # d <= 0 (or NaN): 0
    _check_branches(prog, "hal_fault_hw_tripped", ())
    stop = {prog.funcs["drive_isr"]}
    indirect = {h: prog.funcs[BOARD_CONTROL]}

    def common(ins: Insn, k: int, n: int) -> bool | None:
        if ins.func == "hal_adc_read" and k == 1:
            return n < 2  # for k in 0..2
        if ins.func == "hal_caps":
            return True  # initialised by drive_init
        if ins.func == "hal_pwm_write":
            return False  # drive_write asks for the applied pattern
        return None

    def first_end(ins: Insn, k: int, n: int) -> bool | None:
        if ins.func == h:
            return (False, None)[k]  # the other ADC has not ended: return
        return common(ins, k, n)

    def typical(ins: Insn, k: int, n: int) -> bool | None:
        if ins.func == h:
            return (True, True)[k]  # both ended: the period; no overrun
        if ins.func == "duty_to_ccr":
            return False  # d > 0: no clamp to 0
        return common(ins, k, n)

    def worst(ins: Insn, k: int, n: int) -> bool | None:
        if ins.func == h:
            return (True, False)[k]  # the period, with the overrun bookkeeping
        return common(ins, k, n)

    cases = {}
    for label, decide, wf in (("typical", typical, False), ("worst", worst, True)):
        first = walk(prog, prog.funcs[h], first_end, stop, wf, indirect=indirect)
        p = walk(prog, prog.funcs[h], decide, stop, wf, indirect=indirect)
        if prog.funcs[BOARD_CONTROL] not in p.pcs:
            raise FluxdriveError(f"{h}: the period path does not reach {BOARD_CONTROL}",
                                 exit_code=1)
        wrapper = [
            Part("first end: exception entry + exit", 0, EXC_ENTRY + EXC_EXIT),
            _path_part(prog, f"first end: {h} (notes the end, returns)", first),
            Part("period: exception entry + exit", 0, EXC_ENTRY + EXC_EXIT),
            Part("period: lazy FP state save + restore (S0-S15, FPSCR)", 0,
                 LAZY_FP_SAVE + LAZY_FP_RESTORE),
            _path_part(prog, f"period: {h} (+ hal_tim1_*, {BOARD_CONTROL})", p),
        ]
        if label == "worst":
            wrapper[2:2] = [Part("re-entry: exception entry + exit", 0, EXC_ENTRY + EXC_EXIT),
                            _path_part(prog, f"re-entry: {h} (no new end, returns)", first)]
        hal = [_path_part(prog, name, walk(prog, _entry(prog, name), decide, stop, wf),
                          HAL_NOTES.get(name, ""))
               for name in BOARD_HAL]
        cases[label] = BoardCase(wrapper, hal)
    trig = []
    for name in BOARD_TRIG:
        if name in prog.funcs:
            # no loops in the bindings: a backward branch joins a shared
            # epilogue (not taken: the longer side); forward ones both ways
            tp = walk(prog, _entry(prog, name),
                      lambda i, k, n: False if i.target is not None and i.target <= i.addr
                      else None, stop, False)
            part = _path_part(prog, name, tp, f"+ {CORDIC_LATENCY} CORDIC latency")
            part.bus += CORDIC_LATENCY
            trig.append(part)
    return BoardBound(elf, cases["typical"], cases["worst"], trig)


def format_board(b: BoardBound) -> str:
    pct = lambda c: f"{100 * c / BUDGET_CYCLES:.1f} %"  # noqa: E731
    lines = [f"Board ISR path outside drive_isr: {b.elf}",
             f"Cortex-M4 cycle model (docs/pil.md, P = {P}); bus wait (read/write): "
             + ", ".join(f"{k} {r}/{w}" for k, (r, w) in BUS_WAIT.items() if r or w)
             + f"; flash worst: ART miss, {FLASH_WS} per 8-byte line / literal"]
    for label, case in (("typical", b.typical), ("worst", b.worst)):
        lines.append(f"{label}:")
        for p in case.wrapper + case.hal:
            lines.append(f"  {p.cycles:6d}  = {p.core:5d} core + {p.bus:4d} wait, "
                         f"{p.insns:4d} instr  {p.name}" + (f" ({p.note})" if p.note else ""))
        w, hh = case.wrapper_cycles, case.hal_cycles
        lines.append(f"  {w:6d}  wrapper + exceptions, every entry ({pct(w)} of {BUDGET_CYCLES})")
        lines.append(f"  {hh:6d}  board HAL called by drive_isr ({pct(hh)}; the PIL counts its "
                     f"stand-ins instead)")
    if b.trig:
        lines.append("board trig per call (CORDIC binding; the PIL runs the software versions):")
        for p in b.trig:
            lines.append(f"  {p.cycles:6d}  = {p.core:5d} core + {p.bus:4d} wait, "
                         f"{p.insns:4d} instr  {p.name} ({p.note})")
    return "\n".join(lines)


def main_board(args) -> int:
    """``fluxdrive cycles-board ELF``: print the board bound."""
    elf = Path(args.elf)
    if not elf.is_file():
        raise FluxdriveError(f"board image not found: {elf}",
                             hint="cmake --preset stm32g474 && cmake --build --preset stm32g474")
    print(format_board(bound_board(load_program(elf), str(elf))))
    return 0
