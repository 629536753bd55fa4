#!/usr/bin/env bash
# Builds the libFuzzer tree (clang, ASan + UBSan on robodiff's code, ROBODIFF_FUZZ=ON) and
# runs each fuzz target of tests/fuzz for FUZZ_SECONDS (default 600), one after the other,
# then prints a table: target, runs, execs/s, coverage, crashes. docs/fuzzing.md.
#
#   bench/fuzz.sh                    # all five targets, 10 minutes each
#   FUZZ_SECONDS=60 bench/fuzz.sh urdf spec
#   bench/fuzz.sh --build-only       # only configure and build build/fuzz (ctest then runs
#                                    # each libFuzzer binary for 20 s, label fuzz)
#
# Environment: FUZZ_SECONDS, FUZZ_BUILD_DIR (default build/fuzz), FUZZ_JOBS (build, default
# nproc), FUZZ_RSS_MB (default 2048). Each target's corpus grows in FUZZ_BUILD_DIR/corpus/
# (seeded from tests/fuzz/corpus), its log is FUZZ_BUILD_DIR/logs/<target>.log and what
# it finds (crash-*, leak-*, timeout-*, oom-*) lands in FUZZ_BUILD_DIR/artifacts/<target>/:
# minimise it (-minimize_crash=1), fix the code, keep it in tests/fuzz/regressions/<target>/.
# Exit status 1 when any target found something.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${FUZZ_SECONDS:-600}
build=${FUZZ_BUILD_DIR:-build/fuzz}
jobs=${FUZZ_JOBS:-$(nproc)}
rss_mb=${FUZZ_RSS_MB:-2048}
all_targets=(urdf spec expression shm_wire dds_wire)
build_only=0
targets=()
for arg in "$@"; do
  case $arg in
    --build-only) build_only=1 ;;
    -h|--help) sed -n 2,18p "$0"; exit 0 ;;
    *) targets+=("$arg") ;;
  esac
done
[[ ${#targets[@]} -eq 0 ]] && targets=("${all_targets[@]}")

# The longest input worth trying per target (bytes).
declare -A max_len=([urdf]=8192 [spec]=8192 [expression]=1024 [shm_wire]=4096 [dds_wire]=4096)

configure_and_build() {
  command -v clang++ >/dev/null || { echo "bench/fuzz.sh: clang++ is not installed (apt-get install clang)"; exit 2; }
  # -O1 -g without NDEBUG: asserts stay on, stacks stay readable.
  cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DROBODIFF_FUZZ=ON \
    -DROBODIFF_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" >/dev/null
  local names=()
  for t in "${targets[@]}"; do names+=("fuzz_$t"); done
  cmake --build "$build" -j"$jobs" --target "${names[@]}"
}

# The last "cov: N ft: M" of a libFuzzer log.
coverage_of() { grep -o 'cov: [0-9]* ft: [0-9]*' "$1" | tail -1 | awk '{print $2 " (" $4 " features)"}'; }
stat_of() { grep -o "stat::$2: *[0-9]*" "$1" | tail -1 | awk '{print $2}'; }

run_target() {
  local t=$1
  local binary=$build/bin/fuzz_$t corpus=$build/corpus/$t artifacts=$build/artifacts/$t log=$build/logs/$t.log
  mkdir -p "$corpus" "$artifacts" "$build/logs"
  cp -n tests/fuzz/corpus/"$t"/* "$corpus"/ 2>/dev/null || true
  local options=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb="$rss_mb" -malloc_limit_mb="$rss_mb"
                 -detect_leaks=1 -max_len="${max_len[$t]}" -print_final_stats=1 -artifact_prefix="$artifacts/")
  [[ -f tests/fuzz/dict/$t.dict ]] && options+=(-dict="tests/fuzz/dict/$t.dict")
  local status=0
  {
    if compgen -G "tests/fuzz/regressions/$t/*" >/dev/null; then
      "$binary" "${options[@]}" tests/fuzz/regressions/"$t"/*
    fi
    "$binary" "${options[@]}" "$corpus"
  } >"$log" 2>&1 || status=$?
  local found
  found=$(find "$artifacts" -type f | wc -l)
  printf '| %s | %s | %s | %s | %s |\n' "$t" "$(stat_of "$log" number_of_executed_units)" \
    "$(stat_of "$log" average_exec_per_sec)" "$(coverage_of "$log")" \
    "$found$([[ $status -ne 0 ]] && echo " (exit $status, see $log)")" >>"$build/fuzz_table.md"
  [[ $found -eq 0 && $status -eq 0 ]]
}

configure_and_build
[[ $build_only -eq 1 ]] && exit 0

printf '| target | runs | execs/s | coverage (edges) | crashes |\n|---|---:|---:|---|---:|\n' >"$build/fuzz_table.md"
failed=0
for t in "${targets[@]}"; do
  echo "fuzzing $t for $seconds s (log: $build/logs/$t.log)"
  run_target "$t" || failed=1
done
echo
cat "$build/fuzz_table.md"
exit "$failed"
