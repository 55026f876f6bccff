#!/usr/bin/env python3
"""Static checks of a fluxdrive STM32G4 firmware ELF (Python 3 stdlib only).

Reads the ELF directly (32-bit little-endian ARM: section headers, symbol
table, section contents) and the part's linker script (MEMORY regions), and
proves:
  1. the vector table (.isr_vector, symbol g_vectors) sits at the FLASH origin
     of the linker script;
  2. word 0 = initial SP = _estack = ORIGIN(RAM) + LENGTH(RAM);
  3. word 1 = Reset_Handler with the Thumb bit set;
  4. the ADC1_2 entry (IRQ 18, RM0440 vector table) = ADC1_2_IRQHandler | 1,
     and SysTick = SysTick_Handler | 1;
  5. drive_isr, ADC1_2_IRQHandler and the board's period body
     (board_control_isr) run from CCM SRAM, and .ccmram has a
     flash load image (copied by startup.c);
  6. every allocated section lies inside its region; .data + .bss + the
     minimum stack fit in RAM; .ccmram + .ccmbss fit in CCM SRAM; the flash
     image (vectors, text, rodata, load images) fits in FLASH;
  7. no heap: no malloc/_sbrk/end symbols are linked.
Usage: check_elf.py FIRMWARE.elf LINKER_SCRIPT.ld
Exit status 0 when every check passes.
"""
import re
import struct
import sys

IRQ_ADC1_2 = 18
SHT_SYMTAB, SHT_NOBITS = 2, 8
SHF_ALLOC = 0x2


class Elf:
    def __init__(self, path):
        with open(path, "rb") as f:
            self.data = f.read()
        d = self.data
        if d[:4] != b"\x7fELF" or d[4] != 1 or d[5] != 1:
            raise ValueError("not a 32-bit little-endian ELF")
        (e_machine,) = struct.unpack_from("<H", d, 18)
        if e_machine != 40:
            raise ValueError("not an ARM ELF")
        e_shoff, = struct.unpack_from("<I", d, 32)
        e_shentsize, e_shnum, e_shstrndx = struct.unpack_from("<HHH", d, 46)
        self.sections = []
        for i in range(e_shnum):
            f = struct.unpack_from("<IIIIIIIIII", d, e_shoff + i * e_shentsize)
            self.sections.append(dict(name_off=f[0], type=f[1], flags=f[2], addr=f[3],
                                      offset=f[4], size=f[5], link=f[6]))
        strtab = self.sections[e_shstrndx]
        for s in self.sections:
            s["name"] = self._str(strtab["offset"], s["name_off"])
        # program headers: load address (LMA) of each section
        e_phoff, = struct.unpack_from("<I", d, 28)
        e_phentsize, e_phnum = struct.unpack_from("<HH", d, 42)
        self.segments = []
        for i in range(e_phnum):
            p = struct.unpack_from("<IIIIIIII", d, e_phoff + i * e_phentsize)
            self.segments.append(dict(type=p[0], offset=p[1], vaddr=p[2], paddr=p[3],
                                      filesz=p[4], memsz=p[5]))
        self.symbols = {}
        self.binding = {}
        for s in self.sections:
            if s["type"] != SHT_SYMTAB:
                continue
            strs = self.sections[s["link"]]
            for k in range(s["size"] // 16):
                name_off, value, size, info, other, shndx = struct.unpack_from(
                    "<IIIBBH", d, s["offset"] + 16 * k)
                name = self._str(strs["offset"], name_off)
                if name:
                    self.symbols[name] = (value, size)
                    self.binding[name] = info >> 4  # 1 global, 2 weak

    def _str(self, base, off):
        end = self.data.index(b"\0", base + off)
        return self.data[base + off:end].decode()

    def section(self, name):
        for s in self.sections:
            if s["name"] == name:
                return s
        return None

    def lma(self, sec):
        for p in self.segments:
            if p["type"] == 1 and p["vaddr"] <= sec["addr"] < p["vaddr"] + max(p["memsz"], 1):
                return p["paddr"] + (sec["addr"] - p["vaddr"])
        return sec["addr"]

    def word(self, sec, index):
        return struct.unpack_from("<I", self.data, sec["offset"] + 4 * index)[0]


def parse_size(text):
    text = text.strip()
    m = re.fullmatch(r"(0x[0-9a-fA-F]+|\d+)\s*([KM]?)", text)
    if not m:
        raise ValueError("cannot parse size %r" % text)
    v = int(m.group(1), 0)
    return v * {"": 1, "K": 1024, "M": 1024 * 1024}[m.group(2)]


def parse_ld(path):
    text = open(path).read()
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    regions = {}
    mem = re.search(r"MEMORY\s*\{(.*?)\}", text, flags=re.S)
    for m in re.finditer(r"(\w+)\s*\([^)]*\)\s*:\s*ORIGIN\s*=\s*([^,]+),\s*LENGTH\s*=\s*([^\n]+)",
                         mem.group(1)):
        regions[m.group(1)] = (int(m.group(2).strip(), 0), parse_size(m.group(3)))
    stack = re.search(r"_Min_Stack_Size\s*=\s*([^;]+);", text)
    heap = re.search(r"_Min_Heap_Size\s*=\s*([^;]+);", text)
    return regions, parse_size(stack.group(1)), parse_size(heap.group(1))


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    elf = Elf(argv[1])
    regions, min_stack, min_heap = parse_ld(argv[2])
    failures = []

    def check(cond, what):
        print(("ok   " if cond else "FAIL ") + what)
        if not cond:
            failures.append(what)

    flash_o, flash_l = regions["FLASH"]
    ram_o, ram_l = regions["RAM"]
    ccm_o, ccm_l = regions["CCMRAM"]
    sym = elf.symbols

    def addr(name):
        return sym[name][0] if name in sym else None

    vec = elf.section(".isr_vector")
    check(vec is not None and vec["addr"] == flash_o,
          ".isr_vector at FLASH origin 0x%08x" % flash_o)
    check(addr("g_vectors") == flash_o, "g_vectors at 0x%08x" % flash_o)
    if vec is None:
        return 1
    check(vec["size"] >= 4 * (16 + IRQ_ADC1_2 + 1), "vector table long enough for IRQ %d" % IRQ_ADC1_2)
    sp0 = elf.word(vec, 0)
    check(addr("_estack") == ram_o + ram_l and sp0 == ram_o + ram_l,
          "initial SP 0x%08x = _estack = top of RAM 0x%08x" % (sp0, ram_o + ram_l))
    rst = elf.word(vec, 1)
    check(addr("Reset_Handler") is not None and rst == (addr("Reset_Handler") | 1),
          "reset vector 0x%08x = Reset_Handler | 1 (Thumb)" % rst)
    check(rst & 1 == 1 and flash_o <= (rst & ~1) < flash_o + flash_l, "reset handler in flash")
    adc = elf.word(vec, 16 + IRQ_ADC1_2)
    check(addr("ADC1_2_IRQHandler") is not None and adc == (addr("ADC1_2_IRQHandler") | 1),
          "vector 16+%d (ADC1_2) 0x%08x = ADC1_2_IRQHandler | 1" % (IRQ_ADC1_2, adc))
    st = elf.word(vec, 15)
    check(addr("SysTick_Handler") is not None and st == (addr("SysTick_Handler") | 1),
          "SysTick vector = SysTick_Handler | 1")
    for i in range(2, vec["size"] // 4):
        w = elf.word(vec, i)
        if w != 0 and (w & 1) == 0:
            check(False, "vector %d 0x%08x has the Thumb bit set" % (i, w))
            break
    else:
        check(True, "all non-zero vectors have the Thumb bit")

    def in_ccm(name):
        a = addr(name)
        return a is not None and ccm_o <= a < ccm_o + ccm_l

    # the core's trigonometry bound to the CORDIC (strong over weak)
    for fn in ("fd_sincosf", "fd_atan2f"):
        check(elf.binding.get(fn) == 1, "%s is the CORDIC binding (global, not the weak software one)" % fn)
    check(in_ccm("drive_isr"), "drive_isr in CCM SRAM (0x%08x)" % (addr("drive_isr") or 0))
    check(in_ccm("ADC1_2_IRQHandler"), "ADC1_2_IRQHandler in CCM SRAM")
    check(in_ccm("board_control_isr"), "board_control_isr (the period body) in CCM SRAM")
    ccm = elf.section(".ccmram")
    if ccm is not None and ccm["size"]:
        lma = elf.lma(ccm)
        check(flash_o <= lma and lma + ccm["size"] <= flash_o + flash_l,
              ".ccmram load image in flash at 0x%08x" % lma)
        check(addr("_siccmram") == lma, "_siccmram = load address of .ccmram")

    # regions
    used = {"FLASH": 0, "RAM": 0, "CCMRAM": 0}
    for s in elf.sections:
        if not (s["flags"] & SHF_ALLOC) or s["size"] == 0:
            continue
        hit = None
        for rname, (o, l) in regions.items():
            if o <= s["addr"] and s["addr"] + s["size"] <= o + l:
                hit = rname
        check(hit is not None, "%s [0x%08x, +0x%x] inside a MEMORY region" % (s["name"], s["addr"], s["size"]))
        if hit:
            used[hit] = max(used[hit], s["addr"] + s["size"] - regions[hit][0])
        if s["type"] != SHT_NOBITS and hit != "FLASH":
            lma = elf.lma(s)
            check(flash_o <= lma and lma + s["size"] <= flash_o + flash_l,
                  "%s load image inside FLASH" % s["name"])
            used["FLASH"] = max(used["FLASH"], lma + s["size"] - flash_o)
    ebss = addr("_ebss")
    check(ebss is not None and ebss + min_stack <= ram_o + ram_l,
          ".data + .bss + _Min_Stack_Size (0x%x) fit in RAM (end of bss 0x%08x)" % (min_stack, ebss or 0))
    check(min_heap == 0, "_Min_Heap_Size = 0")
    for bad in ("malloc", "_malloc_r", "_sbrk", "_sbrk_r", "end", "__wrap_malloc"):
        check(bad not in sym, "no '%s' symbol (no heap)" % bad)

    print("memory: FLASH %d / %d B, RAM %d / %d B (incl. min stack), CCMRAM %d / %d B"
          % (used["FLASH"], flash_l, used["RAM"], ram_l, used["CCMRAM"], ccm_l))
    if failures:
        print("%d check(s) FAILED" % len(failures))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
