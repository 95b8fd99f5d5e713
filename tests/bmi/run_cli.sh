#!/usr/bin/env bash
# The `dpsm run` test: runs configurations and reads the netCDF they write
# back with ncdump (netcdf-bin).
#
#   usage: run_cli.sh <dpsm program> <source-dir>
#
#  1. tests/bmi/data/run_column.yaml (2d, open sides, a source): 5 snapshots
#     at 0, 0.1, 0.2, 0.3 and the end 0.35; h(time, y, x); the last total
#     volume in the file is the one printed, and the ledger closes in the file
#  2. tests/bmi/data/run_mesh.yaml (a UGRID mesh made with ncgen): 4
#     snapshots, h(time, cell), the mesh topology, the volume kept by the wall
#  3. a bad configuration: exit 1 and a message naming the file's line; a
#     bad command line: exit 2
#  4. every configuration in examples/config: runs and writes a file whose
#     last snapshot is at the end time and whose ledger closes
set -euo pipefail

if [[ $# -ne 2 ]]; then
    echo "usage: $0 <dpsm program> <source-dir>" >&2
    exit 2
fi
dpsm=$1
src=$(cd "$2" && pwd)
data=$src/tests/bmi/data
work=$(mktemp -d "${TMPDIR:-/tmp}/dpsm-run.XXXXXX")
trap 'rm -rf "$work"' EXIT
fail() {
    printf 'FAIL: %s\n' "$*" >&2
    exit 1
}
command -v ncdump >/dev/null || fail "ncdump is not installed (apt-get install netcdf-bin)"
command -v ncgen >/dev/null || fail "ncgen is not installed (apt-get install netcdf-bin)"

# The values of variable $2 in file $1, one per line.
values() {
    ncdump -v "$2" "$1" | awk -v name="$2" '/^data:/ { data = 1 } data && $1 == name && $2 == "=" { on = 1 } on { print; if (/;/) exit }' |
        sed "s/^ $2 = //; s/;//" | tr ',' '\n' | awk 'NF { print $1 }'
}
last() { values "$1" "$2" | tail -n 1; }
# |a - b| <= tol * max(1, |a|, |b|)
close_to() { awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; s = 1;
    if (a > s || -a > s) s = (a < 0 ? -a : a); if (b > s || -b > s) s = (b < 0 ? -b : b); exit !(d <= tol * s) }'; }
snapshots() { ncdump -h "$1" | sed -n 's/.*time = UNLIMITED ; \/\/ (\([0-9]*\) currently).*/\1/p'; }
ledger_closes() {
    local total sourced external outflow
    total=$(last "$1" total_volume)
    sourced=$(last "$1" sourced_volume)
    external=$(last "$1" external_volume)
    outflow=$(last "$1" outflow_volume)
    close_to "$total" "$(awk -v s="$sourced" -v e="$external" -v o="$outflow" 'BEGIN { printf "%.17g", s + e - o }')" 1e-12 ||
        fail "$1: the ledger does not close: total $total, sourced $sourced, external $external, outflow $outflow"
}

echo "== 1. a column on a 2d grid"
cp "$data/run_column.yaml" "$work/"
"$dpsm" run "$work/run_column.yaml" >"$work/column.log" || { cat "$work/column.log"; fail "dpsm run run_column.yaml failed"; }
cat "$work/column.log"
out=$work/column_out.nc
[[ -f $out ]] || fail "no $out"
[[ $(snapshots "$out") == 5 ]] || fail "$out holds $(snapshots "$out") snapshots, expected 5"
[[ $(values "$out" time | tr '\n' ' ') == "0 0.1 0.2 0.3 0.35 " ]] || fail "times $(values "$out" time | tr '\n' ' ')"
header=$(ncdump -h "$out")
[[ $header == *'double h(time, y, x)'* ]] || fail "$out has no h(time, y, x)"
[[ $header == *':Conventions = "CF-1.8"'* ]] || fail "$out does not say CF-1.8"
printed=$(sed -n 's/^  total  *//p' "$work/column.log")
close_to "$(last "$out" total_volume)" "$printed" 1e-14 ||
    fail "the last total volume in the file, $(last "$out" total_volume), is not the printed $printed"
ledger_closes "$out"
# The source worked over the whole run: 0.001 m/s on 32 x 24 cells of 0.0025 m2 for 0.35 s.
close_to "$(last "$out" sourced_volume)" 0.000672 1e-9 || fail "sourced volume $(last "$out" sourced_volume), expected 0.000672"
awk -v o="$(last "$out" outflow_volume)" 'BEGIN { exit !(o > 0) }' || fail "nothing left through the open sides"

echo "== 2. a cone on a UGRID mesh"
cp "$data/run_mesh.yaml" "$work/"
ncgen -o "$work/run_mesh.nc" "$data/run_mesh.cdl"
"$dpsm" run "$work/run_mesh.yaml" >"$work/mesh.log" || { cat "$work/mesh.log"; fail "dpsm run run_mesh.yaml failed"; }
out=$work/mesh_out.nc
[[ $(snapshots "$out") == 4 ]] || fail "$out holds $(snapshots "$out") snapshots, expected 4"
header=$(ncdump -h "$out")
for want in 'double h(time, cell)' 'mesh:cf_role = "mesh_topology"' 'mesh:topology_dimension = 2' \
    'int mesh_face_nodes(cell, max_cell_nodes)' 'h:mesh = "mesh"' 'h:location = "face"' 'cell = 48' 'node = 49' \
    ':Conventions = "CF-1.8 UGRID-1.0"'; do
    [[ $header == *"$want"* ]] || fail "$out: no '$want' in its header"
done
close_to "$(last "$out" total_volume)" "$(values "$out" total_volume | head -n 1)" 1e-13 ||
    fail "the wall kept no volume: $(values "$out" total_volume | tr '\n' ' ')"
ledger_closes "$out"
# The surface moved: the first and the last snapshot differ.
ncdump -v h "$out" | awk '/^data:/ { data = 1 } data && $1 == "h" && $2 == "=" { on = 1 } on { print; if (/;/) exit }' >"$work/h.txt"
first=$(tr -d ' ;h=\n' <"$work/h.txt" | tr ',' '\n' | head -n 48 | tr '\n' ' ')
final=$(tr -d ' ;h=\n' <"$work/h.txt" | tr ',' '\n' | tail -n 48 | tr '\n' ' ')
[[ $first != "$final" ]] || fail "the cone did not move"

echo "== 3. refusals"
cp "$data/run_bad.yaml" "$work/"
status=0
"$dpsm" run "$work/run_bad.yaml" 2>"$work/bad.err" >/dev/null || status=$?
[[ $status == 1 ]] || fail "a bad configuration exited with $status, expected 1"
grep -q 'run_bad.yaml:4: time.step: expected a positive number, got "-1"' "$work/bad.err" ||
    fail "unexpected message: $(cat "$work/bad.err")"
status=0
"$dpsm" frobnicate 2>/dev/null || status=$?
[[ $status == 2 ]] || fail "an unknown command exited with $status, expected 2"
status=0
"$dpsm" 2>/dev/null || status=$?
[[ $status == 2 ]] || fail "no command exited with $status, expected 2"
[[ $("$dpsm" --version) == "dpsm "[0-9]* ]] || fail "dpsm --version"

echo "== 4. the example configurations"
# Whatever their layout, each writes one new netCDF file next to itself, and
# its last progress line says the end time.
for config in "$src"/examples/config/*.yaml; do
    name=$(basename "$config" .yaml)
    rm -rf "$work/examples" && cp -r "$src/examples/config" "$work/examples"
    ls "$work/examples" >"$work/before.txt"
    "$dpsm" run "$work/examples/$name.yaml" >"$work/$name.log" || { cat "$work/$name.log"; fail "examples/config/$name.yaml failed"; }
    new=$(ls "$work/examples" | comm -13 "$work/before.txt" - | grep '\.nc$' || true)
    [[ $(wc -w <<<"$new") == 1 ]] || fail "examples/config/$name.yaml wrote '$new', expected one netCDF file"
    end=$(sed -n 's/^t = .* \/ \([^ ]*\) s .*/\1/p' "$work/$name.log" | tail -n 1)
    [[ -n $end ]] || fail "examples/config/$name.yaml printed no progress"
    close_to "$(last "$work/examples/$new" time)" "$end" 1e-6 || fail "$name: the last snapshot is not at the end time $end"
    ledger_closes "$work/examples/$new"
    echo "   $name.yaml: $(snapshots "$work/examples/$new") snapshots to $new, ledger closed"
done
echo "== dpsm run checks passed"
