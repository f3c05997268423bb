#!/usr/bin/env bash
# Fuzzes the model-file loader with libFuzzer for SECONDS (default 60): builds the target with
# clang (installed from Debian's packages if missing, with the fuzzer runtime and the OpenMP
# runtime SUNDIALS' CMake package asks for), seeds the corpus from the bundled and
# test models, and runs on one core. Inputs that crash are written to build-fuzz/artifacts/.
#
#   make fuzz FUZZ_SECONDS=600
set -euo pipefail
seconds=${1:-60}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$root/build-fuzz
work=$root/fuzz/corpus-work

need=()
command -v clang > /dev/null || need+=(clang)
for p in libclang-rt-14-dev libomp-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
done
if ((${#need[@]})); then
  sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  echo "fuzz: installing ${need[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}"
fi

/usr/bin/cmake -S "$root/fuzz" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang > /dev/null
/usr/bin/cmake --build "$build" --target fuzz_model_file

mkdir -p "$work" "$build/artifacts"
seeds=$(mktemp -d)
trap 'rm -rf "$seeds"' EXIT
cp "$root"/models/*.json "$seeds"/
cp "$root"/tests/python/models/*.json "$seeds"/ 2> /dev/null || true

# Leak detection stays on: a leak on any error path is a finding.
"$build/fuzz_model_file" "$work" "$seeds" \
  -dict="$root/fuzz/model_file.dict" -max_total_time="$seconds" -max_len=16384 -timeout=10 \
  -rss_limit_mb=2048 -artifact_prefix="$build/artifacts/" -print_final_stats=1
