#!/usr/bin/env bash
# One style, enforced: every C++ file matches .clang-format (Google-based).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
files=$(git ls-files '*.cpp' '*.h' '*.hpp' 2>/dev/null || true)
[ -z "$files" ] && { echo "check_format: no files"; exit 0; }
bad=0
for f in $files; do
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "check_format: $f is not clang-formatted (run: clang-format -i $f)" >&2
    bad=1
  fi
done
[ "$bad" = 0 ] && echo "check_format: $(echo "$files" | wc -w) files formatted"
exit $bad
