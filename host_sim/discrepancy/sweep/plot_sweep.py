#!/usr/bin/env python3
"""The robustness sweep's heat map: one row per effect and size, one column per procedure, each
cell its success rate (green all judged right, red none), the cell's text "right" or the first
criterion missed (with the rate when a cell holds several cases). The sweep's planned cells not run yet are grey ("not run").
A cell marked † holds a case the true model itself cannot pass (the sweep's truth_reach).

usage: plot_sweep.py SWEEP_JSON OUT_PNG   (SWEEP_JSON: robustness_sweep.py summarise's sweep.json)"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    summary = json.load(open(sys.argv[1]))
    cells = summary["cells"]
    planned = [tuple(c) for c in summary.get("planned_cells", [])] + [(c["effect"], c["size"], c["procedure"]) for c in cells]
    rows = sorted({(e, s) for e, s, _ in planned}, key=lambda r: (r[0] in ("null", "pair"), r))
    procs = sorted({p for _, _, p in planned})
    grid = np.full((len(rows), len(procs)), np.nan)
    text = {(rows.index((e, s)), procs.index(p)): "not run" for e, s, p in planned}
    for c in cells:
        i, j = rows.index((c["effect"], c["size"])), procs.index(c["procedure"])
        grid[i, j] = c["success_rate"]
        missed = ", ".join(sorted(set(c.get("missed", []))))
        text[i, j] = ("right" if not missed else missed) if c["cases"] == 1 else \
            f"{100 * c['success_rate']:.0f} % of {c['cases']}" + (f" ({missed})" if missed else "")
    missed_by_truth = {(m["effect"], m["size"], m["procedure"]) for m in
                       (summary.get("truth_reach") or {}).get("missed_by_true_model", []) if "effect" in m}
    for e, s, p in missed_by_truth:
        i, j = rows.index((e, s)), procs.index(p)
        text[i, j] += " †"
    fig, ax = plt.subplots(figsize=(4.5 + 1.6 * len(procs), max(3.5, 1.2 + 0.32 * len(rows))))
    cmap = matplotlib.colormaps["RdYlGn"].copy()
    cmap.set_bad("#d0d0d0")
    ax.imshow(np.ma.masked_invalid(grid), cmap=cmap, vmin=0, vmax=1, aspect="auto")
    for (i, j), label in text.items():
        ax.text(j, i, label, ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(procs)), [f"procedure {p}" for p in procs])
    ax.set_yticks(range(len(rows)), [f"{e} {s}" for e, s in rows], fontsize=7)
    rate = "–" if summary["success_rate"] is None else f"{100 * summary['success_rate']:.0f} %"
    ax.set_title(f"discrepancy workflow, robustness sweep: {rate} of {summary['cases_judged']} cases right"
                 + ("\n†: the true model itself does not halve the error" if missed_by_truth else ""), fontsize=9)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
