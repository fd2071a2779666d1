#!/usr/bin/env python3
"""Per-family auto regret from a work_precision CSV (the rule of writeRegret in
auto_regret_table.cpp: a row reached a tolerance when its residual is <= it and it converged,
or is a direct / iteration-capped row). Siconos here = best of its fc3d and LCP methods.

    bench/auto_regret_families.py bench/results/work_precision_auto.csv
"""
import collections
import csv
import math
import sys

OWN = {"nlgs", "nlgs-sor1.3", "apgd", "newton", "prox", "pgs", "lemke", "pgs-pyramid4", "lemke-pyramid4"}


def reached(r, tol):
    try:
        res, _ = float(r["residual"]), float(r["time_s"])
    except ValueError:
        return False
    if not res <= tol:
        return False
    return r["status"] == "converged" or r["setting"] == "direct" or r["setting"].startswith("it=")


def geomean(v):
    return math.exp(sum(map(math.log, v)) / len(v)) if v else float("nan")


def main(path):
    rows = list(csv.DictReader(open(path)))
    print("| family | tolerance | auto / fastest own (n) | auto / best Siconos (n) | fastest own / best Siconos |")
    print("|---|---|---|---|---|")
    for fam in ["fc3d", "lcp", "scenes"]:
        for tol in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]:
            cells = collections.defaultdict(dict)
            for r in rows:
                if r["family"] != fam:
                    continue
                if r["tolerance"] != "" and abs(float(r["tolerance"]) - tol) > 1e-3 * tol:
                    continue
                if not reached(r, tol):
                    continue
                c, t, s = cells[r["problem"]], float(r["time_s"]), r["solver"]
                if s == "auto":
                    c["auto"] = t
                elif s in OWN:
                    c["own"] = min(c.get("own", math.inf), t)
                elif s.startswith("siconos"):
                    c["sic"] = min(c.get("sic", math.inf), t)
            own = [c["auto"] / c["own"] for c in cells.values() if "auto" in c and "own" in c]
            sic = [c["auto"] / c["sic"] for c in cells.values() if "auto" in c and "sic" in c]
            best = [c["own"] / c["sic"] for c in cells.values() if "own" in c and "sic" in c]
            print(f"| {fam} | {tol:.0e} | {geomean(own):.2f} ({len(own)}) | {geomean(sic):.2f} ({len(sic)}) | {geomean(best):.2f} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results/work_precision_auto.csv")
