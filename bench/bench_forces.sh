#!/usr/bin/env bash
# Force evaluation benchmark: springmass against the reference kernel, side by side.
#
#   bench/bench_forces.sh BUILD_DIR [REPEATS]
#
# For n = 32, 128, 256 runs the reference kernel (../shared/bench/spring_kernel.c, built with
# cc -O3 -march=native -ffast-math) REPEATS times (default 3; each run prints its best of 5) and
# springmass's bench_forces (median of 7 trials), and prints
#   forces n=<n> springs_per_s=<v> ceiling_springs_per_s=<v> ratio=<v>
#   forces+jacobian n=<n> springs_per_s=<v> ceiling_springs_per_s=<v> ratio=<v>
# where the ceiling is the median over the kernel's runs and ratio = springs_per_s / ceiling;
# then the same for the two ways of filling the assembled sparse matrices as well
# (forces+csr, forces+fill; bench/README.md says what each kind evaluates).
set -euo pipefail

build_dir=${1:?usage: bench_forces.sh BUILD_DIR [REPEATS]}
repeats=${2:-3}
top=$(cd "$(dirname "$0")/.." && pwd)
# The reference programs: REFERENCE_BENCH, or the shared benchmark folder beside the checkout.
shared_bench="${REFERENCE_BENCH:-$top/../shared/bench}"
bench="$build_dir/bench/bench_forces"

if [[ ! -x "$bench" ]]; then
	echo "bench_forces.sh: $bench not found; build first (make build)" >&2
	exit 1
fi
if [[ ! -f "$shared_bench/spring_kernel.c" ]]; then
	echo "bench_forces.sh: reference kernel not found at $shared_bench/spring_kernel.c" \
		"(set REFERENCE_BENCH to the folder that holds it)" >&2
	exit 1
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cc -O3 -march=native -ffast-math "$shared_bench/spring_kernel.c" -lm -o "$work/spring_kernel"

median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
field() { sed -n "s/.*[[:space:]]$1=\([^[:space:]]*\).*/\1/p"; }

for n in 32 128 256; do
	for ((r = 0; r < repeats; r++)); do
		"$work/spring_kernel" "$n" | field springs_per_s
	done >"$work/ceiling"
	ceiling=$(median <"$work/ceiling")
	"$bench" "$n" 7 2>/dev/null >"$work/ours"
	for kind in forces forces+jacobian forces+csr forces+fill; do
		ours=$(grep "^$kind n=" "$work/ours" | field springs_per_s)
		awk -v k="$kind" -v n="$n" -v o="$ours" -v c="$ceiling" \
			'BEGIN { printf "%s n=%d springs_per_s=%.4g ceiling_springs_per_s=%.4g ratio=%.3f\n", k, n, o, c, o / c }'
	done
done
