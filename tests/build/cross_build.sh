#!/usr/bin/env bash
# Cross-compiles firmware/core and firmware/app for Cortex-M4F with -Werror
# (preset cortex-m4f) into BUILD_DIR and prints their size.
set -euo pipefail
src=$1
build=$2
cd "$src"
cmake --preset cortex-m4f -B "$build" >/dev/null
cmake --build "$build" --target fd_core fd_app
echo "arm-none-eabi-size (Cortex-M4F, MinSizeRel):"
arm-none-eabi-size -t "$build/firmware/libfd_core.a" | tail -n 1 | awk '{print "fd_core total: text " $1 " B, data " $2 " B, bss " $3 " B"}'
arm-none-eabi-size -t "$build/firmware/libfd_app.a" | tail -n 1 | awk '{print "fd_app  total: text " $1 " B, data " $2 " B, bss " $3 " B"}'
arm-none-eabi-size "$build/firmware/libfd_core.a"
