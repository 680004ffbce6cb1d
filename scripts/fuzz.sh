#!/usr/bin/env bash
# libFuzzer runs of EvFlow's file readers under AddressSanitizer + UndefinedBehaviorSanitizer
# (harnesses in tests/fuzz/, built with clang-14 into build-fuzz/).
#   scripts/fuzz.sh NAME SECONDS   fuzz harness NAME (or "all": each in turn) for SECONDS each
#   scripts/fuzz.sh --check RUNS   every harness, RUNS inputs each from the committed seeds and
#                                  regressions alone, fixed seed: the same inputs every time (the
#                                  test command's run)
#   scripts/fuzz.sh --list         the harness names
#   scripts/fuzz.sh --seeds        rewrite the seed corpora with EvFlow's own writers
# A run starts from the committed seeds (tests/fuzz/corpus/NAME) and the inputs of every crash
# found so far (tests/fuzz/regressions/NAME, replayed first); inputs that reach new code go to
# build-fuzz/corpus/NAME (kept between runs, not committed). A crash stops the run, leaves its
# input in build-fuzz/crashes/NAME/ and fails the script. Prints one line per harness:
# executions, seconds, executions per second, corpus size.
set -euo pipefail
cd "$(dirname "$0")/.."
HARNESSES=(ply gltf_splats gltf_scene npy h5_events txt_events dataset checkpoint safetensors)
if [ "${1:-}" = "--list" ]; then printf '%s\n' "${HARNESSES[@]}"; exit 0; fi
if [ "${1:-}" != "--seeds" ] && [ $# -ne 2 ]; then
  echo "usage: scripts/fuzz.sh NAME|all SECONDS | --check RUNS | --seeds | --list" >&2
  exit 2
fi

cmake -S tests/fuzz -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
  -DCMAKE_CXX_COMPILER=clang++-14 >/dev/null
work=$(mktemp -d /dev/shm/evflow-fuzz.XXXXXX)
trap 'rm -rf "$work"' EXIT
export EVF_FUZZ_DIR="$work"
if [ "$1" = "--seeds" ]; then
  cmake --build build-fuzz -j"$(nproc)" --target write_seeds
  rm -rf tests/fuzz/corpus
  build-fuzz/write_seeds tests/fuzz/corpus
  exit 0
fi

name=$1 limit=(-max_total_time="$2")
if [ "$name" = "--check" ]; then name=all limit=(-runs="$2" -seed=1); fi
if [ "$name" = "all" ]; then names=("${HARNESSES[@]}"); else names=("$name"); fi
for n in "${names[@]}"; do
  [[ " ${HARNESSES[*]} " == *" $n "* ]] || { echo "fuzz.sh: no harness '$n' (--list)" >&2; exit 2; }
done
cmake --build build-fuzz -j"$(nproc)" --target "${names[@]/#/fuzz_}"

# allocator_may_return_null: a huge request returns NULL as it would outside ASan (HDF5 checks for
# that; our own code gets std::bad_alloc, which the harnesses report as a finding).
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0}"
for n in "${names[@]}"; do
  corpus="build-fuzz/corpus/$n"
  [ "$1" = "--check" ] && corpus="$work/corpus_$n"  # new inputs: thrown away
  mkdir -p "$corpus" "build-fuzz/crashes/$n"
  dirs=("$corpus" "tests/fuzz/corpus/$n")
  [ -d "tests/fuzz/regressions/$n" ] && dirs+=("tests/fuzz/regressions/$n")
  log="build-fuzz/fuzz_$n.log"
  if ! "build-fuzz/fuzz_$n" "${limit[@]}" -timeout=20 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
    -print_final_stats=1 -artifact_prefix="build-fuzz/crashes/$n/" "${dirs[@]}" >"$log" 2>&1; then
    tail -n 60 "$log" >&2
    echo "fuzz $n: FAILED (input in build-fuzz/crashes/$n/, log $log)" >&2
    exit 1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  secs=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log")
  printf 'fuzz %-12s %10s executions in %4s s (%s/s), 0 crashes, corpus %s inputs\n' "$n" "$runs" "$secs" \
    "$((runs / (secs > 0 ? secs : 1)))" "$(find "$corpus" -type f | wc -l)"
done
