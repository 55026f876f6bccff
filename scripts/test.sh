#!/usr/bin/env bash
# Every test: unit (cmocka), plant accuracy, SIL scenarios, reference checks,
# lint, cross builds and pytest, all through CTest on the sanitizer build.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cmake --preset host-debug -DFD_PYTHON="$PWD/.venv/bin/python" >/dev/null
cmake --build --preset host-debug
ctest --preset host-debug "$@"
