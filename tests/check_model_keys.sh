#!/usr/bin/env bash
# docs/model-format.md documents every key that a model file may hold: each string of the key
# lists the loader checks objects against (the `static const char* const ...keys[]` arrays of
# lib/model_file*.c, which refuse any other key; model_file_save.c, which writes them, apart)
# appears there as `key` or "key", and in the fuzzer's dictionary (fuzz/model_file.dict) as "\"key\"".
# Prints the keys it does not find.
# Usage: check_model_keys.sh SOURCE_DIR
set -u
cd "$1" || exit 1
doc=docs/model-format.md
[ -f "$doc" ] || { echo "$doc is missing"; exit 1; }
keys=$(awk '/static const char\* const [A-Za-z_]*keys\[/ { inside = 1 }
            inside { print }
            inside && /};/ { inside = 0 }' $(ls lib/model_file*.c | grep -v model_file_save.c) | grep -o '"[^"]*"' | tr -d '"' | sort -u)
[ -n "$keys" ] || { echo "no key lists found in lib/model_file*.c"; exit 1; }
missing=()
for k in $keys; do
  grep -qF "\`$k\`" "$doc" || grep -qF "\"$k\"" "$doc" || missing+=("$k")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "keys of lib/model_file*.c that $doc does not document:"
  printf '  %s\n' "${missing[@]}"
  exit 1
fi
dict=fuzz/model_file.dict
[ -f "$dict" ] || { echo "$dict is missing"; exit 1; }
for k in $keys; do
  grep -qxF "\"\\\"$k\\\"\"" "$dict" || missing+=("$k")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "keys of lib/model_file*.c that the fuzzer's $dict lacks:"
  printf '  %s\n' "${missing[@]}"
  exit 1
fi
echo "check_model_keys: the $(echo "$keys" | wc -l) keys of model files are documented in $doc and in $dict"
