#!/usr/bin/env python3
"""How often the truth's contact force alternates from one world step to the next: a world check.

usage: force_chatter.py EVAL_DIR --out DIR [--threshold-n N]

For each case of an evaluation (EVAL_DIR/cases/NAME with truth.csv and summary.json, as `scopekin
evaluate` writes them) the study takes the truth's largest station force (max_station_force_N) at
the world's steps (every summary "time_step_s"; truth.csv interpolates the box's periods between
them) and counts the steps whose force lies more than --threshold-n (default 3 N) off the mean of
its two neighbours, |f_k - (f_k-1 + f_k+1) / 2| > N: period-2 chatter, a force that goes 0, 18, 0,
18 N from step to step (model/truth/README.md). A smooth force, even a fast one (a 20 N rise over
100 ms), stays far below it. Only the steps before the scope went through the wall are counted
(summary "truth"."scope_through_wall_s"), as the scorecard does.

Writes DIR/force_chatter.csv (a row per case: its style, the steps counted, the share chattering),
DIR/force_chatter.json (per physician style and over all cases: median / 90th percentile / worst
share, and the cases above 10 %) and DIR/force_chatter.png (each case's share; needs
python3-matplotlib, skipped with a note without it). Prints one line per case. Exit status 2 for
bad input (no complete case, a missing column), 3 if an output cannot be written.
"""
import argparse
import json
import os
import sys

import numpy as np

from case_columns import BadInput, case_folders, columns, complete_summary, write_rows


def case_style(name):
    """The physician style from the case's name (p1001-expert-s1 -> expert)."""
    parts = name.split("-")
    return parts[1] if len(parts) >= 3 else "other"


def chatter_share(folder, summary, threshold_n):
    """(steps counted, steps chattering) of one case."""
    step_s = summary.get("time_step_s")
    if not isinstance(step_s, (int, float)) or step_s <= 0:
        raise BadInput(f"{folder}/summary.json: no time_step_s")
    truth = columns(os.path.join(folder, "truth.csv"), ["time_s", "max_station_force_N"])
    t, f = truth["time_s"], truth["max_station_force_N"]
    through = (summary.get("truth") or {}).get("scope_through_wall_s")
    steps = np.abs(t / step_s - np.round(t / step_s)) < 1e-6  # the world's own steps
    if through is not None:
        steps &= t < through
    force = f[steps]
    force = force[np.isfinite(force)]
    if force.size < 3:
        return 0, 0
    off = np.abs(force[1:-1] - 0.5 * (force[:-2] + force[2:]))
    return int(off.size), int(np.count_nonzero(off > threshold_n))


def distribution(shares):
    if not shares:
        return None
    a = np.array(shares)
    return {"cases": int(a.size), "median": float(np.median(a)),
            "p90": float(np.percentile(a, 90)), "worst": float(a.max()),
            "cases_above_10_percent": int(np.count_nonzero(a > 0.10))}


def write_outputs(out, rows, report):
    os.makedirs(out, exist_ok=True)
    write_rows(os.path.join(out, "force_chatter.csv"), ["case", "style", "steps", "chattering", "share"], rows)
    with open(os.path.join(out, "force_chatter.json"), "w") as f:
        json.dump(report, f, indent=1)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("force_chatter: no python3-matplotlib, force_chatter.png not drawn", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(max(6.0, 0.3 * len(rows)), 3.5))
    colours = {"expert": "tab:blue", "trainee": "tab:red", "bench": "tab:green"}
    ax.bar(range(len(rows)), [100 * r["share"] for r in rows],
           color=[colours.get(r["style"], "tab:gray") for r in rows])
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels([r["case"] for r in rows], rotation=90, fontsize=7)
    ax.set_ylabel(f"world steps chattering [%]\n(> {report['threshold_N']:g} N off its neighbours)")
    ax.set_title("Period-2 chatter of the truth's largest station force")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "force_chatter.png"), dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("eval_dir")
    parser.add_argument("--out", required=True)
    parser.add_argument("--threshold-n", type=float, default=3.0)
    args = parser.parse_args()
    try:
        if not args.threshold_n > 0:
            raise BadInput(f"--threshold-n {args.threshold_n}: must be > 0")
        cases = case_folders(args.eval_dir)
        rows = []
        for k, (name, folder) in enumerate(cases):
            summary = complete_summary(folder)
            if summary is None:
                print(f"[{k + 1}/{len(cases)}] {name}: not a complete case, skipped", flush=True)
                continue
            steps, chattering = chatter_share(folder, summary, args.threshold_n)
            share = chattering / steps if steps else 0.0
            rows.append({"case": name, "style": case_style(name), "steps": steps,
                         "chattering": chattering, "share": share})
            print(f"[{k + 1}/{len(cases)}] {name}: {100 * share:.1f} % of {steps} steps", flush=True)
        if not rows:
            raise BadInput(f"{args.eval_dir}: no complete case (run `scopekin evaluate` first)")
    except BadInput as e:
        print(f"force_chatter: {e}", file=sys.stderr)
        return 2
    styles = sorted({r["style"] for r in rows})
    report = {"threshold_N": args.threshold_n,
              "all": distribution([r["share"] for r in rows]),
              "styles": {s: distribution([r["share"] for r in rows if r["style"] == s]) for s in styles}}
    try:
        write_outputs(args.out, rows, report)
    except OSError as e:
        print(f"force_chatter: cannot write {args.out}: {e}", file=sys.stderr)
        return 3
    for s, d in [("all", report["all"])] + list(report["styles"].items()):
        print(f"{s:8s} {d['cases']:3d} cases: median {100 * d['median']:.1f} %, 90th percentile "
              f"{100 * d['p90']:.1f} %, worst {100 * d['worst']:.1f} %, "
              f"{d['cases_above_10_percent']} above 10 %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
