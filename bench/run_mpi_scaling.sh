#!/usr/bin/env bash
# Regenerates the figures of docs/guide_mpi.md (scaling): builds dpsm-bench-mpi
# and runs strong and weak scaling on 1 .. MAX_RANKS ranks (default: the
# cores of this machine), and the communication alone, into
# docs/data/mpi_scaling.csv (a log in docs/data/mpi_scaling.log); then the
# distributed triangle mesh of MESH_N (default 708: 1,002,528 cells) on 1, 2
# and 4 ranks (oversubscribed past the cores), with two layers of ghosts and
# with deeper ones (MESH_LAYERS, default "8 12": 2 and 4 sub-steps per
# exchange), into docs/data/mpi_mesh_scaling.csv, a local pile on the same mesh (what ranks
# at rest compute and send) into docs/data/mpi_mesh_rest.csv, local time steps on a
# graded mesh of 180,000 triangles against the global sub-step into
# docs/data/mpi_mesh_graded.csv, and the cost
# model extrapolated to 1,024 ranks into docs/data/mpi_mesh_model.txt.
# MESH_ONLY=1 runs the mesh alone.
#
#   bash bench/run_mpi_scaling.sh      # a few minutes on 2 cores
#
# BUILD_DIR (default build-bench) is the build tree. Runs as root too (CI does).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${BUILD_DIR:-$root/build-bench}
ranks_max=${MAX_RANKS:-$(nproc)}
data=$root/docs/data
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DDPSM_BUILD_BENCH=ON \
      -DDPSM_BUILD_TESTS=OFF -DDPSM_BUILD_DOCS=OFF -DDPSM_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$build" --target dpsm-bench-mpi dpsm-bench-mpi-mesh
bench=$build/bench/dpsm-bench-mpi
mesh_bench=$build/bench/dpsm-bench-mpi-mesh
[[ -x $bench ]] || { echo "no $bench: was MPI found?" >&2; exit 1; }
mkdir -p "$data"

run() { mpiexec -n "$1" --bind-to core "$bench" "${@:2}" | tail -n 1; }

mesh_n=${MESH_N:-708}
{
  head=1
  for p in 1 2 4; do
    bind=core
    [[ $p -gt $(nproc) ]] && bind=none
    mpiexec -n "$p" --oversubscribe --bind-to "$bind" "$mesh_bench" "$mesh_n" 5 | if [[ $head == 1 ]]; then cat; else tail -n 1; fi
    head=0
  done
  for layers in ${MESH_LAYERS:-8 12}; do
    for p in 2 4; do
      bind=core
      [[ $p -gt $(nproc) ]] && bind=none
      mpiexec -n "$p" --oversubscribe --bind-to "$bind" "$mesh_bench" "$mesh_n" 5 "$layers" | tail -n 1
    done
  done
} >"$data/mpi_mesh_scaling.csv"
# A pile near a corner and one at the centre (where the parts meet), the rest
# of the mesh at rest: what each rank computes and sends.
{
  head=1
  for pile in corner centre; do
    for p in 1 2 4; do
      bind=core
      [[ $p -gt $(nproc) ]] && bind=none
      mpiexec -n "$p" --oversubscribe --bind-to "$bind" "$mesh_bench" "$mesh_n" 5 "$pile" | if [[ $head == 1 ]]; then cat; else tail -n 1; fi
      head=0
    done
  done
} >"$data/mpi_mesh_rest.csv"
# Local time steps on a graded mesh against the global sub-step (a pile on the coarse cells).
{
  head=1
  for p in 1 2; do
    mpiexec -n "$p" --bind-to core "$mesh_bench" 300 5 graded | if [[ $head == 1 ]]; then cat; else tail -n 1; fi
    head=0
  done
} >"$data/mpi_mesh_graded.csv"
{
  echo "generated: $(date -u +%Y-%m-%dT%H:%M:%SZ) by bench/run_mpi_scaling.sh, source tree $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "machine: $(uname -m), $(nproc --all) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'); load average after the runs: $(cut -d' ' -f1-3 /proc/loadavg)"
  python3 "$root/bench/mpi_mesh_model.py" "$data/mpi_mesh_scaling.csv"
} | tee "$data/mpi_mesh_model.txt"
if [[ ${MESH_ONLY:-0} == 1 ]]; then exit 0; fi
{
  echo "generated: $(date -u +%Y-%m-%dT%H:%M:%SZ) by bench/run_mpi_scaling.sh"
  echo "source tree $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "machine: $(uname -m), $(nproc --all) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //')"
  echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "mpiexec: $(mpiexec --version 2>&1 | head -1)"
} >"$data/mpi_scaling.log"

{
  echo "mode,ranks,nx_global,ny_global,cells_per_rank,seconds_per_sweep,mcell_updates_per_s,blocks_alone_seconds_per_sweep"
  for p in $(seq 1 "$ranks_max"); do run "$p" strong 2048 10; done
  for p in $(seq 1 "$ranks_max"); do run "$p" weak 1024 10; done
} >"$data/mpi_scaling.csv"
{
  echo "mode,ranks,width,halo_bytes_per_rank,halo_exchange_s,allreduce_8_doubles_s"
  for w in 1024 2048 8192; do run "$ranks_max" comm "$w" 2000; done
} >"$data/mpi_comm.csv"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$data/mpi_scaling.log"
cat "$data/mpi_scaling.csv" "$data/mpi_comm.csv"
