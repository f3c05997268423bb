#!/usr/bin/env bash
# The commands the build runs for an FMU (assembling the runtime, the reference table, packaging)
# stay whole in a build folder whose name holds what a shell reads: spaces, quotes, parentheses,
# '&', '$', a backquote, '%' and a non-ASCII letter. The project is configured in such a folder
# (nothing is compiled); every command of the build plan of an FMU that is not a compiler's or a
# linker's must parse as the shell that runs it reads it, and the reference table's command, run
# as the build runs it, writes its table in that folder. ('#', ';', '\' and '"' are refused by
# CMake itself in a build folder's name, whatever the project.) And the Makefile, in a checkout
# whose folder has such a name (and '#'), gives CMake the path of the checkout's Python as one
# argument, as it is.
# Usage: check_build_paths.sh SOURCE_DIR CMAKE PYTHON [CMAKE_ARGUMENT ...] (where the build found
# its dependencies, e.g. -DSUNDIALS_DIR=...)
set -euo pipefail
source=$1 cmake=$2 python=$3
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() {
	echo "check_build_paths: $*" >&2
	exit 1
}
build="$work/build 'a' (b) & é \$HOME \`c\` 50%41"
"$cmake" -S "$source" -B "$build" -G Ninja -DSPRINGMASS_BUILD_TESTS=OFF -DSPRINGMASS_PYTHON="$python" "$@" \
    > "$work/configure.log" 2>&1 || fail "configuring in $build: $(tail -n 5 "$work/configure.log")"
ninja=$(sed -n 's/^CMAKE_MAKE_PROGRAM:[A-Z]*=//p' "$build/CMakeCache.txt")
# Custom commands start by going to their folder; compilers and linkers are called otherwise.
mapfile -t commands < <("$ninja" -C "$build" -t commands fmu_oscillator | grep '^cd ')
[ "${#commands[@]}" -ge 3 ] || fail "the build plan of fmu_oscillator has ${#commands[@]} commands of its own, not 3"
for command in "${commands[@]}"; do
	error=$(sh -n -c "$command" 2>&1) || fail "the build would run a command the shell cannot read ($error): $command"
done
reference=$(printf '%s\n' "${commands[@]}" | grep reference_table.cmake) ||
	fail "no command of the build plan writes the reference table"
sh -c "$reference" > "$work/reference.log" 2>&1 || fail "the reference table's command failed: $(cat "$work/reference.log")"
tail -n +2 "$source/tests/references/oscillator.csv" | cmp -s - "$build/fmus/references/oscillator.csv" ||
	fail "the reference table's command did not write $build/fmus/references/oscillator.csv"

# `make`'s configuration in a checkout of such a name: setup.sh and CMake stand-ins, the latter
# writing the arguments it is given one per line.
checkout="$work/checkout 'a' (b) & é \$HOME \`c\` 50%41 #d"
mkdir -p "$checkout/tools"
cp "$source/Makefile" "$checkout/"
printf '#!/bin/sh\n' > "$checkout/tools/setup.sh"
printf '#!/bin/sh\nprintf "%%s\\n" "$@" > "%s/arguments"\n' "$work" > "$work/cmake"
chmod +x "$checkout/tools/setup.sh" "$work/cmake"
make -s -C "$checkout" CMAKE="$work/cmake" build-plain/build.ninja BUILD_DIR=build-plain > "$work/make.log" 2>&1 ||
	fail "make in $checkout: $(cat "$work/make.log")"
grep -qxF -- "-DSPRINGMASS_PYTHON=$checkout/.venv/bin/python" "$work/arguments" ||
	fail "make in $checkout gave CMake these arguments, not the checkout's Python as one: $(cat "$work/arguments")"
