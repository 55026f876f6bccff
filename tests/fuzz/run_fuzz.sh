#!/usr/bin/env bash
# Runs one harness of BUILD_DIR for SECONDS on the committed corpus of
# tests/fuzz/corpus/HARNESS (read only: new inputs go to a temporary
# directory, removed afterwards). A crash or an invariant violation fails
# (exit 1); the input is kept as BUILD_DIR/crash-HARNESS-* (docs/fuzzing.md).
set -euo pipefail
src=$1
build=$2
harness=$3
seconds=$4
exe=$build/$harness
if [ ! -x "$exe" ]; then
  echo "fuzz: $exe not built (CTest fuzz/build, tests/fuzz/build_fuzz.sh)" >&2
  exit 1
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
dict=()
[ -f "$src/tests/fuzz/$harness.dict" ] && dict=(-dict="$src/tests/fuzz/$harness.dict")
"$exe" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -print_final_stats=1 \
       -artifact_prefix="$build/crash-$harness-" "${dict[@]}" \
       "$tmp" "$src/tests/fuzz/corpus/$harness" 2>"$tmp/log" || {
  grep -av -E '^#[0-9]+ +(NEW|REDUCE|pulse)' "$tmp/log" | tail -n 60 >&2
  echo "fuzz: $harness FAILED: the input is $build/crash-$harness-* (docs/fuzzing.md)" >&2
  exit 1
}
grep -a -E 'INITED|DONE|stat::(number_of_executed_units|average_exec_per_sec|new_units_added)' \
     "$tmp/log"
