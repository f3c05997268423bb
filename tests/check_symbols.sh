#!/usr/bin/env bash
# Every global symbol the static library defines carries the sm_ prefix, so that a program that
# links it may define any other name. And no mutable global state: no object of the library, nor
# of the further archives and objects given (the FMU binary's own), holds writable static data
# (.data, .bss, their thread-local forms, common symbols; .data.rel.ro is read-only once loaded),
# so that FMU instances and threads share nothing. Prints the offenders and fails if there are any.
# Usage: check_symbols.sh LIBRARY [ARCHIVE_OR_OBJECT...] (an argument may be a ;-separated list)
set -u
files=()
for argument in "$@"; do
  IFS=';' read -ra listed <<< "$argument"
  files+=("${listed[@]}")
done
status=0
others=$(nm -g --defined-only "$1" | awk 'NF == 3 && $3 !~ /^sm_/ { print $3 }' | sort -u)
if [ -n "$others" ]; then
  echo "global symbols without the sm_ prefix in $1:"
  echo "$others"
  status=1
else
  echo "check_symbols: every global symbol of $(basename "$1") starts with sm_"
fi
for file in "${files[@]}"; do
  writable=$(objdump -t "$file" | awk '
    / file format / { member = $1; sub(/:$/, "", member) }
    / O \.(data|bss|tdata|tbss)/ && !/ O \.data\.rel\.ro/ || / O \*COM\*/ { print "  " member ": " $NF }')
  if [ -n "$writable" ]; then
    echo "writable static data (mutable global state) in $file:"
    echo "$writable"
    status=1
  fi
done
[ $status -ne 0 ] || echo "check_symbols: no writable static data in $(for f in "${files[@]}"; do basename "$f"; done | xargs)"
exit $status
