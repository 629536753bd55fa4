#!/usr/bin/env bash
# The installed tree, used from outside the build. Usage: check_package.sh BUILD SOURCE
#  1. `cmake --install BUILD --prefix TMP` (everything) puts each expected file in place, the
#     systemd units name the installed robodiffd and configuration (and pass
#     `systemd-analyze verify` when it and iox-roudi are here), and `--component client`
#     alone installs the client package and no program;
#  2. a consumer builds and runs against the installed client with find_package(robodiff)
#     and with pkg-config, and examples/mpc/mpc_horizon.cpp builds against it too;
#  3. the installed programs run with PATH=/usr/bin:/bin and nothing of the build tree:
#     `robodiff --help`, robodiffd reading the installed robodiffd.conf, `robodiff warmup`
#     compiling through the installed worker (libexec/robodiff), and an installed robodiffd
#     on DDS (the installed cyclonedds.xml, domain 231: the tests' fixtures use 1..230)
#     serving the example and compiling a function through its worker, then stopping on
#     SIGTERM with status 0.
set -euo pipefail
build=$1 source=$2
tmp=$(mktemp -d)
server_pid=
cleanup() {
  if [ -n "$server_pid" ] && kill -0 "$server_pid" 2>/dev/null; then
    kill -KILL "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "check_package: $*" >&2; exit 1; }

# ------------------------------------------------------------------ 1. the installed files
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
libdir=$(dirname "$(find "$prefix" -name robodiff.pc)")/..
for file in bin/robodiff bin/robodiffd libexec/robodiff/robodiff-worker; do
  test -x "$prefix/$file" || fail "$file is not installed (or not executable)"
done
for file in include/robodiff/client/client.hpp include/robodiff/schema/status.hpp \
            etc/robodiff/robodiffd.conf etc/robodiff/roudi.toml etc/robodiff/cyclonedds.xml \
            share/robodiff/deploy/cyclonedds-lan.xml lib/systemd/system/robodiffd.service \
            lib/systemd/system/iox-roudi.service lib/sysusers.d/robodiff.conf; do
  test -f "$prefix/$file" || fail "$file is not installed"
done
test -f "$libdir/librobodiff_client.so" || fail "librobodiff_client.so is not installed"
test -f "$libdir/cmake/robodiff/robodiffConfig.cmake" || fail "robodiffConfig.cmake is not installed"
cmp -s "$prefix/etc/robodiff/cyclonedds.xml" "$source/deploy/cyclonedds-loopback.xml" ||
  fail "etc/robodiff/cyclonedds.xml is not deploy/cyclonedds-loopback.xml"

unit=$prefix/lib/systemd/system/robodiffd.service
grep -qx "ExecStart=$prefix/bin/robodiffd --config $prefix/etc/robodiff/robodiffd.conf --roudi external.*" "$unit" ||
  fail "robodiffd.service does not run the installed robodiffd: $(grep ExecStart= "$unit")"
grep -qx "Environment=CYCLONEDDS_URI=file://$prefix/etc/robodiff/cyclonedds.xml" "$unit" ||
  fail "robodiffd.service does not name the installed cyclonedds.xml"
grep -qx "ExecStart=/usr/bin/iox-roudi -c $prefix/etc/robodiff/roudi.toml.*" "$prefix/lib/systemd/system/iox-roudi.service" ||
  fail "iox-roudi.service does not name the installed roudi.toml"
if grep -n "/usr/local/bin\|/etc/robodiff/" "$prefix"/lib/systemd/system/*.service | grep -v "$prefix"; then
  fail "an installed unit still names a path outside the prefix"
fi
if command -v systemd-analyze >/dev/null && [ -x /usr/bin/iox-roudi ]; then
  verify=$(systemd-analyze verify "$prefix"/lib/systemd/system/{iox-roudi,robodiffd}.service 2>&1) ||
    fail "systemd-analyze verify refuses the installed units: $verify"
  [ -z "$verify" ] || fail "systemd-analyze verify has something to say: $verify"
else
  echo "package: systemd-analyze or /usr/bin/iox-roudi missing: the installed units are not verified"
fi

# An edited configuration survives a reinstall; the shipped one stays in share/.
echo "# edited" >> "$prefix/etc/robodiff/robodiffd.conf"
cmake --install "$build" --prefix "$prefix" --component service >/dev/null
tail -n 1 "$prefix/etc/robodiff/robodiffd.conf" | grep -qx "# edited" || fail "a reinstall replaced an edited robodiffd.conf"
cmp -s "$prefix/share/robodiff/deploy/robodiffd.conf" "$source/deploy/robodiffd.conf" ||
  fail "share/robodiff/deploy/robodiffd.conf is not the shipped file"

cmake --install "$build" --component client --prefix "$tmp/client-prefix" >/dev/null
test -f "$tmp/client-prefix/include/robodiff/client/client.hpp" || fail "--component client installs no header"
[ ! -e "$tmp/client-prefix/bin" ] || fail "--component client installs programs: $(ls "$tmp/client-prefix/bin")"

# ------------------------------------------------------- 2. programs built against the client
cmake -S "$source/tests/package/consumer" -B "$tmp/cmake-build" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_RPATH="$libdir" >/dev/null
cmake --build "$tmp/cmake-build" >/dev/null
mkdir -p "$tmp/cache1"
"$tmp/cmake-build/consumer" "$source/examples/robots/arm7.urdf" "$tmp/cache1"

export PKG_CONFIG_PATH=$libdir/pkgconfig
pc_libdir=$(pkg-config --variable=libdir robodiff)
c++ "$source/tests/package/consumer/main.cpp" -o "$tmp/pc-consumer" $(pkg-config --cflags --libs robodiff) \
  -Wl,-rpath,"$pc_libdir"
mkdir -p "$tmp/cache2"
"$tmp/pc-consumer" "$source/examples/robots/arm7.urdf" "$tmp/cache2"

# The example finds the project's arm7 when the shared robots are not there.
c++ -std=c++20 -O2 "$source/examples/mpc/mpc_horizon.cpp" -o "$tmp/mpc_horizon" \
  -DROBODIFF_SOURCE_DIR="\"$source\"" -DROBODIFF_SHARED_DIR="\"$tmp/no-shared\"" \
  $(pkg-config --cflags --libs robodiff) -Wl,-rpath,"$pc_libdir"
echo "package: find_package(robodiff) and pkg-config robodiff both build and run; mpc_horizon builds"

# --------------------------------------------------------- 3. the installed programs, alone
mkdir -p "$tmp/home"
installed() { env -i HOME="$tmp/home" PATH=/usr/bin:/bin "$@"; }
# (Outputs are read whole: `grep -q` in a pipe may end the program early with SIGPIPE.)
out=$(installed "$prefix/bin/robodiff" --help) && grep -q "^Subcommands:" <<<"$out" ||
  fail "installed robodiff --help: $out"
out=$(installed "$prefix/libexec/robodiff/robodiff-worker" --help) && grep -q "Usage: robodiff-worker" <<<"$out" ||
  fail "installed robodiff-worker --help: $out"
out=$(installed "$prefix/bin/robodiffd" --config "$prefix/etc/robodiff/robodiffd.conf" --print-config --no-http) &&
  grep -q '^worker_executable = ' <<<"$out" || fail "installed robodiffd --print-config: $out"

arm7=$source/examples/robots/arm7.urdf
warmup=$(installed "$prefix/bin/robodiff" warmup --urdf "$arm7" --spec "$source/examples/specs/crba.json" \
  --cache "$tmp/cli-cache" -j 1 2>&1) || fail "installed robodiff warmup failed: $warmup"
grep -q "1 built" <<<"$warmup" || fail "installed robodiff warmup built nothing: $warmup"
# ... and through that one: without it the same command names what it looked for.
if [ ! -e /usr/bin/robodiff-worker ] && [ ! -e /bin/robodiff-worker ]; then
  mv "$prefix/libexec/robodiff/robodiff-worker" "$tmp/robodiff-worker.aside"
  status=0
  out=$(installed "$prefix/bin/robodiff" warmup --urdf "$arm7" --spec "$source/examples/specs/crba.json" \
    --cache "$tmp/cli-cache-2" -j 1 2>&1) || status=$?
  mv "$tmp/robodiff-worker.aside" "$prefix/libexec/robodiff/robodiff-worker"
  [ "$status" -eq 1 ] && grep -q "cannot find robodiff-worker: .* nor in ../libexec/robodiff from it" <<<"$out" ||
    fail "robodiff warmup without its worker: status $status: $out"
fi
echo "package: the installed robodiff compiled arm7's CRBA through libexec/robodiff/robodiff-worker"

domain=231
dds="CYCLONEDDS_URI=file://$prefix/etc/robodiff/cyclonedds.xml"
# env itself, not the function `installed` (a subshell): $! is then robodiffd's own pid.
env -i HOME="$tmp/home" PATH=/usr/bin:/bin "$dds" "$prefix/bin/robodiffd" --config "$prefix/etc/robodiff/robodiffd.conf" --no-iceoryx --no-http \
  --dds-domain $domain --cache "$tmp/server-cache" --log-level warn 2>"$tmp/robodiffd.log" &
server_pid=$!
installed "$dds" "$prefix/bin/robodiff" health --server dds:$domain --timeout 30 >/dev/null ||
  fail "the installed robodiffd does not answer over DDS: $(cat "$tmp/robodiffd.log")"
installed "$dds" "$tmp/mpc_horizon" --server dds:$domain --knots 5 --iterations 20 ||
  fail "mpc_horizon on the installed robodiffd: $(cat "$tmp/robodiffd.log")"
served=$(installed "$dds" "$prefix/bin/robodiff" warmup --server dds:$domain --urdf "$arm7" \
  --spec "$source/examples/specs/crba.json" --timeout 120 2>&1) ||
  fail "the installed robodiffd did not compile arm7's CRBA: $served $(cat "$tmp/robodiffd.log")"
kill -TERM "$server_pid"
status=0
wait "$server_pid" || status=$?
server_pid=
[ "$status" -eq 0 ] || fail "the installed robodiffd exited with $status on SIGTERM: $(cat "$tmp/robodiffd.log")"
echo "package: the installed robodiffd served mpc_horizon over DDS, compiled through its worker, stopped with 0"
