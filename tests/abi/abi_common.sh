# shellcheck shell=bash
# Shared by tests/abi/check and tests/abi/update-baseline (source it).
#
# The ABI baseline is three files:
#   libdpsm.abi    abidw's description of libdpsm.so: the exported functions and
#                  the public types they use (types defined outside the public
#                  headers, such as the inside of the opaque dpsm_grid, are
#                  dropped), from a build with debug information;
#   libdpsm_mpi.abi the same of libdpsm_mpi.so (every function of libdpsm and
#                  those of dpsm_mpi.h), checked when MPI is found;
#   constants.txt  the values of the header's enumeration macros (status codes,
#                  sides, kinds, ...), which compiled hosts carry in their own
#                  code and abidw cannot see.

# shellcheck disable=SC2034 # used by the scripts that source this file
# One set of options for writing and for comparing: no source locations or
# paths (they change with every edit and every checkout).
DPSM_ABIDW_FLAGS=(--exported-interfaces-only --drop-private-types --no-show-locs --no-corpus-path --no-comp-dir-path
                  --drop-undefined-syms --no-elf-needed --type-id-style hash)
# shellcheck disable=SC2034
DPSM_ABIDIFF_FLAGS=(--exported-interfaces-only --drop-private-types)

# dpsm_abi_build <source dir> <work dir> [C compiler] [C++ compiler]
# Configures (Debug: -g) and builds the shared library alone in <work dir>.
# Prints the path of the library.
dpsm_abi_build() {
    local src=$1 work=$2 cc=${3:-} cxx=${4:-} compilers=() generator=()
    [[ -n $cc ]] && compilers+=("-DCMAKE_C_COMPILER=$cc")
    [[ -n $cxx ]] && compilers+=("-DCMAKE_CXX_COMPILER=$cxx")
    mkdir -p "$work"
    if [[ ! -f $work/CMakeCache.txt ]] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
    cmake -S "$src" -B "$work" "${generator[@]}" "${compilers[@]}" -DCMAKE_BUILD_TYPE=Debug \
        -DDPSM_BUILD_TESTS=OFF -DDPSM_BUILD_DOCS=OFF -DDPSM_BUILD_EXAMPLES=OFF -DDPSM_BUILD_BENCH=OFF \
        -DDPSM_BUILD_FORTRAN=OFF -DDPSM_INSTALL_PYTHON=OFF --no-warn-unused-cli >"$work/configure.log" 2>&1 || {
        cat "$work/configure.log" >&2
        echo "error: configuring the debug build of the library failed" >&2
        return 1
    }
    cmake --build "$work" --target dpsm >"$work/build.log" 2>&1 || {
        cat "$work/build.log" >&2
        echo "error: building the debug build of the library failed" >&2
        return 1
    }
    # The MPI component too, where the configuration found MPI (its target exists).
    if grep -q '/src/mpi/' "$work/CMakeFiles/TargetDirectories.txt" 2>/dev/null; then
        cmake --build "$work" --target dpsm_mpi >>"$work/build.log" 2>&1 || {
            cat "$work/build.log" >&2
            echo "error: building the debug build of libdpsm_mpi failed" >&2
            return 1
        }
    fi
    local lib
    lib=$(find "$work/src" -maxdepth 1 -name 'libdpsm.so.*.*.*' -type f | head -n 1)
    [[ -n $lib ]] || {
        echo "error: no libdpsm.so.X.Y.Z in $work/src" >&2
        return 1
    }
    printf '%s\n' "$lib"
}

# dpsm_abi_mpi_lib <work dir>: the path of libdpsm_mpi.so.X.Y.Z that
# dpsm_abi_build made, or nothing when MPI was not found.
dpsm_abi_mpi_lib() {
    find "$1/src/mpi" -maxdepth 1 -name 'libdpsm_mpi.so.*.*.*' -type f 2>/dev/null | head -n 1
}

# dpsm_abi_headers <source dir> <work dir> [suffix]: the --headers-dir and
# --header-file arguments (abidw; abidiff's for its second file with suffix 2)
# that say which types are public, one a line.
dpsm_abi_headers() {
    printf '%s\n' "--headers-dir${3:-}" "$1/include/dpsm" "--header-file${3:-}" "$2/include/dpsm/dpsm_version.h"
}

# dpsm_abi_constants <source dir> <work dir> [C compiler]: "NAME VALUE" for
# every DPSM_* macro of dpsm.h but the include guard, DPSM_API, the version
# and the defaults, sorted.
dpsm_abi_constants() {
    local src=$1 work=$2 cc=${3:-cc}
    printf '#include <dpsm/dpsm.h>\n' |
        "$cc" -dM -E -I"$src/include" -I"$work/include" -x c - |
        awk '$1 == "#define" && $2 ~ /^DPSM_/ && $2 !~ /^DPSM_(DPSM_H|API|VERSION_|DEFAULT_|BUILDING_|STATIC_)/ {
                 name = $2; $1 = ""; $2 = ""; sub(/^ +/, ""); print name, $0 }' |
        LC_ALL=C sort
}
