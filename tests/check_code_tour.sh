#!/usr/bin/env bash
# docs/code-tour.md stays in step with the sources: it names every C source and header of lib/,
# fmu/ and tools/ (as `file.c`), and every C file it names exists (in lib/, fmu/, tools/,
# include/springmass/, tests/ or fuzz/, or at the path it gives). Prints what differs.
# Usage: check_code_tour.sh SOURCE_DIR
set -u
cd "$1" || exit 1
tour=docs/code-tour.md
[ -f "$tour" ] || { echo "$tour is missing"; exit 1; }
missing=()
for f in lib/*.[ch] fmu/*.[ch] tools/*.[ch]; do
  grep -qF "\`$(basename "$f")\`" "$tour" || missing+=("$f")
done
stale=()
while read -r name; do
  if [[ $name == */* ]]; then
    [ -f "$name" ] || stale+=("$name")
  else
    found=0
    for d in lib fmu tools include/springmass tests fuzz; do
      [ -f "$d/$name" ] && found=1
    done
    [ $found -eq 1 ] || stale+=("$name")
  fi
done < <(grep -oE '`[A-Za-z0-9_./]+\.[ch]`' "$tour" | tr -d '`' | sort -u)
if [ ${#missing[@]} -gt 0 ] || [ ${#stale[@]} -gt 0 ]; then
  [ ${#missing[@]} -eq 0 ] || { echo "files $tour does not name:"; printf '  %s\n' "${missing[@]}"; }
  [ ${#stale[@]} -eq 0 ] || { echo "files $tour names that do not exist:"; printf '  %s\n' "${stale[@]}"; }
  exit 1
fi
echo "check_code_tour: $tour names every C file of lib/, fmu/ and tools/, and only files that exist"
