#!/usr/bin/env bash
# clang-tidy (.clang-tidy) over the host-compiled C sources of firmware/,
# hal/sil/ and sil/, with the build's compile_commands.json.
set -euo pipefail
src=$1
build=$2
cd "$src"
files=$(git ls-files -co --exclude-standard 'firmware/*.c' 'hal/sil/*.c' 'sil/*.c')
# -fsingle-precision-constant is a GCC flag clang does not know
clang-tidy -p "$build" --quiet --extra-arg=-Wno-ignored-optimization-argument \
  --extra-arg=-Wno-unknown-warning-option $files
echo "clang-tidy: $(echo "$files" | wc -w) files clean"
