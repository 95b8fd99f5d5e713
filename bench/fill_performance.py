#!/usr/bin/python3
"""Writes the tables of docs/performance.md from docs/data/speed_*.csv (the
output of bench/run_speed.sh), between the page's marker comments, so that the
page always shows the figures of the last run.

usage: /usr/bin/python3 bench/fill_performance.py DATA_DIR PAGE
"""
import csv
import os
import re
import sys


def rows(data, name):
    return list(csv.DictReader(open(os.path.join(data, f"speed_{name}.csv"))))


def speed_table(data):
    thr = rows(data, "throughput")
    out = ["| benchmark | dpsm | reference loop | vectorised loop | target | met? |",
           "| --- | --- | --- | --- | --- | --- |"]
    for n in sorted({int(r["n"]) for r in thr}):
        by = {int(r["threads"]): r for r in thr if int(r["n"]) == n}
        ref = float(by[1]["reference_mcells_per_s"])
        best = max(float(r["mcells_per_s"]) for r in by.values())
        target, met = "", ""
        if n == 2048:
            target = "1000 Mcells/s on 2 threads, and 8 x the reference"
            two = float(by[2]["mcells_per_s"]) if 2 in by else 0.0
            met = f"{'yes' if two >= 1000 else 'no'} ({two:.0f}); {'yes' if best >= 8 * ref else 'no'} ({best / ref:.0f} x)"
        cells = " / ".join(f"{float(by[t]['mcells_per_s']):.0f}" for t in sorted(by))
        vec = " / ".join(f"{float(by[t]['vectorised_mcells_per_s']):.0f}" for t in sorted(by)
                         if by[t].get("vectorised_mcells_per_s"))
        out.append(f"| throughput {n}^2, Mcells/s on {' / '.join(str(t) for t in sorted(by))} threads | {cells} | "
                   f"{ref:.1f} | {vec} | {target} | {met} |")
    sp = rows(data, "sparse")[0]
    ratio = float(sp["ratio"])
    out.append(f"| sparse {sp['n']}^2, {100 * float(sp['slip_face_fraction']):.1f} % of cells on slip faces: a sub-step "
               f"against a fully active one ({100 * float(sp['cells_visited_fraction']):.1f} % of cells visited) | "
               f"{100 * ratio:.1f} % | | | 3 % | {'yes' if ratio <= 0.03 else 'no'} |")
    idle = rows(data, "idle")[0]
    r = float(idle["ratio"])
    out.append(f"| idle {idle['n']}^2: seconds per dpsm_step (against a fully active sub-step) | "
               f"{float(idle['idle_s_per_step']):.1e} s ({r:.1e}) | | | 1/1000 | {'yes' if r <= 1e-3 else 'no'} |")
    cone = rows(data, "cone")
    ref = {r["tolerance"]: r for r in cone if r["method"] == "reference"}
    for r in (r for r in cone if r["method"] in ("dpsm", "dpsm-to-rest")):
        s, err = float(r["seconds"]), float(r["top_error_percent"])
        rs = ref.get(r["tolerance"])
        met = "yes" if s <= 0.02 and abs(err) <= 0.5 else f"no: {s / 0.02:.1f} x too slow" if abs(err) <= 0.5 else "no"
        fast = r["method"] == "dpsm-to-rest"
        how = "relaxed to rest (DPSM_RELAX_TO_REST)" if fast else \
            "to rest by time-accurate sub-steps (the default)"
        work = "flux evaluations" if fast else "sub-steps"
        out.append(f"| cone 101^2 {how} at 33 deg, tolerance {r['tolerance']}: seconds, top ({float(r['top']):.3f}, "
                   f"exact 22.89) | {s:.3f} s, {err:+.2f} % ({r['substeps']} {work}) | "
                   f"{float(rs['seconds']):.3f} s | | 0.02 s, 0.5 % | {met} |" if rs else "")
    if os.path.exists(os.path.join(data, "speed_deposits.csv")):
        dep = rows(data, "deposits")
        for rounds in sorted({r.get("rounds", "1") for r in dep}, key=int):
            by = {r["method"]: r for r in dep if r.get("rounds", "1") == rounds}
            timed, relaxed = by.get("dpsm-default"), by.get("dpsm-to-rest")
            if not (timed and relaxed):
                continue
            what = (f"{timed['deposits']} heaps of 10^2 cells dropped one by one on {timed['n']}^2"
                    if rounds == "1" else
                    f"{int(timed['deposits']) * int(rounds)} such heaps on {timed['deposits']} growing piles")
            out.append(f"| {what}, each stepped to rest: seconds by the default (time-accurate) / relaxed to rest | "
                       f"{float(timed['seconds']):.3f} s ({timed['substeps']} sub-steps) / "
                       f"{float(relaxed['seconds']):.3f} s ({relaxed['substeps']} flux evaluations) | | | | |")
    if os.path.exists(os.path.join(data, "speed_wind.csv")):
        w = rows(data, "wind")[0]
        ratio, with_source = float(w["ratio"]), float(w["ratio_with_source"])
        out.append(f"| wind {w['n']}^2: a dune field, a source on every cell, {100 * float(w['slip_face_fraction']):.1f} % "
                   f"of cells on slip faces; a call of {w['substeps']} sub-steps against as many fully active ones "
                   f"({100 * float(w['cells_visited_fraction']):.1f} % of cells visited per sub-step; with "
                   f"dpsm_set_source before it) | {100 * ratio:.1f} % ({100 * with_source:.1f} %) | "
                   f"{100 * float(w['ratio_to_reference']):.2f} % of the reference's sub-steps | | 5 % | "
                   f"{'yes' if ratio <= 0.05 else 'no'} |")
    if os.path.exists(os.path.join(data, "speed_short.csv")):
        for r in rows(data, "short"):
            short, auto = float(r["short_over_long"]), float(r["default_over_time_accurate"])
            out.append(f"| short calls {r['n']}^2, {r['threads']} thread(s): Mcells/s of calls of one sub-step / of a "
                       f"call of 58 (time-accurate / default) | {float(r['short_mcells_per_s']):.0f} / "
                       f"{float(r['long_mcells_per_s']):.0f} / {float(r['default_long_mcells_per_s']):.0f} "
                       f"(short {short:.2f} x, default {auto:.2f} x) | {float(r['reference_mcells_per_s']):.1f} | | "
                       f"1.2 x, 1.25 x | {'yes' if short <= 1.2 else 'no'}, {'yes' if auto <= 1.25 else 'no'} |")
    return out


def steps_table(data):
    out = ["| scene | method | tolerance | sweeps | seconds | top | top error | deposit error (L1) | "
           "from explicit (L1) | at rest |",
           "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows(data, "steps"):
        exact = float(r["deposit_error_percent"])  # nan where no exact deposit is known
        top_error = f"{float(r['top_error_percent']):+.2f} %" if exact == exact else "(no exact top)"
        deposit = f"{exact:.2f} %" if exact == exact else ""
        out.append(f"| {r['scene']} | {r['method']} | {r['tolerance']} | {r['sweeps']} | {float(r['seconds']):.3f} | "
                   f"{float(r['top']):.4f} | {top_error} | {deposit} | "
                   f"{float(r['difference_from_explicit_percent']):.3f} % | {'yes' if r['at_rest'] == '1' else 'no'} |")
    return out


def fill(page, name, lines):
    pattern = re.compile(rf"(<!-- {name} table:[^\n]*-->\n).*?(<!-- end {name} table -->)", re.S)
    return pattern.sub(lambda m: m.group(1) + "\n".join(lines) + "\n" + m.group(2), page)


def main(data, target):
    page = open(target).read()
    page = fill(page, "speed", speed_table(data))
    page = fill(page, "steps", steps_table(data))
    open(target, "w").write(page)
    print(f"wrote the tables of {target}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
