#!/usr/bin/env bash
# Install/consume test: installs a built dpsm to a temporary prefix and builds
# small programs against it from outside the source tree, as a user would.
#
#   usage: run.sh <build-dir> <source-dir>
#
#  1. cmake --install <build-dir> --prefix <tmp>/prefix
#  2. pkg-config: cc prog.c $(pkg-config --cflags --libs dpsm), also as C++ and
#     linked statically with `pkg-config --static`; each program is run.
#  3. CMake: a project with find_package(dpsm 0.1 CONFIG REQUIRED) linking
#     dpsm::dpsm and dpsm::dpsm_static; both programs are run; requests for
#     versions 1.0 and 0.99 must be refused.
#  4. Relocation: the prefix is moved elsewhere; no installed file may name the
#     old prefix, and the pkg-config and CMake builds must work from the new place.
#  5. Fortran (when the Fortran binding was built, i.e. dpsm-fortran.pc is
#     installed): $FC prog.f90 $(pkg-config --cflags --libs dpsm-fortran), run
#     through LD_LIBRARY_PATH and through an rpath; before and after the move.
#  6. Python: prog.py imports the installed package with PYTHONPATH=<its dir>
#     and no DPSM_LIBRARY; it must load the library installed next to it, with
#     numpy and with DPSM_NO_NUMPY=1; before and after the move. The Python
#     BMI conformance test (tests/python/test_bmi.py, test_config.py) runs
#     against the installed package too.
#  7. MPI (when the MPI component was built, i.e. dpsm-mpi.pc is installed):
#     $CC prog_mpi.c $(pkg-config --cflags --libs dpsm-mpi), run on 2 ranks;
#     before and after the move.
#
# Environment: CC, CXX; DPSM_FC (default $FC or gfortran), DPSM_PYTHON (default
# /usr/bin/python3 when it exists, else python3).
set -euo pipefail

if [[ $# -ne 2 ]]; then
    echo "usage: $0 <build-dir> <source-dir>" >&2
    exit 2
fi
build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
here=$src/tests/consume
CC=${CC:-cc}
CXX=${CXX:-c++}
FC=${DPSM_FC:-${FC:-gfortran}}
if [[ -n ${DPSM_PYTHON:-} ]]; then
    PYTHON=$DPSM_PYTHON
elif [[ -x /usr/bin/python3 ]]; then
    PYTHON=/usr/bin/python3
else
    PYTHON=python3
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/dpsm-consume.XXXXXX")
trap 'rm -rf "$work"' EXIT

say() { printf '== %s\n' "$*"; }
fail() {
    printf 'FAIL: %s\n' "$*" >&2
    exit 1
}
need() { command -v "$1" >/dev/null 2>&1 || fail "$1 is not installed"; }
need cmake
need pkg-config
need "$CC"
need "$CXX"
need readelf

version=$(sed -n 's/^#define DPSM_VERSION_STRING "\(.*\)"$/\1/p' "$build/include/dpsm/dpsm_version.h")
[[ -n $version ]] || fail "no DPSM_VERSION_STRING in $build/include/dpsm/dpsm_version.h"
soversion=${version%%.*}

# ---- 1. install -------------------------------------------------------------
say "cmake --install $build --prefix $work/prefix"
cmake --install "$build" --prefix "$work/prefix" >"$work/install.log" ||
    { cat "$work/install.log"; fail "cmake --install failed"; }

# Finds the one installed file called $2 under prefix $1 (lib or lib64 or lib/<triplet>).
installed() {
    local found
    found=$(find "$1" -name "$2" -print -quit)
    [[ -n $found ]] || fail "$2 was not installed under $1"
    printf '%s\n' "$found"
}
for f in dpsm.h dpsm_version.h "libdpsm.so.$soversion" libdpsm.a dpsm.pc dpsmConfig.cmake \
    dpsmConfigVersion.cmake dpsmTargets.cmake; do
    installed "$work/prefix" "$f" >/dev/null
done
[[ -f $work/prefix/include/dpsm/dpsm.h && -f $work/prefix/include/dpsm/dpsm_version.h ]] ||
    fail "the headers are not in <prefix>/include/dpsm"

# ---- 2. pkg-config ----------------------------------------------------------
# Builds and runs prog.c against the prefix $1 with pkg-config, into directory $2.
# The flags from pkg-config are split into words on purpose, as in a Makefile.
# shellcheck disable=SC2086
pkgconfig_build() {
    local prefix=$1 out=$2 pcdir libdir cflags libs static_libs
    mkdir -p "$out"
    pcdir=$(dirname "$(installed "$prefix" dpsm.pc)")
    export PKG_CONFIG_PATH=$pcdir
    say "pkg-config against $prefix (PKG_CONFIG_PATH=$pcdir)"

    [[ $(pkg-config --modversion dpsm) == "$version" ]] ||
        fail "pkg-config --modversion dpsm gives '$(pkg-config --modversion dpsm)', expected $version"
    [[ $(realpath "$(pkg-config --variable=prefix dpsm)") == "$(realpath "$prefix")" ]] ||
        fail "pkg-config prefix '$(pkg-config --variable=prefix dpsm)' is not $prefix"
    libdir=$(realpath "$(pkg-config --variable=libdir dpsm)")
    [[ -e $libdir/libdpsm.so ]] || fail "pkg-config libdir $libdir holds no libdpsm.so"
    cflags=$(pkg-config --cflags dpsm)
    libs=$(pkg-config --libs dpsm)
    echo "   cflags: $cflags"
    echo "   libs:   $libs"

    # C, shared, run through LD_LIBRARY_PATH.
    (cd "$out" && set -x && $CC -std=c99 -Wall -Wextra -Wpedantic -Werror "$here/prog.c" -o prog_c $cflags $libs -lm) 2>&1 ||
        fail "C build with pkg-config failed"
    [[ $(LD_LIBRARY_PATH=$libdir ldd "$out/prog_c") == *"libdpsm.so.$soversion => $libdir/"* ]] ||
        fail "prog_c does not load libdpsm.so.$soversion from $libdir"
    LD_LIBRARY_PATH=$libdir "$out/prog_c" || fail "prog_c (C, pkg-config) failed"

    # C++, shared, run through an rpath.
    (cd "$out" && set -x && $CXX -x c++ -std=c++11 -Wall -Wextra -Werror "$here/prog.c" -o prog_cxx $cflags $libs \
        -Wl,-rpath,"$libdir") 2>&1 || fail "C++ build with pkg-config failed"
    "$out/prog_cxx" || fail "prog_cxx (C++, pkg-config) failed"

    # C, static: libdpsm.a plus Libs.private (the C++ runtime).
    static_libs=$(pkg-config --static --libs dpsm | sed 's/-ldpsm\( \|$\)/-l:libdpsm.a\1/')
    (cd "$out" && set -x && $CC -std=c99 "$here/prog.c" -o prog_static $cflags $static_libs) 2>&1 ||
        fail "static C build with 'pkg-config --static' failed"
    if [[ $(readelf -d "$out/prog_static") == *"Shared library: [libdpsm"* ]]; then
        fail "prog_static still needs the shared libdpsm"
    fi
    "$out/prog_static" || fail "prog_static (C, static, pkg-config) failed"
    unset PKG_CONFIG_PATH
}

# Builds and runs the CMake project against the prefix $1, in directory $2.
cmake_build() {
    local prefix=$1 out=$2 found_dir libdir
    say "CMake find_package(dpsm 0.1 CONFIG REQUIRED) against $prefix"
    cmake -S "$here/cmake" -B "$out" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
        -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_C_COMPILER="$CC" >"$out.log" 2>&1 ||
        { cat "$out.log"; fail "configuring the CMake consumer failed"; }
    found_dir=$(sed -n 's/^dpsm_DIR:PATH=//p' "$out/CMakeCache.txt")
    [[ $(realpath "$found_dir") == "$(realpath "$prefix")"/* ]] ||
        fail "find_package found dpsm in $found_dir, not under $prefix"
    cmake --build "$out" >>"$out.log" 2>&1 || { cat "$out.log"; fail "building the CMake consumer failed"; }
    libdir=$(dirname "$(installed "$prefix" "libdpsm.so.$soversion")")
    [[ $(ldd "$out/consumer") == *"libdpsm.so.$soversion => $libdir/"* ]] ||
        fail "consumer does not load libdpsm.so.$soversion from $libdir through its rpath"
    "$out/consumer" || fail "consumer (CMake, dpsm::dpsm) failed"
    "$out/consumer_static" || fail "consumer_static (CMake, dpsm::dpsm_static) failed"
    if [[ $(readelf -d "$out/consumer_static") == *"Shared library: [libdpsm"* ]]; then
        fail "consumer_static still needs the shared libdpsm"
    fi
    cmake -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -P "$here/version_check.cmake" ||
        fail "the package version check failed"
}

# ---- 5. Fortran: dpsm-fortran.pc --------------------------------------------
# Builds and runs prog.f90 against the prefix $1 with pkg-config, into directory $2.
# shellcheck disable=SC2086
fortran_build() {
    local prefix=$1 out=$2 pc pcdir libdir cflags libs
    pc=$(find "$prefix" -name dpsm-fortran.pc -print -quit)
    if [[ -z $pc ]]; then
        say "Fortran: no dpsm-fortran.pc under $prefix (dpsm was built without Fortran): skipped"
        return 0
    fi
    need "$FC"
    installed "$prefix" dpsm.mod >/dev/null
    installed "$prefix" "libdpsm_fortran.so.$soversion" >/dev/null
    mkdir -p "$out"
    pcdir=$(dirname "$pc")
    export PKG_CONFIG_PATH=$pcdir
    say "Fortran: $FC prog.f90 \$(pkg-config --cflags --libs dpsm-fortran) against $prefix"
    [[ $(pkg-config --modversion dpsm-fortran) == "$version" ]] ||
        fail "pkg-config --modversion dpsm-fortran gives '$(pkg-config --modversion dpsm-fortran)', expected $version"
    libdir=$(realpath "$(pkg-config --variable=libdir dpsm-fortran)")
    [[ -e $libdir/libdpsm_fortran.so ]] || fail "pkg-config libdir $libdir holds no libdpsm_fortran.so"
    cflags=$(pkg-config --cflags dpsm-fortran)
    libs=$(pkg-config --libs dpsm-fortran)
    echo "   cflags: $cflags"
    echo "   libs:   $libs"

    # Shared, run through LD_LIBRARY_PATH.
    (cd "$out" && set -x && $FC -Wall -Werror "$here/prog.f90" -o prog_f $cflags $libs) 2>&1 ||
        fail "Fortran build with pkg-config failed"
    local deps
    deps=$(LD_LIBRARY_PATH=$libdir ldd "$out/prog_f")
    [[ $deps == *"libdpsm_fortran.so.$soversion => $libdir/"* && $deps == *"libdpsm.so.$soversion => $libdir/"* ]] ||
        fail "prog_f does not load libdpsm_fortran.so.$soversion and libdpsm.so.$soversion from $libdir: $deps"
    LD_LIBRARY_PATH=$libdir "$out/prog_f" || fail "prog_f (Fortran, pkg-config) failed"

    # Through an rpath only: libdpsm_fortran must find libdpsm next to itself.
    (cd "$out" && set -x && $FC "$here/prog.f90" -o prog_f_rpath $cflags $libs -Wl,-rpath,"$libdir") 2>&1 ||
        fail "Fortran build with an rpath failed"
    env -u LD_LIBRARY_PATH "$out/prog_f_rpath" || fail "prog_f_rpath (Fortran, rpath) failed"
    unset PKG_CONFIG_PATH
}

# ---- 6. Python: the installed package ---------------------------------------
# Imports the package installed under prefix $1 with PYTHONPATH alone and runs prog.py.
python_import() {
    local prefix=$1 pkgdir pydir libdir
    need "$PYTHON"
    pkgdir=$(dirname "$(installed "$prefix" _libpath.py)")
    [[ -f $pkgdir/__init__.py ]] || fail "$pkgdir has _libpath.py but no __init__.py"
    pydir=$(dirname "$pkgdir")
    libdir=$(dirname "$(installed "$prefix" "libdpsm.so.$soversion")")
    say "Python: PYTHONPATH=$pydir $PYTHON prog.py (no DPSM_LIBRARY)"
    env -u DPSM_LIBRARY -u DPSM_NO_NUMPY PYTHONPATH="$pydir" PYTHONDONTWRITEBYTECODE=1 \
        "$PYTHON" "$here/prog.py" "$libdir" || fail "the installed Python package failed"
    env -u DPSM_LIBRARY PYTHONPATH="$pydir" PYTHONDONTWRITEBYTECODE=1 DPSM_NO_NUMPY=1 \
        "$PYTHON" "$here/prog.py" "$libdir" || fail "the installed Python package failed without numpy"
    say "Python: the BMI conformance test (tests/python/test_bmi.py) against the installed package"
    (cd "$work" && env -u DPSM_LIBRARY -u DPSM_NO_NUMPY PYTHONPATH="$pydir:$src/tests/python" \
        PYTHONDONTWRITEBYTECODE=1 "$PYTHON" -m unittest -q test_bmi test_config) ||
        fail "the Python BMI conformance test failed against the installed package"
}

# ---- 7. MPI: dpsm-mpi.pc ----------------------------------------------------
# When the MPI component is installed: builds prog_mpi.c against prefix $1 with
# `pkg-config dpsm-mpi` (the plain C compiler: the .pc carries MPI's flags),
# into directory $2, and runs it on 2 ranks through an rpath.
# shellcheck disable=SC2086
mpi_build() {
    local prefix=$1 out=$2 pc libdir cflags libs deps
    pc=$(find "$prefix" -name dpsm-mpi.pc -print -quit)
    if [[ -z $pc ]]; then
        say "MPI: no dpsm-mpi.pc under $prefix (dpsm was built without MPI): skipped"
        return 0
    fi
    need mpiexec
    installed "$prefix" dpsm_mpi.h >/dev/null
    installed "$prefix" "libdpsm_mpi.so.$soversion" >/dev/null
    mkdir -p "$out"
    export PKG_CONFIG_PATH
    PKG_CONFIG_PATH=$(dirname "$pc")
    say "MPI: $CC prog_mpi.c \$(pkg-config --cflags --libs dpsm-mpi) against $prefix"
    [[ $(pkg-config --modversion dpsm-mpi) == "$version" ]] ||
        fail "pkg-config --modversion dpsm-mpi gives '$(pkg-config --modversion dpsm-mpi)', expected $version"
    libdir=$(realpath "$(pkg-config --variable=libdir dpsm-mpi)")
    cflags=$(pkg-config --cflags dpsm-mpi)
    libs=$(pkg-config --libs dpsm-mpi)
    (cd "$out" && set -x && $CC -Wall -Werror "$here/prog_mpi.c" -o prog_mpi $cflags $libs -lm -Wl,-rpath,"$libdir") 2>&1 ||
        fail "the MPI build with pkg-config failed"
    deps=$(ldd "$out/prog_mpi")
    [[ $deps == *"libdpsm_mpi.so.$soversion => $libdir/"* && $deps != *"libdpsm.so"* ]] ||
        fail "prog_mpi does not load libdpsm_mpi.so.$soversion (alone) from $libdir: $deps"
    env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 \
        mpiexec -n 2 --oversubscribe "$out/prog_mpi" || fail "prog_mpi (MPI, pkg-config) failed on 2 ranks"
    unset PKG_CONFIG_PATH
}

pkgconfig_build "$work/prefix" "$work/pc"
cmake_build "$work/prefix" "$work/cm"
fortran_build "$work/prefix" "$work/f"
python_import "$work/prefix"
mpi_build "$work/prefix" "$work/mpi"

# ---- 4. relocation ----------------------------------------------------------
say "relocation: no installed file names the prefix"
if grep -rl -- "$work/prefix" "$work/prefix"; then
    fail "the files above name the install prefix $work/prefix: the install is not relocatable"
fi
mkdir -p "$work/elsewhere/deeper"
mv "$work/prefix" "$work/elsewhere/deeper/moved"
[[ ! -e $work/prefix ]] || fail "the old prefix is still there"
pkgconfig_build "$work/elsewhere/deeper/moved" "$work/pc-moved"
cmake_build "$work/elsewhere/deeper/moved" "$work/cm-moved"
fortran_build "$work/elsewhere/deeper/moved" "$work/f-moved"
python_import "$work/elsewhere/deeper/moved"
mpi_build "$work/elsewhere/deeper/moved" "$work/mpi-moved"

say "install/consume checks passed"
