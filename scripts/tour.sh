#!/usr/bin/env bash
# A tour of the robodiff CLI, without the service (scripts/run.sh shows the service):
# `robodiff compute` on the project's own robots (and on the Panda arm when ../shared is
# present), the engine (a function generated, compiled and cross-checked against the
# double reference and finite differences), and the cache (functions built by worker
# processes, then found again).
set -euo pipefail
cd "$(dirname "$0")/.."

deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target robodiff_cli robodiff_worker

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
