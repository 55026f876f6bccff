#!/usr/bin/env bash
# Long fuzzing run of one harness (docs/fuzzing.md):
#   scripts/fuzz.sh fuzz_can|fuzz_scenario|fuzz_fluxmap SECONDS
# Builds the clang tree build/fuzz, fuzzes on one core starting from the
# committed corpus (tests/fuzz/corpus/HARNESS, read only) and out/fuzz/HARNESS
# (local: the new inputs of every run are merged there), then prints the
# executions, their rate and the coverage. A crash or an invariant violation
# stops the run: the input is out/fuzz/crash-HARNESS-*.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  fuzz_can | fuzz_scenario | fuzz_fluxmap) ;;
  *) echo "usage: scripts/fuzz.sh fuzz_can|fuzz_scenario|fuzz_fluxmap SECONDS" >&2; exit 2 ;;
esac
h=$1
secs=${2:?usage: scripts/fuzz.sh HARNESS SECONDS}
./scripts/setup.sh
tests/fuzz/build_fuzz.sh "$PWD" build/fuzz >/dev/null
mkdir -p "out/fuzz/$h"
dict=()
[ -f "tests/fuzz/$h.dict" ] && dict=(-dict="tests/fuzz/$h.dict")
log=out/fuzz/$h.log
rc=0
"build/fuzz/$h" -max_total_time="$secs" -timeout=20 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="out/fuzz/crash-$h-" "${dict[@]}" "out/fuzz/$h" "tests/fuzz/corpus/$h" \
  2>"$log" || rc=$?
grep -a -E 'INITED|DONE|stat::(number_of_executed_units|average_exec_per_sec|new_units_added|peak_rss_mb)' "$log" || true
echo "fuzz: $h: $(ls "out/fuzz/$h" | wc -l) inputs in out/fuzz/$h (log: $log)"
if [ $rc -ne 0 ]; then
  grep -a -E 'invariant violated|ERROR|runtime error|SUMMARY' "$log" | head -n 5
  echo "fuzz: $h FAILED; reproduce: build/fuzz/$h $(ls -t out/fuzz/crash-$h-* 2>/dev/null | head -n 1)" >&2
  exit 1
fi
