#!/usr/bin/env bash
# Every global symbol the static library defines carries the sm_ prefix, so that a program that
# links it may define any other name. Prints the others and fails if there are any.
set -u
others=$(nm -g --defined-only "$1" | awk 'NF == 3 && $3 !~ /^sm_/ { print $3 }' | sort -u)
[ -z "$others" ] || { echo "global symbols without the sm_ prefix in $1:"; echo "$others"; exit 1; }
echo "check_symbols: every global symbol of $(basename "$1") starts with sm_"
