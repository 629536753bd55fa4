#!/usr/bin/env bash
# Installs the client package from BUILD into a temporary prefix, then builds and runs a
# consumer with find_package(robodiff) and with pkg-config. Usage: check_package.sh BUILD SOURCE
set -euo pipefail
build=$1 source=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --component client --prefix "$tmp/prefix" >/dev/null
test -f "$tmp/prefix/include/robodiff/client/client.hpp"

# CMake package
cmake -S "$source/tests/package/consumer" -B "$tmp/cmake-build" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_RPATH="$tmp/prefix/lib" >/dev/null
cmake --build "$tmp/cmake-build" >/dev/null
mkdir -p "$tmp/cache1"
"$tmp/cmake-build/consumer" "$source/examples/robots/arm7.urdf" "$tmp/cache1"

# pkg-config
pc=$(find "$tmp/prefix" -name robodiff.pc | head -n 1)
export PKG_CONFIG_PATH=$(dirname "$pc")
libdir=$(pkg-config --variable=libdir robodiff)
c++ "$source/tests/package/consumer/main.cpp" -o "$tmp/pc-consumer" $(pkg-config --cflags --libs robodiff) \
  -Wl,-rpath,"$libdir"
mkdir -p "$tmp/cache2"
"$tmp/pc-consumer" "$source/examples/robots/arm7.urdf" "$tmp/cache2"
echo "package: find_package(robodiff) and pkg-config robodiff both build and run"
