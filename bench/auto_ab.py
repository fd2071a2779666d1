#!/usr/bin/env python3
"""A/B of two builds of auto: auto-only work_precision runs of a base core and a variant
(`work_precision --solvers auto`, each core through LD_LIBRARY_PATH), compared cell by cell.
Several runs of one side (comma list) are pooled, each cell's fastest repeat (time_min_s)
over them: this machine's speed drifts by up to 1.6x within minutes, so alternate the runs
(base, variant, base, variant) and pool them.

    bench/auto_ab.py STUDY.csv BASE.csv[,BASE2.csv] VARIANT.csv[,VARIANT2.csv]

STUDY.csv is a full study (every solver): a cell's regret there (auto / fastest own, the
median time, as in the regret table) times the variant's time ratio estimates the variant's
regret where auto's work changed (below); where it did not, the ratio is the noise between
the runs and the regret is kept. Printed: per tolerance the geometric mean of the time
ratios over all cells and over the changed ones, and the cells above 1.5x before and after;
every changed cell; the spread of the ratio over the unchanged cells. The work compared is
auto's path and iterations, both the slowest island's on a problem solved by islands, and
the iterations summed over the islands (total_iterations; CSVs from before that column hide
a change on the other islands).
"""
import collections
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from auto_regret_families import reached  # noqa: E402
from regret_reproducibility import TOLS, quantile, regrets  # noqa: E402


def study_regrets(path):
    """(problem, tolerance) -> auto / fastest own, the regret table's (median times)."""
    rows = list(csv.DictReader(open(path)))
    return {(problem, tol): r[0] for (_, problem, tol), r in regrets(rows, "time_s").items()}


def pooled(paths):
    """(problem, tolerance) -> (fastest time over the runs, path, work), or None where a run
    did not reach the tolerance. The work: the slowest island's iterations, then (newer CSVs)
    "/" and all islands'."""
    out = {}
    for path in paths.split(","):
        for r in csv.DictReader(open(path)):
            if r["solver"] != "auto" or r["tolerance"] == "":
                continue
            tol = min(TOLS, key=lambda t: abs(math.log(t / float(r["tolerance"]))))
            key = (r["problem"], tol)
            if not reached(r, tol, "time_min_s"):
                out[key] = None
            elif out.get(key, 0) is not None:
                t = float(r["time_min_s"])
                if key not in out or t < out[key][0]:
                    total = r.get("total_iterations") or ""
                    out[key] = (t, r["path"], r["iterations"] + ("/" + total if total else ""))
    return out


def main(study, base_runs, variant_runs):
    regret = study_regrets(study)
    base, variant = pooled(base_runs), pooled(variant_runs)
    logs, logs_changed = collections.defaultdict(list), collections.defaultdict(list)
    above = collections.defaultdict(lambda: [0, 0])
    changed, same = [], []
    for key, b in sorted(base.items()):
        if key not in regret or key not in variant:
            continue
        v = variant[key]
        if (b is None) != (v is None):
            print(f"reached in one side only: {key[0]} {key[1]:g} (base {b is not None}, variant {v is not None})")
        if b is None or v is None:
            continue
        ratio, work_changed = v[0] / b[0], b[1:] != v[1:]
        logs[key[1]].append(math.log(ratio))
        if work_changed:
            logs_changed[key[1]].append(math.log(ratio))
        above[key[1]][0] += regret[key] > 1.5
        above[key[1]][1] += regret[key] * (ratio if work_changed else 1.0) > 1.5
        (changed if work_changed else same).append((ratio, key, b, v))
    for tol in TOLS:
        if logs[tol]:
            g = math.exp(sum(logs[tol]) / len(logs[tol]))
            c = logs_changed[tol]
            gc = f"{math.exp(sum(c) / len(c)):.3f} ({len(c)} cells)" if c else "-"
            print(f"{tol:g}: variant/base geo mean {g:.3f}, over the changed cells {gc}; "
                  f"cells above 1.5x {above[tol][0]} -> {above[tol][1]}")
    print(f"cells whose work changed: {len(changed)}")
    for ratio, key, b, v in sorted(changed):
        r = regret[key]
        print(f"  {key[0][:40]:40} {key[1]:<6g} x{ratio:.2f}  regret {r:.2f} -> {r * ratio:.2f}  "
              f"{b[1]}({b[2]}) -> {v[1]}({v[2]})")
    if same:
        s = sorted(x[0] for x in same)
        print(f"same work ({len(s)} cells), variant/base: p10 {quantile(s, 0.1):.2f}, "
              f"median {quantile(s, 0.5):.2f}, p90 {quantile(s, 0.9):.2f}")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
