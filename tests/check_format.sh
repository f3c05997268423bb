#!/usr/bin/env bash
# Every C source and header of the project is laid out as .clang-format says, by the clang-format
# that tools/requirements.txt pins. Prints the files that are not and how to fix them.
# Usage: check_format.sh CLANG_FORMAT SOURCE_DIR
set -u
clang_format=$1
cd "$2" || exit 1
mapfile -t files < <(git ls-files '*.c' '*.h' 2>/dev/null || true)
if [ ${#files[@]} -eq 0 ]; then  # not a git checkout: the folders the layout covers
  mapfile -t files < <(find lib include fmu tools tests examples bench -name '*.[ch]' | sort)
fi
wrong=()
for f in "${files[@]}"; do
  "$clang_format" --dry-run -Werror "$f" >/dev/null 2>&1 || wrong+=("$f")
done
if [ ${#wrong[@]} -gt 0 ]; then
  echo "laid out otherwise than .clang-format says (${#wrong[@]} of ${#files[@]} files):"
  printf '  %s\n' "${wrong[@]}"
  echo "fix with: $clang_format -i FILE..."
  exit 1
fi
echo "check_format: ${#files[@]} C files laid out as .clang-format says ($("$clang_format" --version))"
