#!/usr/bin/env bash
# Installs the build tree into a scratch prefix, builds the programs of examples/ against it with
# find_package(springmass), and runs them (each checks itself: the oscillator against its closed
# form, the trampoline its static reactions and energy balance); then builds and runs them again
# with a plain compiler call and pkg-config, as a project without CMake would.
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
pc=$(find "$work/prefix" -name springmass.pc)
for example in oscillator trampoline; do
	cc -std=c11 -Wall -Wextra -Wpedantic -Werror "$source/examples/$example.c" -o "$work/$example-pc" \
	    $(PKG_CONFIG_PATH=$(dirname "$pc") pkg-config --cflags --libs springmass)
	"$work/$example-pc" > /dev/null
done
