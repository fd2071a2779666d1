#!/usr/bin/env python3
"""Per-family auto regret from a work_precision CSV (the rule of writeRegret in
auto_regret_table.cpp: a row reached a tolerance when its residual is <= it and it converged,
or is a direct / iteration-capped row). Siconos here = best of its fc3d and LCP methods. Families: fc3d, lcp, scenes, mujoco (those
present in the CSV).

    bench/auto_regret_families.py bench/results/work_precision_auto.csv [--figure PNG]

With --figure it also draws, per family, auto's time over the fastest of our solvers for
every problem and tolerance (one dot each; the lines are the issue's 1.2x and 1.5x), and the
same over the best Siconos method.
"""
import collections
import csv
import math
import sys

OWN = {"nlgs", "nlgs-sor1.3", "apgd", "newton", "prox", "pgs", "lemke", "pgs-pyramid4", "lemke-pyramid4"}


def reached(r, tol, time_col="time_s"):
    try:
        res, _ = float(r["residual"]), float(r[time_col])
    except ValueError:
        return False
    if not res <= tol:
        return False
    return r["status"] == "converged" or r["setting"] == "direct" or r["setting"].startswith("it=")


def geomean(v):
    return math.exp(sum(map(math.log, v)) / len(v)) if v else float("nan")


def ratios(rows, fam, tol, time_col="time_s"):
    """auto / fastest own and auto / best Siconos for every problem of `fam` at `tol`
    (times from `time_col`: the median of the repeats, or time_min_s, the fastest)."""
    cells = collections.defaultdict(dict)
    for r in rows:
        if r["family"] != fam:
            continue
        if r["tolerance"] != "" and abs(float(r["tolerance"]) - tol) > 1e-3 * tol:
            continue
        if not reached(r, tol, time_col):
            continue
        c, t, s = cells[r["problem"]], float(r[time_col]), r["solver"]
        if s == "auto":
            c["auto"] = t
            c["path"] = (r["path"], r["iterations"])
        elif s in OWN:
            c["own"] = min(c.get("own", math.inf), t)
        elif s.startswith("siconos"):
            c["sic"] = min(c.get("sic", math.inf), t)
    return cells


def figure(rows, families, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    tols = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
    fig, axes = plt.subplots(2, len(families), figsize=(4 * len(families), 7), sharey="row", squeeze=False)
    for col, fam in enumerate(families):
        for row, (key, label) in enumerate([("own", "auto / fastest own"), ("sic", "auto / best Siconos")]):
            ax = axes[row][col]
            for k, tol in enumerate(tols):
                cells = ratios(rows, fam, tol)
                v = [c["auto"] / c[key] for c in cells.values() if "auto" in c and key in c]
                ax.scatter([k] * len(v), v, s=10, alpha=0.6, color="C0")
                if v:
                    ax.scatter([k], [geomean(v)], marker="_", s=300, color="C3")
            for y in ([1.2, 1.5] if key == "own" else [0.5, 1.0]):
                ax.axhline(y, color="grey", lw=0.8, ls="--")
            ax.set_yscale("log")
            ax.set_xticks(range(len(tols)))
            ax.set_xticklabels([f"{t:.0e}" for t in tols], rotation=60, fontsize=7)
            ax.set_title(f"{fam}: {label}", fontsize=9)
    axes[0][0].set_ylabel("ratio (dots: problems, red: geometric mean)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(path, figure_path=None):
    rows = list(csv.DictReader(open(path)))
    print("| family | tolerance | auto / fastest own: geo mean (n) | max | > 1.5x | auto missed "
          "| auto / best Siconos: geo mean (n) | Siconos solved, auto not | fastest own / best Siconos |")
    print("|---|---|---|---|---|---|---|---|---|")
    families = [f for f in ["fc3d", "lcp", "scenes", "mujoco"] if any(r["family"] == f for r in rows)]
    for fam in families:
        for tol in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]:
            cells = ratios(rows, fam, tol)
            own = [c["auto"] / c["own"] for c in cells.values() if "auto" in c and "own" in c]
            missed = sum(1 for c in cells.values() if "own" in c and "auto" not in c)
            sic = [c["auto"] / c["sic"] for c in cells.values() if "auto" in c and "sic" in c]
            sic_only = sum(1 for c in cells.values() if "sic" in c and "auto" not in c)
            best = [c["own"] / c["sic"] for c in cells.values() if "own" in c and "sic" in c]
            worst = max(own) if own else float("nan")
            over = sum(1 for x in own if x > 1.5)
            print(f"| {fam} | {tol:.0e} | {geomean(own):.2f} ({len(own)}) | {worst:.2f} | {over} | {missed} "
                  f"| {geomean(sic):.2f} ({len(sic)}) | {sic_only} | {geomean(best):.2f} |")
    if figure_path:
        figure(rows, families, figure_path)

if __name__ == "__main__":
    args = sys.argv[1:]
    fig_path = None
    if "--figure" in args:
        i = args.index("--figure")
        fig_path = args[i + 1]
        del args[i : i + 2]
    main(args[0] if args else "bench/results/work_precision_auto.csv", fig_path)
