#!/usr/bin/env bash
# `springmass check`: every bundled model is valid and summarised; every file of
# tests/bad_models is refused (exit status 1) with exactly the error listed in expected.txt;
# usage errors exit with 2.
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

[ $failures -eq 0 ] && echo "check_cli: all passed"
exit $((failures > 0))
