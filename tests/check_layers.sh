#!/usr/bin/env bash
# Checks the floors of src/ (docs/architecture.md, "The folders"): a file of
# each folder includes only the folders of its row below (its own among
# them), and no file of src/ outside src/mpi/ includes an MPI header. Every
# violation is named; the exit status is 1 if there is any.
#
#   usage: tests/check_layers.sh [source root]
set -euo pipefail
root=${1:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
src=$root/src

# The folders each folder may include, bottom up: the ground first.
declare -A may_include=(
    [model]="model"
    [io]="io model"
    [structured]="structured model"
    [mesh]="mesh model"
    [stepping]="stepping structured mesh model"
    [api]="api stepping io model"
    [mpi]="mpi api stepping io structured mesh model"
    # Above the C API: C over the public header alone, and the run configuration.
    [config]="config"
    [bmi]="bmi config"
    [cli]="cli config"
)

failures=0
complain() {
    printf 'check_layers: %s\n' "$*" >&2
    failures=$((failures + 1))
}

for dir in "$src"/*/; do
    folder=$(basename "$dir")
    if [[ -z ${may_include[$folder]+set} ]]; then
        complain "src/$folder/ has no row in this script's table (and docs/architecture.md's): say what it may include"
        continue
    fi
    allowed=" ${may_include[$folder]} "
    while IFS= read -r file; do
        relative=${file#"$root"/}
        # Quoted includes name a header from src/ by its folder ("model/grid.hpp");
        # dpsm/ is the public API, which every folder may include.
        while IFS= read -r hit; do
            line=${hit%%:*}
            target=$(sed -n 's/.*include[[:space:]]*"\([^"]*\)".*/\1/p' <<<"${hit#*:}")
            [[ $target == */* ]] || continue
            included=${target%%/*}
            [[ $included == dpsm ]] && continue
            [[ $allowed == *" $included "* ]] ||
                complain "$relative:$line includes \"$target\": src/$folder/ may include only ${may_include[$folder]}"
        done < <(grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$file" || true)
        if [[ $folder != mpi ]] && grep -nE '^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]mpi\.h[>"]' "$file" >/dev/null; then
            complain "$relative includes an MPI header: only src/mpi/ may (libdpsm itself never depends on MPI)"
        fi
    done < <(find "$dir" -type f \( -name '*.hpp' -o -name '*.cpp' -o -name '*.h' -o -name '*.c' \) | sort)
done

if [[ $failures -gt 0 ]]; then
    printf 'check_layers: %d violation(s) of the floors of src/ (docs/architecture.md)\n' "$failures" >&2
    exit 1
fi
echo "check_layers: every folder of src/ includes only the folders below it"
