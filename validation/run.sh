#!/usr/bin/env bash
# Regenerates everything behind docs/validation.md: builds dpsm-validate and
# dpsm-bench, writes the CSVs (and run logs) into docs/data/, and plots them into
# docs/figures/.
#
#   bash validation/run.sh            # the full set (about 10-20 min on 2 cores)
#   WP_MAX_N=128 bash validation/run.sh   # a quick run: work-precision up to 128^2
#
# WP_THREADS (default 1) is the thread count of the work-precision runs (0: the
# library's default, one per core).
# BUILD_DIR (default build-val) is the build tree; PYTHON (default
# /usr/bin/python3) runs the plots, which need python3-matplotlib; without it
# the CSVs are still written and the plotting steps say so and skip.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${BUILD_DIR:-$root/build-val}
python=${PYTHON:-/usr/bin/python3}
wp_max_n=${WP_MAX_N:-512}
wp_threads=${WP_THREADS:-1}
data=$root/docs/data
figures=$root/docs/figures

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DDPSM_BUILD_BENCH=ON \
      -DDPSM_BUILD_TESTS=OFF -DDPSM_BUILD_DOCS=OFF -DDPSM_BUILD_EXAMPLES=ON >/dev/null
cmake --build "$build" --target dpsm-validate dpsm-bench dpsm-dune

validate=$build/validation/dpsm-validate
bench=$build/bench/dpsm-bench
mkdir -p "$data" "$figures"

# Where the numbers come from.
{
  echo "generated: $(date -u +%Y-%m-%dT%H:%M:%SZ) by validation/run.sh"
  echo "dpsm: $("$validate" --help | head -1 | sed 's/.*(dpsm \(.*\))/\1/')," \
       "source tree $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "machine: $(uname -m), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ //')"
  echo "compiler: $(${CC:-cc} --version 2>/dev/null | head -1)"
  echo "threads: dpsm-validate: the library default (one per core); dpsm-bench work-precision: $wp_threads"
} > "$data/provenance.txt"

run() {  # run NAME COMMAND...: the command's stderr goes to docs/data/NAME.log
  local name=$1; shift
  local t0=$SECONDS
  echo "== $name: $*"
  "$@" 2> "$data/$name.log"
  echo "   $((SECONDS - t0)) s (log: docs/data/$name.log)"
  echo "$name: $((SECONDS - t0)) s" >> "$data/provenance.txt"
}

run column_sweep "$validate" column-sweep "$data"
run table_1d "$validate" table-1d "$data"
run table_2d "$validate" table-2d "$data"
run work_precision bash -c '"$1" work-precision "$2" "$3" > "$4"' _ "$bench" "$wp_max_n" "$wp_threads" \
    "$data/work_precision.csv"

run dune_fig10 bash -c '"$1" "$2" > "$3"' _ "$build/examples/dpsm-dune" "$data/dune_fig10.csv" \
    "$data/dune_fig10_summary.txt"

"$python" "$root/validation/plot.py" "$data" "$figures"
"$python" "$root/validation/plot_dune.py" "$data/dune_fig10.csv" "$figures/dune_fig10.png"
"$python" "$root/bench/plot_work_precision.py" "$data/work_precision.csv" "$figures/work_precision.png" \
  | tee "$data/work_precision_orders.txt"
echo "done: CSVs in docs/data/, figures in docs/figures/"
