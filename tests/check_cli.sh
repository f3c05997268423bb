#!/usr/bin/env bash
# `springmass check`: every bundled model is valid, summarised and warns of nothing; every file of
# tests/bad_models is refused (exit status 1) with exactly the error listed in expected.txt;
# usage errors exit with 2. Then `springmass run` at the edges of its output grid.
# Usage: check_cli.sh CLI [FMU]: FMU 0 for a build without FMU support, whose `springmass fmu`
# only says so (its cases are then left out).
set -u
cli=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
with_fmu=${2:-1}
root=$(cd "$(dirname "$0")/.." && pwd)
failures=0
fail() { echo "FAILED: $*"; failures=$((failures + 1)); }

for model in "$root"/models/*.json; do
  out=$("$cli" check "$model" 2>&1)
  status=$?
  [ $status -eq 0 ] || fail "check $(basename "$model") exited with $status: $out"
  grep -q "^particles " <<< "$out" && grep -q "^fastest " <<< "$out" && grep -q "^ok$" <<< "$out" ||
    fail "check $(basename "$model") printed no summary: $out"
  # A bundled model is an example to follow: nothing in it to warn of.
  ! grep -q "^warning" <<< "$out" || fail "check $(basename "$model") warned: $out"
done

cd "$root/tests/bad_models"
while IFS='|' read -r file expected; do
  [[ -z "$file" || "$file" == \#* ]] && continue
  out=$("$cli" check "$file" 2>&1)
  status=$?
  [ $status -eq 1 ] || fail "check $file exited with $status, expected 1"
  [ "$out" = "springmass check: $expected" ] || fail "check $file printed '$out', expected 'springmass check: $expected'"
done < expected.txt

version=$(sed -n 's/^#define SM_VERSION_\(MAJOR\|MINOR\|PATCH\) \([0-9]*\)$/\2/p' "$root/include/springmass/base.h" | paste -sd.)
[ "$("$cli" --version)" = "springmass $version" ] || fail "--version printed '$("$cli" --version)', expected 'springmass $version'"
"$cli" check --help | grep -q "^usage: springmass check MODEL" || fail "check --help printed no usage"
"$cli" check > /dev/null 2>&1; [ $? -eq 2 ] || fail "check without a file did not exit with 2"
"$cli" check a.json b.json > /dev/null 2>&1; [ $? -eq 2 ] || fail "check with two files did not exit with 2"
"$cli" check --frobnicate x.json > /dev/null 2>&1; [ $? -eq 2 ] || fail "check with an unknown option did not exit with 2"

# `springmass run` at the edges of its output grid, and a model without springs.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# Only regular files are model files: a device would be read without end, a FIFO wait for a writer.
mkfifo "$tmp/check_fifo.json"
for special in /dev/zero "$tmp/check_fifo.json"; do
  out=$(timeout 20 "$cli" check "$special" 2>&1)
  status=$?
  [ $status -eq 1 ] && [ "$out" = "springmass check: $special: cannot read: not a regular file" ] ||
    fail "check $special exited with $status and printed '$out'"
done
# A valid model too fast for any integrator (stiffness / mass overflows): check says so instead of
# printing infinite frequencies and a stable step of 0 s.
cat > "$tmp/too_fast.json" << 'JSON'
{"springmass": 1, "name": "too_fast", "gravity": [0, 0, 0],
 "particles": [{"name": "a", "position": [0, 0, 0], "fixed": true}, {"name": "b", "position": [1.1, 0, 0], "mass": 1e-10}],
 "springs": [{"a": "a", "b": "b", "stiffness": 1e300, "rest_length": 1}]}
JSON
out=$("$cli" check "$tmp/too_fast.json" 2>&1)
grep -q "^fastest      sqrt(k/m) overflows at spring 0" <<< "$out" && grep -q "^warning .*no integrator" <<< "$out" &&
  ! grep -q "inf\|explicit" <<< "$out" || fail "check of a model whose stiffness / mass overflows: $out"
out=$("$cli" run "$root/models/oscillator.json" --t-end 1e-11 -q -o - 2>&1)
[ "$(wc -l <<< "$out")" -eq 3 ] && [ "$(tail -1 <<< "$out" | cut -d, -f1)" = "1e-11" ] ||
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
# A valid model whose kinetic energy is beyond a double (1e300 kg at 1e5 m/s: 5e309 J) runs (its
# motion is a free fall), and its summary says there is no energy balance rather than print
# inf - inf as nan.
cat > "$tmp/heavy_fast.json" << 'JSON'
{"springmass": 1, "name": "heavy_fast",
 "particles": [{"name": "p", "position": [0, 0, 0], "velocity": [1e5, 0, 0], "mass": 1e300}]}
JSON
out=$("$cli" run "$tmp/heavy_fast.json" --t-end 0.1 -o /dev/null 2>&1)
[ $? -eq 0 ] && grep -q "^springmass run: kinetic .*: inf J at the start, inf J at the end: beyond a double" <<< "$out" &&
  ! grep -qi "nan" <<< "$out" || fail "run's summary of energies beyond a double: $out"
# Without springs a VTK file has no lines (VTK's legacy reader fails on "LINES 0 0" and drops the
# point data after it), in run's XML series, statics and modes alike; modes of a model without free
# particles still writes the CSV asked for (the particles, no mode columns).
"$cli" run "$tmp/falling.json" --t-end 0.1 -q -o /dev/null --vtk "$tmp/falling_vtk" > /dev/null 2>&1 &&
  "$cli" modes "$tmp/falling.json" --vtk "$tmp/falling_modes" > /dev/null 2>&1 &&
  ! grep -q '<Lines>' "$tmp"/falling_vtk/*.vtp && ! grep -q LINES "$tmp"/falling_modes/*.vtk &&
  grep -q "^POINT_DATA 1$" "$tmp/falling_modes/mode_1.vtk" || fail "VTK files of a model without springs"
cat > "$tmp/held.json" << 'JSON'
{"springmass": 1, "name": "held", "particles": [{"name": "a", "position": [0, 0, 0], "fixed": true}]}
JSON
echo stale > "$tmp/held.csv"
# The report says that the CSV holds the particles only.
out=$("$cli" modes "$tmp/held.json" -o "$tmp/held.csv" 2>&1) &&
  [ "$(paste -sd ' ' "$tmp/held.csv")" = "particle,name 0,a" ] &&
  [ "$(tail -1 <<< "$out")" = "mode shapes written to $tmp/held.csv (no modes: the particles only)" ] ||
  fail "modes without free particles: $(cat "$tmp/held.csv"), printed '$out'"
# With --vtk the folder is made, no mode file in it, and the report says so.
out=$("$cli" modes "$tmp/held.json" --vtk "$tmp/held_vtk" 2>&1) && [ -d "$tmp/held_vtk" ] &&
  [ -z "$(ls "$tmp/held_vtk")" ] && [ "$(tail -1 <<< "$out")" = "no mode shapes to write to $tmp/held_vtk" ] ||
  fail "modes --vtk without free particles: $(ls "$tmp/held_vtk"), printed '$out'"
# ... and so does the sparse solver, asked for explicitly: nothing to solve is not too few degrees
# of freedom for it.
for n in 0 10; do
  out=$("$cli" modes "$tmp/held.json" --solver sparse -n $n 2>&1)
  [ $? -eq 0 ] && [ "$(tail -1 <<< "$out")" = "no free particle: nothing vibrates" ] ||
    fail "modes --solver sparse -n $n without free particles: $out"
done
# Column names stay unique: an unnamed particle is p[i], primed past a particle of that name.
cat > "$tmp/names.json" << 'JSON'
{"springmass": 1, "name": "names", "gravity": [0, 0, 0],
 "particles": [{"name": "p[1]", "position": [0, 0, 0], "fixed": true}, {"position": [1, 0, 0]}],
 "springs": [{"a": 0, "b": 1, "stiffness": 1}]}
JSON
out=$("$cli" run "$tmp/names.json" --t-end 0.01 --positions -q -o - 2>&1 | head -1)
[ "$out" = "time,energy.kinetic,energy.elastic,energy.gravity,energy.dissipated,energy.input,particle.p[1].x,particle.p[1].y,particle.p[1].z,particle.p[1]'.x,particle.p[1]'.y,particle.p[1]'.z" ] ||
  fail "run --positions column names: $out"
# A particle's name and the description are shown escaped where a terminal would act on them or
# not show them (a right-to-left override, a zero-width space), as the library's messages do.
printf '%s\n' '{"springmass": 1, "name": "shown", "description": "left \u202e right",' \
  ' "particles": [{"name": "a\u200bb", "position": [0, 0, 0], "fixed": true}, {"position": [0, 0, -1]}],' \
  ' "springs": [{"a": 0, "b": 1, "stiffness": 10, "rest_length": 1}]}' > "$tmp/shown.json"
out=$("$cli" check "$tmp/shown.json" 2>&1)
grep -qF 'description  left \u202e right' <<< "$out" && grep -qF 'a\u200bb (particle 0)' <<< "$out" ||
  fail "check shows a name or description unescaped: $out"
out=$("$cli" statics "$tmp/shown.json" 2>&1)
grep -qE '^0 +a\\u200bb +' <<< "$out" || fail "statics shows a name unescaped: $out"
# A free particle on its anchor, a rest-length spring of 1 m between them and no gravity: the force
# balances only by the convention that the spring exerts none at its singular point (model.h), at a
# maximum of its energy (k l0^2 / 2 = 5 J). Not stable, and not for the reason of a saddle or a
# mechanism, for which the message sends to `modes --at-equilibrium`, which refuses this state.
cat > "$tmp/on_anchor.json" << 'JSON'
{"springmass": 1, "name": "on_anchor", "gravity": [0, 0, 0],
 "particles": [{"name": "a", "position": [0, 0, 0], "fixed": true}, {"name": "b", "position": [0, 0, 0]}],
 "springs": [{"a": "a", "b": "b", "stiffness": 10, "rest_length": 1}]}
JSON
out=$("$cli" statics "$tmp/on_anchor.json" -q 2>&1)
grep -qF 'stable           no (spring 0 (between a and b) has its two particles at one point' <<< "$out" &&
  ! grep -q 'saddle' <<< "$out" || fail "statics at a spring's singular point: $out"

# Options: each line is the exit status, the first line the command prints on stderr (empty for
# none) and its arguments. Numbers are decimal, as in a model file (no hexadecimal, infinities or
# spaces, which strtod alone would take); numbers below the smallest normal double are numbers; a
# malformed --set is a usage error in every command.
check_cases() {
  while IFS='|' read -r expected_status expected args; do
    [ "$with_fmu" = 0 ] && [[ "$args" == fmu\ * ]] && continue
    out=$(eval "\"$cli\" $args" 2>&1 > /dev/null)
    status=$?
    expected=${expected//\$tmp/$tmp}
    [ $status -eq "$expected_status" ] && [ "$(head -1 <<< "$out")" = "$expected" ] ||
      fail "$args: exit status $status (expected $expected_status), printed '$(head -1 <<< "$out")', expected '$expected'"
  done
}
touch "$tmp/a_file"
osc="$root/models/oscillator.json"
# No output overwrites a file the command reads, under its own name or another (a link); "-" is
# standard output only for run's CSV (and no folder: --vtk - made one called -). Each refusal
# comes before anything is written.
cp "$osc" "$tmp/own.json"
ln -s "$tmp/own.json" "$tmp/own_link.json"
check_cases << 'CASES'
2|springmass run: -o $tmp/own.json would overwrite the model file $tmp/own.json, which it reads; give another name|run "$tmp/own.json" -q -o "$tmp/own.json"
2|springmass run: -o $tmp/own_link.json would overwrite the model file $tmp/own.json, which it reads; give another name|run "$tmp/own.json" -q -o "$tmp/own_link.json"
2|springmass statics: -o $tmp/own.json would overwrite the model file $tmp/own.json, which it reads; give another name|statics "$tmp/own.json" -q -o "$tmp/own.json"
2|springmass statics: --save-model $tmp/own.json would overwrite the model file $tmp/own.json, which it reads; give another name|statics "$tmp/own.json" -q --save-model "$tmp/own.json"
2|springmass modes: -o $tmp/own.json would overwrite the model file $tmp/own.json, which it reads; give another name|modes "$tmp/own.json" -o "$tmp/own.json"
2|springmass fmu: -o $tmp/own.json would overwrite the model file $tmp/own.json, which it reads; give another name|fmu "$tmp/own.json" -o "$tmp/own.json"
2|springmass fmu: -o $tmp/a_file would overwrite the reference $tmp/a_file, which it reads; give another name|fmu "$tmp/own.json" -o "$tmp/a_file" --reference "$tmp/a_file"
2|springmass fmu: -o -: this output is a file, not standard output; give its name|fmu "$tmp/own.json" -o -
2|springmass statics: -o -: this output is a file, not standard output; give its name|statics "$tmp/own.json" -q -o -
2|springmass modes: -o -: this output is a file, not standard output; give its name|modes "$tmp/own.json" -o -
2|springmass run: --vtk -: this output is a folder of files, not standard output; give its name (./- for a folder called -)|run "$tmp/own.json" -q -o "$tmp/fresh.csv" --vtk -
2|springmass statics: --vtk -: this output is a folder of files, not standard output; give its name (./- for a folder called -)|statics "$tmp/own.json" -q --vtk -
2|springmass modes: --vtk -: this output is a folder of files, not standard output; give its name (./- for a folder called -)|modes "$tmp/own.json" --vtk -
CASES
cmp -s "$osc" "$tmp/own.json" && [ ! -e ./- ] || fail "a refused output was written"
# run's other outputs: the default CSV (NAME.csv in the working folder) and the ParaView series
# (DIR/NAME.pvd, DIR/NAME_<k>.vtp) are no model file, and the series' files are not the CSV.
mkdir -p "$tmp/clash/vt1" "$tmp/clash/vt2"
cp "$osc" "$tmp/clash/oscillator.csv"
cp "$osc" "$tmp/clash/vt1/oscillator.pvd"
cp "$osc" "$tmp/clash/vt2/oscillator_000001.vtp"
out=$(cd "$tmp/clash" && "$cli" run oscillator.csv -q --t-end 0.02 2>&1)
status=$?
[ $status -eq 2 ] && [ "$out" = "springmass run: the output oscillator.csv (NAME.csv, without -o) would overwrite the model file oscillator.csv, which it reads; give another name with -o" ] ||
  fail "run onto its model file by the default output: exit status $status, printed '$out'"
check_cases << 'CASES'
2|springmass run: --vtk $tmp/clash/vt1: the series' file $tmp/clash/vt1/oscillator.pvd would overwrite the model file $tmp/clash/vt1/oscillator.pvd; give another folder|run "$tmp/clash/vt1/oscillator.pvd" -q --t-end 0.02 -o - --vtk "$tmp/clash/vt1"
2|springmass run: --vtk $tmp/clash/vt2: the series' file $tmp/clash/vt2/oscillator_000001.vtp would overwrite the model file $tmp/clash/vt2/oscillator_000001.vtp; give another folder|run "$tmp/clash/vt2/oscillator_000001.vtp" -q --t-end 0.02 -o - --vtk "$tmp/clash/vt2"
2|springmass run: --vtk $tmp/clash/vt3: the series' file $tmp/clash/vt3/oscillator.pvd would overwrite the CSV output $tmp/clash/vt3/oscillator.pvd; give another folder or -o|run "$osc" -q --t-end 0.02 --vtk "$tmp/clash/vt3" -o "$tmp/clash/vt3/oscillator.pvd"
2|springmass run: --vtk $tmp/clash/vt4: the series' file $tmp/clash/vt4/oscillator_000001.vtp would overwrite the CSV output $tmp/clash/vt4/oscillator_000001.vtp; give another folder or -o|run "$osc" -q --t-end 0.02 --vtk "$tmp/clash/vt4" -o "$tmp/clash/vt4/oscillator_000001.vtp"
CASES
for f in oscillator.csv vt1/oscillator.pvd vt2/oscillator_000001.vtp; do
  cmp -s "$osc" "$tmp/clash/$f" || fail "run overwrote its model file $f"
done
# Nor are they the input signals run --input reads.
mkdir -p "$tmp/clash/vt5" "$tmp/clash/vt6"
printf 'time,tip.fx\n0,1\n' | tee "$tmp/clash/vt5/oscillator.pvd" > "$tmp/clash/vt6/oscillator_000001.vtp"
check_cases << 'CASES'
2|springmass run: --vtk $tmp/clash/vt5: the series' file $tmp/clash/vt5/oscillator.pvd would overwrite the input signals $tmp/clash/vt5/oscillator.pvd; give another folder|run "$osc" -q --t-end 0.02 -o - --vtk "$tmp/clash/vt5" --input "$tmp/clash/vt5/oscillator.pvd"
2|springmass run: --vtk $tmp/clash/vt6: the series' file $tmp/clash/vt6/oscillator_000001.vtp would overwrite the input signals $tmp/clash/vt6/oscillator_000001.vtp; give another folder|run "$osc" -q --t-end 0.02 -o - --vtk "$tmp/clash/vt6" --input "$tmp/clash/vt6/oscillator_000001.vtp"
CASES
for f in vt5/oscillator.pvd vt6/oscillator_000001.vtp; do
  [ "$(cat "$tmp/clash/$f")" = "$(printf 'time,tip.fx\n0,1')" ] || fail "run overwrote its input signals $f"
done
# Nor is the CSV by its default name, NAME.csv in the working folder.
mkdir -p "$tmp/clash/in"
printf 'time,tip.fx\n0,1\n' > "$tmp/clash/in/oscillator.csv"
out=$(cd "$tmp/clash/in" && "$cli" run "$osc" -q --t-end 0.02 --input oscillator.csv 2>&1)
status=$?
[ $status -eq 2 ] && [ "$out" = "springmass run: the output oscillator.csv (NAME.csv, without -o) would overwrite the input signals oscillator.csv, which it reads; give another name with -o" ] &&
  [ "$(cat "$tmp/clash/in/oscillator.csv")" = "$(printf 'time,tip.fx\n0,1')" ] ||
  fail "run onto its input signals by the default output: exit status $status, printed '$out'"
# Nor are statics' and modes' VTK files the model file.
mkdir -p "$tmp/clash/st" "$tmp/clash/mo"
cp "$osc" "$tmp/clash/st/statics.vtk"
cp "$osc" "$tmp/clash/mo/mode_2.vtk"
check_cases << 'CASES'
2|springmass statics: --vtk $tmp/clash/st: its file $tmp/clash/st/statics.vtk would overwrite the model file $tmp/clash/st/statics.vtk, which it reads; give another folder|statics "$tmp/clash/st/statics.vtk" -q --vtk "$tmp/clash/st"
2|springmass modes: --vtk $tmp/clash/mo: its file $tmp/clash/mo/mode_2.vtk would overwrite the model file $tmp/clash/mo/mode_2.vtk, which it reads; give another folder|modes "$tmp/clash/mo/mode_2.vtk" --vtk "$tmp/clash/mo"
CASES
for f in st/statics.vtk mo/mode_2.vtk; do
  cmp -s "$osc" "$tmp/clash/$f" || fail "statics or modes overwrote its model file $f"
done
[ ! -e "$tmp/clash/mo/mode_1.vtk" ] || fail "modes wrote a mode file beside a refused one"
# statics and modes check where every output goes before solving: none is written when one of
# them cannot be (a missing folder, a file where a folder goes).
check_cases << 'CASES'
1|springmass statics: --save-model $tmp/none/x.json: cannot write there: the folder it would go in does not exist|statics "$osc" -q -o "$tmp/fresh.csv" --save-model "$tmp/none/x.json"
1|springmass modes: --vtk $tmp/a_file: cannot write there: a file of that name exists|modes "$osc" -o "$tmp/fresh_modes.csv" --vtk "$tmp/a_file"
CASES
[ ! -e "$tmp/fresh.csv" ] && [ ! -e "$tmp/fresh_modes.csv" ] || fail "an output was written before a refusal"
# Outputs that are one file under two names are refused before anything is written (only the last
# written would be left), and a write that fails at its place (nothing may be made in /proc) leaves
# no other output written: each is written under a temporary name and moved once all are.
mkdir -p "$tmp/apart"
check_cases << 'CASES'
2|springmass statics: -o $tmp/apart/same.json and --save-model $tmp/apart/same.json are one file, which only the last would hold; give each its own|statics "$osc" -q -o "$tmp/apart/same.json" --save-model "$tmp/apart/same.json"
2|springmass statics: -o $tmp/apart/statics.vtk and --vtk's file $tmp/apart/statics.vtk are one file, which only the last would hold; give each its own|statics "$osc" -q -o "$tmp/apart/statics.vtk" --vtk "$tmp/apart"
2|springmass modes: -o $tmp/apart/mode_1.vtk and --vtk's file $tmp/apart/mode_1.vtk are one file, which only the last would hold; give each its own|modes "$osc" -o "$tmp/apart/mode_1.vtk" --vtk "$tmp/apart"
2|springmass statics: -o $tmp/apart/one and --vtk $tmp/apart/one are one file, which only the last would hold; give each its own|statics "$osc" -q -o "$tmp/apart/one" --vtk "$tmp/apart/one"
2|springmass statics: --save-model $tmp/apart/one and --vtk $tmp/apart/./one are one file, which only the last would hold; give each its own|statics "$osc" -q --save-model "$tmp/apart/one" --vtk "$tmp/apart/./one"
2|springmass modes: -o $tmp/apart/one and --vtk $tmp/apart/one are one file, which only the last would hold; give each its own|modes "$osc" -o "$tmp/apart/one" --vtk "$tmp/apart/one"
2|springmass run: -o $tmp/apart/one and --vtk $tmp/apart/one are one file, which only the last would hold; give each its own|run "$osc" -q -o "$tmp/apart/one" --vtk "$tmp/apart/one"
CASES
# (As root the check of the place passes, and the write itself fails; otherwise the check refuses.)
"$cli" statics "$osc" -q -o "$tmp/apart/fresh.csv" --save-model /proc/springmass_x.json > /dev/null 2>&1
[ $? -eq 1 ] || fail "statics --save-model into /proc did not fail with exit status 1"
[ -z "$(ls -A "$tmp/apart")" ] || fail "an output was written, or a temporary left, beside a refused one: $(ls -A "$tmp/apart")"
# A new folder named with a trailing slash is a place the folder can go.
"$cli" modes "$osc" --vtk "$tmp/slash_dir/" > /dev/null 2>&1 && [ -e "$tmp/slash_dir/mode_1.vtk" ] ||
  fail "modes --vtk NEW_DIR/ was refused or wrote nothing"

# A run stopped by a signal (Ctrl-C, a kill) or by the reader of its pipe ends after the row it was
# writing: the CSV holds whole rows, the series' index is closed, and the exit status is the
# signal's (143 for SIGTERM; a pipe's reader gone is SIGPIPE's, 141).
cat > "$tmp/slow.json" << 'JSON'
{"springmass": 1, "name": "slow", "gravity": [0, 0, -9.81],
 "structures": [{"type": "sheet", "name": "s", "edge_u": [1, 0, 0], "edge_v": [0, 1, 0], "nu": 24, "nv": 24, "mass": 1,
   "structural": {"strain_stiffness": 1000}, "shear": {"strain_stiffness": 1000}}],
 "fixed": ["s[0,0]", "s[0,23]"]}
JSON
timeout --preserve-status -s TERM 2 "$cli" run "$tmp/slow.json" --t-end 100 -q -o "$tmp/slow.csv" --vtk "$tmp/slow_vtk" 2> "$tmp/slow.err"
status=$?
fields=$(head -1 "$tmp/slow.csv" | awk -F, '{ print NF }')
[ $status -eq 143 ] && [ "$(tail -c 1 "$tmp/slow.csv" | od -An -c | tr -d ' ')" = '\n' ] &&
  awk -F, -v n="$fields" 'NF != n { exit 1 }' "$tmp/slow.csv" && [ "$(tail -1 "$tmp/slow_vtk/slow.pvd")" = "</VTKFile>" ] &&
  [ "$(grep -c DataSet "$tmp/slow_vtk/slow.pvd")" -eq "$(($(wc -l < "$tmp/slow.csv") - 1))" ] &&
  grep -q "^springmass run: stopped by Terminated; the outputs hold the rows up to t = " "$tmp/slow.err" ||
  fail "run stopped by SIGTERM: exit status $status, last row or index torn: $(tail -c 80 "$tmp/slow.csv"); $(tail -1 "$tmp/slow_vtk/slow.pvd"); $(cat "$tmp/slow.err")"
"$cli" run "$tmp/slow.json" --t-end 100 -q -o - --vtk "$tmp/piped_vtk" 2> "$tmp/piped.err" | head -1 > /dev/null
status=${PIPESTATUS[0]}
[ $status -eq 141 ] && [ "$(tail -1 "$tmp/piped_vtk/slow.pvd")" = "</VTKFile>" ] && [ ! -s "$tmp/piped.err" ] ||
  fail "run into a pipe closed early: exit status $status, index $(tail -1 "$tmp/piped_vtk/slow.pvd"), $(cat "$tmp/piped.err")"

# A closed standard stream is no file the tool writes: its reports go nowhere, not into the CSV or
# the series' index, which would take the closed stream's descriptor.
"$cli" run "$osc" -o "$tmp/closed_err.csv" --t-end 0.05 2>&-
"$cli" run "$osc" -q -o - --t-end 0.05 --vtk "$tmp/closed_out" >&- 2> /dev/null
! grep -q springmass "$tmp/closed_err.csv" && [ "$(head -c 5 "$tmp/closed_out/oscillator.pvd")" = "<?xml" ] ||
  fail "a report written into an output through a closed standard stream: $(tail -1 "$tmp/closed_err.csv")"
# What a command writes to a closed standard output cannot be written, as in any Unix tool (exit
# status 1, the reason named), not thrown away with success; what it reads from a closed standard
# input cannot be read (not an empty file). Diagnostics to a closed standard error go nowhere, the
# command succeeding.
"$cli" run "$osc" -q -o - --t-end 0.05 >&- 2> "$tmp/closed.err"
status=$?
[ $status -eq 1 ] && [ "$(cat "$tmp/closed.err")" = "springmass run: cannot write standard output: Bad file descriptor" ] ||
  fail "run -o - into a closed standard output: exit status $status, $(cat "$tmp/closed.err")"
"$cli" check "$osc" >&- 2> "$tmp/closed.err"
status=$?
[ $status -eq 1 ] && [ "$(cat "$tmp/closed.err")" = "springmass: cannot write standard output: Bad file descriptor" ] ||
  fail "check into a closed standard output: exit status $status, $(cat "$tmp/closed.err")"
"$cli" run "$osc" -q -o "$tmp/closed_in.csv" --input - <&- 2> "$tmp/closed.err"
status=$?
[ $status -eq 1 ] &&
  [ "$(cat "$tmp/closed.err")" = "springmass run: cannot read the input signals from standard input: Bad file descriptor" ] ||
  fail "run --input - from a closed standard input: exit status $status, $(cat "$tmp/closed.err")"
"$cli" run "$osc" -o "$tmp/closed_err.csv" --t-end 0.05 2>&- >&- || fail "run -o FILE with closed standard streams failed"
# Input signals from standard input are held to a file's limit: 1 GiB is read whole (these zeros
# are then refused as no text), one byte more is refused as too large. Standard input filled its
# buffer to 1 GiB before it saw the end, and took that for a byte past the limit.
for bytes in $((1 << 30)) $(((1 << 30) + 1)); do
  out=$(head -c $bytes /dev/zero | "$cli" run "$osc" -q -o "$tmp/large_in.csv" --input - 2>&1)
  status=$?
  expected="springmass run: --input -:1:1: a NUL byte: not a text file"
  [ $bytes -eq $((1 << 30)) ] ||
    expected="springmass run: cannot read the input signals from standard input: larger than 1 GiB"
  [ $status -eq 1 ] && [ "$out" = "$expected" ] ||
    fail "run --input - of $bytes bytes: exit status $status, $out"
done
# An output that is standard output under another name, where that is a file, would be
# overwritten by the report: refused. /dev/null stays an output like any other.
"$cli" statics "$osc" -q -o /dev/stdout > "$tmp/stdout.txt" 2> "$tmp/stdout.err"
[ $? -eq 2 ] && grep -q "is standard output" "$tmp/stdout.err" || fail "statics -o /dev/stdout into a file was not refused"
"$cli" statics "$osc" -q -o /dev/null > /dev/null || fail "statics -o /dev/null failed"

# modes --zero-tolerance: two zero-length springs of 1 and 1e12 N/m in a chain of two 1 kg
# particles have no zero mode, but the soft one (omega^2 = 0.5 1/s^2 per axis, to 1/(8e12)) lies
# below the default 1e-12 of the stiffest (2e12 1/s^2): the default calls it zero, 1e-15 resolves
# it, to the round-off of the stiff spring (eps 1e12 / 1 = 2e-4 of it; 1e-3 allowed).
cat > "$tmp/stiff.json" << 'JSON'
{"springmass": 1, "name": "stiff", "gravity": [0, 0, 0],
 "particles": [{"name": "anchor", "position": [0, 0, 0], "fixed": true}, {"position": [1, 0, 0]}, {"position": [2, 0, 0]}],
 "springs": [{"a": 0, "b": 1, "kind": "zero_length", "stiffness": 1}, {"a": 1, "b": 2, "kind": "zero_length", "stiffness": 1e12}]}
JSON
zero_default=$("$cli" modes "$tmp/stiff.json" -n 0 | sed -n 's/^zero modes *\([0-9]*\) .*/\1/p')
resolved=$("$cli" modes "$tmp/stiff.json" -n 0 --zero-tolerance 1e-15)
zero_resolved=$(sed -n 's/^zero modes *\([0-9]*\) .*/\1/p' <<< "$resolved")
soft=$(awk '$1 == "1" && NF == 5 { print $4 }' <<< "$resolved")
[ "$zero_default" = 3 ] && [ "$zero_resolved" = 0 ] && awk -v w="$soft" 'BEGIN { exit !(w > 0.4995 && w < 0.5005) }' ||
  fail "modes --zero-tolerance: zero modes $zero_default by default, $zero_resolved at 1e-15, soft omega^2 '$soft'"

# --set values are taken together: a rope's new start beyond its old end, with the new end.
cp "$root/tests/python/models/rope_ends.json" "$tmp/rope_ends.json"
ends="$tmp/rope_ends.json"
check_cases << 'CASES'
2|springmass run: --t-end expects a finite number, got 'nan'|run "$osc" -q -o - --t-end nan
2|springmass run: --t-end expects a finite number, got '0x10'|run "$osc" -q -o - --t-end 0x10
2|springmass run: --t-end expects a finite number, got ' 1'|run "$osc" -q -o - --t-end ' 1'
2|springmass run: --t-end expects a finite number, got '1e'|run "$osc" -q -o - --t-end 1e
2|springmass run: --t-end expects a finite number, got '.'|run "$osc" -q -o - --t-end .
0||run "$osc" -q -o - --t-end .01 --output-interval 1e-2 --max-steps 1e3
0||run "$osc" -q -o - --t-end 0.01 --rtol +1.E-5
2|springmass run: --max-steps needs a count from 1 to 2e9, got '0x10'|run "$osc" -q -o - --max-steps 0x10
2|springmass run: --max-step needs a step >= 0 [s] (0: no limit), got '-1e-3'|run "$osc" -q -o - --max-step -1e-3
2|springmass run: --max-step needs 0 (no limit) or a step above 5.562684646268003e-309 s (1 / DBL_MAX: CVODE takes its inverse), got '1e-309'|run "$osc" -q -o - --max-step 1e-309
2|springmass run: --max-step needs 0 (no limit) or a step above 5.562684646268003e-309 s (1 / DBL_MAX: CVODE takes its inverse), got '5.562684646268003e-309'|run "$osc" -q -o - --max-step 5.562684646268003e-309
0||run "$osc" -q -o - --t-end 0.01 --max-step 0
2|springmass run: --max-steps needs a count from 1 to 2e9, got '0'|run "$osc" -q -o - --max-steps 0
2|springmass run: --max-steps needs a count from 1 to 2e9, got '3e9'|run "$osc" -q -o - --max-steps 3e9
0||run "$osc" -q -o - --t-end 0.01 --max-steps 2e9
2|springmass run: --max-steps needs a count from 1 to 2e9, got ' 5'|run "$osc" -q -o - --max-steps ' 5'
2|springmass statics: --max-iterations needs a count from 1 to 1000000, got ' 5'|statics "$osc" -q --max-iterations ' 5'
2|springmass statics: --max-iterations needs a count from 1 to 1000000, got '2.5'|statics "$osc" -q --max-iterations 2.5
0||statics "$osc" -q --max-iterations 1e3
2|springmass modes: -n needs a count from 0 to 1e8, got ' +3'|modes "$osc" -n ' +3'
2|springmass modes: --count needs a count from 0 to 1e8, got '0x10'|modes "$osc" --count 0x10
0||modes "$osc" -n 1e0
2|springmass modes: -n needs a count from 0 to 1e8, got '1e-400'|modes "$osc" -n 1e-400
0||modes "$osc" -n 0e5
2|springmass modes: -n needs a count from 0 to 1e8, got '100000001'|modes "$osc" -n 100000001
2|springmass statics: --max-iterations needs a count from 1 to 1000000, got '1000001'|statics "$osc" -q --max-iterations 1000001
0||statics "$osc" -q --max-iterations 1000000
0||modes "$osc" -n 100000000
2|springmass run: --t-end needs a value|run "$osc" -q -o - --t-end
2|springmass run: --jacobian: unknown Jacobian 'positive' (exact, definite)|run "$osc" -q -o - --jacobian positive
2|springmass modes: --steps-per-period needs a finite number >= 1, got 'infinity'|modes "$osc" --steps-per-period infinity
2|springmass run: --rtol must be > 0, got '0'|run "$osc" -q -o - --rtol 0
2|springmass run: --rtol must be at least 2.220446049250313e-16, the machine epsilon (CVODE cannot meet a smaller relative tolerance), got '1e-17'|run "$osc" -q -o - --rtol 1e-17
0||run "$osc" -q -o - --t-end 1e-3 --rtol 2.220446049250313e-16
2|springmass run: --atol must be > 0, got '-1'|run "$osc" -q -o - --atol -1
2|springmass run: --atol-velocity must be > 0, got '0'|run "$osc" -q -o - --atol-velocity 0
2|springmass run: --atol must be at least 1e-150 (CVODE's error norm overflows below), got '1e-200'|run "$osc" -q -o - --atol 1e-200
2|springmass run: --atol-position must be at least 1e-150 (CVODE's error norm overflows below), got '1e-151'|run "$osc" -q -o - --atol-position 1e-151
0||run "$osc" -q -o - --t-end 1e-3 --atol 1e-150
2|springmass run: --atol-position expects a finite number, got 'x'|run "$osc" -q -o - --atol-position x
0||run "$osc" -q -o - --t-end 1e-320
0||run "$osc" -q -o - --t-end 0.01 --set k=1e-400
2|springmass run: --set k=1e999: '1e999' is not a finite number|run "$osc" -q -o - --set k=1e999
2|springmass run: --set k=0x1p3: '0x1p3' is not a finite number|run "$osc" -q -o - --set k=0x1p3
1|springmass run: --vtk $tmp/a_file: cannot write there: a file of that name exists|run "$osc" -q -o - --vtk "$tmp/a_file"
1|springmass run: --vtk $tmp/a_file/series: cannot write there: the folder it would go in is a file|run "$osc" -q -o - --vtk "$tmp/a_file/series"
1|springmass run: -o $tmp/a_file/out.csv: cannot write there: the folder it would go in is a file|run "$osc" -q -o "$tmp/a_file/out.csv"
1|springmass statics: --save-model $tmp/a_file/x.json: cannot write there: the folder it would go in is a file|statics "$osc" -q -o "$tmp/fresh_statics.csv" --save-model "$tmp/a_file/x.json"
2|springmass statics: --set expects NAME=VALUE, got 'k'|statics "$osc" --set k
2|springmass modes: --set expects NAME=VALUE, got 'k'|modes "$osc" --set k
1|springmass modes: --set zz=1: the model has no parameter named "zz"|modes "$osc" --set k=1 --set zz=1
0||run "$ends" -q -o - --t-end 0.01 --set xa=1 --set xb=3
1|springmass run: --set xa=2 --set xb=2: $tmp/rope_ends.json: structures[0]: rope: start = end = (2, 0, 0) m: its springs have rest length 0, and the structural group's per-strain stiffness (E / l0) needs a rest length > 0: give it an absolute stiffness, or the rope a length (with parameter xa = 2 and parameter xb = 2)|run "$ends" -q -o - --set xa=2 --set xb=2
2|springmass statics: --tolerance needs a positive finite number of newtons, got 'inf'|statics "$osc" --tolerance inf
2|springmass statics: --tolerance needs a positive finite number of newtons, got '0x1p-20'|statics "$osc" --tolerance 0x1p-20
2|springmass statics: --tolerance needs a positive finite number of newtons, got '0'|statics "$osc" --tolerance 0
CASES
# A parameter name of up to 255 characters is looked up; a longer one is a usage error.
long=$(printf 'n%.0s' $(seq 255))
out=$("$cli" run "$osc" -q -o /dev/null --set "$long=1" 2>&1)
status=$?
[ $status -eq 1 ] && [ "$out" = "springmass run: --set $long=1: the model has no parameter named \"$long\"" ] ||
  fail "--set with a name of 255 characters: exit status $status, printed '$out'"
out=$("$cli" run "$osc" -q -o /dev/null --set "${long}n=1" 2>&1)
status=$?
[ $status -eq 2 ] && [ "$out" = "springmass run: --set ${long}n=1: the parameter's name is too long (255 bytes at most)" ] ||
  fail "--set with a name of 256 characters: exit status $status, printed '$out'"
# An absolute tolerance the simulation would refuse is refused by the loader already.
printf '{"springmass": 1, "name": "t", "particles": [{"name": "a", "position": [0, 0, 0]}], "simulation": {"atol_velocity": 1e-200}}' > "$tmp/tiny_atol.json"
out=$("$cli" check "$tmp/tiny_atol.json" 2>&1)
[ "$out" = "springmass check: $tmp/tiny_atol.json: simulation.atol_velocity: 1e-200 must be at least 1e-150 (CVODE's error norm overflows below)" ] ||
  fail "check tiny_atol.json printed '$out'"
# check says what each parameter feeds, with its value as it reads back exactly and the unit of what
# it stands for (none for a count or a ratio).
cat > "$tmp/uses.json" << 'JSON'
{"springmass": 1, "name": "uses", "parameters": {"n": 4, "L": 1, "E": 10, "b": 0.1, "tol": 1e-6, "spare": 4999.999},
 "structures": [{"type": "rope", "name": "r", "start": [0, 0, 0], "end": ["L", 0, 0], "segments": "n",
                 "structural": {"strain_stiffness": "E"}}],
 "fixed": [{"min": [-1, -1, -1], "max": ["b", 1, 1]}], "simulation": {"rtol": "tol"}}
JSON
out=$("$cli" check "$tmp/uses.json" 2>&1)
for line in "n = 4 feeds counts" "L = 1 m feeds initial state" "E = 10 N feeds constants" \
            "b = 0.1 m feeds held particles" "tol = 1e-06 feeds settings" "spare = 4999.999 feeds nothing"; do
  grep -q "^  $(sed 's/ = / *= /; s/ feeds / *feeds /' <<< "$line")$" <<< "$out" || fail "check uses.json: no line '$line' in: $out"
done
# The absolute tolerances one at a time: --atol-position and --atol-velocity win over --atol
# whatever the order, and a looser velocity tolerance is a different run (fewer steps on the
# hanging rope, whose particles near the anchor move slowly: CVODE's error weights differ).
rope="$root/models/hanging_rope.json"
both=$("$cli" run "$rope" -q -o - --t-end 0.5 --atol 1e-8 --atol-velocity 1e-3)
split=$("$cli" run "$rope" -q -o - --t-end 0.5 --atol-velocity 1e-3 --atol-position 1e-8)
reversed=$("$cli" run "$rope" -q -o - --t-end 0.5 --atol-velocity 1e-3 --atol 1e-8)
tight=$("$cli" run "$rope" -q -o - --t-end 0.5 --atol 1e-8)
[ -n "$both" ] && [ "$both" = "$split" ] && [ "$both" = "$reversed" ] ||
  fail "--atol 1e-8 --atol-velocity 1e-3, the same split and reversed gave different CSVs"
[ "$both" != "$tight" ] || fail "--atol-velocity 1e-3 changed nothing against --atol 1e-8"
# --atol sets both: the same run as --atol-position and --atol-velocity of its value (the file
# leaves the velocity tolerance at its default, 1e-6, which would give another run).
[ "$tight" = "$("$cli" run "$rope" -q -o - --t-end 0.5 --atol-position 1e-8 --atol-velocity 1e-8)" ] ||
  fail "--atol 1e-8 is not --atol-position 1e-8 --atol-velocity 1e-8"
# All the modes of a model above CLI_DENSE_LIMIT (2000) degrees of freedom would take the dense
# eigensolver minutes (2100 here; hours at 10000): refused at once unless --solver dense is given.
cat > "$tmp/long_rope.json" << 'JSON'
{"springmass": 1, "name": "long_rope", "fixed": ["r[0]"], "structures": [{"type": "rope", "name": "r",
 "start": [0, 0, 0], "end": [7, 0, 0], "segments": 700, "structural": {"strain_stiffness": 1000}}]}
JSON
out=$(timeout 60 "$cli" modes "$tmp/long_rope.json" -n 0 2>&1 > /dev/null)
[ $? -eq 2 ] && [[ "$out" == "springmass modes: all the modes of 2100 degrees of freedom need the dense eigensolver,"* ]] ||
  fail "modes -n 0 of 2100 degrees of freedom: $out"
out=$(timeout 60 "$cli" modes "$tmp/long_rope.json" -n 3 2>&1 > /dev/null)
[ $? -eq 0 ] && [ -z "$out" ] || fail "modes -n 3 of 2100 degrees of freedom: $out"
# The sparse solver gives at most (dof - 40) / 4 = 515 of them: one more is refused at once too.
out=$(timeout 60 "$cli" modes "$tmp/long_rope.json" -n 516 2>&1 > /dev/null)
[ $? -eq 2 ] && [[ "$out" == "springmass modes: that many modes of 2100 degrees of freedom need the dense eigensolver,"*"(the sparse solver, N <= 515 here)"* ]] ||
  fail "modes -n 516 of 2100 degrees of freedom: $out"
# --solver sparse asked for more than it gives, or for a model too small for it: usage errors,
# refused before the linearisation.
out=$("$cli" modes "$root/models/cloth.json" --solver sparse -n 0 2>&1)
[ $? -eq 2 ] && [ "$out" = "springmass modes: --solver sparse gives the lowest modes, 1 to (dof - 40) / 4 = 180 of this model's 762 degrees of freedom, not all of them (-n 0): use --solver dense" ] ||
  fail "modes --solver sparse -n 0: $out"
out=$("$cli" modes "$root/models/oscillator.json" --solver sparse -n 1 2>&1)
[ $? -eq 2 ] && [ "$out" = "springmass modes: --solver sparse needs at least 44 free degrees of freedom, the model has 3: use --solver dense" ] ||
  fail "modes --solver sparse of 3 degrees of freedom: $out"

# A particle name with a comma or a quote is one quoted CSV field (RFC 4180).
cat > "$tmp/comma.json" << 'JSON'
{"springmass": 1, "name": "comma", "particles": [{"name": "a,\"b\"", "position": [0, 0, 0], "fixed": true}]}
JSON
out=$("$cli" run "$tmp/comma.json" --t-end 0.01 --positions -q -o - 2>&1 | head -1)
[ "$out" = 'time,energy.kinetic,energy.elastic,energy.gravity,energy.dissipated,energy.input,"particle.a,""b"".x","particle.a,""b"".y","particle.a,""b"".z"' ] ||
  fail "run --positions with a comma in a particle's name: $out"
out=$("$cli" statics "$tmp/comma.json" -q -o "$tmp/comma.csv" 2>&1 > /dev/null; tail -1 "$tmp/comma.csv")
[ "$out" = '0,"a,""b""",0,0,0,0,0,0,0,0,9.81' ] || fail "statics -o with a comma in a particle's name: $out"
# So is a name with a quote and no comma, its quote doubled.
cat > "$tmp/quote.json" << 'JSON'
{"springmass": 1, "name": "quote", "particles": [{"name": "a\"b", "position": [0, 0, 0], "fixed": true}]}
JSON
out=$("$cli" statics "$tmp/quote.json" -q -o "$tmp/quote.csv" 2>&1 > /dev/null; tail -1 "$tmp/quote.csv")
[ "$out" = '0,"a""b",0,0,0,0,0,0,0,0,9.81' ] || fail "statics -o with a quote in a particle's name: $out"

# Column names are unique: the bundled chain names its ports after their particles.
header=$("$cli" run "$root/models/two_mass_chain.json" --t-end 0.01 --positions -q -o - 2>&1 | head -1)
[ -z "$(tr ',' '\n' <<< "$header" | sort | uniq -d)" ] && [[ "$header" == *,m1.x,*,particle.m1.x,* ]] ||
  fail "run --positions on two_mass_chain: repeated or missing column names: $header"

# Failures of run: a relative tolerance of 1 is a usage error; output that cannot be written is an
# error (standard output too); a refused --vtk folder leaves an existing CSV as it was; a run that
# fails midway leaves a well-formed .pvd index of the rows it wrote.
"$cli" run "$root/models/oscillator.json" --rtol 1 -q -o - > /dev/null 2>&1; [ $? -eq 2 ] || fail "run --rtol 1 did not exit with 2"
if [ -w /dev/full ]; then
  out=$("$cli" run "$root/models/oscillator.json" -q -o - 2>&1 > /dev/full)
  [ $? -eq 1 ] && [ "$out" = "springmass run: cannot write standard output: No space left on device" ] ||
    fail "run -o - to a full device: $out"
  # A file that cannot be written is named, and the run stops at the row that failed: the
  # oscillator has 501 rows, and the first stdio buffer (4 KB, about 30 rows) fills the device,
  # so far fewer than 501 VTK files are written.
  out=$("$cli" run "$root/models/oscillator.json" -q -o /dev/full --vtk "$tmp/full_vtk" 2>&1 > /dev/null)
  rc=$?
  written=$(ls "$tmp/full_vtk" | grep -c '\.vtp$')
  [ $rc -eq 1 ] && [ "$out" = "springmass run: cannot write /dev/full: No space left on device" ] &&
    [ "$written" -lt 100 ] || fail "run -o /dev/full: exit $rc, '$out', $written VTK files"
  # Every command's files and reports: a report on standard output that cannot be written fails
  # the command too, as in any Unix tool.
  for cmd in "statics -q -o /dev/full" "statics -q --save-model /dev/full" "modes -o /dev/full"; do
    "$cli" $cmd "$root/models/two_mass_chain.json" > /dev/null 2> "$tmp/full.err"
    rc=$?
    [ $rc -eq 1 ] && grep -q "/dev/full: .*No space left on device" "$tmp/full.err" ||
      fail "$cmd: exit $rc, $(cat "$tmp/full.err")"
  done
  # The cloth's saved model (200 KB) is written past stdio's buffer in one write, which fails
  # there, leaving nothing for the close to fail on: the reason is still the write's.
  "$cli" statics "$root/models/cloth.json" -q --save-model /dev/full > /dev/null 2> "$tmp/full.err"
  rc=$?
  [ $rc -eq 1 ] && [ "$(cat "$tmp/full.err")" = "springmass statics: cannot write /dev/full: No space left on device" ] ||
    fail "statics --save-model /dev/full of a large model: exit $rc, $(cat "$tmp/full.err")"
  for cmd in "check" "statics" "modes" "run -o -" "--help" "run --help"; do
    out=$("$cli" $cmd "$root/models/two_mass_chain.json" 2>&1 > /dev/full)
    rc=$?
    [ $rc -eq 1 ] && case "$out" in *"cannot write standard output: No space left on device") true ;; *) false ;; esac ||
      fail "$cmd > /dev/full: exit $rc, '$out'"
  done
fi
echo "earlier" > "$tmp/earlier.csv"
"$cli" run "$root/models/oscillator.json" -q -o "$tmp/earlier.csv" --vtk "$tmp/earlier.csv/vtk" > /dev/null 2>&1
[ $? -eq 1 ] && [ "$(cat "$tmp/earlier.csv")" = earlier ] || fail "run with a refused --vtk folder changed the CSV"
# A run that stops after its first frame (5 internal steps allowed per output interval, where
# rtol 1e-12 takes hundreds) leaves an index that ends and names that frame.
"$cli" run "$root/models/oscillator.json" --t-end 0.05 --rtol 1e-12 --atol 1e-14 --max-steps 5 -q -o /dev/null \
  --vtk "$tmp/stopped_vtk" > /dev/null 2>&1
[ $? -eq 1 ] && [ "$(tail -2 "$tmp/stopped_vtk/oscillator.pvd" | paste -sd ' ')" = "</Collection> </VTKFile>" ] &&
  grep -q 'file="oscillator_000000.vtp"' "$tmp/stopped_vtk/oscillator.pvd" ||
  fail "run failing midway left a broken .pvd index"
"$cli" modes "$root/models/oscillator.json" -n "" > /dev/null 2>&1; [ $? -eq 2 ] || fail "modes -n '' did not exit with 2"

# `springmass fmu` only ever writes its output: a directory named by mistake stays (it was
# removed when empty, and the archive went to DIR.zip), and a name without an extension is the
# file written (zip alone would add ".zip"). A stand-in runtime keeps the archives small.
mkdir -p "$tmp/runtime/binaries/linux64"
echo "stand-in" > "$tmp/runtime/binaries/linux64/springmass_fmu.so"
# The cases after the first need a working `springmass fmu`: if it fails, that is the failure.
if [ "$with_fmu" = 0 ]; then
  out=$("$cli" fmu "$root/models/oscillator.json" -o "$tmp/oscillator" 2>&1)
  [ $? -eq 1 ] && grep -q "^springmass fmu: this build has no FMU support" <<< "$out" ||
    fail "fmu in a build without FMU support printed '$out'"
elif ! out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/oscillator" 2>&1); then
  fail "fmu -o NAME failed (the other fmu cases are not run): $out"
else
  [ -f "$tmp/oscillator" ] && [ ! -e "$tmp/oscillator.zip" ] ||
    fail "fmu -o NAME without an extension did not write NAME"
  # No output goes into the runtime the FMU is packed from (it would replace the binary).
  out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/runtime/binaries/linux64/springmass_fmu.so" 2>&1)
  [ $? -eq 2 ] && [ "$(cat "$tmp/runtime/binaries/linux64/springmass_fmu.so")" = "stand-in" ] ||
    fail "fmu -o into its runtime was not refused: $out"
  mkdir "$tmp/folder"
  out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/folder" 2>&1)
  status=$?
  [ $status -eq 1 ] && [ -d "$tmp/folder" ] && [ ! -e "$tmp/folder.zip" ] &&
    [ "$out" = "springmass fmu: cannot write $tmp/folder: Is a directory" ] ||
    fail "fmu -o DIR exited with $status and printed '$out'"
  # Only regular files are packed: a device would be read without end, a FIFO wait for a writer.
  mkfifo "$tmp/fifo.json"
  for special in /dev/zero "$tmp/fifo.json"; do
    out=$(timeout 20 "$cli" fmu "$special" --runtime "$tmp/runtime" -o "$tmp/special.fmu" 2>&1)
    status=$?
    [ $status -eq 1 ] && [ "$out" = "springmass fmu: cannot read $special: not a regular file" ] ||
      fail "fmu $special exited with $status and printed '$out'"
  done
  # The same inputs give the same bytes (reproducible builds) whatever the packer's time zone and
  # umask: entries in name order with fixed modes, dated SOURCE_DATE_EPOCH (UTC) when it is set
  # and 1980-01-01 00:00 otherwise.
  (umask 077; TZ=Asia/Tokyo "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/again" \
    > /dev/null 2>&1)
  SOURCE_DATE_EPOCH=1700000000 "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" \
    -o "$tmp/dated.fmu" > /dev/null 2>&1
  cmp -s "$tmp/oscillator" "$tmp/again" && [ "$(unzip -Z1 "$tmp/again" | paste -sd ' ')" = "binaries/ \
binaries/linux64/ binaries/linux64/oscillator.so documentation/ documentation/index.html modelDescription.xml \
resources/ resources/model.json" ] && unzip -Z -T "$tmp/again" | grep -q " 19800101\.000000 binaries/$" &&
    unzip -Z -T "$tmp/dated.fmu" | grep -q " 20231114\.221320 binaries/$" ||
    fail "fmu: two packings differ, or their entries or dates are not as documented: $(unzip -Z -T "$tmp/again")"
  # Beyond a zip date's range, SOURCE_DATE_EPOCH dates the entries at its last, 2107-12-31 23:59:58
  # (zip wrapped the next second to 1980); a value that is no count of seconds is refused.
  SOURCE_DATE_EPOCH=4354819199 "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" \
    -o "$tmp/late.fmu" > /dev/null 2>&1
  unzip -Z -T "$tmp/late.fmu" | grep -q " 21071231\.235958 binaries/$" ||
    fail "fmu: SOURCE_DATE_EPOCH past 2107 not dated at the last zip date: $(unzip -Z -T "$tmp/late.fmu")"
  out=$(SOURCE_DATE_EPOCH=-5 "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/neg.fmu" 2>&1)
  [ $? -eq 2 ] && [ ! -e "$tmp/neg.fmu" ] &&
    [ "$out" = "springmass fmu: SOURCE_DATE_EPOCH '-5' is not a count of seconds since 1970" ] ||
    fail "fmu: a malformed SOURCE_DATE_EPOCH was not refused: $out"
  # An earlier output is replaced whole (written beside it, then renamed over it: a full disk
  # leaves it as it was) and keeps its permissions; a link keeps pointing at the file it names.
  echo "earlier" > "$tmp/earlier.fmu"
  chmod 640 "$tmp/earlier.fmu"
  ln -s earlier.fmu "$tmp/link.fmu"
  "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/link.fmu" > /dev/null 2>&1 &&
    [ -L "$tmp/link.fmu" ] && [ "$(stat -c %a "$tmp/earlier.fmu")" = 640 ] &&
    [ "$(head -c 2 "$tmp/earlier.fmu")" = PK ] && ! ls "$tmp" | grep -q partial ||
    fail "fmu -o LINK to an earlier output: not replaced in place with its permissions"
  # A link to no file yet creates the file it names, as fopen would, and stays a link.
  ln -s later.fmu "$tmp/dangling.fmu"
  "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/dangling.fmu" > /dev/null 2>&1 &&
    [ -L "$tmp/dangling.fmu" ] && [ "$(head -c 2 "$tmp/later.fmu")" = PK ] ||
    fail "fmu -o LINK to no file: the link replaced or the file it names not written"
  # A chain of links to no file, relative to each link's folder: the file at its end is written
  # under a temporary name beside it and renamed (no partial file left); a cycle is refused.
  mkdir -p "$tmp/chain/sub"
  ln -s chain/first.fmu "$tmp/chained.fmu"
  ln -s sub/last.fmu "$tmp/chain/first.fmu"
  "$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/chained.fmu" > /dev/null 2>&1 &&
    [ -L "$tmp/chained.fmu" ] && [ -L "$tmp/chain/first.fmu" ] && [ "$(head -c 2 "$tmp/chain/sub/last.fmu")" = PK ] &&
    ! ls -R "$tmp" | grep -q partial ||
    fail "fmu -o through a chain of links to no file: not the file at its end, or a partial file left"
  # An absolute link to no file names it from the root, not from the link's folder.
  ln -s "$tmp/absolute_target.fmu" "$tmp/absolute.fmu"
  out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/absolute.fmu" 2>&1) &&
    [ -L "$tmp/absolute.fmu" ] && [ "$(head -c 2 "$tmp/absolute_target.fmu")" = PK ] && ! ls "$tmp" | grep -q partial ||
    fail "fmu -o an absolute link to no file: the file it names not written ($out)"
  # A name as long as a file system takes (255 bytes) is written too: the temporary name beside
  # it must not be longer.
  long="$(printf '%0251d' 0 | tr 0 f).fmu"
  out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/$long" 2>&1) &&
    [ "$(head -c 2 "$tmp/$long")" = PK ] && ! ls "$tmp" | grep -q partial ||
    fail "fmu -o a file name of 255 bytes: not written ($out)"
  ln -s cycle.fmu "$tmp/cycle.fmu"
  out=$("$cli" fmu "$root/models/oscillator.json" --runtime "$tmp/runtime" -o "$tmp/cycle.fmu" 2>&1)
  [ $? = 1 ] && printf '%s' "$out" | grep -q "symbolic links" && [ -L "$tmp/cycle.fmu" ] ||
    fail "fmu -o through a cycle of links: not refused with the reason ($out)"
  # --set as in `springmass run`: a malformed setting is a usage error, an unknown parameter or a
  # value the model refuses a bad model; each is refused before anything is written.
  cp "$root/tests/python/models/rope_n.json" "$tmp/rope_n.json"
  check_cases << 'CASES'
2|springmass fmu: --set expects NAME=VALUE, got 'n'|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n
2|springmass fmu: --set expects NAME=VALUE, got '=8'|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set =8
2|springmass fmu: --set n=inf: 'inf' is not a finite number|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n=inf
2|springmass fmu: --set n=8x: '8x' is not a finite number|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n=8x
2|springmass fmu: --set needs a value|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set
1|springmass fmu: --set zz=1: the model has no parameter named "zz"|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n=8 --set zz=1
1|springmass fmu: --set n=2.5: $tmp/rope_n.json: structures[0].segments: parameter n = 2.5 must be a whole number from 1 to 4194304|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n=2.5
1|springmass fmu: --set n=2: $tmp/rope_n.json: ports[1].particle: "rope[4]" is outside structure rope ([0] to [2]) (with parameter n = 2)|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n=2
1|springmass fmu: --set E=-1: $tmp/rope_n.json: structures[0].structural.strain_stiffness: parameter E = -1 must be >= 0|fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set E=-1
CASES
  [ ! -e "$tmp/set.fmu" ] || fail "fmu --set with a refused value wrote its output"
  "$cli" fmu --help | grep -q -- "--set NAME=VALUE" || fail "fmu --help says nothing of --set"
  # The values that differ from the file's go beside it into resources/parameters.txt, which the
  # GUID hashes too; values the file has change nothing.
  guid() { sed -n 's/.*GUID \({[-0-9a-f]*}\).*/\1/p' <<< "$1"; }
  plain=$("$cli" fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/plain.fmu" 2>&1)
  same=$("$cli" fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/same.fmu" --set n=4 --set E=100 2>&1)
  with_set=$("$cli" fmu "$tmp/rope_n.json" --runtime "$tmp/runtime" -o "$tmp/set.fmu" --set n=4e0 --set n=8 --set E=150 2>&1)
  [ -n "$(guid "$plain")" ] && [ "$(guid "$same")" = "$(guid "$plain")" ] && [ "$(guid "$with_set")" != "$(guid "$plain")" ] &&
    [ "$(unzip -Z1 "$tmp/same.fmu" | grep -c parameters.txt)" = 0 ] &&
    [ "$(unzip -p "$tmp/set.fmu" resources/parameters.txt)" = "$(printf 'n=8\nE=150')" ] &&
    cmp -s "$tmp/rope_n.json" <(unzip -p "$tmp/set.fmu" resources/model.json) &&
    unzip -p "$tmp/set.fmu" modelDescription.xml | grep -q 'name="p\[8\].vz"' ||
    fail "fmu --set n=8 --set E=150: $with_set (without --set: $plain, with the file's values: $same)"
fi

[ $failures -eq 0 ] && echo "check_cli: all passed"
exit $((failures > 0))
