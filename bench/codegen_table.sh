#!/usr/bin/env bash
# docs/benchmarks.md's generated-code tables: `robodiff bench --markdown` for every robot of
# ../shared/robots (Panda, UR5, Talos with a fixed base, Talos with a floating base),
# one markdown section per robot on stdout; progress goes to stderr.
#
# Build first (scripts/test.sh, or cmake -S . -B build -DCMAKE_BUILD_TYPE=Release &&
# cmake --build build -j"$(nproc)"), then, from the repository root:
#
#   bench/codegen_table.sh > codegen_table.md            # full timing (~7 x 20 ms per row)
#   bench/codegen_table.sh --quick > codegen_table.md    # shorter, noisier timing
#
# Extra arguments are passed to every `robodiff bench` (e.g. --quick; not --keep DIR,
# where every robot would build into the same DIR). Environment:
#   ROBODIFF        the robodiff executable (default: build/bin/robodiff)
#   ROBODIFF_SHARED the shared folder (default: ../shared beside the repository)
# Each robot builds its five functions cold (Talos takes minutes on 2 cores); the
# machine should be otherwise idle: the figures are timings.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
robodiff="${ROBODIFF:-$root/build/bin/robodiff}"
shared="${ROBODIFF_SHARED:-$root/../shared}"

if [[ ! -x "$robodiff" ]]; then
  echo "codegen_table.sh: $robodiff not found; build first (scripts/test.sh or cmake --build build)" >&2
  exit 1
fi
if [[ ! -d "$shared/robots" ]]; then
  echo "codegen_table.sh: no shared robots in $shared/robots (set ROBODIFF_SHARED); nothing to do" >&2
  exit 0
fi

# file, extra option
robots=(
  "panda_arm_fixed_fingers.urdf|"
  "ur5_robot.urdf|"
  "talos_reduced.urdf|"
  "talos_reduced.urdf|--floating-base"
)

status=0
for entry in "${robots[@]}"; do
  file="${entry%%|*}"
  option="${entry#*|}"
  urdf="$shared/robots/$file"
  if [[ ! -f "$urdf" ]]; then
    echo "codegen_table.sh: $urdf missing, skipping" >&2
    continue
  fi
  echo "codegen_table.sh: $file $option" >&2
  # shellcheck disable=SC2086  # $option is empty or one word
  if ! "$robodiff" bench --urdf "$urdf" $option --markdown "$@"; then
    echo "codegen_table.sh: robodiff bench failed for $file $option" >&2
    status=1
  fi
done
exit $status
