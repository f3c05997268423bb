#!/usr/bin/env bash
# The benchmark scripts' own arithmetic and output, without timing anything: bench/bench_cloth.sh
# over a stand-in bench_cloth and stand-in peers whose figures are known, so that the speedup
# lines can be checked against them.
# The line of the real bench_cloth, on a cloth small and short enough to take milliseconds, holds
# the benchmark's agreed fields first and in their agreed order.
# The force and port benchmarks refuse an argument that is not a count in range, as bench_cloth does.
# Usage: check_bench.sh SOURCE_DIR BENCH_CLOTH BENCH_FORCES [BENCH_PORTS]
set -u
root=$(cd "$1" && pwd)
bench_cloth=$2
bench_forces=$3
bench_ports=${4:-}
failures=0
fail() { echo "FAILED: $*"; failures=$((failures + 1)); }
[ -x "$root/.venv/bin/python" ] || { echo "$root/.venv/bin/python is missing (make setup)"; exit 1; }

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# A stand-in for build/bench/bench_cloth N SOLVER REPEATS: auto (which reports the solver it
# chose, pcg) takes n / 32 s, every other solver 100 s.
mkdir -p "$tmp/build/bench" "$tmp/peer" "$tmp/failing_peer" "$tmp/unfinished_peer"
cat > "$tmp/build/bench/bench_cloth" << 'SH'
#!/usr/bin/env bash
wall=100
solver=$2
if [ "$2" = auto ]; then
  wall=$(awk -v n="$1" 'BEGIN { print n / 32 }')
  solver=pcg
fi
echo "cloth n=$1 solver=$solver wall_s=$wall steps=1 rhs=1 jac=1 z_corner=-0.1 threads=${THREADS:-1} lin_iters=0 fact=0 restarts=0 etf=0 ncf=0 force_s=0 jacobian_s=0 linear_s=0"
SH
chmod +x "$tmp/build/bench/bench_cloth"
# Stand-ins for the peer (its output: n particles springs steps rhs_evals wall_s z status): n s
# of wall time at size n; the failing one exits with an error at n = 8, the unfinished one exits
# normally at n = 8 but with solve_ivp's status -1 (the integration stopped before T_END).
cat > "$tmp/peer/scipy_cloth.py" << 'PY'
import sys
n = int(sys.argv[1])
print(n, n * n, 0, 1, 1, f"{n:.3f}", "-0.100000", 0)
PY
cat > "$tmp/failing_peer/scipy_cloth.py" << 'PY'
import sys
n = int(sys.argv[1])
if n == 8:
    sys.exit("no module named scipy")
print(n, n * n, 0, 1, 1, f"{n:.3f}", "-0.100000", 0)
PY
cat > "$tmp/unfinished_peer/scipy_cloth.py" << 'PY'
import sys
n = int(sys.argv[1])
print(n, n * n, 0, 1, 1, f"{n:.3f}", "-0.100000", -1 if n == 8 else 0)
PY

# speedup = the peer's wall time / auto's at the same n: 8 / 0.25 and 16 / 0.5.
out=$(REFERENCE_BENCH="$tmp/peer" "$root/bench/bench_cloth.sh" "$tmp/build" 2> /dev/null)
status=$?
[ $status -eq 0 ] || fail "bench_cloth.sh exited with $status: $out"
for expected in "peer n=8 wall_s=8.000 z_corner=-0.100000" "speedup n=8 32.0" \
                "peer n=16 wall_s=16.000 z_corner=-0.100000" "speedup n=16 32.0"; do
  grep -qxF "$expected" <<< "$out" || fail "bench_cloth.sh printed no '$expected': $out"
done

# A peer that fails at one size: a line says so, no speedup for it, and the next size still runs.
out=$(REFERENCE_BENCH="$tmp/failing_peer" "$root/bench/bench_cloth.sh" "$tmp/build" 2> /dev/null)
status=$?
[ $status -eq 0 ] || fail "bench_cloth.sh with a failing peer exited with $status: $out"
grep -q "^peer n=8 failed" <<< "$out" || fail "bench_cloth.sh did not say that the peer failed at n = 8: $out"
! grep -q "^speedup n=8 " <<< "$out" || fail "bench_cloth.sh printed a speedup for a failed peer: $out"
grep -qxF "speedup n=16 32.0" <<< "$out" || fail "bench_cloth.sh did not go on to n = 16 after the peer failed: $out"

# A peer that exits normally but whose solve_ivp did not reach T_END failed as well.
out=$(REFERENCE_BENCH="$tmp/unfinished_peer" "$root/bench/bench_cloth.sh" "$tmp/build" 2> /dev/null)
status=$?
[ $status -eq 0 ] || fail "bench_cloth.sh with an unfinished peer exited with $status: $out"
grep -qF "peer n=8 failed (exit status 0, solve_ivp status -1)" <<< "$out" ||
  fail "bench_cloth.sh did not say that solve_ivp did not finish at n = 8: $out"
! grep -q "^speedup n=8 " <<< "$out" || fail "bench_cloth.sh printed a speedup for an unfinished peer: $out"
grep -qxF "speedup n=16 32.0" <<< "$out" || fail "bench_cloth.sh did not go on to n = 16 after solve_ivp failed: $out"

# The benchmark's agreed format: cloth n=<n> solver=<name> wall_s=<median> steps=<v> rhs=<v> jac=<v> z_corner=<v>,
# then the driver's further fields.
line=$("$bench_cloth" 4 pcg 1 0.01)
grep -qE '^cloth n=4 solver=pcg wall_s=[0-9.e+-]+ steps=[0-9]+ rhs=[0-9]+ jac=[0-9]+ z_corner=-?[0-9.]+( |$)' <<< "$line" ||
  fail "bench_cloth printed '$line', not the agreed fields first and in their order"

# A setting or argument that is not one stops it (exit status 2, naming what was given) instead of
# measuring something else under its name: atof would read "1e-4x" as 1e-4 and "abc" as 0 (the
# default), and a mistyped "of" would leave the detection on.
for setting in RESTART_EVERY=abc RESTART_EVERY=nan RESTART_EVERY=-1 ATOL_VELOCITY=1e-4x ATOL_VELOCITY=0 THREADS=2.5 \
               THREADS=0 STABILITY_LIMIT_DETECTION=of; do
  err=$(env "$setting" "$bench_cloth" 4 pcg 1 0.01 2>&1 > /dev/null)
  status=$?
  [ $status -eq 2 ] && grep -qF "bench_cloth: $setting: " <<< "$err" ||
    fail "bench_cloth with $setting: exit status $status, '$err'"
done
for args in "4x pcg" "4 nosuch" "4 pcg 0" "4 pcg 1 0.01s" "4 pcg 1 0"; do
  # $args unquoted: split into its arguments on purpose.
  "$bench_cloth" $args > /dev/null 2>&1
  status=$?
  [ $status -eq 2 ] || fail "bench_cloth $args: exit status $status, not 2"
done
# Settings given (or left empty, as unset) run and are reported.
line=$(THREADS=2 STABILITY_LIMIT_DETECTION=off RESTART_EVERY= "$bench_cloth" 4 pcg 1 0.01)
grep -qE '^cloth n=4 solver=pcg .* threads=2 ' <<< "$line" || fail "bench_cloth with THREADS=2 printed '$line'"

# bench_forces N [TRIALS] and bench_ports N [TRIALS] [STEPS]: atoi read "4x" as 4 and "7.5" as 7,
# and a huge N overflowed n * n; each is refused now (exit status 2) before anything is measured.
for args in "4x" "4 1x" "4 7.5" "2" "5000" "4 0" "1e3"; do
  "$bench_forces" $args > /dev/null 2>&1
  status=$?
  [ $status -eq 2 ] || fail "bench_forces $args: exit status $status, not 2"
done
line=$("$bench_forces" 4 1 2> /dev/null | head -n 1)
grep -qE '^forces n=4 springs=[0-9]+ springs_per_s=' <<< "$line" || fail "bench_forces 4 1 printed '$line'"
if [ -n "$bench_ports" ]; then
  for args in "16x" "16 1x" "16 1 1x" "15" "5000" "16 0" "16 1 0" "16 1 2.5"; do
    "$bench_ports" $args > /dev/null 2>&1
    status=$?
    [ $status -eq 2 ] || fail "bench_ports $args: exit status $status, not 2"
  done
  line=$("$bench_ports" 16 1 1 2> /dev/null)
  grep -qE '^ports n=16 particles=256 motion=60 ' <<< "$line" || fail "bench_ports 16 1 1 printed '$line'"
fi

[ $failures -eq 0 ] || exit 1
echo "bench scripts: ok"
