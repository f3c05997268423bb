#!/usr/bin/env bash
# docs/model-format.md and the loader give every key of a model file the same unit: the unit a
# row of the docs' key tables gives in its meaning (`[N s/m]`, written `N.s/m` by the loader, `^`
# left out: `m/s^2` is `m/s2`) is the one key_unit in lib/model_file_values.c gives the key,
# which is what `springmass check` prints after a parameter standing for it and the unit the FMU
# declares; a key whose row gives two units (a section, a width or an area) has none there, its
# unit depends on where it stands. The other way round, every key key_unit gives a unit has it in
# the docs: in each table row that names the key, or after the key in the text ("`force` [N]").
# Prints what differs.
# Usage: check_model_units.sh SOURCE_DIR
set -u
cd "$1" || exit 1
doc=docs/model-format.md
code=lib/model_file_values.c
[ -f "$doc" ] || { echo "$doc is missing"; exit 1; }
[ -f "$code" ] || { echo "$code is missing"; exit 1; }
# key_unit's table: one "key unit" per line.
units=$(awk '/^static const char\* key_unit\(/ { inside = 1 }
             inside { print }
             inside && /^}/ { exit }' "$code" |
        grep -oE '\{"[a-z_]+", "[^"]+"\}' | sed -E 's/\{"([a-z_]+)", "([^"]+)"\}/\1 \2/')
[ -n "$units" ] || { echo "no key units found in key_unit of $code"; exit 1; }
# Keys read element by element, outside key_unit, with their unit given at the call: a mesh's
# vertices (lib/model_file_structures.c).
units=$(printf '%s\nvertices m\n' "$units")

# The docs: "row KEY UNIT..." for every key of a row of a table whose first column is "key" (its
# meaning's bracketed units, links and `code` left out, in the loader's spelling), and
# "text KEY UNIT" for a key in backquotes followed by a bracketed unit in a paragraph.
found=$(awk '
  function spelling(u) { gsub(/ /, ".", u); gsub(/\^/, "", u); return u }
  function flush(   t, k, u) {
    t = paragraph; paragraph = ""
    while (match(t, /`[a-z_]+` \[[^]]+\]/)) {
      k = substr(t, RSTART + 1, RLENGTH); sub(/`.*/, "", k)
      u = substr(t, RSTART, RLENGTH); sub(/^[^[]*\[/, "", u); sub(/\]$/, "", u)
      print "text", k, spelling(u)
      t = substr(t, RSTART + RLENGTH)
    }
  }
  /^```/ { flush(); fenced = !fenced; next }
  fenced { next }
  /^\|/ {
    flush()
    n = split($0, cell, "|")
    first = cell[2]; gsub(/^ +| +$/, "", first)
    if (first ~ /^-+$/) next
    if (!(first ~ /`/)) { keys_table = first == "key"; next }
    if (!keys_table) next
    meaning = cell[n - 1]
    gsub(/`[^`]*`/, "", meaning); gsub(/\[[^]]*\]\([^)]*\)/, "", meaning)
    list = ""
    while (match(meaning, /\[[^]]+\]/)) {
      u = spelling(substr(meaning, RSTART + 1, RLENGTH - 2))
      if (index(" " list " ", " " u " ") == 0) list = list (list == "" ? "" : " ") u
      meaning = substr(meaning, RSTART + RLENGTH)
    }
    rest = first
    while (match(rest, /`[a-z_]+`/)) {
      print "row", substr(rest, RSTART + 1, RLENGTH - 2), list
      rest = substr(rest, RSTART + RLENGTH)
    }
    next
  }
  /^$/ { flush(); next }
  { paragraph = paragraph " " $0 }
  END { flush() }
' "$doc")

problems=()
unit_of() { awk -v k="$1" '$1 == k { print $2; exit }' <<<"$units"; }
while read -r kind key rest; do
  [ "$kind" = row ] || continue
  read -r -a given <<<"$rest"
  unit=$(unit_of "$key")
  if [ ${#given[@]} -gt 1 ]; then
    [ -z "$unit" ] || problems+=("$key: $doc gives it ${given[*]}, key_unit only $unit")
  elif [ ${#given[@]} -eq 1 ] && [ "$unit" != "${given[0]}" ]; then
    problems+=("$key: $doc gives it ${given[0]}, key_unit ${unit:-none}")
  elif [ ${#given[@]} -eq 0 ] && [ -n "$unit" ]; then
    problems+=("$key: key_unit gives it $unit, a row of $doc's tables none")
  fi
done <<<"$found"
while read -r key unit; do
  grep -qxF -e "row $key $unit" -e "text $key $unit" <<<"$found" ||
    problems+=("$key: key_unit gives it $unit, $doc does not (\`$key\` [$unit] in the text or its table row)")
done <<<"$units"
while read -r kind key rest; do
  [ "$kind" = text ] || continue
  unit=$(unit_of "$key")
  [ -z "$unit" ] || [ "$unit" = "$rest" ] || problems+=("$key: $doc gives it $rest in the text, key_unit $unit")
done <<<"$found"
if [ ${#problems[@]} -gt 0 ]; then
  echo "units of $doc and key_unit in $code that differ:"
  printf '  %s\n' "${problems[@]}"
  exit 1
fi
echo "check_model_units: the $(wc -l <<<"$units") keys with a unit have the same one in $doc and $code"
