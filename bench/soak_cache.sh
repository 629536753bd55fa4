#!/usr/bin/env bash
# Issue 4's repetition target: the concurrency and kill tests, 20 times in a row each
# (zero duplicate builds, zero partial artifacts). Run by hand after a build:
#   bench/soak_cache.sh [REPEATS]
# Prints one line per test binary and exits non-zero at the first failing repetition.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${ROBODIFF_BUILD:-$root/build}/tests"
repeats="${1:-20}"
run() {
  local binary="$1" filter="$2"
  local start=$SECONDS
  if ! "$bin/$binary" --gtest_repeat="$repeats" --gtest_break_on_failure --gtest_filter="$filter" > /tmp/soak-$binary.log 2>&1; then
    echo "FAIL  $binary $filter (log: /tmp/soak-$binary.log)"
    exit 1
  fi
  local passed
  passed=$(grep -c '^\[       OK \]' /tmp/soak-$binary.log || true)
  echo "ok    $binary $filter: $passed test runs passed in $((SECONDS - start)) s"
}
run cache_tests '*Concurrent*:*DeadProcess*:*Lease*'
run workers_tests '*Kill*:*Crash*:*Timeout*'
run cli_tests '*Together*:*Concurrent*'
