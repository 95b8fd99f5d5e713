#!/usr/bin/env bash
# The `dpsm plot` test: draws the output of `dpsm run` and refuses what is
# not such an output.
#
#   usage: run_plot.sh <dpsm program> <source-dir> <python3>
#
# The environment (CMakeLists.txt) puts the package of the source tree on
# PYTHONPATH and names the library just built in DPSM_LIBRARY.
#  1. examples/config/column.yaml (2d), dune.yaml (1d) and mesh.yaml (UGRID):
#     dpsm run, then dpsm plot (beside the output, or -o FILE); the PNG
#     exists, has the PNG signature, is larger than 10 kB and its surface
#     panel is drawn on (check_png.py); python -m dpsm plot does the same
#  2. refusals, each with exit status 1 and a message: a netCDF file without
#     h, a file that is not there, a mesh whose cells name nodes that are not
#     there, a file that is not netCDF, numpy missing; no file named: exit 2
#  3. the C program's own failures: an interpreter that cannot be run, a
#     Python that cannot import the package
set -euo pipefail

if [[ $# -ne 3 ]]; then
    echo "usage: $0 <dpsm program> <source-dir> <python3>" >&2
    exit 2
fi
dpsm=$1
src=$(cd "$2" && pwd)
python=$3
here=$src/tests/cli
work=$(mktemp -d "${TMPDIR:-/tmp}/dpsm-plot.XXXXXX")
trap 'rm -rf "$work"' EXIT
fail() {
    printf 'FAIL: %s\n' "$*" >&2
    exit 1
}
command -v ncgen >/dev/null || fail "ncgen is not installed (apt-get install netcdf-bin)"
export DPSM_PYTHON=$python
unset DISPLAY WAYLAND_DISPLAY MPLBACKEND # headless, whatever the caller has

# A PNG of a drawn surface: the signature, more than 10 kB, colour in the surface panel.
is_figure() {
    [[ -f $1 ]] || fail "no $1"
    [[ $(head -c 8 "$1" | od -An -tx1 | tr -d ' \n') == 89504e470d0a1a0a ]] || fail "$1 does not start with the PNG signature"
    local size
    size=$(stat -c %s "$1")
    ((size > 10000)) || fail "$1 has $size bytes, expected more than 10 kB"
    "$python" "$here/check_png.py" "$1" || fail "$1: the surface panel is empty"
}
# refuses STATUS MESSAGE COMMAND...: COMMAND exits with STATUS and says MESSAGE on stderr.
refuses() {
    local want=$1 message=$2 status=0
    shift 2
    "$@" >"$work/out.txt" 2>"$work/err.txt" || status=$?
    [[ $status == "$want" ]] || fail "'$*' exited with $status, expected $want: $(cat "$work/err.txt")"
    grep -qF -- "$message" "$work/err.txt" || fail "'$*' did not say '$message', it said: $(cat "$work/err.txt")"
    echo "   refused ($status): $(head -n 1 "$work/err.txt")"
}

echo "== 1. dpsm plot on the output of each kind of grid"
cp -r "$src/examples/config" "$work/examples"
for name in column dune mesh; do
    "$dpsm" run "$work/examples/$name.yaml" >"$work/$name.log" || { cat "$work/$name.log"; fail "dpsm run $name.yaml failed"; }
done
out=$("$dpsm" plot "$work/examples/column_out.nc") || fail "dpsm plot column_out.nc failed"
[[ $out == "$work/examples/column_out.png" ]] || fail "dpsm plot printed '$out', expected the PNG beside the file"
is_figure "$work/examples/column_out.png"
out=$("$dpsm" plot "$work/examples/mesh_out.nc" -o "$work/mesh.png") || fail "dpsm plot mesh_out.nc failed"
[[ $out == "$work/mesh.png" ]] || fail "dpsm plot -o printed '$out'"
is_figure "$work/mesh.png"
(cd "$work/examples" && "$python" -m dpsm plot dune_out.nc -o ../dune.png >/dev/null) || fail "python -m dpsm plot dune_out.nc failed"
is_figure "$work/dune.png"
[[ $("$python" -m dpsm --version) == "dpsm "[0-9]*" (C library "*", loaded from "* ]] || fail "python -m dpsm --version"

echo "== 2. refusals"
cat >"$work/no_h.cdl" <<'CDL'
netcdf no_h {
dimensions:
	time = UNLIMITED ;
variables:
	double time(time) ;
		time:units = "s" ;
data:
 time = 0 ;
}
CDL
ncgen -o "$work/no_h.nc" "$work/no_h.cdl"
refuses 1 "no_h.nc is not an output of dpsm run: it has no variable h (the heights)" "$dpsm" plot "$work/no_h.nc"
refuses 1 "absent.nc: no such file" "$dpsm" plot "$work/absent.nc"
cp "$work/examples/mesh_out.nc" "$work/bad_mesh.nc"
"$python" -c 'import sys, netCDF4
with netCDF4.Dataset(sys.argv[1], "a") as f: f.variables["mesh_face_nodes"][0, 0] = 999' "$work/bad_mesh.nc"
refuses 1 "bad_mesh.nc is not an output of dpsm run: its mesh_face_nodes names nodes that are not there" \
    "$dpsm" plot "$work/bad_mesh.nc"
refuses 1 "column.yaml: not a netCDF file" "$dpsm" plot "$work/examples/column.yaml"
refuses 1 "dpsm plot: the Python package numpy is missing (Debian: apt-get install python3-numpy)" \
    "$python" "$src/tests/python/block_imports.py" numpy "$src/bindings/python/dpsm/__main__.py" plot "$work/examples/column_out.nc"
refuses 2 "dpsm plot: expected the netCDF file written by dpsm run" "$dpsm" plot
[[ ! -e $work/no_h.png && ! -e $work/absent.png && ! -e $work/bad_mesh.png ]] || fail "a refused file left a PNG"

echo "== 3. no Python to hand over to"
refuses 1 'cannot run the Python interpreter "/nonexistent/python3"' \
    env DPSM_PYTHON=/nonexistent/python3 "$dpsm" plot "$work/examples/column_out.nc"
if (cd "$work" && PYTHONPATH= "$python" -c 'import dpsm' 2>/dev/null); then
    echo "   (skipped: $python imports dpsm without PYTHONPATH)"
else
    (cd "$work" && refuses 1 "the Python package dpsm cannot be imported by" env PYTHONPATH= "$dpsm" plot examples/column_out.nc)
fi
echo "== dpsm plot checks passed"
