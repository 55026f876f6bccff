#!/bin/sh
# Cross-build the STM32G4 firmware for each board preset from a clean build
# directory, print the memory use, and run the static ELF checks.
# Usage: tests/target/run_target_checks.sh [PRESET...]   (default: both)
# Presets: stm32g474 stm32g431-esc1, and stm32g474-map (the g474 image with
# the flux map maps/syr_1k1.fdmap linked as the table `fluxdrive map ctable`
# generates: FD_MACHINE_MAP) and stm32g474-dfc (the g474 image with the
# Direct Flux Control window: FD_STAR_WINDOW). Exit status non-zero on any
# failure.
# FD_TARGET_BUILD_DIR=dir puts the build trees in dir/<preset> instead of
# the presets' binaryDir (build/<preset>).
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
[ $# -gt 0 ] || set -- stm32g474 stm32g431-esc1 stm32g474-map stm32g474-dfc
status=0
for preset in "$@"; do
  case "$preset" in
    stm32g474)      board=g474;         ld=stm32g474re.ld ;;
    stm32g474-map)  board=g474;         ld=stm32g474re.ld ;;
    stm32g474-dfc)  board=g474;         ld=stm32g474re.ld ;;
    stm32g431-esc1) board=b_g431b_esc1; ld=stm32g431cb.ld ;;
    *) echo "unknown preset $preset"; exit 2 ;;
  esac
  bdir="${FD_TARGET_BUILD_DIR:-$ROOT/build}/$preset"
  echo "=== $preset (FD_BOARD=$board) in $bdir"
  rm -rf "$bdir"
  extra=""
  if [ "$preset" = stm32g474-map ]; then
    extra="-DFD_MACHINE_MAP=$ROOT/maps/syr_1k1.fdmap"
  fi
  if [ "$preset" = stm32g474-dfc ]; then
    extra="-DFD_STAR_WINDOW=ON"
  fi
  base=${preset%-map}
  base=${base%-dfc}
  if ! cmake --preset "$base" -B "$bdir" $extra >/dev/null || ! cmake --build "$bdir"; then
    echo "FAIL: build of $preset"; status=1; continue
  fi
  elf="$bdir/boards/stm32g4/fluxdrive-$board.elf"
  arm-none-eabi-size -A -x "$elf" | grep -E '^(\.isr_vector|\.ccmram|\.text|\.rodata|\.data|\.bss|\.ccmbss|\._stack) '
  if ! python3 "$ROOT/tests/target/check_elf.py" "$elf" "$ROOT/hal/stm32g4/$ld"; then
    echo "FAIL: static checks of $elf"; status=1
  fi
  if [ "$preset" = stm32g474-map ]; then
    # the map is const data in flash, its words the committed blob's
    size=$(wc -c < "$ROOT/maps/syr_1k1.fdmap")
    if ! arm-none-eabi-nm -S "$elf" | grep -qiE "^[0-9a-f]+ 0*$(printf '%x' "$size") R fd_machine_map$"; then
      echo "FAIL: fd_machine_map ($size bytes, read-only) not in $elf"; status=1
    else
      echo "fd_machine_map: $size bytes in flash"
    fi
  fi
done
exit $status
