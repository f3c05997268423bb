#!/usr/bin/env bash
# Fuzzes with libFuzzer for SECONDS (default 60) each target named (default all of them):
#   model_file        the model-file loader, seeded from the bundled and test models
#   mesh_file         the OBJ files of meshes ("file"), read and built into a mesh, seeded with
#                     the OBJ files of models/ and tests/bad_models and two files of every form
#                     of a face
#   simulation_state  simulation states read back from bytes and restored, seeded with states
#                     the target writes of its own model and of one of other sizes
#   fmu_state         the FMU's serialised states read back (fmi2DeSerializeFMUstate), set and
#                     stepped, seeded with states the target writes of its own FMU instance
#   reference         the reference results `springmass fmu --reference` checks, seeded with
#                     a result of the hanging rope's variables
#   inputs            the input signals of `springmass run --input`, read for a model of the
#                     target's own and run for 0.05 s, seeded with signals of both port kinds
# Builds the targets with clang (installed from Debian's packages if missing, with the fuzzer
# runtime and the OpenMP runtime SUNDIALS' CMake package asks for) and runs them one after the
# other on one core. Each keeps its corpus in fuzz/corpus-work/ (the loader's),
# fuzz/corpus-work-mesh-file/, fuzz/corpus-work-simulation-state/, fuzz/corpus-work-fmu-state/,
# fuzz/corpus-work-reference/ or fuzz/corpus-work-inputs/; inputs that crash are written to build-fuzz/artifacts/.
#
#   make fuzz FUZZ_SECONDS=600
#   make fuzz FUZZ_SECONDS=600 FUZZ_TARGETS=simulation_state
#   make fuzz FUZZ_SECONDS=600 FUZZ_TARGETS=fmu_state
set -euo pipefail
seconds=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(model_file mesh_file simulation_state fmu_state reference inputs)
root=$(cd "$(dirname "$0")/.." && pwd)
build=$root/build-fuzz

for target in "${targets[@]}"; do
  case $target in
  model_file | mesh_file | simulation_state | fmu_state | reference | inputs) ;;
  *)
    echo "fuzz: unknown target $target (model_file, mesh_file, simulation_state, fmu_state, reference, inputs)" >&2
    exit 2
    ;;
  esac
done

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

/usr/bin/cmake -S "$root/fuzz" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DSPRINGMASS_PYTHON="$root/.venv/bin/python" > /dev/null
/usr/bin/cmake --build "$build" --target "${targets[@]/#/fuzz_}"

mkdir -p "$build/artifacts"
seeds=$(mktemp -d)
trap 'rm -rf "$seeds"' EXIT

# Leak detection stays on: a leak on any error path is a finding.
for target in "${targets[@]}"; do
  rm -rf "${seeds:?}"/*
  case $target in
  model_file)
    work=$root/fuzz/corpus-work
    cp "$root"/models/*.json "$seeds"/
    cp "$root"/tests/python/models/*.json "$seeds"/ 2> /dev/null || true
    # Every setting of the simulation and fmu sections, which no bundled or test model gives.
    printf '{ "springmass": 1, "name": "settings",\n  "particles": [ { "name": "a", "position": [0, 0, 0], "fixed": true }, { "name": "b", "position": [0, 0, -1] } ],\n  "springs": [ { "a": "a", "b": "b", "stiffness": 10 } ],\n  "simulation": { "stop_time": 1, "output_interval": 0.1, "rtol": 1e-5, "atol": 1e-7, "atol_velocity": 1e-5,\n    "method": "adams", "solver": "klu", "jacobian": "definite", "max_step": 0.01, "max_steps": 500, "input_changes": "keep",\n    "stability_limit_detection": false },\n  "fmu": { "particle_variables": false } }\n' > "$seeds/settings.json"
    mkdir -p "$work"
    # From models/, where the bundled models' OBJ files are: the target finds a mesh's "file"
    # relative to the working folder, and a bundled model that reads one then loads whole.
    (cd "$root/models" && "$build/fuzz_model_file" "$work" "$seeds" \
      -dict="$root/fuzz/model_file.dict" -max_total_time="$seconds" -max_len=16384 -timeout=10 \
      -rss_limit_mb=2048 -artifact_prefix="$build/artifacts/" -print_final_stats=1)
    ;;
  mesh_file)
    work=$root/fuzz/corpus-work-mesh-file
    cp "$root"/tests/bad_models/*.obj "$root"/models/*.obj "$seeds"/
    printf 'v 0 0 0\r\nv 1 0 0 1\r\nv 1 1 0 0.5 0.5 0.5\r\nvt 0 0\r\nvn 0 0 1\r\nf 1/1/1 2//1 \\\r\n 3/1 -1\r\n' > "$seeds/forms.obj"
    printf '# hexagon\nv 0 0 0\nv 1 0 0\nv .5 .866 0\nf -3 -2 -1\nv -.5 .866 0\nf 1 -2 -1\ng rest\nusemtl m\nl 1 2\n' > "$seeds/relative.obj"
    mkdir -p "$work"
    "$build/fuzz_mesh_file" "$work" "$seeds" \
      -dict="$root/fuzz/mesh_file.dict" -max_total_time="$seconds" -max_len=8192 -timeout=10 \
      -rss_limit_mb=2048 -artifact_prefix="$build/artifacts/mesh-file-" -print_final_stats=1
    ;;
  reference)
    work=$root/fuzz/corpus-work-reference
    printf '"time","tip.x","tip.z",energy.kinetic\r\n0,1,0,0\r\n0.5,0.5,-0.5,1e-3\r\n0.5,0.5,-0.5,2\r\n' > "$seeds/result.csv"
    mkdir -p "$work"
    "$build/fuzz_reference" "$work" "$seeds" -max_total_time="$seconds" -max_len=1024 -timeout=10 \
      -rss_limit_mb=2048 -artifact_prefix="$build/artifacts/reference-" -print_final_stats=1
    ;;
  inputs)
    work=$root/fuzz/corpus-work-inputs
    printf 'time,tip.fx,base.x\n0,0,0\n0.02,1.5,0.01\n0.02,-1,0.01\n0.04,0,-0.02\n' > "$seeds/positions.csv"
    printf '"time","base.vx","base.z","tip.fz"\r\n-1,0,0,0\r\n0.03,2,0.1,-3\r\n' > "$seeds/velocities.csv"
    mkdir -p "$work"
    "$build/fuzz_inputs" "$work" "$seeds" -max_total_time="$seconds" -max_len=1024 -timeout=10 \
      -rss_limit_mb=2048 -artifact_prefix="$build/artifacts/inputs-" -print_final_stats=1
    ;;
  simulation_state | fmu_state)
    # Seeds: real states the target writes of its own model.
    work=$root/fuzz/corpus-work-${target//_/-}
    SPRINGMASS_FUZZ_WRITE_SEEDS="$seeds" "$build/fuzz_$target"
    mkdir -p "$work"
    "$build/fuzz_$target" "$work" "$seeds" \
      -max_total_time="$seconds" -max_len=1024 -timeout=10 -rss_limit_mb=2048 \
      -artifact_prefix="$build/artifacts/$target-" -print_final_stats=1
    ;;
  esac
done
