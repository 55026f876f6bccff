#!/bin/sh
# Cross-build the STM32G4 firmware for each board preset from a clean build
# directory, print the memory use, and run the static ELF checks.
# Usage: tests/target/run_target_checks.sh [PRESET...]   (default: both)
# Presets: stm32g474 stm32g431-esc1. Exit status non-zero on any failure.
# FD_TARGET_BUILD_DIR=dir puts the build trees in dir/<preset> instead of
# the presets' binaryDir (build/<preset>).
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
[ $# -gt 0 ] || set -- stm32g474 stm32g431-esc1
status=0
for preset in "$@"; do
  case "$preset" in
    stm32g474)      board=g474;         ld=stm32g474re.ld ;;
    stm32g431-esc1) board=b_g431b_esc1; ld=stm32g431cb.ld ;;
    *) echo "unknown preset $preset"; exit 2 ;;
  esac
  bdir="${FD_TARGET_BUILD_DIR:-$ROOT/build}/$preset"
  echo "=== $preset (FD_BOARD=$board) in $bdir"
  rm -rf "$bdir"
  if ! cmake --preset "$preset" -B "$bdir" >/dev/null || ! cmake --build "$bdir"; then
    echo "FAIL: build of $preset"; status=1; continue
  fi
  elf="$bdir/hal/stm32g4/fluxdrive-$board.elf"
  arm-none-eabi-size -A -x "$elf" | grep -E '^(\.isr_vector|\.ccmram|\.text|\.rodata|\.data|\.bss|\.ccmbss|\._stack) '
  if ! python3 "$ROOT/tests/target/check_elf.py" "$elf" "$ROOT/hal/stm32g4/$ld"; then
    echo "FAIL: static checks of $elf"; status=1
  fi
done
exit $status
