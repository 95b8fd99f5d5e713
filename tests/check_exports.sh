#!/usr/bin/env bash
# Checks what the shared library exports:
#  - `nm -D --defined-only` shows only dpsm_* symbols,
#  - every function the header declares with DPSM_API is among them, and no
#    other dpsm_* symbol is,
#  - the SONAME is the expected one (libdpsm.so.<major>).
#
#   usage: check_exports.sh <libdpsm.so file> <expected SONAME> <dpsm.h>
set -euo pipefail

if [[ $# -ne 3 ]]; then
    echo "usage: $0 <shared library> <expected SONAME> <dpsm.h>" >&2
    exit 2
fi
lib=$1 expected_soname=$2 header=$3
status=0
indent() { sed 's/^/  /'; }

# Text (T), data (D, B, R...) and weak symbols alike; the version node
# names nm may print after '@' are stripped.
exported=$(nm -D --defined-only "$lib" | awk 'NF >= 3 { sub(/@.*/, "", $3); print $3 }' | sort -u)
if [[ -z $exported ]]; then
    echo "FAIL: $lib exports nothing" >&2
    exit 1
fi
stray=$(grep -v '^dpsm_' <<<"$exported" || true)
if [[ -n $stray ]]; then
    echo "FAIL: $lib exports symbols outside dpsm_*:" >&2
    indent <<<"$stray" >&2
    status=1
fi

declared=$(tr '\n' ' ' <"$header" | grep -o 'DPSM_API[^;(]*(' | grep -o 'dpsm_[A-Za-z0-9_]*[[:space:]]*($' |
    tr -d ' (' | sort -u)
missing=$(comm -23 <(printf '%s\n' "$declared") <(printf '%s\n' "$exported"))
extra=$(comm -13 <(printf '%s\n' "$declared") <(printf '%s\n' "$exported"))
if [[ -n $missing ]]; then
    echo "FAIL: declared with DPSM_API in $header but not exported:" >&2
    indent <<<"$missing" >&2
    status=1
fi
if [[ -n $extra ]]; then
    echo "FAIL: exported but not declared with DPSM_API in $header:" >&2
    indent <<<"$extra" >&2
    status=1
fi

soname=$(readelf -d "$lib" | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')
if [[ $soname != "$expected_soname" ]]; then
    echo "FAIL: SONAME of $lib is '$soname', expected '$expected_soname'" >&2
    status=1
fi

if [[ $status -eq 0 ]]; then
    echo "ok: $(wc -l <<<"$exported") symbols, all dpsm_* and all declared in $(basename "$header"); SONAME $soname"
fi
exit $status
