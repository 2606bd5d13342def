#!/usr/bin/python3
"""Draw the plots of a scorecard written by `scopekin evaluate`: DIR/distributions.png,
DIR/worst_cases.png and, when the set has physician cases, DIR/procedures.png.

Usage: plot_evaluation.py DIR [--scorecard FILE] [--quiet]

distributions.png: per measure, one box plot per estimator over the cases (scorecard.csv: tip
position error RMS and max, largest contact force error RMS, loop alarm latency, false loop
alarms per 10 min, share of loop and contact force episodes detected within 0.5 s); a dot per
case on top of each box.
worst_cases.png: the three worst cases (scorecard.json "overall.worst_cases": by the box's
tip error), one column each, from the case's estimates.csv: the true and estimated
tip along the colon; the true loop episodes (shaded) with each estimator's loop alarm; the
true largest station force with the estimated one and each estimator's contact level.
procedures.png (physician cases only): the insertion at cecal intubation, a histogram per style
(100 mm bins, stacked) with the 1,330 mm of an intermediate colonoscope marked, and each style's
cecal intubation rate in the legend; without physician cases an older procedures.png is removed.
The scorecard is read from FILE (`scopekin evaluate` draws the plots from scorecard.json.part,
which it renames last). Each PNG is written as NAME.part, then renamed. Exit status: 0 ok, 2 a
missing or malformed input (the message names the file and line), 3 an output that cannot be
written.
"""
import argparse
import csv
import json
import math
import os
import sys
import textwrap

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_run import DPI, OI, InputError, OutputError, plt, save  # noqa: E402

COLOURS = [OI["blue"], OI["orange"], OI["green"], OI["purple"], OI["vermillion"], OI["sky"]]
MEASURES = [  # (column suffix in scorecard.csv, title)
    ("tip_error_rms_mm", "tip position error, RMS [mm]"),
    ("tip_error_max_mm", "tip position error, max [mm]"),
    ("force_error_rms_N", "largest contact force error, RMS [N]"),
    ("loop_median_latency_s", "loop alarm latency, median [s]"),
    ("loop_false_alarms_per_10min", "false loop alarms per 10 min"),
    ("loop_detected_share", "loop episodes detected within 0.5 s"),
    ("warning_detected_share", "contact >= 10 N detected within 0.5 s"),
    ("critical_detected_share", "contact >= 14 N detected within 0.5 s"),
]


def number(text, where):
    if text == "":
        return math.nan
    try:
        v = float(text)
    except ValueError:
        raise InputError(f"{where}: '{text[:80]}' is not a number")
    return v


def read_rows(path):
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (no such file)")
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise InputError(f"{path}: empty (no header)")
        rows = []
        for line, cells in enumerate(reader, start=2):
            if len(cells) != len(header):
                raise InputError(f"{path}: line {line}: {len(cells)} cells, the header has {len(header)}")
            rows.append((line, dict(zip(header, cells))))
    return header, rows


def detected_share(row, prefix, where):
    episodes = number(row[prefix + "_episodes"], where)
    detected = number(row[prefix + "_detected"], where)
    return detected / episodes if episodes and episodes > 0 else math.nan


def plot_distributions(directory, scorecard, path):
    csv_path = os.path.join(directory, "scorecard.csv")
    header, rows = read_rows(csv_path)
    for needed in ["case", "status", "estimator"]:
        if needed not in header:
            raise InputError(f"{csv_path}: line 1: no column '{needed}'")
    estimators = [(e["name"], e["label"]) for e in scorecard["overall"]["estimators"]]
    values = {}  # (measure, estimator) -> list
    for line, row in rows:
        if row["status"] != "complete":
            continue
        where = f"{csv_path}: line {line}"
        for key, _ in MEASURES:
            if key.endswith("_detected_share"):
                v = detected_share(row, key[: -len("_detected_share")], where)
            else:
                if key not in row:
                    raise InputError(f"{csv_path}: line 1: no column '{key}'")
                v = number(row[key], where)
            values.setdefault((key, row["estimator"]), []).append(v)
    fig, axes = plt.subplots(2, 4, figsize=(16, 7.5), layout="constrained")
    for ax, (key, title) in zip(axes.flat, MEASURES):
        data, labels, colours = [], [], []
        for i, (name, label) in enumerate(estimators):
            vs = [v for v in values.get((key, name), []) if math.isfinite(v)]
            data.append(vs)
            # The full label is the scorecard's; a tick gets its head, wrapped to the column.
            labels.append(textwrap.fill(label.split(" (")[0], 14))
            colours.append(COLOURS[i % len(COLOURS)])
        positions = list(range(1, len(data) + 1))
        drawn = [(p, d, c) for p, d, c in zip(positions, data, colours) if d]
        if drawn:
            box = ax.boxplot([d for _, d, _ in drawn], positions=[p for p, _, _ in drawn], widths=0.5,
                             patch_artist=True, showfliers=False)
            for patch, (_, _, c) in zip(box["boxes"], drawn):
                patch.set_facecolor(c)
                patch.set_alpha(0.35)
            for p, d, c in drawn:
                jitter = [p + 0.18 * ((k * 0.618) % 1.0 - 0.5) for k in range(len(d))]
                ax.plot(jitter, d, "o", color=c, markersize=3.5, alpha=0.85)
        for p, d in zip(positions, data):
            if not d:
                ax.text(p, 0.5, "n/a", transform=ax.get_xaxis_transform(), ha="center", va="center",
                        color=OI["grey"])
        ax.set_xticks(positions)
        ax.set_xticklabels(labels, fontsize=7)
        ax.set_xlim(0.4, len(positions) + 0.6)
        ax.set_title(title, fontsize=9)
        ax.grid(axis="y", alpha=0.3)
    o = scorecard["overall"]
    fig.suptitle(f"Scorecard '{scorecard.get('manifest', '')}': {o.get('scored', 0)} of {o.get('cases', 0)} "
                 f"cases scored (one dot per case)", fontsize=11)
    save(fig, path)


def read_estimates(path):
    header, rows = read_rows(path)
    cols = {name: [] for name in header}
    for line, row in rows:
        for name in header:
            cols[name].append(number(row[name], f"{path}: line {line}, column {name}"))
    return cols


def plot_worst(directory, scorecard, path):
    worst = scorecard["overall"].get("worst_cases", [])
    cases = {c["case"]: c for c in scorecard.get("cases", [])}
    estimators = [(e["name"], e["label"]) for e in scorecard["overall"]["estimators"]]
    n = max(1, len(worst))
    fig, axes = plt.subplots(3, n, figsize=(5.5 * n, 8.5), layout="constrained", squeeze=False,
                             gridspec_kw={"height_ratios": [2, 1.2, 1.6]})
    if not worst:
        for ax in axes[:, 0]:
            ax.text(0.5, 0.5, "no scored case", ha="center", va="center", transform=ax.transAxes)
    for col, name in enumerate(worst):
        case = cases.get(name)
        if case is None:
            raise InputError(f"worst case '{name}' is not among the scorecard's cases")
        est = read_estimates(os.path.join(directory, case["folder"], "estimates.csv"))
        t = est["time_s"]
        ax_tip, ax_loop, ax_force = axes[0, col], axes[1, col], axes[2, col]
        ax_tip.plot(t, est["true_tip_path_mm"], color=OI["black"], lw=1.6, label="true tip")
        for i, (e, label) in enumerate(estimators):
            key = e + "_tip_path_mm"
            if key in est and any(math.isfinite(v) for v in est[key]):
                ax_tip.plot(t, est[key], color=COLOURS[i % len(COLOURS)], lw=1.1, label=label)
        rms = case["estimators"].get(estimators[0][0], {}).get("tip_error_mm") or {}
        ax_tip.set_title(f"{name}\ntip error RMS {rms.get('rms', math.nan):.0f} mm, max {rms.get('max', math.nan):.0f} mm",
                         fontsize=9)
        ax_tip.set_ylabel("tip along the colon [mm]")
        ax_tip.legend(fontsize=7, loc="upper left")
        # Loop episodes shaded, each estimator's alarm as a step line at its own height.
        loop = est["true_loop"]
        ax_loop.fill_between(t, 0, [len(estimators) + 0.5 if v > 0 else 0 for v in loop], step="post",
                             color=OI["yellow"], alpha=0.45, label="true loop episode")
        for i, (e, label) in enumerate(estimators):
            key = e + "_loop_alarm"
            if key in est:
                ax_loop.step(t, [i + 0.15 + 0.7 * (v > 0) for v in est[key]], where="post",
                             color=COLOURS[i % len(COLOURS)], lw=1.2, label=label)
        ax_loop.set_yticks([])
        ax_loop.set_ylabel("loop alarm")
        ax_loop.legend(fontsize=7, loc="upper left")
        ax_force.plot(t, est["true_max_station_force_N"], color=OI["black"], lw=1.2,
                      label="true largest station force")
        for i, (e, label) in enumerate(estimators):
            key = e + "_max_force_N"
            if key in est and any(math.isfinite(v) for v in est[key]):
                ax_force.plot(t, est[key], color=COLOURS[i % len(COLOURS)], lw=1.0, label=label + " (estimate)")
            key = e + "_contact_level"
            if key in est:
                ax_force.step(t, [10.0 * v if v < 2 else 14.0 for v in est[key]], where="post",
                              color=COLOURS[i % len(COLOURS)], lw=0.9, ls="--",
                              label=label + " alarm level (10 / 14 N)")
        ax_force.axhline(10, color=OI["grey"], lw=0.6, ls=":")
        ax_force.axhline(14, color=OI["grey"], lw=0.6, ls=":")
        ax_force.set_ylabel("force [N]")
        ax_force.set_xlabel("time [s]")
        ax_force.legend(fontsize=6.5, loc="upper left")
    fig.suptitle("The worst cases (by the box's tip error)", fontsize=11)
    save(fig, path)


def plot_procedures(scorecard, path):
    """The insertion at cecal intubation per style (scorecard.json cases[].procedure)."""
    by_style = {}
    for c in scorecard.get("cases", []):
        p = c.get("procedure")
        if not isinstance(p, dict) or p.get("kind") != "physician":
            continue
        style = c.get("style") or "?"
        entry = by_style.setdefault(style, {"cases": 0, "insertions": []})
        entry["cases"] += 1
        if p.get("cecum_reached") and isinstance(p.get("insertion_at_cecum_mm"), (int, float)):
            entry["insertions"].append(float(p["insertion_at_cecum_mm"]))
    if not by_style:
        if os.path.exists(path):
            os.remove(path)
        return False
    fig, ax = plt.subplots(figsize=(7.5, 4.2), dpi=DPI)
    bins = list(range(500, 1800 + 1, 100))
    styles = sorted(by_style)
    data = [by_style[s]["insertions"] for s in styles]
    labels = [f"{s}: {len(by_style[s]['insertions'])} of {by_style[s]['cases']} reached the cecum"
              for s in styles]
    ax.hist(data, bins=bins, stacked=True, label=labels, color=COLOURS[:len(styles)], edgecolor="white")
    ax.axvline(1330, color="black", linestyle="--", linewidth=1)
    ax.text(1335, ax.get_ylim()[1] * 0.95, "1,330 mm\n(intermediate scope)", fontsize=7, va="top")
    ax.set_xlim(bins[0], bins[-1])
    ax.set_xlabel("insertion at cecal intubation [mm]")
    ax.set_ylabel("cases")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("Insertion at cecal intubation, per physician style", fontsize=10)
    save(fig, path)
    return True


def main(argv=None):
    ap = argparse.ArgumentParser(prog="plot_evaluation.py",
                                 description="Plot a scorecard: distributions.png and worst_cases.png in DIR.")
    ap.add_argument("directory", metavar="DIR", help="the --out folder of scopekin evaluate")
    ap.add_argument("--scorecard", metavar="FILE", help="read the scorecard from FILE (default DIR/scorecard.json)")
    ap.add_argument("--quiet", action="store_true", help="print nothing on success")
    args = ap.parse_args(argv)
    try:
        path = args.scorecard or os.path.join(args.directory, "scorecard.json")
        if not os.path.isfile(path):
            raise InputError(f"{path}: missing (no such file)")
        try:
            with open(path) as f:
                scorecard = json.load(f)
        except json.JSONDecodeError as e:
            raise InputError(f"{path}: line {e.lineno}, column {e.colno}: {e.msg}")
        outputs = [os.path.join(args.directory, "distributions.png"), os.path.join(args.directory, "worst_cases.png")]
        plot_distributions(args.directory, scorecard, outputs[0])
        plot_worst(args.directory, scorecard, outputs[1])
        procedures = os.path.join(args.directory, "procedures.png")
        if plot_procedures(scorecard, procedures):
            outputs.append(procedures)
        if not args.quiet:
            for p in outputs:
                print(f"plot_evaluation: wrote {p} ({os.path.getsize(p)} bytes)")
    except InputError as e:
        sys.stderr.write(f"plot_evaluation: {e}\n")
        return 2
    except OutputError as e:
        sys.stderr.write(f"plot_evaluation: {e}\n")
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
