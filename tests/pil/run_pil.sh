#!/usr/bin/env bash
# PIL test (docs/pil.md): cross-builds the PIL image (preset cortex-m4f, the
# board's MinSizeRel flags, -Werror) into BUILD_DIR, then `fluxdrive pil`
# replays the two PIL scenarios with every law on QEMU mps2-an386: outputs
# must agree with this host build's within the stated tolerance, and the
# DB-DFVC worst case must stay below 2000 instructions. Prints the report
# and writes its markdown section to BUILD_DIR/benchmarks.md.
# Usage: run_pil.sh SRC_DIR BUILD_DIR PYTHON FLUXDRIVE_SIL
set -euo pipefail
src=$1
build=$2
python=$3
sil=$4
cmake --preset cortex-m4f -S "$src" -B "$build/cross" >/dev/null
cmake --build "$build/cross" --target fluxdrive-pil.elf
cd "$build"
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_torque_step.json" \
  "$src/sil/scenarios/pil_fw_ramp.json" --law foc,pi_dfvc,db_dfvc --isrs 3000 \
  --sil "$sil" --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks.md" --check-worst 2000
