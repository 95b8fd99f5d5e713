#!/usr/bin/env bash
# Regenerates the figures behind docs/performance.md: builds dpsm-bench, runs
# the speed benchmarks (throughput, sparse, idle, cone, deposits, wind,
# short calls, the modes on the column collapse, the physics of real scenes,
# steps, and the tile kernel alone) into docs/data/speed_*.csv and plots the
# throughput into docs/figures/.
#
#   bash bench/run_speed.sh        # about 6 minutes on 2 cores (the steps study takes 1-2), on a quiet machine
#
# BUILD_DIR (default build-bench) is the build tree; PYTHON (default
# /usr/bin/python3) runs the plot, which needs python3-matplotlib.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${BUILD_DIR:-$root/build-bench}
python=${PYTHON:-/usr/bin/python3}
data=$root/docs/data
figures=$root/docs/figures

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DDPSM_BUILD_BENCH=ON \
      -DDPSM_BUILD_TESTS=OFF -DDPSM_BUILD_DOCS=OFF -DDPSM_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$build" --target dpsm-bench dpsm-bench-kernel
bench=$build/bench/dpsm-bench
mkdir -p "$data" "$figures"

{
  echo "generated: $(date -u +%Y-%m-%dT%H:%M:%SZ) by bench/run_speed.sh"
  echo "source tree $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "machine: $(uname -m), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ //')," \
       "AVX-512: $(grep -q avx512f /proc/cpuinfo && echo yes || echo no)"
  echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "compiler: $(${CXX:-c++} --version 2>/dev/null | head -1)"
} > "$data/speed_provenance.txt"

for what in throughput sparse idle cone deposits wind short modes physics steps; do
  echo ">> dpsm-bench $what"
  "$bench" "$what" > "$data/speed_$what.csv" 2> "$data/speed_$what.log"
  cat "$data/speed_$what.csv"
done
"$bench" cone 1e-3 | tail -n +2 >> "$data/speed_cone.csv"
"$bench" deposits 4096 40 10 2>> "$data/speed_deposits.log" | tail -n +2 >> "$data/speed_deposits.csv"
echo ">> dpsm-bench-kernel"
"$build/bench/dpsm-bench-kernel" > "$data/speed_kernel.csv"
cat "$data/speed_kernel.csv"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$data/speed_provenance.txt"
"$python" "$root/bench/plot_speed.py" "$data/speed_throughput.csv" "$figures/speed_throughput.png"
"$python" "$root/bench/fill_performance.py" "$data" "$root/docs/performance.md"
