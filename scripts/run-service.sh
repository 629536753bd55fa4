#!/usr/bin/env bash
# Steps 1-4 of the README's run command (scripts/run.sh builds, then runs this): robodiffd
# on its built-in defaults, the Panda warmed through it, a client's timings, the
# dashboard's address, then serving until Ctrl-C on a terminal (elsewhere it stops at
# once, or after $ROBODIFF_RUN_HOLD seconds) and a clean stop (SIGTERM, exit status 0).
#
#   scripts/run-service.sh [BUILD_DIR]        (default: build)
#
# For tests only, extra arguments can reach the programs without changing the defaults
# shown to a person: $ROBODIFFD_ARGS (robodiffd), $SERVICE_DEMO_ARGS (service_demo), the
# CLI's own $ROBODIFF_SERVER, and $ROBODIFF_RUN_LOG (robodiffd's log file).
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build}/bin"
read -r -a robodiffd_args <<<"${ROBODIFFD_ARGS:-}"
read -r -a service_demo_args <<<"${SERVICE_DEMO_ARGS:-}"

robot=../shared/robots/panda_arm_fixed_fingers.urdf
robot_name="the Franka Panda arm ($robot)"
if [ ! -f "$robot" ]; then
  robot=examples/robots/arm7.urdf
  robot_name="arm7, the project's own 7-joint arm (../shared/robots is absent here: no Panda)"
fi
log="${ROBODIFF_RUN_LOG:-${1:-build}/run-robodiffd.log}"
# DDS on this host only unless CYCLONEDDS_URI says otherwise: robodiffd serves open
# (unauthenticated) DDS only on loopback (deploy/security.md).
export CYCLONEDDS_URI="${CYCLONEDDS_URI:-file://$PWD/deploy/cyclonedds-loopback.xml}"
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
"$bin/robodiffd" --log-format text "${robodiffd_args[@]}" >"$log" 2>&1 &
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
"$bin/robodiff" warmup --server --urdf "$robot" --spec examples/specs/rnea_jacobian.json \
  --spec examples/specs/aba_jacobian.json --spec examples/specs/crba.json
elapsed_ms=$(($(date +%s%3N) - start_ms))
printf 'warmed in %d.%03d s (a second run finds every library in the cache)\n' $((elapsed_ms / 1000)) $((elapsed_ms % 1000))

echo
echo "== a client evaluates the Jacobian of RNEA, over iceoryx and over DDS"
echo "\$ service_demo --urdf $robot"
"$bin/service_demo" --urdf "$robot" "${service_demo_args[@]}"

echo
echo "== a function you write: an MPC knot (Euler step + Jacobians, tracking cost + gradient"
echo "   and Hessian, collision barrier + gradient; examples/specs/*_mpc_knot.json), built by"
echo "   robodiffd and evaluated over a 20-knot horizon in one batch call"
echo "\$ mpc_user_horizon"
"$bin/mpc_user_horizon"

echo
echo "== robodiffd's health, as the CLI sees it"
"$bin/robodiff" health

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
