#!/usr/bin/env bash
# The C BMI conformance test against the installed component, as a framework
# meets it:
#
#   usage: run.sh <build-dir> <bmi_host>
#
#  1. cmake --install <build-dir> --prefix <tmp>/prefix (as tests/consume does)
#  2. the install has dpsm/bmi.h, libdpsm_bmi.so, dpsm-bmi.pc and the CMake
#     export, and the library exports register_bmi and register_bmi_dpsm only
#  3. <bmi_host> dlopen()s the installed libdpsm_bmi.so, with no
#     LD_LIBRARY_PATH (it finds libdpsm next to itself), and checks it
#  4. a C program built with `pkg-config --cflags --libs dpsm-bmi` calls
#     register_bmi_dpsm() through the installed header; so does one built by
#     CMake with find_package(dpsm) and dpsm::dpsm_bmi
set -euo pipefail

if [[ $# -ne 2 ]]; then
    echo "usage: $0 <build-dir> <bmi_host>" >&2
    exit 2
fi
build=$(cd "$1" && pwd)
host=$2
CC=${CC:-cc}
work=$(mktemp -d "${TMPDIR:-/tmp}/dpsm-bmi.XXXXXX")
trap 'rm -rf "$work"' EXIT
fail() {
    printf 'FAIL: %s\n' "$*" >&2
    exit 1
}

echo "== cmake --install $build --prefix $work/prefix"
cmake --install "$build" --prefix "$work/prefix" >"$work/install.log" ||
    { cat "$work/install.log"; fail "cmake --install failed"; }
lib=$(find "$work/prefix" -name libdpsm_bmi.so -print -quit)
[[ -n $lib ]] || fail "libdpsm_bmi.so was not installed"
[[ -f $work/prefix/include/dpsm/bmi.h ]] || fail "dpsm/bmi.h was not installed"
pc=$(find "$work/prefix" -name dpsm-bmi.pc -print -quit)
[[ -n $pc ]] || fail "dpsm-bmi.pc was not installed"
[[ -n $(find "$work/prefix" -name dpsmBmiTargets.cmake -print -quit) ]] || fail "dpsmBmiTargets.cmake was not installed"

exported=$(nm -D --defined-only "$lib" | awk 'NF >= 3 { sub(/@.*/, "", $3); print $3 }' | sort -u | tr '\n' ' ')
[[ $exported == "register_bmi register_bmi_dpsm " ]] ||
    fail "libdpsm_bmi.so exports '$exported', expected register_bmi and register_bmi_dpsm only"

# The installed dpsm program runs from the prefix, finding libdpsm through its rpath.
if [[ -x $work/prefix/bin/dpsm ]]; then
    [[ $(env -u LD_LIBRARY_PATH "$work/prefix/bin/dpsm" --version) == "dpsm "[0-9]* ]] ||
        fail "the installed dpsm program does not run"
fi

echo "== $host $lib"
env -u LD_LIBRARY_PATH "$host" "$lib" || fail "the conformance host failed"

# A sanitized build (scripts/sanitize) cannot serve the plain programs below:
# its library needs the sanitizer runtime loaded first.
if [[ $(ldd "$lib") == *libasan* || $(ldd "$lib") == *libtsan* ]]; then
    echo "== $lib is built with a sanitizer: the pkg-config and CMake consumers are skipped"
    exit 0
fi

echo "== pkg-config dpsm-bmi"
cat >"$work/prog.c" <<'PROG'
#include <dpsm/bmi.h>
#include <stdio.h>
#include <string.h>
int main(void) {
    Bmi model;
    char name[BMI_MAX_COMPONENT_NAME];
    if (register_bmi_dpsm(&model) != &model || model.get_component_name(&model, name) != BMI_SUCCESS) return 1;
    printf("component %s\n", name);
    return strcmp(name, "dpsm") != 0;
}
PROG
libdir=$(dirname "$lib")
# shellcheck disable=SC2046
(cd "$work" && PKG_CONFIG_PATH=$(dirname "$pc") $CC -std=c99 -Wall -Wextra -Werror prog.c -o prog \
    $(PKG_CONFIG_PATH=$(dirname "$pc") pkg-config --cflags --libs dpsm-bmi) -Wl,-rpath,"$libdir") ||
    fail "building against dpsm-bmi.pc failed"
"$work/prog" || fail "the pkg-config program failed"
echo "== CMake: find_package(dpsm) gives dpsm::dpsm_bmi"
mkdir -p "$work/cmake"
cp "$work/prog.c" "$work/cmake/prog.c"
cat >"$work/cmake/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.16)
project(bmi_consumer C)
find_package(dpsm 0.1 CONFIG REQUIRED)
add_executable(prog prog.c)
target_link_libraries(prog PRIVATE dpsm::dpsm_bmi)
CMAKE
cmake -S "$work/cmake" -B "$work/cmake/build" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
    >"$work/cmake.log" 2>&1 && cmake --build "$work/cmake/build" >>"$work/cmake.log" 2>&1 ||
    { cat "$work/cmake.log"; fail "the CMake consumer of dpsm::dpsm_bmi failed to build"; }
"$work/cmake/build/prog" || fail "the CMake consumer of dpsm::dpsm_bmi failed"
echo "== the C BMI conformance checks passed"
