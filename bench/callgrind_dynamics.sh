#!/usr/bin/env bash
# Instructions per call of FK, RNEA, CRBA and ABA (valgrind's callgrind: repeatable,
# unlike timings on a shared machine). valgrind does not know AVX-512, so this uses a
# build without -march=native:
#   cmake -S . -B build-cg -DROBODIFF_NATIVE=OFF -DCMAKE_CXX_FLAGS=-march=haswell -DROBODIFF_BUILD_TESTS=OFF
#   cmake --build build-cg --target dynamics_repeat
#   bench/callgrind_dynamics.sh build-cg/bin/dynamics_repeat ROBOT.urdf [--floating-base]
set -euo pipefail
bin=$1; urdf=$2; shift 2
count() {
  local alg=$1 reps=$2
  shift 2
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$urdf" "$alg" "$reps" "$@" 2>&1 >/dev/null |
    sed -n 's/.*Collected : *//p'
}
n=1000
printf "%-6s %14s\n" algorithm "instr/call"
for alg in fk rnea crba aba; do
  base=$(count "$alg" 0 "$@")
  full=$(count "$alg" $n "$@")
  printf "%-6s %14d\n" "$alg" $(( (full - base) / n ))
done
