#!/usr/bin/env bash
# `cmake --install` says in one line where the Python package went and, when
# the interpreter the build found does not look there, what to add:
#
#   tests/install/python_note.sh <build dir> <work dir> <python or "">
#
#  - to a fresh prefix: "... where <python> does not look: export PYTHONPATH=<dir>",
#    and with that PYTHONPATH the interpreter imports the installed package;
#  - to prefix /usr (staged under DESTDIR), on Debian: "... where <python> finds it".
set -euo pipefail
build=$1 work=$2 python=${3:-}
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)
failures=0
fail() {
    echo "FAIL: $*"
    failures=$((failures + 1))
}

prefix=$work/prefix dir=$work/prefix/lib/python3/dist-packages
cmake --install "$build" --prefix "$prefix" >"$work/install.log" 2>&1 || { cat "$work/install.log"; exit 1; }
grep 'dpsm: the Python package' "$work/install.log" || true
[[ $(grep -c 'dpsm: the Python package' "$work/install.log") == 1 ]] || fail "expected exactly one line about the Python package"
[[ -f $dir/dpsm/__init__.py ]] || fail "the package is not in $dir"
if [[ -n $python ]]; then
    grep -q "^-- dpsm: the Python package dpsm went to $dir/dpsm, where $python does not look: export PYTHONPATH=$dir\$" \
        "$work/install.log" || fail "the line does not say to export PYTHONPATH=$dir"
    # What the line says to add is enough (from elsewhere, no DPSM_LIBRARY).
    (cd "$work" && env -u DPSM_LIBRARY PYTHONPATH="$dir" "$python" -c \
        'import dpsm, sys; assert dpsm.__file__.startswith(sys.argv[1]), dpsm.__file__; print("imported", dpsm.__file__)' "$dir") ||
        fail "with PYTHONPATH=$dir the interpreter does not import the installed package"
    # Where Debian's interpreter looks (prefix /usr): it says so, and nothing to add.
    if env -u PYTHONPATH "$python" -c 'import sys; sys.exit(0 if "/usr/lib/python3/dist-packages" in sys.path else 1)'; then
        DESTDIR=$work/stage cmake --install "$build" --prefix /usr >"$work/install-usr.log" 2>&1 ||
            { cat "$work/install-usr.log"; exit 1; }
        grep 'dpsm: the Python package' "$work/install-usr.log" || true
        grep -q "^-- dpsm: the Python package dpsm went to /usr/lib/python3/dist-packages/dpsm, where $python finds it\$" \
            "$work/install-usr.log" || fail "prefix /usr: the line does not say the interpreter finds it"
        [[ -f $work/stage/usr/lib/python3/dist-packages/dpsm/__init__.py ]] || fail "DESTDIR: the package is not staged"
    fi
else
    grep -q "no Python interpreter was found to ask.*export PYTHONPATH=$dir" "$work/install.log" ||
        fail "without an interpreter the line does not say what to add"
fi
[[ $failures == 0 ]] || { echo "$failures check(s) failed"; exit 1; }
echo "python note: all checks passed"
