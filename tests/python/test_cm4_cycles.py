"""Cortex-M4 cycle model (fluxdrive.cm4_cycles) and the PIL trace parser.

Every expected total below is written out by hand from the model table in
docs/pil.md, so a change of any class's cost fails a test.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fluxdrive import cm4_cycles as cm
from fluxdrive import pil
from fluxdrive.errors import FluxdriveError

REPO = Path(__file__).resolve().parents[2]
PIL_ELF = REPO / "build" / "cortex-m4f" / "pil" / "fluxdrive-pil.elf"
BOARD_ELF = REPO / "build" / "stm32g474" / "boards" / "stm32g4" / "fluxdrive-g474.elf"


def line(addr: int, size: int, text: str) -> str:
    """One objdump -d line (the encoding's digits only give the size)."""
    mnem, _, ops = text.partition(" ")
    enc = "f000 f000" if size == 4 else "bf00     "
    return f"{addr:8x}:\t{enc} \t{mnem}\t{ops}".rstrip()


def listing(*funcs: tuple[int, str, list[tuple[int, str]]]) -> str:
    out = ["", "x.elf:     file format elf32-littlearm", "", "Disassembly of section .text:"]
    for start, name, insns in funcs:
        out += ["", f"{start:08x} <{name}>:"]
        a = start
        for size, text in insns:
            if text.startswith(".word"):
                out.append(f"{a:8x}:\t{int(text.split()[1], 0):08x} \t.word\t{text.split()[1]}")
            else:
                out.append(line(a, size, text))
            a += size
    return "\n".join(out) + "\n"


# ----------------------------------------------------------- single classes
# (instruction, inside an IT block, cycles, taken penalty)
CLASSES = [
    ("adds r2, #1", False, 1, 0),
    ("mov.w r3, #1342177280", False, 1, 0),
    ("cmp r1, r2", False, 1, 0),
    ("uxth r2, r2", False, 1, 0),
    ("ubfx r0, r1, #2, #3", False, 1, 0),
    ("movw r0, #4660", False, 1, 0),
    ("nop ", False, 1, 0),
    ("mul r0, r1, r2", False, 1, 0),
    ("mla r0, r1, r2, r3", False, 1, 0),
    ("smull r0, r1, r2, r3", False, 1, 0),
    ("sdiv r0, r0, r1", False, 12, 0),
    ("udiv r0, r0, r1", False, 12, 0),
    ("ldr r3, [pc, #60]", False, 2, 0),
    ("ldr.w r3, [r2, #3464]", False, 2, 0),
    ("ldrb r2, [r1, #1]", False, 2, 0),
    ("ldrsh.w r2, [r1, r3]", False, 2, 0),
    ("ldr.w r2, [r4], #4", False, 2, 0),
    ("str r2, [r3, #0]", False, 1, 0),
    ("strb.w r3, [sp, #32]", False, 1, 0),
    ("str r3, [r2, r1]", False, 2, 0),
    ("ldrd r0, r1, [sp, #8]", False, 3, 0),
    ("strd r0, r1, [r3]", False, 3, 0),
    ("push {r3, lr}", False, 3, 0),
    ("push {r4, r5, r6, r7, r8, r9, sl, fp, lr}", False, 10, 0),
    ("pop {r4, r5, r6, pc}", False, 7, 0),  # 1 + 4 + P
    ("pop {r4, r5}", False, 3, 0),
    ("ldmia r3!, {r0, r1}", False, 3, 0),
    ("stmia.w r3, {r0, r1}", False, 3, 0),
    ("vldr s15, [pc, #224]", False, 2, 0),
    ("vldr d7, [r0]", False, 3, 0),
    ("vstr s15, [r0, #12]", False, 2, 0),
    ("vpush {d8-d10}", False, 7, 0),  # 1 + 6 words
    ("vpop {d8}", False, 3, 0),
    ("vstmia r6!, {s14}", False, 2, 0),
    ("vldmia r0, {s0-s3}", False, 5, 0),
    ("vadd.f32 s15, s15, s14", False, 1, 0),
    ("vsub.f32 s0, s0, s15", False, 1, 0),
    ("vmul.f32 s14, s14, s8", False, 1, 0),
    ("vnmul.f32 s0, s1, s2", False, 1, 0),
    ("vabs.f32 s0, s0", False, 1, 0),
    ("vneg.f32 s0, s0", False, 1, 0),
    ("vcvt.f32.s32 s13, s14", False, 1, 0),
    ("vcmpe.f32 s0, #0.0", False, 1, 0),
    ("vcmp.f32 s0, s15", False, 1, 0),
    ("vmrs APSR_nzcv, fpscr", False, 1, 0),
    ("vmov.f32 s14, #112", False, 1, 0),
    ("vmov.f32 s12, s15", False, 1, 0),
    ("vmov s14, r2", False, 1, 0),
    ("vmov r0, s15", False, 1, 0),
    ("vmov r0, r1, d0", False, 2, 0),
    ("vmla.f32 s15, s14, s13", False, 3, 0),
    ("vmls.f32 s15, s14, s13", False, 3, 0),
    ("vnmls.f32 s14, s13, s10", False, 3, 0),
    ("vfma.f32 s0, s1, s2", False, 3, 0),
    ("vdiv.f32 s0, s1, s2", False, 14, 0),
    ("vsqrt.f32 s0, s0", False, 14, 0),
    ("it ne", False, 1, 0),
    ("itttt ne", False, 1, 0),
    ("b.n 100 <f>", False, 3, 0),
    ("b.w 100 <f>", False, 3, 0),
    ("beq.n 100 <f>", False, 1, 2),
    ("bls.n 100 <f>", False, 1, 2),
    ("cbz r0, 100 <f>", False, 1, 2),
    ("cbnz r3, 100 <f>", False, 1, 2),
    ("bl 100 <f>", False, 3, 0),
    ("bx lr", False, 3, 0),
    ("blx r3", False, 3, 0),
    ("mov pc, lr", False, 3, 0),
    ("ldr.w pc, [pc]", False, 4, 0),
    ("tbb [pc, r0]", False, 4, 0),
    ("dsb sy", False, 1, 0),
    ("isb sy", False, 3, 0),
    ("cpsid i", False, 1, 0),
    ("mrs r4, PRIMASK", False, 1, 0),
    # inside an IT block: conditional; PC writes pay P only when taken
    ("movne r0, #1", True, 1, 0),
    ("ldrne.w r3, [r4, #744]", True, 2, 0),
    ("vmovgt.f32 s0, s15", True, 1, 0),
    ("vdivgt.f32 s0, s1, s2", True, 14, 0),
    ("bxeq lr", True, 1, 2),
    ("popne {r4, pc}", True, 3, 2),
    ("bne.n 100 <f>", True, 1, 2),
]


@pytest.mark.parametrize("text, in_it, cycles, pen", CLASSES)
def test_class_cost(text: str, in_it: bool, cycles: int, pen: int) -> None:
    mnem, _, ops = text.partition(" ")
    ins = cm.classify(cm.Insn(0x200, 4, "f", mnem, ops.strip()), in_it)
    assert ins.cls != "unclassified", text
    assert (ins.cost, ins.pen) == (cycles, pen), (text, ins.cls)


def test_model_constants() -> None:
    """The headline figures of the model (docs/pil.md)."""
    assert (cm.P, cm.FP_DIV, cm.FP_MAC, cm.LOAD, cm.PIPELINED, cm.STORE, cm.DIV) == \
        (2, 14, 3, 2, 1, 1, 12)
    assert (cm.EXC_ENTRY, cm.EXC_EXIT, cm.LAZY_FP_SAVE, cm.LAZY_FP_RESTORE) == (12, 12, 17, 17)
    assert cm.BUS_WAIT["AHB"] == (2, 1) and cm.BUS_WAIT["APB"] == (3, 2)
    assert cm.BUDGET_CYCLES == pil.BUDGET_CYCLES == 10625


def test_docs_show_the_model_table() -> None:
    text = (REPO / "docs" / "pil.md").read_text(encoding="utf-8")
    assert cm.format_model_table() in text


# ------------------------------------------------------- pairs and a trace
ISR = [
    (2, "ldr r3, [pc, #20]"),  # 100  2 literal load
    (2, "ldr r2, [r3, #0]"),  # 102  2 address uses the previous load's result: not pipelined
    (2, "ldr r1, [r3, #4]"),  # 104  1 pipelined after a load
    (2, "str r1, [r0, #0]"),  # 106  1
    (2, "ldr r0, [r2, r1]"),  # 108  2 nothing pipelines after a store
    (2, "adds r2, #4"),  # 10a  1
    (2, "ldr r1, [r2, #0]"),  # 10c  3 address register written by the ALU op before: +1
    (2, "push {r4, r5, lr}"),  # 10e  4
    (4, "vpush {d8-d9}"),  # 110  5
    (4, "vdiv.f32 s0, s0, s1"),  # 114 14
    (4, "vsqrt.f32 s0, s0"),  # 118 14
    (4, "vmla.f32 s0, s0, s1"),  # 11c  3
    (2, "cmp r0, #0"),  # 120  1
    (2, "beq.n 12a <drive_isr+0x2a>"),  # 122  1, +2 when taken
    (2, "it ne"),  # 124  1
    (2, "movne r0, #1"),  # 126  1
    (2, "b.n 12c <drive_isr+0x2c>"),  # 128  3
    (2, "movs r0, #2"),  # 12a  1 (+2: beq taken)
    (4, "bl 150 <helper>"),  # 12c  3
    (4, "vpop {d8-d9}"),  # 130  5
    (2, "pop {r4, r5, pc}"),  # 134  6
    (2, "nop"),  # 136
    (4, ".word 0x20000000"),  # 138
]
HELPER = [
    (4, "sdiv r0, r0, r1"),  # 150 12
    (4, "ldrd r2, r3, [r0]"),  # 154  3 + 1 (address r0 written by sdiv)
    (4, "vmov r0, s0"),  # 158  1
    (4, "vmov r0, r1, d0"),  # 15c  2
    (2, "bx lr"),  # 160  3
]
STEP = [
    (4, "bl 100 <drive_isr>"),  # 200
    (2, "nop"),  # 204
    (2, "b.n 200 <pil_step>"),  # 206
]
LISTING = listing((0x100, "drive_isr", ISR), (0x150, "helper", HELPER), (0x200, "pil_step", STEP))

HEAD = [0x100, 0x102, 0x104, 0x106, 0x108, 0x10A, 0x10C, 0x10E, 0x110, 0x114, 0x118, 0x11C,
        0x120, 0x122]
TAIL = [0x12C, 0x150, 0x154, 0x158, 0x15C, 0x160, 0x130, 0x134]
NOT_TAKEN = HEAD + [0x124, 0x126, 0x128] + TAIL  # 25 instructions
TAKEN = HEAD + [0x12A] + TAIL  # 23 instructions
# by hand: head 2+2+1+1+2+1+3+4+5+14+14+3+1+1 = 54 (beq not yet taken)
#   not taken: + it 1 + movne 1 + b.n 3 = 59; tail: bl 3 + helper 12+4+1+2+3 + vpop 5 + pop 6 = 36
#   taken:     + movs 1 + 2 (beq taken) = 57; + tail 36
CYC_NOT_TAKEN, CYC_TAKEN = 95, 93
HELPER_CYC = 22  # 12 + 4 + 1 + 2 + 3


def test_sequence_cycles_by_hand() -> None:
    prog = cm.parse_objdump(LISTING)
    assert prog.unclassified() == {}
    assert 0x138 not in prog.insns and prog.words[0x138] == 0x20000000
    assert cm.sequence_cycles(prog, NOT_TAKEN) == CYC_NOT_TAKEN
    assert cm.sequence_cycles(prog, TAKEN) == CYC_TAKEN
    # seq vs jump cost of single instructions
    assert (prog.insns[0x104].seq_cost, prog.insns[0x104].cost) == (1, 2)  # pipelined load
    assert (prog.insns[0x102].seq_cost, prog.insns[0x102].cost) == (2, 2)  # dependent address
    assert (prog.insns[0x10C].seq_cost, prog.insns[0x10C].cost) == (3, 2)  # AGU stall
    assert (prog.insns[0x154].seq_cost, prog.insns[0x154].cost) == (4, 3)  # AGU stall on LDRD


def test_pairs_that_do_not_pipeline() -> None:
    prog = cm.parse_objdump(listing((0x300, "f", [
        (2, "ldr r0, [r1, #0]"),  # 300
        (4, "ldr.w pc, [pc]"),  # 302: load to PC after a load: 4, never pipelined
        (4, "ldr.w r2, [r4], #4"),  # 306
        (2, "ldr r3, [r5, #0]"),  # 30a: after a writeback load: 2
        (2, "ldr r3, [r5, #4]"),  # 30c: pipelined: 1
        (2, "str r3, [r6, r7]"),  # 30e: register-offset store after a load: 1
        (2, "ldr r3, [r5, #8]"),  # 310: after a store: 2
        (4, "vldr s0, [r5, #12]"),  # 312: pipelined FP load: 1
        (4, "vstr s0, [r6, #0]"),  # 316: FP store after a load: 1
        (2, "movs r6, #0"),  # 31a
        (4, "vstr s0, [r6, #4]"),  # 31c: base written by the ALU op before: 2 + 1
    ])))
    seq = {a: i.seq_cost for a, i in prog.insns.items()}
    assert seq == {0x300: 2, 0x302: 4, 0x306: 2, 0x30A: 2, 0x30C: 1, 0x30E: 1, 0x310: 2,
                   0x312: 1, 0x316: 1, 0x31A: 1, 0x31C: 3}


def trace_lines(pcs: list[int], prog: cm.Program) -> list[bytes]:
    return [b"Trace 0: 0x7f9f04%06x [00800400/%08x/00000010/ff000201] %s\n"
            % (k * 0x40, pc, prog.insns[pc].func.encode()) for k, pc in enumerate(pcs)]


def test_trace_parser_counts_and_cycles() -> None:
    prog = cm.parse_objdump(LISTING)
    pcs = [0x200] + NOT_TAKEN + [0x204, 0x206, 0x200] + TAKEN + [0x204, 0x206]
    lines = trace_lines(pcs, prog)
    lines.insert(3, b"some other log line\n")
    res = pil.TraceResult()
    pil._parse_trace(iter(lines), res, cm.trace_table(prog))
    assert res.counts == [25, 23]
    assert res.cycles == [CYC_NOT_TAKEN, CYC_TAKEN]
    assert res.funcs == [{"drive_isr": 20, "helper": 5}, {"drive_isr": 18, "helper": 5}]
    # one call of helper per ISR, 5 instructions; drive_isr from entry to the end
    assert res.calls == [{"helper": [1, 5], "drive_isr": [1, 25]},
                         {"helper": [1, 5], "drive_isr": [1, 23]}]
    assert res.func_cycles == [{"drive_isr": CYC_NOT_TAKEN - HELPER_CYC, "helper": HELPER_CYC},
                               {"drive_isr": CYC_TAKEN - HELPER_CYC, "helper": HELPER_CYC}]
    assert not res.unknown_pcs


def test_trace_parser_unknown_pc() -> None:
    prog = cm.parse_objdump(LISTING)
    lines = trace_lines([0x200, 0x100], prog)
    lines.append(b"Trace 0: 0x7f9f04001000 [00800400/00000300/00000010/ff000201] mystery\n")
    lines += trace_lines([0x204], prog)
    res = pil.TraceResult()
    pil._parse_trace(iter(lines), res, cm.trace_table(prog))
    assert res.unknown_pcs == {b"00000300"}
    assert res.counts == [2] and res.funcs == [{"drive_isr": 1, "mystery": 1}]
    assert res.cycles == [2 + 1]  # literal load + 1 for the unknown instruction


# ------------------------------------------------------------- the walker
WAIT = [
    (2, "ldr r2, [pc, #12]"),  # 400: r2 = 0x50000100 (AHB)
    (2, "movs r3, #3"),  # 402
    (2, "ldr r1, [r2, #0]"),  # 404: AHB read, +2 wait
    (2, "lsls r1, r1, #25"),  # 406
    (2, "bmi.n 40e <isr+0xe>"),  # 408
    (2, "subs r3, #1"),  # 40a
    (2, "bne.n 404 <isr+0x4>"),  # 40c
    (2, "bx lr"),  # 40e
    (4, ".word 0x50000100"),  # 410
]


def test_walker_loop_and_bus_waits() -> None:
    prog = cm.parse_objdump(listing((0x400, "isr", WAIT)))
    never_ready = cm.walk(prog, 0x400, lambda i, k, n: False if k == 0 else n < 2)
    assert len(never_ready.pcs) == 2 + 3 * 5 + 1
    # 2 + 1, loop 6 / 8 / 8 (4 = load + taken bne), bx 3; three AHB reads x 2
    assert cm.sequence_cycles(prog, never_ready.pcs) == 28
    assert never_ready.bus == 6 and never_ready.accesses["AHB"] == 3
    ready = cm.walk(prog, 0x400, lambda i, k, n: True if k == 0 else n < 2)
    assert ready.pcs == [0x400, 0x402, 0x404, 0x406, 0x408, 0x40E]
    assert cm.sequence_cycles(prog, ready.pcs) == 2 + 1 + 2 + 1 + 1 + 3 + 2
    assert ready.bus == 2
    with pytest.raises(FluxdriveError, match="needs a bound"):
        cm.walk(prog, 0x400, lambda i, k, n: False if k == 0 else None)
    both = cm.walk(prog, 0x400, lambda i, k, n: None if k == 0 else n < 2)
    assert both.cycles(prog) == 28 + 6  # the longer alternative


def test_walker_calls_veneer_and_single_register_pop() -> None:
    prog = cm.parse_objdump(listing(
        (0x500, "caller", [
            (4, "str.w lr, [sp, #-4]!"),  # 500  1: push {lr}
            (4, "bl 510 <__leaf_veneer>"),  # 504  3
            (4, "ldr.w pc, [sp], #4"),  # 508  4 (2 + P): pop {pc}
            (4, "nop"),
        ]),
        (0x510, "__leaf_veneer", [
            (4, "ldr.w pc, [pc]"),  # 510  4: to 0x08000100 (flash)
            (4, ".word 0x08000101"),
        ]),
        (0x08000100, "leaf", [
            (2, "bx lr"),  # 3
        ]),
    ))
    p = cm.walk(prog, 0x500, lambda i, k, n: None)
    assert p.pcs == [0x500, 0x504, 0x510, 0x08000100, 0x508]
    assert cm.sequence_cycles(prog, p.pcs) == 1 + 3 + 4 + 3 + 4
    assert p.bus == 0  # ART hit
    worst = cm.walk(prog, 0x500, lambda i, k, n: None, worst_flash=True)
    assert worst.bus == cm.FLASH_WS  # one flash line entered


def test_stand_ins_follow_calls_made_only_by_the_hal() -> None:
    """The replay HAL's helpers (hal_pattern.h's roundf) are stand-ins too;
    a function the core also calls (memcpy) is not."""
    prog = cm.parse_objdump(listing(
        (0x600, "drive_isr", [(4, "bl 610 <hal_pwm_write>"), (4, "bl 620 <memcpy>"),
                              (4, "bl 630 <hal_adc_read>"), (2, "bx lr")]),
        (0x610, "hal_pwm_write", [(4, "bl 640 <roundf>"), (4, "b.w 620 <memcpy>")]),
        (0x620, "memcpy", [(2, "bx lr")]),
        (0x630, "hal_adc_read", [(2, "bx lr")]),
        (0x640, "roundf", [(4, "bl 650 <helper>"), (2, "bx lr")]),
        (0x650, "helper", [(2, "bx lr")]),
    ))
    assert prog.callers()["memcpy"] == {"drive_isr", "hal_pwm_write"}
    assert cm.stand_ins(prog) == {"hal_pwm_write", "hal_adc_read", "roundf", "helper"}


# ------------------------------------------------------------ real images
@pytest.mark.skipif(not PIL_ELF.is_file(), reason="PIL image not built (preset cortex-m4f)")
def test_pil_image_fully_classified() -> None:
    prog = cm.load_program(PIL_ELF)
    assert prog.unclassified() == {}
    tab = cm.trace_table(prog)
    assert tab[b"%08x" % prog.funcs["drive_isr"]][4] == "drive_isr"
    # the replay HAL the board replaces: its three ISR functions, nothing of
    # the core (the timer model's rounding is inline, no libm call)
    assert cm.stand_ins(prog) == {"hal_adc_read", "hal_fault_hw_tripped", "hal_pwm_write"}


@pytest.mark.skipif(not BOARD_ELF.is_file(), reason="board image not built (preset stm32g474)")
def test_board_bound() -> None:
    b = cm.bound_board(cm.load_program(BOARD_ELF), str(BOARD_ELF))
    t, w = b.typical, b.worst
    # two entries a period (first ADC end, then the period), a third in the worst case
    names = [p.name.split(":")[0] for p in t.wrapper]
    assert names == ["first end", "first end", "period", "period", "period"]
    assert [p.name.split(":")[0] for p in w.wrapper] == ["first end", "first end", "re-entry",
                                                         "re-entry", "period", "period", "period"]
    assert t.wrapper[0].cycles == t.wrapper[2].cycles == 24 and t.wrapper[3].cycles == 34
    # the first end: a few register accesses, no wait, no call
    assert t.wrapper[1].insns < 30 and "APB" not in t.wrapper[1].note
    # no wait loop: the worst case adds the re-entry, the overrun count, ART misses only
    assert t.wrapper_cycles < w.wrapper_cycles < 2 * t.wrapper_cycles
    assert w.wrapper_cycles < 0.05 * cm.BUDGET_CYCLES
    assert [p.name for p in t.hal] == list(cm.BOARD_HAL)
    assert cm.BOARD_HAL == ("hal_adc_read", "hal_fault_hw_tripped", "hal_pwm_write")
    assert 0 < t.hal_cycles <= w.hal_cycles
    # drive_isr's board HAL calls, as linked (no hal_caps call in the ISR)
    prog = cm.load_program(BOARD_ELF)
    calls = prog.callers()
    assert "drive_isr" in calls["hal_adc_read"] and "__hal_fault_hw_tripped_veneer" in \
        prog.funcs and "drive_isr" in calls["__hal_fault_hw_tripped_veneer"]
    assert "drive_write" in calls["hal_pwm_write"]
    assert "hal_adc_read" not in calls.get("__hal_caps_veneer", set()) | calls.get("hal_caps", set())
    adc = t.hal[0]
    assert "AHB x5" in adc.note  # three currents, v_dc, star point through s_jdr
    assert "APB x3" in t.hal[2].note  # CCR1..3
    text = cm.format_board(b)
    assert "wrapper + exception" in text


# ----------------------------------------------------------------- report
def fake_run() -> pil.PilRun:
    c = pil.Counts(isrs=10, mean=1800.0, worst=1845, worst_isr=7, blocks={"DFVC step": 1800.0},
                   funcs={"dfvc_step": 1800.0}, cycles_mean=3188.0, cycles_worst=3300,
                   cycles_worst_isr=8, block_cycles={"DFVC step": 3188.0},
                   func_cycles={"dfvc_step": 3100.0, "hal_adc_read": 50.0,
                                "hal_pwm_write": 26.0, "roundf": 12.0},
                   stand_ins=frozenset(cm.BOARD_HAL) | {"roundf"})
    a = pil.Agreement(100, 0.0, 0, 0, 0, 0, 0)
    return pil.PilRun("scen", "db_dfvc", a, c, True)


def test_report_cycles_columns() -> None:
    r = fake_run()
    assert r.counts.cpi == pytest.approx(3188.0 / 1800.0)
    md = pil.format_markdown([r], 3000, None, "flags")
    assert "| scen | db_dfvc | 10 | 1800 | 1845 | 3188 | 3300 | 1.77 | 30 % | 31 % | 0 | 100 |" in md
    assert "1.2" not in md and "legacy" not in md
    md = pil.format_markdown([r], 3000, 1.2, "flags")
    assert "worst x 1.2 (legacy)" in md and "| 21 % |" in md  # 1845 x 1.2 / 10625
    text = pil.format_report([r], 3000)
    assert "mean 3188, worst 3300 (ISR 8); 1.77 cycles/instruction; 30 % mean / 31 % worst" in text


def test_board_estimate() -> None:
    case_t = cm.BoardCase([cm.Part("w", 40, 100, 10)], [cm.Part("h", 90, 200, 20)])
    case_w = cm.BoardCase([cm.Part("w", 1000, 1600, 400)], [cm.Part("h", 90, 210, 30)])
    b = cm.BoardBound("x.elf", case_t, case_w, [])
    # PIL minus its replay HAL (50 + 26 + 12) plus the board's HAL and wrapper
    assert pil.board_estimate(fake_run().counts, b) == (3188 - 88 + 220 + 110,
                                                        3300 - 88 + 240 + 2000)
    md = pil.format_markdown([fake_run()], 3000, None, "flags", b)
    assert "| scen | db_dfvc | 3430 (32 %) | 5452 (51 %) |" in md
