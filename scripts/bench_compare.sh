#!/usr/bin/env bash
# Side-by-side SIL real-time factor: this tree against another revision.
#
#   scripts/bench_compare.sh [-n ROUNDS] [-i] REV [SCENARIO...]
#
# Builds REV's release runner (git archive of REV into
# ${TMPDIR:-/tmp}/fluxdrive-bench/<commit>, cmake preset host-release, kept
# there for the next call: no worktree is registered) and this tree's
# (build/host-release), then runs the two runners alternately on each
# scenario, ROUNDS times each (default 9), `fluxdrive-sil SCENARIO --bench`
# (no log), and prints the best real-time factor of each and their ratio.
# Alternating in one session is what makes the ratio meaningful on a shared
# machine whose speed varies from one session to the next (docs/benchmarks.md).
# A scenario is given as a path in this tree; REV runs its own file at the
# same path when it has one (the schema may differ), else this tree's.
# Default scenarios: default.json, foc_speed_load.json.
# -i adds the deterministic figure: instructions per simulated period of
# each runner (valgrind --tool=callgrind, total Ir / steps), the same on any
# load; a run of 15-25 ms is at the mercy of a loaded machine's scheduler,
# the instruction count is not.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

rounds=9
instr=0
while [[ "${1:-}" == -* ]]; do
  case $1 in
    -n) rounds=$2; shift 2 ;;
    -i) instr=1; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
if [[ $# -lt 1 ]]; then
  awk 'NR > 1 && !/^#/ {exit} NR > 1 {sub(/^# ?/, ""); print}' "$0"
  exit 2
fi
rev=$1
shift
scenarios=("$@")
if [[ ${#scenarios[@]} -eq 0 ]]; then
  scenarios=(sil/scenarios/default.json sil/scenarios/foc_speed_load.json)
fi

sha=$(git rev-parse --verify "$rev^{commit}")
base_src="${TMPDIR:-/tmp}/fluxdrive-bench/$sha"
if [[ ! -x "$base_src/build/host-release/sil/fluxdrive-sil" ]]; then
  echo "building $rev ($sha) in $base_src" >&2
  rm -rf "$base_src"
  mkdir -p "$base_src"
  git archive "$sha" | tar -x -C "$base_src"
  (cd "$base_src" && cmake --preset host-release -DBUILD_TESTING=OFF >/dev/null &&
    cmake --build --preset host-release --target fluxdrive-sil >/dev/null)
fi
echo "building this tree (build/host-release)" >&2
cmake --preset host-release >/dev/null
cmake --build --preset host-release --target fluxdrive-sil >/dev/null

base_sil="$base_src/build/host-release/sil/fluxdrive-sil"
this_sil="$ROOT/build/host-release/sil/fluxdrive-sil"

rtf_of() { # runner scenario -> real-time factor
  "$1" "$2" --bench | awk '/real-time factor/ {print $NF}'
}

ir_per_period() { # runner scenario -> instructions per simulated period
  local out
  out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$1" "$2" --bench 2>&1)
  awk '/Collected :/ {ir = $NF} /^steps:/ {n = $2} END {printf "%.0f", ir / n}' <<<"$out"
}

best() { # the larger of two numbers (awk: floats)
  awk -v a="$1" -v b="$2" 'BEGIN {print (b > a ? b : a)}'
}

printf '%s vs this tree (%s), best of %d, alternating\n' "$rev" "$(git rev-parse --short HEAD)$(
  git diff --quiet HEAD -- . 2>/dev/null || echo '+changes')" "$rounds"
printf '%-40s %10s %10s %7s\n' scenario "$rev" this ratio
for scen in "${scenarios[@]}"; do
  base_scen="$base_src/$scen"
  [[ -f "$base_scen" ]] || base_scen="$ROOT/$scen"
  b=0
  t=0
  for ((i = 0; i < rounds; i++)); do
    b=$(best "$b" "$(rtf_of "$base_sil" "$base_scen")")
    t=$(best "$t" "$(rtf_of "$this_sil" "$ROOT/$scen")")
  done
  printf '%-40s %10.2f %10.2f %6.2fx\n' "$(basename "$scen")" "$b" "$t" \
    "$(awk -v a="$b" -v c="$t" 'BEGIN {print (a > 0 ? c / a : 0)}')"
  if [[ $instr == 1 ]]; then
    bi=$(ir_per_period "$base_sil" "$base_scen")
    ti=$(ir_per_period "$this_sil" "$ROOT/$scen")
    printf '%-40s %10d %10d %6.2fx  (instructions per period, callgrind)\n' "" "$bi" "$ti" \
      "$(awk -v a="$bi" -v c="$ti" 'BEGIN {print (c > 0 ? a / c : 0)}')"
  fi
done
