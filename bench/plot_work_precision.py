#!/usr/bin/python3
"""Figures and tables of the work-precision study (bench/work_precision.cpp).

Reads the CSV and writes
  docs/figures/wp_<group>.png        work-precision (residual vs time), one panel per problem,
                                     one line per solver
  docs/figures/profile_<family>.png  Dolan-More performance profiles at residual 1e-4, 1e-6, 1e-8
  docs/figures/summary_fc3d.png      problems solved vs target residual, per solver
  <tables>                           markdown: time to accuracy per problem (failures marked),
                                     solved counts and geometric means; spliced into
                                     docs/BENCHMARKS.md between BENCH-TABLES-BEGIN/END

"Time to accuracy" of a solver on a problem at a target is the median time of the FIRST
setting of its sweep (loosest tolerance, or fewest iterations) whose measured residual (the
core's natural map, the same for every solver) is <= the target; no such setting = failure.

Usage: bench/plot_work_precision.py CSV [--figures DIR] [--doc docs/BENCHMARKS.md]
       [--budget S]
Needs only Debian's python3-matplotlib (and numpy, which it pulls in).
"""
import argparse
import csv
import math
import os
import re
import sys
from collections import OrderedDict, defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TARGETS = [1e-4, 1e-6, 1e-8]

OURS = ["auto", "nlgs", "nlgs-sor1.3", "apgd", "newton", "pgs", "lemke", "pgs-pyramid4", "lemke-pyramid4"]
PEERS = ["siconos-nsgs", "siconos-nsn-ac", "siconos-prox", "siconos-lemke", "siconos-pgs",
         "bullet-dantzig", "bullet-pgs"]

STYLE = {
    "auto": ("black", "-", "o"),
    "nlgs": ("tab:blue", "-", "o"),
    "nlgs-sor1.3": ("tab:cyan", "-", "v"),
    "apgd": ("tab:green", "-", "s"),
    "newton": ("tab:red", "-", "D"),
    "pgs": ("tab:blue", "-", "o"),
    "lemke": ("tab:purple", "-", "*"),
    "pgs-pyramid4": ("tab:olive", "-", "^"),
    "lemke-pyramid4": ("tab:purple", "-", "*"),
    "siconos-nsgs": ("tab:orange", "--", "o"),
    "siconos-nsn-ac": ("tab:brown", "--", "D"),
    "siconos-prox": ("tab:pink", "--", "s"),
    "siconos-lemke": ("tab:gray", "--", "*"),
    "siconos-pgs": ("tab:orange", "--", "o"),
    "bullet-dantzig": ("darkgoldenrod", ":", "P"),
    "bullet-pgs": ("darkviolet", ":", "x"),
}

GROUPS = OrderedDict([
    ("fc3d_small", ("fc3d", re.compile(r"^(Rover|FC3D|FrictionContact3D|Confeti|NESpheres)"),
                    "fc3d, small (Rover, FC3D, Confeti, NESpheres)")),
    ("fc3d_large", ("fc3d", re.compile(r"^(Capsules|BoxesStack|OneObject|LMGC)"),
                    "fc3d, large (Capsules, BoxesStack, OneObject, LMGC)")),
    ("lcp", ("lcp", re.compile(r".*"), "LCP (Siconos test set)")),
    ("scenes", ("scenes", re.compile(r".*"), "scenes: box pyramids and sphere piles of growing size")),
])


def fnum(s):
    if s is None or s == "":
        return float("nan")
    if s == "inf":
        return float("inf")
    return float(s)


def read_rows(path):
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            for k in ("tolerance", "time_s", "time_min_s", "residual", "model_residual", "peer_error"):
                r[k] = fnum(r[k])
            for k in ("contacts", "rows", "iterations", "repeats", "converged"):
                r[k] = int(r[k])
            rows.append(r)
    return rows


def solver_order(names):
    order = [s for s in OURS + PEERS if s in names]
    return order + sorted(n for n in names if n not in order)


def is_peer(s):
    return s in PEERS or s.startswith("siconos") or s.startswith("bullet")


def measured(r):
    return not math.isnan(r["time_s"]) and not math.isnan(r["residual"])


def time_to_accuracy(rows, target):
    """{(problem, solver): time or None} from the first setting reaching the target."""
    out = {}
    by = defaultdict(list)
    for r in rows:
        by[(r["problem"], r["solver"])].append(r)
    for key, rs in by.items():
        t = None
        for r in rs:  # CSV order = sweep order, loosest first
            if measured(r) and r["residual"] <= target:
                t = r["time_s"]
                break
        out[key] = t
    return out


def problems_of(rows):
    seen = OrderedDict()
    for r in rows:
        seen.setdefault(r["problem"], (r["contacts"], r["rows"]))
    return seen


def plot_work_precision(rows, group, title, figdir):
    probs = list(problems_of(rows).items())
    if not probs:
        return None
    solvers = solver_order({r["solver"] for r in rows})
    n = len(probs)
    cols = 4 if n > 6 else (3 if n > 2 else n)
    nrows = int(math.ceil(n / cols))
    height = 3.4 * nrows + 1.5
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, height), squeeze=False)
    handles = {}
    for ax, (p, (nc, nr)) in zip(axes.flat, probs):
        for s in solvers:
            pts = [(r["time_s"], max(r["residual"], 1e-17)) for r in rows
                   if r["problem"] == p and r["solver"] == s and measured(r) and math.isfinite(r["residual"])]
            if not pts:
                continue
            color, ls, mk = STYLE.get(s, ("k", "-", "."))
            h, = ax.plot([x for x, _ in pts], [y for _, y in pts], linestyle=ls, marker=mk, color=color,
                         markersize=4, linewidth=1.2, label=s)
            handles[s] = h
        ax.set_xscale("log")
        ax.set_yscale("log")
        for t in TARGETS:
            ax.axhline(t, color="0.8", linewidth=0.6, zorder=0)
        ax.set_title(f"{p}  ({nc} c, {nr} rows)", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.grid(True, which="major", alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    for ax in axes[:, 0]:
        ax.set_ylabel("residual (natural map)", fontsize=8)
    for ax in axes[-1, :]:
        ax.set_xlabel("time [s] (median)", fontsize=8)
    order = [s for s in solvers if s in handles]
    fig.suptitle(f"Work-precision: {title}", y=1 - 0.08 / height, fontsize=12)
    fig.legend([handles[s] for s in order], order, loc="upper center", bbox_to_anchor=(0.5, 1 - 0.4 / height),
               ncol=min(8, len(order)), fontsize=9, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 1.1 / height))
    path = os.path.join(figdir, f"wp_{group}.png")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def performance_profile(rows, family, figdir, solvers_subset=None):
    solvers = solver_order({r["solver"] for r in rows})
    if solvers_subset:
        solvers = [s for s in solvers if s in solvers_subset]
    probs = list(problems_of(rows))
    fig, axes = plt.subplots(1, len(TARGETS), figsize=(5.2 * len(TARGETS), 5.4), squeeze=False)
    for ax, target in zip(axes[0], TARGETS):
        tta = time_to_accuracy(rows, target)
        ratios = defaultdict(list)
        for p in probs:
            times = {s: tta.get((p, s)) for s in solvers}
            ok = [t for t in times.values() if t is not None]
            if not ok:
                for s in solvers:
                    ratios[s].append(float("inf"))
                continue
            best = min(ok)
            for s in solvers:
                t = times[s]
                ratios[s].append(float("inf") if t is None else max(t, 1e-12) / max(best, 1e-12))
        tau_max = 1.0
        for s in solvers:
            fin = [r for r in ratios[s] if math.isfinite(r)]
            if fin:
                tau_max = max(tau_max, max(fin))
        tau_max = min(tau_max * 1.5, 1e5)
        for s in solvers:
            rs = sorted(ratios[s])
            xs, ys = [1.0], [0.0]
            for i, r in enumerate(rs):
                if not math.isfinite(r):
                    break
                xs += [r, r]
                ys += [ys[-1], (i + 1) / len(rs)]
            xs.append(tau_max)
            ys.append(ys[-1])
            color, ls, _ = STYLE.get(s, ("k", "-", "."))
            ax.step(xs, ys, where="post", color=color, linestyle=ls, linewidth=1.6, label=s)
        ax.set_xscale("log", base=2)
        ax.set_xlim(1, tau_max)
        ax.set_ylim(0, 1.02)
        ax.set_xlabel("τ (time / best time on the problem)")
        ax.set_title(f"residual ≤ {target:.0e}")
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel(f"fraction of {family} problems ({len(probs)})")
    h, lab = axes[0][0].get_legend_handles_labels()
    fig.suptitle(f"Dolan-Moré performance profiles, {family} ({len(probs)} problems)", y=0.99)
    fig.legend(h, lab, loc="upper center", bbox_to_anchor=(0.5, 0.93), ncol=min(8, len(lab)), fontsize=9,
               frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 0.86))
    path = os.path.join(figdir, f"profile_{family}.png")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def solved_vs_target(rows, family, figdir):
    solvers = solver_order({r["solver"] for r in rows})
    probs = list(problems_of(rows))
    targets = [10.0 ** (-k) for k in range(2, 11)]
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    for s in solvers:
        counts = []
        for t in targets:
            tta = time_to_accuracy(rows, t)
            counts.append(sum(1 for p in probs if tta.get((p, s)) is not None))
        color, ls, mk = STYLE.get(s, ("k", "-", "."))
        ax.plot(targets, counts, color=color, linestyle=ls, marker=mk, label=s)
    ax.set_xscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("target residual")
    ax.set_ylabel(f"problems solved (of {len(probs)})")
    ax.set_title(f"{family}: problems whose residual reached the target")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    path = os.path.join(figdir, f"summary_{family}.png")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def geomean(xs):
    xs = [x for x in xs if x is not None]
    if not xs:
        return None
    return math.exp(sum(math.log(max(x, 1e-9)) for x in xs) / len(xs))


def fmt_t(t):
    if t is None:
        return "✗"
    if t < 1e-3:
        return f"{t * 1e6:.0f} µs"
    if t < 1:
        return f"{t * 1e3:.3g} ms"
    return f"{t:.3g} s"


def table_time_to_accuracy(rows, target, budget):
    """Markdown table: problems x solvers, time to reach `target` (✗ failure, – not run)."""
    solvers = solver_order({r["solver"] for r in rows})
    tta = time_to_accuracy(rows, target)
    probs = problems_of(rows)
    head = "| problem | contacts | " + " | ".join(solvers) + " |"
    sep = "|---|---:|" + "---:|" * len(solvers)
    lines = [head, sep]
    for p, (nc, _) in probs.items():
        cells = []
        ts = [tta[(p, s)] for s in solvers if (p, s) in tta and tta[(p, s)] is not None]
        best = min(ts) if ts else None
        for s in solvers:
            if (p, s) not in tta:
                cells.append("–")
                continue
            t = tta[(p, s)]
            c = fmt_t(t)
            if t is not None and best is not None and t == best:
                c = f"**{c}**"
            cells.append(c)
        lines.append(f"| {p} | {nc} | " + " | ".join(cells) + " |")
    # summary rows
    solved = []
    gm = []
    for s in solvers:
        ran = [p for p in probs if (p, s) in tta]
        ok = [tta[(p, s)] for p in ran if tta[(p, s)] is not None]
        solved.append(f"{len(ok)}/{len(ran)}")
        pen = [tta[(p, s)] if tta[(p, s)] is not None else budget for p in ran]
        g = geomean(pen)
        gm.append(fmt_t(g) if g is not None else "–")
    lines.append("| **solved** | | " + " | ".join(solved) + " |")
    lines.append(f"| **geo. mean** (failure = {budget:g} s) | | " + " | ".join(gm) + " |")
    return "\n".join(lines)


def target_summary(rows, budget):
    """The two targets of the study on fc3d, as markdown lines and a dict of numbers."""
    out = []
    probs = list(problems_of(rows))
    solvers = solver_order({r["solver"] for r in rows})
    ours = [s for s in solvers if not is_peer(s)]
    peers = [s for s in solvers if is_peer(s)]
    for target in TARGETS:
        tta = time_to_accuracy(rows, target)
        solved = {s: {p for p in probs if tta.get((p, s)) is not None} for s in solvers}
        peer_union = set().union(*[solved[s] for s in peers]) if peers else set()
        ours_union = set().union(*[solved[s] for s in ours]) if ours else set()
        out.append(f"**residual ≤ {target:.0e}** ({len(probs)} fc3d problems)\n")
        out.append("| solver | solved | geo. mean time, failures = budget | geo. mean on its solved problems |")
        out.append("|---|---:|---:|---:|")
        for s in solvers:
            pen = [tta.get((p, s)) if tta.get((p, s)) is not None else budget for p in probs]
            own = [tta.get((p, s)) for p in probs if tta.get((p, s)) is not None]
            out.append(f"| {s} | {len(solved[s])} | {fmt_t(geomean(pen))} | {fmt_t(geomean(own)) if own else '–'} |")
        out.append("")
        out.append(f"- solved by some peer: {len(peer_union)}; by some solver of ours: {len(ours_union)}; "
                   f"solved by a peer but by none of ours: {sorted(peer_union - ours_union) or 'none'}")
        for s in ("auto",) + tuple(x for x in ("newton", "nlgs", "apgd") if x in ours):
            if s in solved:
                missing = sorted(peer_union - solved[s])
                out.append(f"- `{s}` misses {len(missing)} problem(s) some peer solves: {missing or 'none'}")
        # head-to-head geometric mean ratio vs the fastest peer, on problems both solve
        if peers:
            best_peer = min(peers, key=lambda s: geomean([tta.get((p, s)) if tta.get((p, s)) is not None
                                                          else budget for p in probs]))
            for s in [x for x in ("auto", "newton", "nlgs") if x in ours]:
                both = [p for p in probs if tta.get((p, s)) is not None and tta.get((p, best_peer)) is not None]
                if both:
                    g_s = geomean([tta[(p, s)] for p in both])
                    g_b = geomean([tta[(p, best_peer)] for p in both])
                    out.append(f"- `{s}` vs fastest peer `{best_peer}` on the {len(both)} problems both solve: "
                               f"{fmt_t(g_s)} vs {fmt_t(g_b)} (ratio {g_s / g_b:.2f})")
            # virtual best of ours vs virtual best of peers
            vb_o = {p: min([tta[(p, s)] for s in ours if tta.get((p, s)) is not None], default=None) for p in probs}
            vb_p = {p: min([tta[(p, s)] for s in peers if tta.get((p, s)) is not None], default=None) for p in probs}
            both = [p for p in probs if vb_o[p] is not None and vb_p[p] is not None]
            if both:
                out.append(f"- best of ours per problem vs best peer per problem, {len(both)} common problems: "
                           f"{fmt_t(geomean([vb_o[p] for p in both]))} vs {fmt_t(geomean([vb_p[p] for p in both]))}")
        out.append("")
    return "\n".join(out)


def splice(doc, text):
    begin, end = "<!-- BENCH-TABLES-BEGIN -->", "<!-- BENCH-TABLES-END -->"
    if not os.path.exists(doc):
        return False
    s = open(doc).read()
    if begin not in s or end not in s:
        return False
    a = s.index(begin) + len(begin)
    b = s.index(end)
    open(doc, "w").write(s[:a] + "\n" + text + "\n" + s[b:])
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--figures", default="docs/figures")
    ap.add_argument("--doc", default="docs/BENCHMARKS.md")
    ap.add_argument("--tables", default="bench/results/tables.md")
    ap.add_argument("--budget", type=float, default=2.0)
    args = ap.parse_args()

    rows = read_rows(args.csv)
    os.makedirs(args.figures, exist_ok=True)
    written = []
    for group, (family, pattern, title) in GROUPS.items():
        sub = [r for r in rows if r["family"] == family and pattern.match(r["problem"])]
        p = plot_work_precision(sub, group, title, args.figures)
        if p:
            written.append(p)
    tables = ["<!-- generated by bench/plot_work_precision.py from the CSV; do not edit by hand -->", ""]
    for family in ("fc3d", "scenes", "lcp"):
        sub = [r for r in rows if r["family"] == family]
        if not sub:
            continue
        written.append(performance_profile(sub, family, args.figures))
        written.append(solved_vs_target(sub, family, args.figures))
    fc3d = [r for r in rows if r["family"] == "fc3d"]
    if fc3d:
        tables += ["### The two targets on fc3d", "", target_summary(fc3d, args.budget)]
    for family in ("fc3d", "scenes", "lcp"):
        sub = [r for r in rows if r["family"] == family]
        if not sub:
            continue
        for target in ([1e-6, 1e-8] if family != "lcp" else [1e-8]):
            tables += [f"### Time to accuracy, {family}, residual ≤ {target:.0e}", "",
                       "Median time of the first setting of each solver's sweep whose measured residual "
                       f"reaches the target; ✗ = no setting reached it (failure), – = not run "
                       f"(not applicable). Fastest per problem in bold. Geometric means count a failure "
                       f"as the {args.budget:g} s budget.", "",
                       table_time_to_accuracy(sub, target, args.budget), ""]
    text = "\n".join(tables)
    os.makedirs(os.path.dirname(args.tables) or ".", exist_ok=True)
    with open(args.tables, "w") as f:
        f.write(text + "\n")
    spliced = splice(args.doc, text)
    for w in written:
        print("wrote", w)
    print("wrote", args.tables, "(spliced into " + args.doc + ")" if spliced else "")


if __name__ == "__main__":
    sys.exit(main())
