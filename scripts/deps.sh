# shellcheck shell=bash
# Shared by scripts/demo and scripts/test (source it; do not run it).
#
# DPSM_APT_PACKAGES is the one list of Debian/Ubuntu packages the build and the
# test suite need beyond git, cmake and a C/C++ compiler. Add new needs here.
#
# Environment:
#   DPSM_BUILD_DIR   build directory (default: <repo>/build)
#   DPSM_SKIP_DEPS=1 do not check or install packages
#   DPSM_JOBS        parallel build jobs (default: all cores)

DPSM_APT_PACKAGES=(
    libcmocka-dev # tests: CMocka
    doxygen       # docs and the `docs` test
    pkg-config    # tests: finding cmocka, the install/consume test
    ninja-build   # the build
    gfortran           # the Fortran binding, its tests and example
    python3            # the Python binding's tests, the binding coverage checks
    python3-numpy      # the Python tests with numpy (Debian's /usr/bin/python3)
    python3-matplotlib # the Python example's plot
    python3-yaml       # dpsm.config: the YAML configuration of the Python BMI component and its tests
    python3-netcdf4    # dpsm.config: netCDF fields and UGRID meshes; tests/python/test_bmi.py's mesh
    python3-mpi4py     # dpsm.mpi (the Python binding of libdpsm_mpi) and its tests, tests/python/test_mpi.py
    python3-venv       # the install_pip test: pip install . into a venv (ensurepip)
    python3-setuptools # the install_pip test: pip install --no-build-isolation uses the system's setuptools
    python3-wheel      # the install_pip test: setuptools builds a wheel for pip
    clang              # scripts/sanitize: ThreadSanitizer and libFuzzer builds
    libclang-rt-14-dev # scripts/sanitize: clang's sanitizer and libFuzzer runtimes
    libomp-14-dev      # scripts/sanitize: OpenMP (libomp and its Archer tool) under ThreadSanitizer
    abigail-tools      # the `abi` test: abidw/abidiff against tests/abi/libdpsm.abi
    libopenmpi-dev     # the MPI component (libdpsm_mpi, dpsm_mpi.h): Open MPI's headers and libraries
    openmpi-bin        # mpiexec, which runs the MPI tests (tests/mpi) on 1, 2 and 4 ranks
    libmetis-dev       # the MPI mesh tests and benchmark partition meshes with METIS (dpsm itself does not need it)
    libyaml-dev        # the run configuration (src/config): libdpsm_bmi and dpsm run read YAML with libyaml
    libnetcdf-dev      # the run configuration's netCDF inputs and UGRID meshes, dpsm run's output
    netcdf-bin         # the dpsm_run test: ncgen makes its mesh, ncdump reads the output back
    libudunits2-dev    # the BMI tests: every variable's units parsed by UDUNITS-2 (C and Python), as frameworks parse them
)

DPSM_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
DPSM_BUILD_DIR=${DPSM_BUILD_DIR:-$DPSM_ROOT/build}

dpsm_say() { printf '>> %s\n' "$*"; }
dpsm_die() {
    printf 'error: %s\n' "$*" >&2
    exit 1
}

# Installs whatever in DPSM_APT_PACKAGES (plus cmake and a compiler, should
# they be missing) is not installed yet: dpkg -s first, one apt-get update, one
# apt-get install; sudo only when not root.
dpsm_install_deps() {
    if [[ ${DPSM_SKIP_DEPS:-0} == 1 ]]; then
        dpsm_say "DPSM_SKIP_DEPS=1: not checking packages"
        return 0
    fi
    if ! command -v dpkg >/dev/null 2>&1 || ! command -v apt-get >/dev/null 2>&1; then
        dpsm_say "no dpkg/apt-get here: install these yourself if missing: ${DPSM_APT_PACKAGES[*]}"
        return 0
    fi
    local wanted=("${DPSM_APT_PACKAGES[@]}") missing=() p
    command -v cmake >/dev/null 2>&1 || wanted+=(cmake)
    command -v c++ >/dev/null 2>&1 || wanted+=(g++)
    command -v cc >/dev/null 2>&1 || wanted+=(gcc)
    for p in "${wanted[@]}"; do
        dpkg -s "$p" 2>/dev/null | grep -q '^Status: install ok installed' || missing+=("$p")
    done
    if [[ ${#missing[@]} -eq 0 ]]; then
        dpsm_say "packages present: ${wanted[*]}"
        return 0
    fi
    local sudo=()
    if [[ $(id -u) -ne 0 ]]; then
        command -v sudo >/dev/null 2>&1 || dpsm_die "not root and no sudo: install ${missing[*]} first"
        sudo=(sudo)
    fi
    dpsm_say "installing: ${missing[*]}"
    "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q ||
        dpsm_die "apt-get update failed"
    "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}" ||
        dpsm_die "apt-get install ${missing[*]} failed"
}

# Configures (Release, Ninja) into DPSM_BUILD_DIR and builds with all cores.
# Arguments are passed to cmake (e.g. -DDPSM_BUILD_TESTS=ON). An existing
# build directory keeps the generator it was made with.
dpsm_configure_and_build() {
    local generator=()
    if [[ ! -f $DPSM_BUILD_DIR/CMakeCache.txt ]] && command -v ninja >/dev/null 2>&1; then
        generator=(-G Ninja)
    fi
    dpsm_say "configuring $DPSM_ROOT into $DPSM_BUILD_DIR"
    cmake -S "$DPSM_ROOT" -B "$DPSM_BUILD_DIR" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@" ||
        dpsm_die "configuring failed"
    local jobs=${DPSM_JOBS:-$(nproc 2>/dev/null || getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)}
    dpsm_say "building with $jobs jobs"
    cmake --build "$DPSM_BUILD_DIR" --parallel "$jobs" || dpsm_die "the build failed"
}
