#!/usr/bin/env bash
# `springmass check`: every bundled model is valid and summarised; every file of
# tests/bad_models is refused (exit status 1) with exactly the error listed in expected.txt;
# usage errors exit with 2. Then `springmass run` at the edges of its output grid.
set -u
cli=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
root=$(cd "$(dirname "$0")/.." && pwd)
failures=0
fail() { echo "FAILED: $*"; failures=$((failures + 1)); }

for model in "$root"/models/*.json; do
  out=$("$cli" check "$model" 2>&1)
  status=$?
  [ $status -eq 0 ] || fail "check $(basename "$model") exited with $status: $out"
  grep -q "^particles " <<< "$out" && grep -q "^fastest " <<< "$out" && grep -q "^ok$" <<< "$out" ||
    fail "check $(basename "$model") printed no summary: $out"
done

cd "$root/tests/bad_models"
while IFS='|' read -r file expected; do
  [[ -z "$file" || "$file" == \#* ]] && continue
  out=$("$cli" check "$file" 2>&1)
  status=$?
  [ $status -eq 1 ] || fail "check $file exited with $status, expected 1"
  [ "$out" = "springmass check: $expected" ] || fail "check $file printed '$out', expected 'springmass check: $expected'"
done < expected.txt

"$cli" check --help | grep -q "^usage: springmass check MODEL" || fail "check --help printed no usage"
"$cli" check > /dev/null 2>&1; [ $? -eq 2 ] || fail "check without a file did not exit with 2"
"$cli" check a.json b.json > /dev/null 2>&1; [ $? -eq 2 ] || fail "check with two files did not exit with 2"
"$cli" check --frobnicate x.json > /dev/null 2>&1; [ $? -eq 2 ] || fail "check with an unknown option did not exit with 2"

# `springmass run` at the edges of its output grid, and a model without springs.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=$("$cli" run "$root/models/oscillator.json" --t-end 1e-11 -q -o - 2>&1)
[ "$(wc -l <<< "$out")" -eq 3 ] && [ "$(tail -1 <<< "$out" | cut -d, -f1)" = "9.9999999999999994e-12" ] ||
  fail "run to 1e-11 s did not write the rows at 0 and 1e-11 s: $out"
"$cli" run "$root/models/oscillator.json" --output-interval 1e-300 -q -o "$tmp/many.csv" > /dev/null 2>&1
[ $? -eq 1 ] && [ ! -e "$tmp/many.csv" ] || fail "run with 1e-300 s output interval was not refused before writing"
"$cli" run "$root/models/oscillator.json" -x > /dev/null 2>&1; [ $? -eq 2 ] || fail "run -x did not exit with 2"
cat > "$tmp/falling.json" << 'JSON'
{"springmass": 1, "name": "falling", "gravity": [0, 0, -9.81],
 "particles": [{"name": "p", "position": [0, 0, 0]}],
 "ports": [{"name": "p", "particle": "p", "kind": "probe"}]}
JSON
# Free fall: z(0.1 s) = -g t^2 / 2 = -0.04905 m, to within twice the default relative tolerance
# (1e-6) of |z|: 1e-7 m (measured 2e-8).
out=$("$cli" run "$tmp/falling.json" --t-end 0.1 --output-interval 0.1 -q -o - 2>&1)
awk -F, 'END { exit !($1 == 0.1 && $4 > -0.04905 - 1e-7 && $4 < -0.04905 + 1e-7) }' <<< "$out" ||
  fail "a falling particle without springs: $out"

# `springmass fmu` only ever writes its output: a directory named by mistake stays (it was
# removed when empty, and the archive went to DIR.zip), and a name without an extension is the
# file written (zip alone would add ".zip"). A stand-in runtime keeps the archives small.
mkdir -p "$tmp/runtime/binaries/linux64"
echo "stand-in" > "$tmp/runtime/binaries/linux64/springmass_fmu.so"
if "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/oscillator" > /dev/null 2>&1; then
  [ -f "$tmp/oscillator" ] && [ ! -e "$tmp/oscillator.zip" ] ||
    fail "fmu -o NAME without an extension did not write NAME"
  mkdir "$tmp/folder"
  out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/folder" 2>&1)
  status=$?
  [ $status -eq 1 ] && [ -d "$tmp/folder" ] && [ ! -e "$tmp/folder.zip" ] &&
    [ "$out" = "springmass fmu: cannot write $tmp/folder: Is a directory" ] ||
    fail "fmu -o DIR exited with $status and printed '$out'"
fi

[ $failures -eq 0 ] && echo "check_cli: all passed"
exit $((failures > 0))
