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
# The CLI's own tour (compute, generate, check, the cache) is scripts/tour.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target robodiff_cli robodiff_worker robodiffd service_demo

robot=../shared/robots/panda_arm_fixed_fingers.urdf
robot_name="the Franka Panda arm ($robot)"
if [ ! -f "$robot" ]; then
  robot=examples/robots/arm7.urdf
  robot_name="arm7, the project's own 7-joint arm (../shared/robots is absent here: no Panda)"
fi
log=build/run-robodiffd.log
daemon=""

# Stops robodiffd (SIGTERM: it drains, then exits) and reports how it ended.
stop_daemon() {
  [ -n "$daemon" ] || return 0
  echo
  echo "\$ kill -TERM robodiffd   (drains in-flight requests, then exits 0)"
  kill -TERM "$daemon" 2>/dev/null || true
  local status=0
  wait "$daemon" || status=$?
  daemon=""
  tail -n 3 "$log" | sed 's/^/  | /'
  echo "robodiffd exited with status $status"
  return "$status"
}
on_interrupt() {
  trap - INT TERM
  echo
  echo "(interrupted)"
  stop_daemon && exit 0 || exit 1
}
trap on_interrupt INT TERM
trap '[ -z "$daemon" ] || kill -TERM "$daemon" 2>/dev/null || true' EXIT

echo
echo "== robodiffd on its built-in defaults"
echo "\$ robodiffd --log-format text   (log: $log)"
build/bin/robodiffd --log-format text >"$log" 2>&1 &
daemon=$!
for _ in $(seq 600); do
  grep -q " serving " "$log" && break
  if ! kill -0 "$daemon" 2>/dev/null; then cat "$log"; echo "robodiffd did not start"; exit 1; fi
  sleep 0.1
done
grep -q " serving " "$log" || { cat "$log"; echo "robodiffd did not serve within 60 s"; exit 1; }
grep -v '^Reserving\|^\[ Reserving\|^Log level' "$log" | sed 's/^/  | /'
dashboard=$(sed -n 's/.* http_listening .*dashboard=\([^ ]*\).*/\1/p' "$log" | head -n 1)
if [ -z "$dashboard" ]; then
  echo "  (no dashboard: the HTTP listener could not start; the log line http_failed says why)"
fi

echo
echo "== warming $robot_name through robodiffd"
echo "\$ robodiff warmup --server --urdf $robot --spec rnea_jacobian.json --spec aba_jacobian.json --spec crba.json"
start_ms=$(date +%s%3N)
build/bin/robodiff warmup --server --urdf "$robot" --spec examples/specs/rnea_jacobian.json \
  --spec examples/specs/aba_jacobian.json --spec examples/specs/crba.json
elapsed_ms=$(($(date +%s%3N) - start_ms))
printf 'warmed in %d.%03d s (a second run finds every library in the cache)\n' $((elapsed_ms / 1000)) $((elapsed_ms % 1000))

echo
echo "== a client evaluates the Jacobian of RNEA, over iceoryx and over DDS"
echo "\$ service_demo --urdf $robot"
build/bin/service_demo --urdf "$robot"

echo
echo "== robodiffd's health, as the CLI sees it"
build/bin/robodiff health

echo
if [ -n "$dashboard" ]; then
  echo "Dashboard: $dashboard   (models, functions and their compile state, builds, cache, jobs, latency)"
  echo "Metrics:   ${dashboard}metrics   Probes: ${dashboard}healthz ${dashboard}readyz"
fi
if [ -t 0 ]; then
  echo "robodiffd keeps serving; press Ctrl-C to stop it."
  while kill -0 "$daemon" 2>/dev/null; do wait "$daemon" || true; done
  echo "robodiffd stopped by itself"; daemon=""; exit 1
elif [ "${ROBODIFF_RUN_HOLD:-0}" != 0 ]; then
  echo "robodiffd keeps serving for ${ROBODIFF_RUN_HOLD} s (ROBODIFF_RUN_HOLD), or until Ctrl-C."
  sleep "$ROBODIFF_RUN_HOLD" &
  wait $! || true
fi
trap - INT TERM
stop_daemon
