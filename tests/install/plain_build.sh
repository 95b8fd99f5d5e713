#!/usr/bin/env bash
# The plain build of the README with only a compiler and CMake:
#
#   tests/install/plain_build.sh <source dir> <work dir>
#
# Runs cmake in a mount namespace (unshare: user and mount namespaces) whose
# /usr/bin holds only copies of CMake, make and the C/C++ toolchain, so that doxygen,
# pkg-config (and through it CMocka), gfortran, python3, mpicc, abidw and clang
# are really absent, wherever CMake would look for them. Checks that
#   1. configuring prints one STATUS line for each part it skips (tests, docs,
#      the Fortran binding, the MPI component), naming the package to install;
#   2. the build and `cmake --install` succeed, and the install holds the
#      library, the header, the CMake and pkg-config files and the Python
#      package, and says in one line where the Python package went and what
#      to add to PYTHONPATH (no interpreter was found to ask);
#   3. asking for a part without its tools (-DDPSM_BUILD_TESTS=ON,
#      -DDPSM_BUILD_DOCS=ON, -DDPSM_BUILD_FORTRAN=ON) fails at configure time
#      naming libcmocka-dev, doxygen, gfortran.
# Exit 77 (skipped) where unprivileged user namespaces are not allowed.
set -euo pipefail
src=$(cd "$1" && pwd)
work=$2
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)

if ! unshare -rm true 2>/dev/null; then
    echo "SKIP: unshare -rm is not permitted here (no unprivileged user namespaces): cannot hide the tools"
    exit 77
fi

failures=0
fail() {
    echo "FAIL: $*"
    failures=$((failures + 1))
}

# What the plain build may use: CMake, make, and the compiler with its binutils.
keep=(cmake make sh bash dash cc c++ gcc g++ cpp as ld ld.bfd ld.gold ar ranlib nm strip objcopy objdump readelf
      x86_64-linux-gnu-gcc-ar x86_64-linux-gnu-gcc-ranlib x86_64-linux-gnu-gcc-nm gcc-ar gcc-ranlib gcc-nm)
for tool in cmake cc c++; do
    command -v "$tool" >/dev/null || { echo "FAIL: $tool is missing, so the plain build cannot run at all"; exit 1; }
done

# Copies of the kept tools (copies, not links: CMake takes the directory of
# its own executable for its prefix and would search it for everything).
tools=$work/tools
mkdir -p "$tools"
for name in "${keep[@]}"; do
    path=$(command -v "$name" 2>/dev/null) || continue
    [[ $path == /usr/bin/* || $path == /bin/* ]] || continue
    cp -L "$path" "$tools/$name"
    # The resolved name too: the compiler driver looks for x86_64-linux-gnu-gcc-12 and the like.
    real=$(readlink -f "$path")
    [[ -e $tools/$(basename "$real") ]] || cp -L "$path" "$tools/$(basename "$real")"
done

# Runs "$@" with /usr/bin (and /bin, which points there) replaced by the
# directory of those copies.
hidden() {
    unshare -rm bash -c 'mount --bind "$0" /usr/bin && PATH=/usr/bin exec "$@"' "$tools" "$@"
}

# The tools really are gone inside.
for tool in doxygen pkg-config gfortran python3 mpicc abidw clang; do
    if hidden bash -c "command -v $tool" >/dev/null 2>&1; then
        fail "$tool is still found inside the namespace"
    fi
done

build=$work/build prefix=$work/prefix
hidden cmake -S "$src" -B "$build" -DDPSM_TILE_KERNEL_OPTIONS="${DPSM_PLAIN_BUILD_KERNEL_OPTIONS:--O1}" \
    >"$work/configure.log" 2>&1 || { cat "$work/configure.log"; fail "configuring the plain build"; exit 1; }
echo "== configure (tools hidden): the dpsm lines"
grep '^-- dpsm' "$work/configure.log" || true

# One STATUS line per skipped part, naming the package.
expect_line() {
    local pattern=$1 what=$2 count
    count=$(grep -cE -- "$pattern" "$work/configure.log" || true)
    [[ $count == 1 ]] || fail "$what: expected one line matching \"$pattern\", found $count"
}
expect_line '^-- dpsm: the tests not built: .*libcmocka-dev' "tests"
expect_line '^-- dpsm: the API reference and the docs test not built: doxygen was not found.*apt-get install doxygen' "docs"
expect_line '^-- dpsm: the Fortran binding, its tests and its example not built: no Fortran compiler.*gfortran' "Fortran"
expect_line '^-- dpsm: MPI not found' "MPI"
expect_line '^-- dpsm: the Python tests not run: no Python 3 interpreter.*apt-get install python3' "Python"
grep -q 'CMake Warning' "$work/configure.log" && fail "the plain configure warns: $(grep -A3 'CMake Warning' "$work/configure.log")"

jobs=${DPSM_PLAIN_BUILD_JOBS:-2}
if ! hidden cmake --build "$build" --parallel "$jobs" >"$work/build.log" 2>&1; then
    tail -40 "$work/build.log"
    fail "building the plain build"
    exit 1
fi
echo "== build: $(tail -1 "$work/build.log")"
if ! hidden cmake --install "$build" --prefix "$prefix" >"$work/install.log" 2>&1; then
    cat "$work/install.log"
    fail "installing the plain build"
    exit 1
fi
echo "== install: the dpsm lines"
grep 'dpsm:' "$work/install.log" || true
for f in include/dpsm/dpsm.h include/dpsm/dpsm_version.h; do
    [[ -f $prefix/$f ]] || fail "the install lacks $f"
done
find "$prefix" -name 'libdpsm.so.0' | grep -q . || fail "the install lacks libdpsm.so.0"
find "$prefix" -name dpsmConfig.cmake | grep -q . || fail "the install lacks dpsmConfig.cmake"
find "$prefix" -name dpsm.pc | grep -q . || fail "the install lacks dpsm.pc"
pkgdir=$prefix/lib/python3/dist-packages
[[ -f $pkgdir/dpsm/__init__.py && -f $pkgdir/dpsm/_libpath.py ]] || fail "the install lacks the Python package in $pkgdir"
# One line naming where the Python package went and what to add (no interpreter to ask here).
count=$(grep -c "^-- dpsm: the Python package dpsm went to $pkgdir/dpsm" "$work/install.log" || true)
[[ $count == 1 ]] || fail "expected one line naming $pkgdir/dpsm, found $count"
grep -q "PYTHONPATH=$pkgdir" "$work/install.log" || fail "the install does not say what to add to PYTHONPATH"
if find "$prefix" -name '*fortran*' | grep -q .; then fail "a Fortran part was installed without a Fortran compiler"; fi

# Asking for a part without its tools fails at configure time, naming the package.
expect_refusal() {
    local option=$1 package=$2 log=$work/refuse-$1.log
    if hidden cmake -S "$src" -B "$work/refuse-$option" "-D$option=ON" >"$log" 2>&1; then
        fail "-D$option=ON configured without its tools"
    elif ! grep -q -- "$package" "$log"; then
        fail "-D$option=ON failed without naming $package: $(grep -A4 'CMake Error' "$log")"
    else
        echo "== -D$option=ON: refused, naming $package"
    fi
}
expect_refusal DPSM_BUILD_TESTS libcmocka-dev

# pkg-config present (a copy outside /usr/bin) but no cmocka.pc it can see:
# AUTO says CMocka is missing, ON fails naming libcmocka-dev.
if pkg_config=$(command -v pkg-config); then
    mkdir -p "$work/pkg-config-bin" "$work/no-pc-files"
    cp -L "$pkg_config" "$work/pkg-config-bin/pkg-config"
    export PKG_CONFIG_LIBDIR=$work/no-pc-files PKG_CONFIG_PATH=
    pc_option=-DPKG_CONFIG_EXECUTABLE=$work/pkg-config-bin/pkg-config
    hidden cmake -S "$src" -B "$work/pc-auto" "$pc_option" >"$work/pc-auto.log" 2>&1 ||
        fail "configuring with pkg-config but without CMocka: $(grep -A4 'CMake Error' "$work/pc-auto.log")"
    grep -qE '^-- dpsm: the tests not built: CMocka was not found.*libcmocka-dev' "$work/pc-auto.log" ||
        fail "with pkg-config but without CMocka the line does not say CMocka is missing"
    if hidden cmake -S "$src" -B "$work/pc-on" "$pc_option" -DDPSM_BUILD_TESTS=ON \
        >"$work/pc-on.log" 2>&1; then
        fail "-DDPSM_BUILD_TESTS=ON configured with pkg-config but without CMocka"
    elif ! grep -q 'CMocka was not found' "$work/pc-on.log" || ! grep -q libcmocka-dev "$work/pc-on.log"; then
        fail "-DDPSM_BUILD_TESTS=ON without CMocka did not name libcmocka-dev: $(grep -A4 'CMake Error' "$work/pc-on.log")"
    else
        echo "== -DDPSM_BUILD_TESTS=ON with pkg-config but no CMocka: refused, naming libcmocka-dev"
    fi
fi
expect_refusal DPSM_BUILD_DOCS doxygen
expect_refusal DPSM_BUILD_FORTRAN gfortran

if [[ $failures -gt 0 ]]; then
    echo "$failures check(s) failed"
    exit 1
fi
echo "plain build: all checks passed"
