#!/usr/bin/env python3
"""How much of auto's regret is the machine: two work_precision CSVs of the same problems
(two study runs), compared cell by cell where auto took the same path with the same
iterations in both, i.e. did the same work. For the median of the repeats (time_s, the
regret table's) and for the fastest repeat (time_min_s): the quantiles of run 2's regret over
run 1's, the cells whose regret is above 1.5x in one run and not in the other, and each run's
cells above 1.5x per tolerance. Regret and "reached" as in auto_regret_families.py.

    bench/regret_reproducibility.py RUN1.csv RUN2.csv
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from auto_regret_families import ratios  # noqa: E402

TOLS = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]


def regrets(rows, time_col):
    """(family, problem, tolerance) -> (auto / fastest own, auto's path and iterations)."""
    out = {}
    for fam in sorted({r["family"] for r in rows}):
        for tol in TOLS:
            for problem, c in ratios(rows, fam, tol, time_col).items():
                if "auto" in c and "own" in c:
                    out[(fam, problem, tol)] = (c["auto"] / c["own"], c["path"])
    return out


def quantile(v, q):
    return v[min(len(v) - 1, int(q * len(v)))]


def main(first, second):
    runs = [list(csv.DictReader(open(f))) for f in (first, second)]
    for time_col in ("time_s", "time_min_s"):
        a, b = (regrets(rows, time_col) for rows in runs)
        same = [k for k in a if k in b and a[k][1] == b[k][1]]
        ratio = sorted(b[k][0] / a[k][0] for k in same)
        crossing = [k for k in same if (a[k][0] > 1.5) != (b[k][0] > 1.5)]
        print(f"{time_col}: {len(same)} cells with the same path and iterations; regret run 2 / run 1: "
              f"p10 {quantile(ratio, 0.1):.2f}, median {quantile(ratio, 0.5):.2f}, "
              f"p90 {quantile(ratio, 0.9):.2f}, max {ratio[-1]:.2f}; above 1.5x in one run only: {len(crossing)}")
        for name, reg in (("run 1", a), ("run 2", b)):
            over = [sum(1 for k, v in reg.items() if k[2] == tol and v[0] > 1.5) for tol in TOLS]
            print(f"  {name}, cells above 1.5x per tolerance 1e-2..1e-10: " + " / ".join(map(str, over)))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
