#!/usr/bin/env bash
# The main job: build the SIL (release), run the default scenario, print the
# summary and write the plot to out/default/plot.png.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cmake --preset host-release >/dev/null
cmake --build --preset host-release
scenario=${1:-sil/scenarios/default.json}
.venv/bin/fluxdrive run "$scenario" --out out/default --plot out/default/plot.png
