#!/usr/bin/env bash
# Benchmark: real-time factor of plant + 16 kHz ISR (release build, one core).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cmake --preset host-release >/dev/null
cmake --build --preset host-release
.venv/bin/fluxdrive bench "${1:-sil/scenarios/default.json}" --repeat "${2:-5}"
