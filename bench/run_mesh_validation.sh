#!/usr/bin/env bash
# Regenerates the figures of docs/guide_meshes.md: the column collapse on every
# mesh kind at three refinements and the cone on triangles (dpsm-bench
# mesh-accuracy, with the gmsh disk when gmsh is installed), the 2D grid's
# isotropic scheme beside them (docs/data/work_precision.csv), the speed of
# the mesh engine (dpsm-bench mesh, mesh-wind, mesh-graded, lts, lts-compare), the error-against-cells figure and the
# picture of a pile on a gmsh mesh (examples/python/mesh_pile.py).
#
#   bash bench/run_mesh_validation.sh     # about 45 minutes on 2 cores, on a quiet machine
#
# The accuracy runs take one thread, as the table of docs/guide_meshes.md
# does: the deposits are the same on any thread count, the cell updates are
# not (the sparse step takes more of the mesh on one thread). The level of
# about 262,000 cells is `dpsm-bench mesh-accuracy 1 4 KIND`, kind by kind:
# it takes 20 minutes to hours a kind.
#
# BUILD_DIR (default build-bench) is the build tree; PYTHON (default
# /usr/bin/python3) runs the plots, which need python3-matplotlib.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${BUILD_DIR:-$root/build-bench}
python=${PYTHON:-/usr/bin/python3}
data=$root/docs/data
figures=$root/docs/figures

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DDPSM_BUILD_BENCH=ON \
      -DDPSM_BUILD_TESTS=OFF -DDPSM_BUILD_DOCS=OFF -DDPSM_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$build" --target dpsm-bench dpsm
bench=$build/bench/dpsm-bench
mkdir -p "$data" "$figures"
{
  echo "generated: $(date -u +%Y-%m-%dT%H:%M:%SZ) by bench/run_mesh_validation.sh"
  echo "source tree $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "machine: $(uname -m), $(nproc) cores; gmsh: $(gmsh --version 2>&1 || echo 'not found')"
} > "$data/mesh_provenance.txt"

echo ">> dpsm-bench mesh-accuracy"
DPSM_DISK_GEO=$root/bench/data/disk.geo "$bench" mesh-accuracy 1 3 > "$data/mesh_accuracy.csv" 2> "$data/mesh_accuracy.log"
cat "$data/mesh_accuracy.csv"
echo ">> dpsm-bench mesh, each kind of mesh three times"
{
  for kind in jittered_triangles hexagons median_dual; do
    for run in 1 2 3; do "$bench" mesh 0 3 "$kind"; done
  done
} 2> "$data/mesh_speed.log" | awk 'NR == 1 || !/^mesh,/' > "$data/mesh_speed.csv"
cat "$data/mesh_speed.csv"
echo ">> dpsm-bench mesh-wind, 1 and 2 threads, three runs each"
{
  for threads in 1 2; do
    for run in 1 2 3; do "$bench" mesh-wind 708 "$threads" 3 2> "$data/mesh_wind.log"; done
  done
} | awk 'NR == 1 { print "build," $0; next } /^cells/ { next } { print "this," $0 }' > "$data/mesh_wind.csv"
cat "$data/mesh_wind.csv"
echo ">> dpsm-bench mesh-graded (issue 34's graded mesh, with and without local time steps, about 100 s)"
"$bench" mesh-graded > "$data/mesh_graded.txt" 2>&1
cat "$data/mesh_graded.txt"
echo ">> dpsm-bench lts, lts-compare (local time steps on quadtrees, about 2 minutes)"
"$bench" lts > "$data/mesh_lts_local.txt" 2>&1
cat "$data/mesh_lts_local.txt"
{
  echo "# dpsm-bench lts-compare 128 3"; "$bench" lts-compare 128 3
  echo "# dpsm-bench lts-compare 128 1"; "$bench" lts-compare 128 1
} > "$data/mesh_lts_compare.txt" 2>&1
cat "$data/mesh_lts_compare.txt"
"$python" "$root/bench/plot_mesh_accuracy.py" "$data/mesh_accuracy.csv" "$data/work_precision.csv" \
    "$figures/mesh_accuracy.png"
PYTHONPATH=$root/bindings/python DPSM_LIBRARY=$build/src/libdpsm.so \
    "$python" "$root/examples/python/mesh_pile.py" --save "$figures/mesh_pile.png"
