#!/usr/bin/env bash
# Formats the C++ sources (engine/, app/, tests/) with clang-format and .clang-format;
# --check changes nothing and fails, listing the files, when one is not formatted.
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files -- 'engine/*.cpp' 'engine/*.h' 'app/*.cpp' 'app/*.h' 'tests/*.cpp' 'tests/*.h')
if [ "${1:-}" = "--check" ]; then
  clang-format --dry-run --Werror "${files[@]}"
else
  clang-format -i "${files[@]}"
fi
