#!/usr/bin/env bash
# cppcheck over the firmware, HALs and SIL (warnings, style, performance).
# Register code: '0u << FIELD_Pos' documents a field value (badBitmaskCheck)
# and two writes to one volatile register are a sequence, not redundant.
set -euo pipefail
cd "$1"
cppcheck --quiet --error-exitcode=1 --enable=warning,style,performance,portability \
  --std=c11 --inline-suppr --suppress=missingIncludeSystem --suppress=unusedFunction \
  --suppress='badBitmaskCheck:hal/stm32g4/*' --suppress='redundantAssignment:hal/stm32g4/*' \
  -I firmware/core -I firmware/app -I hal -I hal/sil -I sil/plant -I sil/runner -I pil \
  firmware hal sil pil boards
echo "cppcheck: clean"
