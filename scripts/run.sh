#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install what is missing, build, then
# robodiff as an operator meets it:
#   1. robodiffd on its built-in defaults (deploy/robodiffd.conf documents them): a RouDi
#      of its own when none runs, the default cache, iceoryx and DDS, and the dashboard on
#      http://127.0.0.1:9464/;
#   2. the Franka Panda warmed through the service (`robodiff warmup --server`: worker
#      processes compile RNEA, ABA and CRBA with their derivatives; a second run finds
#      them in the cache), or the project's own 7-joint arm where ../shared is absent;
#   3. a client evaluating over iceoryx and DDS, with its timings;
#   4. the dashboard's address, then robodiffd keeps serving until Ctrl-C on a terminal
#      (elsewhere it stops at once, or after $ROBODIFF_RUN_HOLD seconds), and stops
#      cleanly: SIGTERM, in-flight requests answered, exit status 0.
# Steps 1-4 are scripts/run-service.sh (tests/deploy drives it through a terminal and
# Ctrl-C). The CLI's own tour (compute, generate, check, the cache) is scripts/tour.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target robodiff_cli robodiff_worker robodiffd service_demo mpc_user_horizon

exec scripts/run-service.sh build
