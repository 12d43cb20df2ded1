#!/usr/bin/env bash
# Checks that every C++ file of the project follows .clang-format: tests/check_format.sh [CLANG_FORMAT]
# (run from the repository root; prints the files that differ and exits 1 when one does).
# To fix: find include src drivers tests -name '*.cpp' -o -name '*.h' | xargs clang-format -i
set -euo pipefail
clang_format=${1:-clang-format}
mapfile -t files < <(find include src drivers tests \( -name '*.cpp' -o -name '*.h' \) -type f | sort)
bad=0
for f in "${files[@]}"; do
  if ! "$clang_format" --dry-run --Werror "$f" > /dev/null 2>&1; then
    echo "check_format: $f differs from .clang-format (clang-format -i $f)"
    bad=1
  fi
done
echo "check_format: ${#files[@]} files checked"
exit $bad
