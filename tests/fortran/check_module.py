#!/usr/bin/env python3
"""Fails when the Fortran module drifts from the C header.

    check_module.py --header dpsm.h --version-header dpsm_version.h
                    --module dpsm.f90 --module-include dpsm_version.inc
                    --test test_fortran.f90 [--selftest]

Checks that
  - every function declared with DPSM_API in dpsm.h has a bind(C) interface
    with as many arguments, a public Fortran procedure of the same name, and is
    called by the test program;
  - every bind(C) interface of the module names a function of the header;
  - every #define constant of dpsm.h is a Fortran parameter of the same name
    and value, and the version macros of dpsm_version.h are there too
    (DPSM_VERSION_NUMBER and DPSM_VERSION_STRING as DPSM_HEADER_VERSION_*).
--selftest also checks that made-up drift (a new function, a new constant, a
changed value, a function the test does not call) is caught.
"""

import argparse
import re
import sys


def strip_c_comments(text):
    return re.sub(r"/\*.*?\*/", " ", text, flags=re.S)


def header_functions(header):
    """{name: number of parameters} of the DPSM_API declarations."""
    text = " ".join(strip_c_comments(header).split())
    functions = {}
    for m in re.finditer(r"DPSM_API\s+[^;(]*?\b(dpsm_\w+)\s*\(([^)]*)\)\s*;", text):
        params = m.group(2).strip()
        functions[m.group(1)] = 0 if params in ("", "void") else len(params.split(","))
    return functions


def header_constants(header):
    """{name: value text} of the object-like #define DPSM_* of the header."""
    constants = {}
    for line in header.splitlines():
        m = re.match(r"\s*#\s*define\s+(DPSM_\w+)(?!\()\s+(.*)$", line)
        if not m or m.group(1) in ("DPSM_API", "DPSM_DPSM_H", "DPSM_VERSION_H"):
            continue
        value = strip_c_comments(m.group(2)).split("//")[0].strip()
        if value:
            constants[m.group(1)] = value
    return constants


def strip_fortran_comments(text):
    lines = []
    for line in text.splitlines():
        out, quote = [], None
        for ch in line:
            if quote:
                if ch == quote:
                    quote = None
            elif ch in "'\"":
                quote = ch
            elif ch == "!":
                break
            out.append(ch)
        lines.append("".join(out))
    # Join continuation lines.
    return re.sub(r"&\s*\n\s*&?", " ", "\n".join(lines))


def fortran_parameters(source):
    """{lower-case name: value text} of the named constants."""
    params = {}
    for m in re.finditer(r"parameter[^:\n]*::\s*(\w+)\s*=\s*([^\n]+)", source, flags=re.I):
        params[m.group(1).lower()] = m.group(2).strip()
    return params


def fortran_bindings(source):
    """{C name: number of dummy arguments} of the bind(C) interfaces."""
    bindings = {}
    pattern = r"(?:function|subroutine)\s+\w+\s*\(([^)]*)\)\s*bind\s*\(\s*c\s*,\s*name\s*=\s*['\"](\w+)['\"]\s*\)"
    for m in re.finditer(pattern, source, flags=re.I):
        args = m.group(1).strip()
        bindings[m.group(2)] = 0 if not args else len(args.split(","))
    return bindings


def fortran_public(source):
    names = set()
    for m in re.finditer(r"^\s*public\s*::\s*([^\n]+)", source, flags=re.I | re.M):
        names.update(n.strip().lower() for n in m.group(1).split(","))
    for m in re.finditer(r"^[^\n!]*\bpublic\b[^\n:]*::\s*(\w+)", source, flags=re.I | re.M):
        names.add(m.group(1).lower())
    return names


def fortran_procedures(source):
    """Lower-case names of the module's procedures and generic interfaces."""
    names = set()
    for m in re.finditer(r"^\s*(?:[\w(),\s]*\s)?(?:subroutine|function)\s+(\w+)", source, flags=re.I | re.M):
        names.add(m.group(1).lower())
    for m in re.finditer(r"^\s*interface\s+(\w+)", source, flags=re.I | re.M):
        names.add(m.group(1).lower())
    return names


def number(text):
    text = text.strip().strip("()")
    text = re.sub(r"_\w+$", "", text)  # a kind suffix: 1.0_c_double
    text = text.replace("d", "e").replace("D", "e")
    return float(text)


def check(header, version_header, module, module_include, test):
    problems = []
    module_src = strip_fortran_comments(module + "\n" + module_include)
    test_src = strip_fortran_comments(test)
    functions = header_functions(header)
    if not functions:
        problems.append("no DPSM_API function found in the header: the parser is broken")
    bindings = fortran_bindings(module_src)
    public = fortran_public(module_src)
    procedures = fortran_procedures(module_src)

    for name, nparams in sorted(functions.items()):
        if name not in bindings:
            problems.append("%s: declared in dpsm.h but no bind(C, name='%s') interface in the module" % (name, name))
        elif bindings[name] != nparams:
            problems.append("%s: %d parameters in dpsm.h, %d in the bind(C) interface" % (name, nparams, bindings[name]))
        if name not in public or name not in procedures:
            problems.append("%s: no public Fortran procedure or generic interface named %s" % (name, name))
        if not re.search(r"\b%s\s*\(" % name, test_src, flags=re.I):
            problems.append("%s: not called by the Fortran test program" % name)
    for name in sorted(bindings):
        if name.startswith("dpsm_") and name not in functions:
            problems.append("%s: the module binds it but dpsm.h does not declare it" % name)

    params = fortran_parameters(module_src)
    constants = header_constants(header)
    if not constants:
        problems.append("no #define constant found in the header: the parser is broken")
    for name, value in sorted(constants.items()):
        if name.lower() not in params:
            problems.append("%s: #define in dpsm.h but no Fortran parameter of that name" % name)
            continue
        try:
            same = number(value) == number(params[name.lower()])
        except ValueError:
            same = value == params[name.lower()]
        if not same:
            problems.append("%s: %s in dpsm.h but %s in the module" % (name, value, params[name.lower()]))

    versions = header_constants(version_header)
    renamed = {"DPSM_VERSION_NUMBER": "DPSM_HEADER_VERSION_NUMBER", "DPSM_VERSION_STRING": "DPSM_HEADER_VERSION_STRING"}
    for name, value in sorted(versions.items()):
        fname = renamed.get(name, name)
        if fname.lower() not in params:
            problems.append("%s: in dpsm_version.h but no Fortran parameter %s" % (name, fname))
        elif name == "DPSM_VERSION_STRING":
            if value.strip('"') != params[fname.lower()].strip("'\""):
                problems.append("%s: %s in dpsm_version.h but %s in the module" % (name, value, params[fname.lower()]))
        elif name != "DPSM_VERSION_NUMBER" and number(value) != number(params[fname.lower()]):
            problems.append("%s: %s in dpsm_version.h but %s in the module" % (name, value, params[fname.lower()]))
    return problems


def selftest(header, version_header, module, module_include, test):
    failures = []
    drifted = (
        header.replace("#endif /* DPSM_DPSM_H */", "")
        + "\nDPSM_API int dpsm_selftest_new_function(dpsm_grid *g,\n    double x);\n"
        + "#define DPSM_SELFTEST_NEW_CONSTANT 3\n"
    )
    drifted = re.sub(r"#define DPSM_MASS_OUTFLOW 3", "#define DPSM_MASS_OUTFLOW 4", drifted)
    problems = "\n".join(check(drifted, version_header, module, module_include, test))
    for expected in ("dpsm_selftest_new_function", "DPSM_SELFTEST_NEW_CONSTANT", "DPSM_MASS_OUTFLOW"):
        if expected not in problems:
            failures.append("drift in the header not caught: %s" % expected)
    untested = re.sub(r"\bdpsm_stable_dt\s*\(", "stable_dt_renamed(", test, flags=re.I)
    if "dpsm_stable_dt: not called" not in "\n".join(check(header, version_header, module, module_include, untested)):
        failures.append("a function the test does not call was not caught")
    unbound = re.sub(r"name='dpsm_step'", "name='dpsm_stepx'", module)
    problems = "\n".join(check(header, version_header, unbound, module_include, test))
    if "dpsm_step: declared in dpsm.h but no bind(C" not in problems or "dpsm_stepx" not in problems:
        failures.append("a missing or stale bind(C) interface was not caught")
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for option in ("header", "version-header", "module", "module-include", "test"):
        parser.add_argument("--" + option, required=True)
    parser.add_argument("--selftest", action="store_true")
    args = parser.parse_args()
    texts = []
    for path in (args.header, args.version_header, args.module, args.module_include, args.test):
        with open(path, encoding="utf-8") as f:
            texts.append(f.read())
    problems = check(*texts)
    for p in problems:
        print("FAIL: " + p, file=sys.stderr)
    if args.selftest:
        for p in selftest(*texts):
            print("FAIL (selftest): " + p, file=sys.stderr)
            problems.append(p)
    if problems:
        return 1
    print("ok: %d functions and %d constants of dpsm.h are in the Fortran module and its test"
          % (len(header_functions(texts[0])), len(header_constants(texts[0]))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
