#!/usr/bin/env bash
# Installs the build tree into a scratch prefix, builds examples/oscillator.c against it with
# find_package(springmass), and runs it (the example checks itself against the closed form).
set -euo pipefail
build=$1 source=$2 cmake=${3:-cmake}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cmake" --install "$build" --prefix "$work/prefix" > /dev/null
"$cmake" -S "$source/tests/consumer" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
    -DEXAMPLE_SOURCE="$source/examples/oscillator.c" > /dev/null
"$cmake" --build "$work/build" > /dev/null
"$work/build/oscillator"
