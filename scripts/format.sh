#!/usr/bin/env bash
# Formats the C++ sources (engine/, app/, tests/) with clang-format and .clang-format;
# --check changes nothing and fails, listing the files, when one is not formatted.
set -euo pipefail
cd "$(dirname "$0")/.."
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files -- 'engine/*.cpp' 'engine/*.h' 'app/*.cpp' 'app/*.h' 'tests/*.cpp' 'tests/*.h')
else  # a copy without git: the same folders
  mapfile -t files < <(find engine app tests \( -name '*.cpp' -o -name '*.h' \) -not -path '*/node_modules/*' | sort)
fi
if [ "${#files[@]}" -eq 0 ]; then echo "format.sh: no C++ sources found" >&2; exit 1; fi
if [ "${1:-}" = "--check" ]; then
  clang-format --dry-run --Werror "${files[@]}"
else
  clang-format -i "${files[@]}"
fi
