#!/usr/bin/env bash
# `pip install .` from a source tree, offline, into a virtual environment
# made with --system-site-packages (Debian's setuptools and wheel serve):
#
#   tests/install/pip_install.sh <source dir> <work dir> <python3>
#
# Copies the source tree (so the build leaves nothing in it), makes the venv,
# runs `pip install --no-build-isolation --no-index`, then, from outside any
# source tree with PYTHONPATH empty and DPSM_LIBRARY unset, checks that
# `python -m dpsm --version` loads the library inside the installed package,
# that a small scene steps with its ledger closed, and that
# examples/python/pile.py runs. Exit 77 (skipped) without python3-venv.
set -euo pipefail
src=$(cd "$1" && pwd)
work=$2 python=$3
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)

if ! "$python" -c 'import ensurepip, venv' 2>/dev/null; then
    echo "SKIP: $python has no venv/ensurepip: apt-get install python3-venv"
    exit 77
fi

# The tracked files only, as a fresh clone has them.
mkdir -p "$work/src"
if git -C "$src" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git -C "$src" ls-files -z --cached --others --exclude-standard | (cd "$src" && xargs -0 cp --parents -t "$work/src")
else
    tar -C "$src" --exclude='./build*' --exclude=./.git -cf - . | tar -C "$work/src" -xf -
fi

"$python" -m venv --system-site-packages "$work/venv"
venv_python=$work/venv/bin/python
# pip and the build see no PYTHONPATH and no DPSM_LIBRARY: only what they install counts.
clean=(env -u DPSM_LIBRARY -u PYTHONPATH -u PIP_INDEX_URL -u PIP_EXTRA_INDEX_URL)
if ! "${clean[@]}" "$venv_python" -m pip install --no-build-isolation --no-index "$work/src" >"$work/pip.log" 2>&1; then
    tail -40 "$work/pip.log"
    echo "FAIL: pip install --no-build-isolation --no-index . failed"
    exit 1
fi
grep -E '^Successfully installed' "$work/pip.log"

failures=0
fail() {
    echo "FAIL: $*"
    failures=$((failures + 1))
}
outside=$work/elsewhere
mkdir -p "$outside"
run() { (cd "$outside" && "${clean[@]}" PYTHONPATH= MPLBACKEND=Agg "$venv_python" "$@"); }

version=$(run -m dpsm --version) || fail "python -m dpsm --version failed"
echo "python -m dpsm --version: $version"
site=$(run -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
[[ $version == "dpsm "*" loaded from $site/dpsm/libdpsm.so.0)" ]] ||
    fail "the library was not loaded from inside the installed package ($site/dpsm): $version"
[[ -f $site/dpsm/libdpsm.so.0 ]] || fail "the package does not carry libdpsm.so.0"

run - <<'PY' || fail "a small scene in the installed package"
import dpsm
with dpsm.Grid.create_2d(16, 12, 0.1, 0.1) as g:
    g.set_repose_angle(0.5)
    for side in (dpsm.XMIN, dpsm.XMAX, dpsm.YMIN, dpsm.YMAX):
        g.set_boundary(side, dpsm.OPEN)
    h = [[1.0 if 5 <= i <= 10 and 4 <= j <= 7 else 0.0 for i in range(16)] for j in range(12)]
    g.set_heights(h)
    before = g.get_mass(dpsm.MASS_TOTAL)
    g.step(0.5)
    total, outflow = g.get_mass(dpsm.MASS_TOTAL), g.get_mass(dpsm.MASS_OUTFLOW)
    assert abs(total + outflow - before) <= 1e-12 * before, (total, outflow, before)
    assert g.get_step_info(dpsm.INFO_SUBSTEPS) > 0
    print("stepped: total %.6f + outflow %.6f = %.6f" % (total, outflow, before))
PY

pile=$(run "$src/examples/python/pile.py" --save "$work/pile.png" 2>&1) || fail "examples/python/pile.py: $pile"
grep -qE "at rest +yes" <<<"$pile" || fail "examples/python/pile.py did not come to rest: $pile"
grep -q "loaded from\|dpsm $(cut -d' ' -f2 <<<"$version")" <<<"$pile" || fail "pile.py names no dpsm version: $pile"
[[ -s $work/pile.png ]] || echo "note: pile.py drew no PNG (no matplotlib in this venv?)"

[[ $failures == 0 ]] || { echo "$failures check(s) failed"; exit 1; }
echo "pip install: all checks passed"
