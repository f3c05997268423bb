#!/usr/bin/env bash
# Installs the build tree into a scratch prefix and moves the prefix elsewhere, as a user may (the
# package, the pkg-config file and the tool find everything relative to themselves), then builds
# the programs of examples/ against it with find_package(springmass), and runs them (each checks
# itself: the oscillator against its closed form, the trampoline its static reactions and energy
# balance), and a shared library that links it with the program that checks it (shared/); then
# builds and runs the examples again with a plain compiler call and pkg-config, as a
# project without CMake would. In a build with FMUs, the installed tool packs an FMU from the
# installed runtime, which PYTHON (when given) simulates with fmpy; installing again replaces that
# runtime. No installed file, and no FMU, names the build tree. The package passes over a SUNDIALS
# of the next major version found first. A build configured as debug also gets a pkg-config file
# that names its library, a project to which springmass is optional goes on without it when jansson is
# missing, and a project that adds springmass's source tree links it into its shared library and
# its module (a plug-in).
set -euo pipefail
build=$1 source=$2 cmake=${3:-cmake} python=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() {
	echo "consumer: $*" >&2
	exit 1
}
build_logical=$(cd "$build" && pwd) build_real=$(cd "$build" && pwd -P)
# The files under $1 that name the build tree, in what a program reads: the debug information of
# a Debug build names its compiler's working folder, which is no use to a running program, so
# binaries are searched without it.
names_build() {
	find "$1" -type f | while read -r file; do
		if [ "$(head -c 4 "$file")" = $'\x7fELF' ] || [ "$(head -c 7 "$file")" = '!<arch>' ]; then
			objcopy --strip-debug "$file" "$work/stripped" && searched=$work/stripped
		else
			searched=$file
		fi
		if grep -qF -e "$build_logical" -e "$build_real" "$searched"; then echo "$file"; fi
	done
}
"$cmake" --install "$build" --prefix "$work/installed" > /dev/null
mv "$work/installed" "$work/prefix"
names=$(names_build "$work/prefix")
[ -z "$names" ] || fail "installed files name the build tree $build: $names"
"$cmake" -S "$source/tests/consumer" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
    -DEXAMPLES_DIR="$source/examples" > /dev/null
"$cmake" --build "$work/build" > /dev/null
"$work/build/oscillator"
"$work/build/trampoline"
"$work/build/frequency_check"
"$work/build/plugin_check"
# A SUNDIALS of the next major version found first (a project's own SUNDIALS 7 on its
# CMAKE_PREFIX_PATH, for a springmass built with 6): the package passes it over for the major
# version springmass was built with, whose interface the library calls. The stand-in's version file
# accepts any older version, as SUNDIALS 7's does; its configuration must not be loaded.
sundials_dir=$(sed -n 's/^SUNDIALS_DIR:PATH=//p' "$build/CMakeCache.txt")
sundials_version=$(sed -n 's/^set(PACKAGE_VERSION "\([0-9.]*\)")$/\1/p' "$sundials_dir/SUNDIALSConfigVersion.cmake")
[ -n "$sundials_version" ] || fail "no SUNDIALS version in $sundials_dir"
later=$work/later-sundials/lib/cmake/sundials
mkdir -p "$later"
cat > "$later/SUNDIALSConfigVersion.cmake" << EOF
set(PACKAGE_VERSION "$((${sundials_version%%.*} + 1)).0.0")
if(PACKAGE_FIND_VERSION_RANGE)
  if(PACKAGE_VERSION VERSION_LESS PACKAGE_FIND_VERSION_MIN
     OR (PACKAGE_FIND_VERSION_RANGE_MAX STREQUAL "INCLUDE" AND PACKAGE_VERSION VERSION_GREATER PACKAGE_FIND_VERSION_MAX)
     OR (PACKAGE_FIND_VERSION_RANGE_MAX STREQUAL "EXCLUDE" AND PACKAGE_VERSION VERSION_GREATER_EQUAL PACKAGE_FIND_VERSION_MAX))
    set(PACKAGE_VERSION_COMPATIBLE FALSE)
  else()
    set(PACKAGE_VERSION_COMPATIBLE TRUE)
  endif()
else()
  if(PACKAGE_VERSION VERSION_LESS PACKAGE_FIND_VERSION)
    set(PACKAGE_VERSION_COMPATIBLE FALSE)
  else()
    set(PACKAGE_VERSION_COMPATIBLE TRUE)
  endif()
endif()
EOF
echo 'message(FATAL_ERROR "the SUNDIALS of the next major version was taken")' > "$later/SUNDIALSConfig.cmake"
if ! "$cmake" -S "$source/tests/consumer" -B "$work/later" -G Ninja -DCMAKE_PREFIX_PATH="$work/later-sundials;$work/prefix" \
    -DEXAMPLES_DIR="$source/examples" > "$work/later.log" 2>&1; then
	fail "with a SUNDIALS of the next major version first on the path: $(grep -A2 'Error' "$work/later.log")"
fi
"$cmake" --build "$work/later" --target oscillator > /dev/null
"$work/later/oscillator" > /dev/null
# The headers are C++ too (extern "C"): each compiles alone as C++11, strictly, where a C++ compiler
# is installed.
if command -v c++ > /dev/null; then
	for header in "$work"/prefix/include/springmass/*.h; do
		echo "#include \"springmass/$(basename "$header")\"" |
			c++ -std=c++11 -Wall -Wextra -Wpedantic -Werror -fsyntax-only -x c++ -I"$work/prefix/include" - ||
			fail "$(basename "$header") is no C++11"
	done
fi
# springmass.pc, or springmassd.pc from a Debug build.
pc=$(find "$work/prefix" -name 'springmass*.pc')
for example in oscillator trampoline; do
	cc -std=c11 -Wall -Wextra -Wpedantic -Werror "$source/examples/$example.c" -o "$work/$example-pc" \
	    $(PKG_CONFIG_PATH=$(dirname "$pc") pkg-config --cflags --libs "$(basename "$pc" .pc)")
	"$work/$example-pc" > /dev/null
done

# A project to which springmass is optional goes on without it when a dependency is missing
# (jansson, hidden from pkg-config here) instead of failing its configuration.
mkdir "$work/no-pkg-config"
if ! out=$(PKG_CONFIG_LIBDIR="$work/no-pkg-config" PKG_CONFIG_PATH="" "$cmake" -S "$source/tests/consumer/optional" \
    -B "$work/optional" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" 2>&1) ||
	! grep -q 'springmass: not found' <<< "$out"; then
	fail "an optional find_package(springmass) without jansson failed the configuration: $out"
fi

# The pkg-config file is named after the library its build makes, and links it, in every build
# type: a build configured as "debug" (any case) makes libspringmassd.a (DEBUG_POSTFIX) and
# springmassd.pc, which share a prefix with a Release build's. Configuring is enough to see it.
"$cmake" -S "$source" -B "$work/debug" -G Ninja -DCMAKE_BUILD_TYPE=debug -DSPRINGMASS_BUILD_TESTS=OFF \
    -DSPRINGMASS_BUILD_FMU=OFF > /dev/null
exported=$(grep -ho 'lib[a-z]*\.a"' $(find "$work/debug" -name 'springmassTargets-*.cmake') | sort -u)
named=$(PKG_CONFIG_PATH=$(dirname "$(find "$work/debug" -name springmassd.pc)") pkg-config --libs-only-l springmassd)
[ "${exported%\"}" = "libspringmassd.a" ] && [[ " $named " == *" -lspringmassd "* ]] ||
	fail "a debug build's package exports ${exported%\"} and its pkg-config file links: $named"

# A build of another type than Debug installs the tool too: "None" (any case), the type Debian's
# packages are built with, their compiler flags given alone. Unoptimised here, which is quick.
"$cmake" -S "$source" -B "$work/none" -G Ninja -DCMAKE_BUILD_TYPE=none -DSPRINGMASS_BUILD_TESTS=OFF \
    -DSPRINGMASS_BUILD_FMU=OFF > /dev/null
"$cmake" --build "$work/none" -j 2 --target springmass_cli > /dev/null
"$cmake" --install "$work/none" --prefix "$work/none-prefix" > /dev/null
[ -x "$work/none-prefix/bin/springmass" ] || fail "a build of type None installs no springmass tool"
"$work/none-prefix/bin/springmass" --version > /dev/null

ninja=$(sed -n 's/^CMAKE_MAKE_PROGRAM:[A-Z]*=//p' "$work/build/CMakeCache.txt")
# springmass added to a project from its source tree (add_subdirectory, FetchContent): the project's
# shared library and module link it as they link the installed package, and springmass's warnings
# stay errors of its own targets only. The project sets no build type, so nothing is optimised.
"$cmake" -S "$source/tests/consumer" -B "$work/embedded" -G Ninja -DSPRINGMASS_SOURCE_DIR="$source" \
    -DSPRINGMASS_BUILD_FMU=OFF -DEXAMPLES_DIR="$source/examples" > /dev/null
"$cmake" --build "$work/embedded" -j 2 --target frequency_check plugin_check > "$work/embedded.log" ||
	fail "a shared library or module of a project that adds springmass with add_subdirectory: $(tail -n 5 "$work/embedded.log")"
"$work/embedded/frequency_check"
"$work/embedded/plugin_check"
# Installed with the project, springmass's tool comes along: a build without a build type is not
# a Debug one.
"$cmake" --build "$work/embedded" -j 2 --target springmass_cli > /dev/null
"$cmake" --install "$work/embedded" --prefix "$work/embedded-prefix" > "$work/embedded-install.log" 2>&1 ||
	fail "installing a project that adds springmass with add_subdirectory: $(tail -n 5 "$work/embedded-install.log")"
[ -x "$work/embedded-prefix/bin/springmass" ] || fail "a build without a build type installs no springmass tool"
# springmass's licence goes to its own documentation folder, beside the project's own licence.
cmp -s "$source/LICENSE" "$work/embedded-prefix/share/doc/springmass/LICENSE" &&
	grep -qx 'The licence of springmass_consumer' "$work/embedded-prefix/share/doc/springmass_consumer/LICENSE" ||
	fail "installed with a project that adds it, springmass's licence is not in share/doc/springmass beside the project's own: $(cd "$work/embedded-prefix" && find . -name LICENSE)"
commands=$("$ninja" -C "$work/embedded" -t commands frequency_check)
! grep -q -- '-Werror.*shared/frequency\.c' <<< "$commands" ||
	fail "springmass added with add_subdirectory makes warnings errors in the project that adds it"
# The package links SUNDIALS's static libraries only: no shared one on a consumer's link line,
# which a linker without --as-needed would make the program need (cmake/sundials_static.cmake).
shared=$("$ninja" -C "$work/build" -t commands | grep -o 'libsundials_[a-z_]*\.so[.0-9]*' | sort -u | tr '\n' ' ' || true)
[ -z "$shared" ] || fail "a consumer of the package links SUNDIALS's shared libraries: $shared"

# Which library each configuration of a consumer links, when a prefix holds a Debug and a Release
# library, and when it holds that of a build without a build type (springmass added with
# add_subdirectory to a project that sets none, and installed with it): from the consumer's build
# plan, nothing compiled. The installed package's files, of whatever build type this build has,
# stand in for the others, renamed.
targets=$(find "$work/prefix" -name 'springmassTargets-*.cmake')
[ "$(wc -w <<< "$targets")" = 1 ] || fail "the package has more or fewer than one configuration: $targets"
installed=$(sed -n 's/^# Generated CMake target import file for configuration "\(.*\)"\.$/\1/p' "$targets")
[ -n "$installed" ] || fail "$targets names no configuration"
library=$(find "$work/prefix" -name 'libspringmass*.a')
stand_in() {  # prefix config CONFIG library-file
	cp -R "$work/prefix" "$1"
	add_config "$@"
}
add_config() {  # prefix config CONFIG library-file: the package's files as those of another build type
	local files=${targets#"$work/prefix"} lib=${library#"$work/prefix"} name
	name=$(basename "$library")
	sed -e "s/${installed^^}/$3/g" -e "s/\"$installed\"/\"$2\"/g" -e "s/${name%.a}\.a/$4/g" "$targets" \
	    > "$1/$(dirname "$files")/springmassTargets-${2,,}.cmake"
	cp "$library" "$1/$(dirname "$lib")/$4"
}
linked() {  # prefix build-type
	rm -rf "$work/map"
	"$cmake" -S "$source/tests/consumer" -B "$work/map" -G Ninja -DCMAKE_PREFIX_PATH="$1" \
	    -DCMAKE_BUILD_TYPE="$2" -DEXAMPLES_DIR="$source/examples" > /dev/null 2>&1 || { echo "no library"; return; }
	"$ninja" -C "$work/map" -t commands oscillator | grep -o 'libspringmassd\?\.a' | sort -u | tr '\n' ' '
}
if [ "${installed,,}" = debug ]; then
	stand_in "$work/both" Release RELEASE libspringmass.a
else
	stand_in "$work/both" Debug DEBUG libspringmassd.a
fi
for config in "" RelWithDebInfo None Debug; do
	expected="libspringmass.a "
	[ "$config" != Debug ] || expected="libspringmassd.a "
	got=$(linked "$work/both" "$config")
	[ "$got" = "$expected" ] || fail "with a Debug and a Release install, build type '$config' links $got"
done
stand_in "$work/noconfig" NoConfig NOCONFIG libspringmass.a
rm "$work/noconfig${targets#"$work/prefix"}"
for config in RelWithDebInfo MinSizeRel; do
	got=$(linked "$work/noconfig" "$config")
	[ "$got" = "libspringmass.a " ] || fail "with the install of a build without a build type, build type '$config' links $got"
done
# The install of a build of type None (above) serves a consumer of any build type.
for config in "" Release RelWithDebInfo MinSizeRel Debug; do
	got=$(linked "$work/none-prefix" "$config")
	[ "$got" = "libspringmass.a " ] || fail "with the install of a build of type None, build type '$config' links $got"
done
# A Debug and a RelWithDebInfo install, no Release: a Release consumer links the optimised one.
cp -R "$work/prefix" "$work/optimised"
rm "$work/optimised${targets#"$work/prefix"}" "$work/optimised${library#"$work/prefix"}"
add_config "$work/optimised" RelWithDebInfo RELWITHDEBINFO libspringmass.a
add_config "$work/optimised" Debug DEBUG libspringmassd.a
got=$(linked "$work/optimised" Release)
[ "$got" = "libspringmass.a " ] || fail "with a Debug and a RelWithDebInfo install, build type Release links $got"

# The tool comes with what its help refers to (docs/) and with the bundled models, which it takes
# from where they are installed (the sail's mesh beside its model).
for doc in README.md docs/model-format.md docs/fmu.md docs/analysis.md docs/simulation.md; do
	[ -f "$work/prefix/share/doc/springmass/$doc" ] || fail "$doc is not installed beside the licence"
done
models=0
for model in "$work"/prefix/share/springmass/models/*.json; do
	[ -f "$model" ] || break
	"$work/prefix/bin/springmass" check "$model" > /dev/null ||
		fail "the installed tool refuses the installed model $model"
	models=$((models + 1))
done
[ "$models" = "$(ls "$source"/models/*.json | wc -l)" ] ||
	fail "$models bundled models installed in share/springmass/models, not every one"
runtime=$(find "$work/prefix" -path '*/springmass/fmu' -type d)
[ -n "$runtime" ] || exit 0  # a build without FMUs installs no runtime
# Installing again replaces the runtime rather than adding to it: the libraries and licences an
# earlier install bundled (here a library under another soname, as after a system upgrade) are not
# packed into the FMUs made after it. Installed through DESTDIR, into the same folder.
cp "$runtime/binaries/linux64/springmass_fmu.so" "$runtime/binaries/linux64/libearlier.so.1"
echo "an earlier install's licence" > "$runtime/documentation/licenses/libearlier1.txt"
DESTDIR=$work "$cmake" --install "$build" --prefix /prefix > /dev/null
earlier=$(find "$runtime" -name '*earlier*')
[ -z "$earlier" ] || fail "installing again kept what an earlier install put into the runtime: $earlier"
fmu=$work/oscillator.fmu
env -u SPRINGMASS_FMU_RUNTIME "$work/prefix/bin/springmass" fmu "$source/models/oscillator.json" -o "$fmu" > /dev/null
mkdir "$work/fmu"
(cd "$work/fmu" && unzip -q "$fmu")
cmp -s "$work/fmu/binaries/linux64/oscillator.so" "$runtime/binaries/linux64/springmass_fmu.so" ||
	fail "the installed tool did not pack the installed runtime's binary"
names=$(names_build "$work/fmu")
[ -z "$names" ] || fail "the FMU packed by the installed tool names the build tree $build: $names"
if [ -n "$python" ]; then
	"$python" -c 'import sys, fmpy
result = fmpy.simulate_fmu(sys.argv[1], stop_time=0.5)
assert result["time"][-1] == 0.5 and abs(result["tip.x"][-1]) < 10, result[-1]' "$fmu"
fi
# Without its installed runtime, the installed tool refuses: it never falls back on the runtime
# of the build tree it came from.
mv "$runtime" "$runtime.away"
if env -u SPRINGMASS_FMU_RUNTIME "$work/prefix/bin/springmass" fmu "$source/models/oscillator.json" \
    -o "$work/without.fmu" 2> /dev/null; then
	fail "the installed tool packed an FMU without an installed runtime (from the build tree's)"
fi
