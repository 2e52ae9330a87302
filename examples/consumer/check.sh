#!/usr/bin/env bash
# Installs SIM from a build tree into a scratch prefix, then builds and runs programs against it
# the three ways users do: find_package (shared and static) and pkg-config.
# Usage: check.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1
source=$2
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cmake --install "$build" --prefix "$scratch/prefix" >/dev/null
cmake -S "$source/examples/consumer" -B "$scratch/consumer" -DCMAKE_PREFIX_PATH="$scratch/prefix" >/dev/null
cmake --build "$scratch/consumer" >/dev/null
export LD_LIBRARY_PATH="$scratch/prefix/lib:$scratch/prefix/lib/$(gcc -print-multiarch 2>/dev/null || true)"
"$scratch/consumer/consumer_cpp" "/consumer_shared_$$"
"$scratch/consumer/consumer_static" "/consumer_static_$$"
export PKG_CONFIG_PATH=$(dirname "$(find "$scratch/prefix" -name sim.pc)")
# shellcheck disable=SC2046
cc "$source/examples/hello.c" -o "$scratch/hello" $(pkg-config --cflags --libs sim)
"$scratch/hello" "/consumer_c_$$"
echo "package consumer: find_package (shared, static) and pkg-config all work"
