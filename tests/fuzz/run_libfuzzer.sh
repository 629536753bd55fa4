#!/usr/bin/env bash
# ctest's run of one libFuzzer target from the clang tree (build/fuzz, bench/fuzz.sh):
#   run_libfuzzer.sh BINARY FUZZ_SOURCE_DIR TARGET SECONDS
# Exit 77 (ctest: skipped) when the binary is not built. The corpus is a scratch copy of
# tests/fuzz/corpus/TARGET (libFuzzer adds to it); regressions are run first.
set -euo pipefail
binary=$1 fuzz_dir=$2 target=$3 seconds=$4
if [[ ! -x $binary ]]; then
  echo "SKIPPED: $binary is not built (configure the clang tree: bench/fuzz.sh --build-only)"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$fuzz_dir/corpus/$target/." "$work/"
options=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -detect_leaks=1 -print_final_stats=1
         -artifact_prefix="$work/crash-" -max_len=8192)
[[ -f $fuzz_dir/dict/$target.dict ]] && options+=(-dict="$fuzz_dir/dict/$target.dict")
if compgen -G "$fuzz_dir/regressions/$target/*" >/dev/null; then
  "$binary" "${options[@]}" "$fuzz_dir/regressions/$target"/*
fi
status=0
"$binary" "${options[@]}" "$work" >"$work.log" 2>&1 || status=$?
grep -v '^#[0-9]' "$work.log" || true  # the log without its progress lines
rm -f "$work.log"
exit "$status"
