#!/usr/bin/env bash
# Installs the build tree into a temporary prefix, then builds and runs a consumer with
# find_package(splintcore CONFIG) and, separately, with pkg-config.
# usage: run.sh BUILD_DIR CONSUMER_SOURCE_DIR CXX
set -eu
build=$1
src=$2
cxx=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_CXX_COMPILER="$cxx" >/dev/null
cmake --build "$work/build" >/dev/null
"$work/build/consumer"
pc=$(find "$work/prefix" -name splintcore.pc | head -n 1)
test -n "$pc"
export PKG_CONFIG_PATH=$(dirname "$pc")
if command -v pkg-config >/dev/null 2>&1; then
  # shellcheck disable=SC2046
  "$cxx" -std=c++17 "$src/consumer.cpp" -o "$work/consumer_pc" $(pkg-config --cflags --libs splintcore)
  "$work/consumer_pc"
else
  echo "pkg-config not installed: pkg-config consumer skipped"
fi
echo "install consumer: ok"
