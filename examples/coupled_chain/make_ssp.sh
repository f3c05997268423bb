#!/usr/bin/env bash
# Packages the split chain as an SSP 1.0 archive: its two halves as FMUs (`springmass fmu`) under
# resources/, and SystemStructure.ssd, which connects them.
#
#   examples/coupled_chain/make_ssp.sh BUILD_DIR OUT.ssp
set -euo pipefail

usage="usage: make_ssp.sh BUILD_DIR OUT.ssp"
build_dir=${1:?$usage}
out=$(realpath -m "${2:?$usage}")
here=$(cd "$(dirname "$0")" && pwd)
cli="$build_dir/tools/springmass"
if [[ ! -x "$cli" ]]; then
	echo "make_ssp.sh: $cli not found; build first (make build)" >&2
	exit 1
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir "$work/resources"
for half in chain_left chain_right; do
	"$cli" fmu "$here/$half.json" -o "$work/resources/$half.fmu" >/dev/null
done
cp "$here/SystemStructure.ssd" "$work/"
rm -f "$out"
(cd "$work" && zip -q -r "$out" SystemStructure.ssd resources)
echo "make_ssp.sh: wrote $out"
