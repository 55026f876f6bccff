#!/usr/bin/env bash
# Every C source and header is clang-formatted (.clang-format).
set -euo pipefail
cd "$1"
files=$(git ls-files -co --exclude-standard '*.c' '*.h' '*.cpp' 2>/dev/null || find firmware hal sil tests -name '*.[ch]')
bad=0
for f in $files; do
  [ -f "$f" ] || continue
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f (run: clang-format -i $f)"
    bad=1
  fi
done
[ $bad -eq 0 ] && echo "clang-format: $(echo "$files" | wc -w) files clean"
exit $bad
