#!/usr/bin/env bash
# Configures and builds the libFuzzer harnesses (tests/fuzz/CMakeLists.txt)
# with clang into BUILD_DIR. Fails with a clear message when clang or its
# fuzzer runtime is missing (scripts/setup.sh installs both).
set -euo pipefail
src=$1
build=$2
cc=${FD_FUZZ_CC:-clang-14}
if ! command -v "$cc" >/dev/null 2>&1; then
  echo "fuzz: $cc not found: install the Debian packages clang-14 and libclang-rt-14-dev" \
       "(scripts/setup.sh)" >&2
  exit 1
fi
if ! "$cc" -print-file-name=libclang_rt.fuzzer-x86_64.a | grep -q /; then
  echo "fuzz: the libFuzzer runtime of $cc is missing: install libclang-rt-14-dev" \
       "(scripts/setup.sh)" >&2
  exit 1
fi
cmake -S "$src/tests/fuzz" -B "$build" -G Ninja -DCMAKE_C_COMPILER="$cc" \
      -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j2
