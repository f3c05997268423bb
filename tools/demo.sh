#!/usr/bin/env bash
# The main job on a bundled model, end to end: check the model file, simulate the hanging cloth
# (CSV of ports and energies, a ParaView series), package the oscillator as an FMU and simulate
# it in fmpy with a PNG plot of its outputs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-build}
case "$build" in /*) ;; *) build=$root/$build ;; esac
springmass=$build/tools/springmass
python=$root/.venv/bin/python
out=$root/out/demo
# What the demo needs, checked before it removes or writes anything.
if [ ! -x "$springmass" ]; then
  echo "demo: no springmass tool in $build: build it first (make build)" >&2
  exit 1
fi
if [ ! -x "$python" ]; then
  echo "demo: no Python environment in $root/.venv: make it with tools/setup.sh" >&2
  exit 1
fi
# out/demo/ holds one run's results: what an earlier run left there goes first, so that a run
# that stops part way (a build without FMU support stops at the FMU) leaves no older FMU or plot
# beside its cloth as if it had made them. A folder that cannot be changed is told in one line.
mkdir -p "$out"
if ! problem=$(rm -rf "$out/cloth.csv" "$out/cloth_vtk" "$out/oscillator.fmu" "$out/oscillator.png" 2>&1); then
  echo "demo: cannot remove the results of an earlier run from $out: ${problem%%$'\n'*}" >&2
  exit 1
fi

echo "== springmass check models/cloth.json"
"$springmass" check "$root/models/cloth.json"

echo
echo "== springmass run models/cloth.json (a cloth hanging from two corners, 2 s)"
"$springmass" run "$root/models/cloth.json" --t-end 2 --output-interval 0.02 \
    --output "$out/cloth.csv" --vtk "$out/cloth_vtk"

echo
echo "== springmass fmu models/oscillator.json, simulated in fmpy"
"$springmass" fmu "$root/models/oscillator.json" -o "$out/oscillator.fmu"
"$python" "$root/tools/fmu_demo.py" "$out/oscillator.fmu" "$out/oscillator.png"

# The folder as the reader finds it from where the demo runs: out/demo/ from the checkout's top
# (where make runs it), its full path from any other folder.
shown=$out
[ "$(pwd -P)" != "$(cd "$root" && pwd -P)" ] || shown=out/demo
cat <<TXT

Results in $shown/:
  cloth.csv            time [s], port positions [m], velocities [m/s] and energies [J] of the
                       cloth (any spreadsheet, or numpy.genfromtxt with the Python of .venv/)
  cloth_vtk/cloth.pvd  the cloth's motion: open it in ParaView and press play; colour the
                       springs by "tension" [N] or "strain", the particles by "velocity" [m/s]
  oscillator.fmu       the oscillator as an FMI 2.0 Co-Simulation FMU (fmpy, or any FMI importer)
  oscillator.png       the FMU's outputs simulated in fmpy: look at it with any image viewer
TXT
