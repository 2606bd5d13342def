#!/usr/bin/python3
"""Plot a discrepancy report: writes outputs.png (measured vs model before and after),
residuals.png (residual before and after, held-out blocks shaded), candidates.png (the
candidates' held-out scores) and profiles.png (each candidate's screening profile: the lowest
training cost at each grid value of a parameter, the start and the fit; identifiability at a
glance) into DIR, from DIR/series.csv and DIR/report.json (or --report FILE). Each PNG is written
as NAME.part and renamed when complete."""
import argparse
import csv
import json
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(directory, report_path=None):
    series = defaultdict(lambda: defaultdict(list))
    with open(os.path.join(directory, "series.csv"), newline="") as f:
        for row in csv.DictReader(f):
            s = series[(row["output"], row["component"])]
            for key in ("time_s", "measured", "before", "after"):
                s[key].append(float(row[key]))
            s["held_out"].append(row["held_out"] == "1")
    with open(report_path or os.path.join(directory, "report.json")) as f:
        report = json.load(f)
    return series, report


def shade_held_out(ax, s):
    t, held = s["time_s"], s["held_out"]
    start = None
    for i, h in enumerate(held):
        if h and start is None:
            start = t[i]
        if (not h or i == len(held) - 1) and start is not None:
            ax.axvspan(start, t[i], color="0.9", zorder=0)
            start = None


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("directory")
    parser.add_argument("--quiet", action="store_true")
    parser.add_argument("--report", metavar="FILE",
                        help="read the report from FILE instead of DIR/report.json (scopekin discrepancy draws the "
                             "plots before it renames report.json.part, last of all)")
    args = parser.parse_args()
    series, report = load(args.directory, args.report)

    def save(fig, name):
        """Writes NAME.part and renames it: a PNG under its name is always complete."""
        path = os.path.join(args.directory, name)
        fig.savefig(path + ".part", dpi=110, format="png")
        os.replace(path + ".part", path)
        plt.close(fig)
    keys = sorted(series.keys())
    verdict = report["verdict"]
    named = ", ".join(e["name"] for e in report["effects"]) or "none"

    for name, value_of, title in (
        ("outputs.png", lambda s: (s["measured"], s["before"], s["after"]), "measured and model"),
        ("residuals.png", lambda s: ([m - b for m, b in zip(s["measured"], s["before"])],
                                     [m - a for m, a in zip(s["measured"], s["after"])]), "residual (measured - model)"),
    ):
        fig, axes = plt.subplots(len(keys), 1, figsize=(11, 1.7 * len(keys) + 1), sharex=True, squeeze=False)
        for ax, key in zip(axes[:, 0], keys):
            s = series[key]
            shade_held_out(ax, s)
            values = value_of(s)
            if len(values) == 3:
                ax.plot(s["time_s"], values[0], ".", ms=1.5, color="0.3", label="measured")
                ax.plot(s["time_s"], values[1], "-", lw=1, color="tab:red", label="model before")
                ax.plot(s["time_s"], values[2], "-", lw=1, color="tab:blue", label="model after")
            else:
                ax.plot(s["time_s"], values[0], "-", lw=0.8, color="tab:red", label="before")
                ax.plot(s["time_s"], values[1], "-", lw=0.8, color="tab:blue", label="after")
                ax.axhline(0, color="0.5", lw=0.5)
            ax.set_ylabel(f"{key[0]}\n{key[1]}" if key[0].endswith("_mm") else key[0], fontsize=7)
            ax.tick_params(labelsize=7)
        axes[0, 0].legend(fontsize=7, loc="upper right", ncol=3)
        axes[-1, 0].set_xlabel("time (s); grey: held-out blocks")
        fig.suptitle(f"{title}: verdict {verdict} ({named})")
        fig.tight_layout()
        save(fig, name)
        if not args.quiet:
            print(f"plot_discrepancy: wrote {os.path.join(args.directory, name)}", file=sys.stderr)

    fig, ax = plt.subplots(figsize=(9, 0.45 * (len(report["candidates"]) + 2) + 1.5))
    labels = ["(model as given)"] + [" + ".join(c["effects"]) for c in report["candidates"]]
    costs = [report["baseline"]["held_out_cost"]] + [c["held_out_cost"] if c["ok"] else float("nan")
                                                     for c in report["candidates"]]
    ax.barh(range(len(labels)), costs, color=["0.6"] + ["tab:blue"] * (len(labels) - 1))
    ax.axvline(report["baseline"]["noise_floor_cost"], color="tab:red", lw=1, label="noise alone")
    ax.set_yticks(range(len(labels)))
    ax.set_yticklabels(labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("held-out cost (sum over outputs of mean squared error / noise variance), log scale")
    ax.legend(fontsize=8)
    ax.set_title(f"candidates: verdict {verdict} ({named})")
    fig.tight_layout()
    save(fig, "candidates.png")
    if not args.quiet:
        print(f"plot_discrepancy: wrote {os.path.join(args.directory, 'candidates.png')}", file=sys.stderr)
    if plot_profiles(report, save, verdict, named) and not args.quiet:
        print(f"plot_discrepancy: wrote {os.path.join(args.directory, 'profiles.png')}", file=sys.stderr)


def profile_panels(report):
    """(effect, parameter, values, costs, start, fitted) per screened parameter with a grid."""
    fitted = {}
    for c in report["candidates"]:
        if len(c["effects"]) == 1 and c["ok"]:
            for p in c["parameters"][0]:
                if p.get("fitted"):
                    fitted.setdefault((c["effects"][0], p["name"]), p["value"])
    panels = []
    for c in report["screening"]["candidates"] if report.get("screening") else []:
        grid = c.get("grid")
        if not grid:
            continue
        for j, prof in enumerate(grid["profile"]):
            start = c["start_values"][j] if j < len(c.get("start_values", [])) else None
            panels.append((c["effect"], prof["parameter"], prof["values"], prof["lowest_training_cost"],
                           start, fitted.get((c["effect"], prof["parameter"]))))
    for c in report["screening"]["candidates"] if report.get("screening") else []:
        frequency = c.get("frequency")
        if frequency and frequency.get("scan"):
            # sigmoid_mobility: the training cost its six runs predict along the band; start: the
            # periodogram's frequency, fitted: the frequency kept.
            panels.append((c["effect"], "frequency_Hz (predicted from six runs)",
                           frequency["scan"]["frequency_Hz"], frequency["scan"]["predicted_cost"],
                           frequency.get("periodogram_Hz"), frequency.get("kept_Hz")))
    return panels


def plot_profiles(report, save, verdict, named):
    """profiles.png: one panel per screened parameter, log training cost along its grid."""
    panels = profile_panels(report)
    if not panels:
        return False
    cols = 3
    rows = (len(panels) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(11, 2.6 * rows + 0.8), squeeze=False)
    base = report["screening"].get("baseline_training_cost")
    for ax, (effect, parameter, values, costs, start, fit) in zip(axes.flat, panels):
        finite = [(v, c) for v, c in zip(values, costs) if c is not None and c == c and c != float("inf")]
        if finite:
            ax.plot([v for v, _ in finite], [c for _, c in finite], "o-", ms=3, lw=1, color="tab:blue",
                    label="grid (lowest over the others)")
        if base:
            ax.axhline(base, color="0.5", lw=0.8, ls="--", label="model as given")
        if start is not None:
            ax.axvline(start, color="tab:orange", lw=1, label="start")
        if fit is not None:
            ax.axvline(fit, color="tab:green", lw=1.2, label="fitted")
        ax.set_yscale("log")
        ax.set_title(f"{effect}\n{parameter}", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    axes[0, 0].legend(fontsize=6)
    fig.supylabel("training cost (log)", fontsize=8)
    fig.suptitle(f"screening profiles: verdict {verdict} ({named}); one clear dip: identified, flat: not")
    fig.tight_layout()
    save(fig, "profiles.png")
    return True


if __name__ == "__main__":
    main()
