#!/usr/bin/env bash
# Installs the build tree into a scratch prefix, builds the programs of examples/ against it with
# find_package(springmass), and runs them (each checks itself: the oscillator against its closed
# form, the trampoline its static reactions and energy balance).
set -euo pipefail
build=$1 source=$2 cmake=${3:-cmake}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cmake" --install "$build" --prefix "$work/prefix" > /dev/null
"$cmake" -S "$source/tests/consumer" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
    -DEXAMPLES_DIR="$source/examples" > /dev/null
"$cmake" --build "$work/build" > /dev/null
"$work/build/oscillator"
"$work/build/trampoline"
