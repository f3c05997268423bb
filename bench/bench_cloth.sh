#!/usr/bin/env bash
# Cloth simulation benchmark: springmass's linear solvers on the benchmark cloth, beside the
# peer (../shared/bench/scipy_cloth.py, SciPy solve_ivp BDF) in the same run.
#
#   bench/bench_cloth.sh BUILD_DIR          (QUICK=1: up to n = 64, peer for n = 8 only;
#                                            LONG=1: also n = 256 with auto, on one thread
#                                            and on every processor: 1.2 - 1.5 hours)
#
# Prints, for n = 16, 32, 64, 128, 256 and each linear solver (1 s simulated, rtol 1e-4,
# atol 1e-6, median of REPEATS runs, default 3; 1 run from n = 64):
#   cloth n=<n> solver=<name> wall_s=<median> steps=<v> rhs=<v> jac=<v> z_corner=<v> threads=1 ...
# a `skip` line for the combinations that would take too long, a `same` line for the solver auto
# chose (measured once, on auto's line, which names it: solver=auto:<choice>), from n = 64 on (4000 free particles, from which the pcg
# solver's loops can run on several threads) auto again on as many threads as processors
# (threads=<t>, the same results), then for the peer
#   peer n=<n> wall_s=<v> z_corner=<v>
#   speedup n=<n> <peer wall / springmass wall with the default solver>
# or, when the peer fails at a size (exit status or solve_ivp status not 0), a line saying so
# instead of those two, and the next size.
set -euo pipefail

build_dir=${1:?usage: bench_cloth.sh BUILD_DIR}
repeats=${REPEATS:-3}
top=$(cd "$(dirname "$0")/.." && pwd)
# The peer: in REFERENCE_BENCH, or the shared benchmark folder beside the checkout.
peer="${REFERENCE_BENCH:-$top/../shared/bench}/scipy_cloth.py"
bench="$build_dir/bench/bench_cloth"
python="$top/.venv/bin/python"

if [[ ! -x "$bench" ]]; then
	echo "bench_cloth.sh: $bench not found; build first (make build)" >&2
	exit 1
fi

sizes=(16 32 64 128 256)
peer_sizes=(8 16)
if [[ "${QUICK:-}" == 1 ]]; then
	sizes=(16 32 64)
	peer_sizes=(8)
fi

# Combinations measured to take many minutes (bench/README.md): SUNDIALS' dense LU above n = 8,
# KLU on the full 6n system above n = 16 (100 s at n = 32), the CHOLMOD-preconditioned solver
# above n = 32, conjugate gradients (auto) above n = 128 (n = 128 takes minutes, n = 256 about
# 50 minutes, 2809 s once: its step count and its cost per step both grow; LONG=1 runs it).
too_slow() {
	local n=$1 solver=$2
	case $solver in
	dense) ((n > 8)) ;;
	klu) ((n > 16)) ;;
	cholmod) ((n > 32)) ;;
	pcg | auto) ((n > 128)) && ! [[ ${LONG:-} == 1 && $solver == auto ]] ;;
	*) false ;;
	esac
}

# OpenBLAS (which CHOLMOD's supernodal factorisation calls) starts a thread per core whose
# waiting spins; on a shared 2-core machine one thread is faster and the figures steadier.
# Only springmass's runs get the setting (the peer keeps its defaults).
blas_threads=${OPENBLAS_NUM_THREADS:-1}

declare -A ours
for n in 8 "${sizes[@]}"; do
	auto_choice=
	for solver in auto dense klu pcg cholmod; do
		if [[ $n == 8 && $solver != auto ]]; then
			continue  # n = 8 only for the speedup against the peer
		fi
		if too_slow "$n" "$solver"; then
			echo "skip n=$n solver=$solver (would take too long: bench/README.md)"
			continue
		fi
		if [[ $solver == "${auto_choice:-}" ]]; then
			echo "same n=$n solver=$solver (auto's choice: the line above)"
			continue
		fi
		r=$repeats
		((n >= 64)) && r=1
		line=$(OPENBLAS_NUM_THREADS=$blas_threads "$bench" "$n" "$solver" "$r")
		if [[ $solver == auto ]]; then
			ours[$n]=$(sed -n 's/.*wall_s=\([^ ]*\).*/\1/p' <<<"$line")
			auto_choice=$(sed -n 's/.*solver=\([^ ]*\).*/\1/p' <<<"$line")
			line=${line/solver=/solver=auto:}
		fi
		[[ $n == 8 ]] || echo "$line"
		processors=$(nproc)
		if [[ $solver == auto ]] && ((n >= 64 && processors > 1)); then
			line=$(THREADS=$processors OPENBLAS_NUM_THREADS=$blas_threads "$bench" "$n" "$solver" "$r")
			echo "${line/solver=/solver=auto:}"
		fi
	done
done

for n in "${peer_sizes[@]}"; do
	if [[ ! -f "$peer" ]]; then
		echo "peer not found at $peer (set REFERENCE_BENCH to the folder that holds it): skipped"
		break
	fi
	# The peer's line: n particles springs steps rhs_evals wall_s z_of_free_corner status, where
	# status is solve_ivp's (0: reached T_END). A peer that fails gives no time to compare with.
	exit_status=0
	out=$("$python" "$peer" "$n" 1) || exit_status=$?
	read -r _ _ _ _ _ wall z status _ <<<"$out" || true
	if [[ $exit_status != 0 || ${status:-} != 0 ]]; then
		echo "peer n=$n failed (exit status $exit_status, solve_ivp status ${status:-none}): no speedup"
		continue
	fi
	echo "peer n=$n wall_s=$wall z_corner=$z"
	if [[ -n "${ours[$n]:-}" ]]; then
		awk -v n="$n" -v p="$wall" -v o="${ours[$n]}" 'BEGIN { printf "speedup n=%d %.1f\n", n, p / o }'
	fi
done
