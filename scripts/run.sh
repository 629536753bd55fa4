#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install what is missing, build, and show
# robodiff working. For now that is `robodiff compute` on the project's own robots (and
# on the Panda arm when ../shared is present), the engine (a function generated,
# compiled and cross-checked), the cache (functions built by worker processes, then
# found again), and the service: robodiffd started on its built-in defaults (a RouDi of
# its own when none runs, the default cache), used by a client over iceoryx and DDS, then
# stopped with SIGTERM.
set -euo pipefail
cd "$(dirname "$0")/.."

deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target robodiff_cli robodiff_worker robodiffd service_demo

rd=build/bin/robodiff
arm=examples/robots/arm7.urdf
show() { echo; echo "\$ robodiff $*"; "$rd" "$@"; }

echo
echo "== robodiff on its own 7-joint arm ($arm), at a random state (seed 1)"
show compute --urdf "$arm" --function rnea --random-state 1 --format table
show compute --urdf "$arm" --function crba --random-state 1 --format table
show compute --urdf "$arm" --function aba --random-state 1 --format table
show compute --urdf "$arm" --function jacobian --frame tool --reference LOCAL_WORLD_ALIGNED --random-state 1 --format table

quad=examples/robots/quadruped.urdf
echo
echo "== a quadruped with a free-flyer base ($quad)"
show compute --urdf "$quad" --floating-base --function com --random-state 2 --format table

out=build/run-generated
echo
echo "== the engine: RNEA and its Jacobian d tau/d[q, v, a] generated as C, compiled, checked"
show generate --urdf "$arm" --spec examples/specs/rnea_jacobian.json --out "$out"
show check --urdf "$arm" --spec examples/specs/rnea_jacobian.json --samples 5
show check --urdf "$quad" --floating-base --spec examples/specs/aba_jacobian.json --samples 3

cache=build/run-cache
rm -rf "$cache"
echo
echo "== the cache: three functions built by worker processes, then found again (key = content)"
show warmup --urdf "$arm" --spec examples/specs/rnea_jacobian.json --spec examples/specs/aba_jacobian.json \
  --spec examples/specs/crba.json --jobs 2 --cache "$cache"
show warmup --urdf "$arm" --spec examples/specs/rnea_jacobian.json --spec examples/specs/aba_jacobian.json \
  --spec examples/specs/crba.json --jobs 2 --cache "$cache"
show cache ls --cache "$cache"
show cache verify --cache "$cache"

panda=../shared/robots/panda_arm_fixed_fingers.urdf
if [ -f "$panda" ]; then
  echo
  echo "== the Franka Panda arm ($panda)"
  show compute --urdf "$panda" --function rnea --random-state 1 --format table
  show compute --urdf "$panda" --function crba --random-state 1 --format table
else
  echo
  echo "(../shared/robots not found: skipping the Panda arm)"
fi

echo
echo "== the service: robodiffd on its built-in defaults (deploy/robodiffd.conf documents them)"
log=build/run-robodiffd.log
echo "\$ robodiffd --log-format text   (log: $log)"
build/bin/robodiffd --log-format text >"$log" 2>&1 &
daemon=$!
trap 'kill -TERM $daemon 2>/dev/null || true' EXIT
for _ in $(seq 600); do
  grep -q " serving " "$log" && break
  if ! kill -0 "$daemon" 2>/dev/null; then cat "$log"; echo "robodiffd did not start"; exit 1; fi
  sleep 0.1
done
grep -q " serving " "$log" || { cat "$log"; echo "robodiffd did not serve within 60 s"; exit 1; }
sed 's/^/  | /' "$log"
echo
echo "\$ service_demo   (a client: arm7's RNEA Jacobian over iceoryx, then over DDS)"
build/bin/service_demo
if [ -f "$panda" ]; then
  echo
  echo "\$ service_demo --urdf $panda --transport iceoryx"
  build/bin/service_demo --urdf "$panda" --transport iceoryx
fi
echo
echo "\$ kill -TERM robodiffd   (drains in-flight requests, then exits 0)"
kill -TERM "$daemon"
status=0
wait "$daemon" || status=$?
trap - EXIT
tail -n 4 "$log" | sed 's/^/  | /'
echo "robodiffd exited with status $status"
[ "$status" -eq 0 ]
