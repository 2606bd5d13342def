#!/usr/bin/env python3
"""Does an alarm's timing depend on how fast the hand moves? A study of a scored evaluation.

usage: alarm_speed.py EVAL_DIR --out DIR [--estimators box,force_monitor,depth_replay]

Issue 21 asks for loop alarms "with delays that do not depend on the hand's speed (a slow advance
must not raise 19 alarms, a fast one must not be late)". For every complete case of an evaluation
scored by `scopekin evaluate` (EVAL_DIR/cases/NAME with estimates.csv, truth.csv and summary.json)
this study scores each estimator's loop alarm (estimates.csv `NAME_loop_alarm`) against the
truth's loop episodes (summary.json truth.loop_episodes) by the scorecard's rule
(host_sim/evaluate/README.md, "The scoring rules": detected by the earliest unused rise in
[onset - 1 s, onset + 0.5 s], late by one before the episode's end, a rise outside every
[onset - 1 s, end] a false alarm), and files each episode and each false alarm under the hand's
speed: the insertion's mean rate over the 2 s before the onset (or the rise), from truth.csv
`insertion_mm`. Speed bins (mm/s): below 5 (holding, creeping), 5-15 (slow), 15-30 (the
physicians' usual 8-40 mm/s advance, middle), 30 and above (fast); withdrawals (below -5) apart.
Per bin and estimator: episodes, detected within 0.5 s, late, missed, median latency (detected and
late), and false alarms per 10 min of the time the hand spent at that speed; over all episodes the
Spearman rank correlation of latency with speed.

Writes DIR/alarm_speed_episodes.csv (one row per episode and estimator), DIR/alarm_speed.json (the
bins and the correlation) and DIR/alarm_speed.png (detected share and false alarms per bin; needs
python3-matplotlib). Prints the table. Exit status 2 for bad input (no complete scored case, a
missing column or estimator), 3 if an output cannot be written.
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

from case_columns import BadInput, case_folders, columns, complete_summary

EARLY_S, WITHIN_S = 1.0, 0.5  # the scorecard's detection window around the onset
SPEED_WINDOW_S = 2.0
BINS = [("withdrawing (< -5)", -np.inf, -5.0), ("holding (-5..5)", -5.0, 5.0),
        ("slow (5..15)", 5.0, 15.0), ("middle (15..30)", 15.0, 30.0), ("fast (>= 30)", 30.0, np.inf)]


def rises(t, alarm):
    """Times of the periods with the alarm up after one with it down (the first if up)."""
    up = alarm > 0.5
    edge = up & ~np.concatenate(([False], up[:-1]))
    return t[edge]


def score_episodes(rise_times, episodes, run_end_s):
    """(outcome, latency_s) per episode and the false alarms' rise times, by the scorecard's rule."""
    used = set()
    outcomes = []
    for onset, end in episodes:
        found = None
        for k, r in enumerate(rise_times):
            if k not in used and onset - EARLY_S <= r <= onset + WITHIN_S:
                found = (k, "detected", max(0.0, r - onset))
                break
        if found is None:
            stop = end if end is not None else run_end_s
            for k, r in enumerate(rise_times):
                if k not in used and onset + WITHIN_S < r <= stop:
                    found = (k, "late", r - onset)
                    break
        if found is None:
            outcomes.append(("missed", None))
        else:
            used.add(found[0])
            outcomes.append(found[1:])
    false = [r for r in rise_times
             if not any(onset - EARLY_S <= r <= (end if end is not None else run_end_s)
                        for onset, end in episodes)]
    return outcomes, false


def speed_bin(speed):
    for name, low, high in BINS:
        if low <= speed < high:
            return name
    return BINS[-1][0]


def hand_speed(t, insertion, at_s):
    """The insertion's mean rate [mm/s] over the SPEED_WINDOW_S before at_s."""
    start = max(t[0], at_s - SPEED_WINDOW_S)
    if at_s - start <= 0:
        return 0.0
    return float((np.interp(at_s, t, insertion) - np.interp(start, t, insertion)) / (at_s - start))


def study_case(folder, estimators):
    summary = complete_summary(folder)
    if summary is None or not os.path.isfile(os.path.join(folder, "estimates.csv")):
        return None
    cut = (summary.get("truth") or {}).get("scope_through_wall_s")
    episodes = [(float(e["onset_s"]), e.get("end_s"))
                for e in (summary.get("truth") or {}).get("loop_episodes", [])]
    est = columns(os.path.join(folder, "estimates.csv"),
                  ["time_s"] + [f"{e}_loop_alarm" for e in estimators])
    truth = columns(os.path.join(folder, "truth.csv"), ["time_s", "insertion_mm"])
    t = est["time_s"]
    if len(t) < 2 or len(truth["time_s"]) < 2:
        raise BadInput(f"{folder}: no periods")
    keep = t <= cut if cut is not None else np.ones(len(t), bool)  # scored up to the wall
    t = t[keep]
    end_s = float(t[-1])
    episodes = [(o, e) for o, e in episodes if o <= end_s]
    # Time at each speed: the speed over the 2 s before each period.
    period_speeds = [hand_speed(truth["time_s"], truth["insertion_mm"], s) for s in t[::20]]
    time_in_bin = {}
    for s in period_speeds:  # every 20th period: 0.1 s each
        time_in_bin[speed_bin(s)] = time_in_bin.get(speed_bin(s), 0.0) + 20 * (t[1] - t[0])
    rows, false_by_bin = [], {e: {} for e in estimators}
    for e in estimators:
        outcomes, false = score_episodes(rises(t, est[f"{e}_loop_alarm"][keep]), episodes, end_s)
        for (onset, _), (outcome, latency) in zip(episodes, outcomes):
            speed = hand_speed(truth["time_s"], truth["insertion_mm"], onset)
            rows.append({"estimator": e, "onset_s": onset, "speed_mm_per_s": speed,
                         "bin": speed_bin(speed), "outcome": outcome, "latency_s": latency})
        for r in false:
            b = speed_bin(hand_speed(truth["time_s"], truth["insertion_mm"], r))
            false_by_bin[e][b] = false_by_bin[e].get(b, 0) + 1
    return rows, false_by_bin, time_in_bin


def spearman(a, b):
    if len(a) < 3:
        return None
    ra = np.argsort(np.argsort(a))
    rb = np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1])


def summarise(all_rows, false_by_bin, time_in_bin, estimators):
    report = {}
    for e in estimators:
        bins = {}
        for name, _, _ in BINS:
            rows = [r for r in all_rows if r["estimator"] == e and r["bin"] == name]
            lat = [r["latency_s"] for r in rows if r["latency_s"] is not None]
            seconds = time_in_bin.get(name, 0.0)
            bins[name] = {
                "episodes": len(rows),
                "detected": sum(r["outcome"] == "detected" for r in rows),
                "late": sum(r["outcome"] == "late" for r in rows),
                "missed": sum(r["outcome"] == "missed" for r in rows),
                "median_latency_s": float(np.median(lat)) if lat else None,
                "false_alarms": false_by_bin[e].get(name, 0),
                "seconds_at_speed": seconds,
                "false_alarms_per_10min": false_by_bin[e].get(name, 0) * 600.0 / seconds if seconds > 0 else None,
            }
        timed = [r for r in all_rows if r["estimator"] == e and r["latency_s"] is not None]
        report[e] = {"bins": bins, "spearman_latency_vs_speed": spearman(
            [r["speed_mm_per_s"] for r in timed], [r["latency_s"] for r in timed]),
            "timed_episodes": len(timed)}
    return report


def write_outputs(out, all_rows, report, args, estimators):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "alarm_speed_episodes.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "estimator", "onset_s", "speed_mm_per_s", "bin",
                                          "outcome", "latency_s"], lineterminator="\n")
        w.writeheader()
        for r in all_rows:
            w.writerow({**r, "latency_s": "" if r["latency_s"] is None else f"{r['latency_s']:.6f}",
                        "speed_mm_per_s": f"{r['speed_mm_per_s']:.3f}"})
    with open(os.path.join(out, "alarm_speed.json"), "w") as f:
        json.dump({"eval_dir": args.eval_dir, "speed_window_s": SPEED_WINDOW_S,
                   "estimators": report}, f, indent=1)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("note: no python3-matplotlib, alarm_speed.png not drawn", file=sys.stderr)
        return
    names = [b[0] for b in BINS]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    width = 0.8 / len(estimators)
    for k, e in enumerate(estimators):
        bins = report[e]["bins"]
        share = [100.0 * bins[n]["detected"] / bins[n]["episodes"] if bins[n]["episodes"] else 0 for n in names]
        fa = [bins[n]["false_alarms_per_10min"] or 0 for n in names]
        x = np.arange(len(names)) + (k - (len(estimators) - 1) / 2) * width
        axes[0].bar(x, share, width, label=e)
        axes[1].bar(x, fa, width, label=e)
    for ax, label in ((axes[0], "loop episodes detected within 0.5 s [%]"),
                      (axes[1], "false loop alarms per 10 min at that speed")):
        ax.set_xticks(range(len(names)), names, rotation=20, fontsize=8)
        ax.set_ylabel(label)
    axes[0].legend(fontsize=8)
    fig.suptitle("the hand's speed over the 2 s before the onset (or the false alarm) [mm/s]")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "alarm_speed.png"), dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("eval_dir")
    parser.add_argument("--out", required=True)
    parser.add_argument("--estimators", default="box,force_monitor,depth_replay")
    args = parser.parse_args()
    estimators = [e for e in args.estimators.split(",") if e]
    try:
        cases = case_folders(args.eval_dir)
        all_rows, false_by_bin, time_in_bin = [], {e: {} for e in estimators}, {}
        scored = 0
        for k, (name, folder) in enumerate(cases):
            result = study_case(folder, estimators)
            if result is None:
                print(f"[{k + 1}/{len(cases)}] {name}: not a complete scored case, skipped", flush=True)
                continue
            rows, false, seconds = result
            scored += 1
            all_rows += [{"case": name, **r} for r in rows]
            for e in estimators:
                for b, n in false[e].items():
                    false_by_bin[e][b] = false_by_bin[e].get(b, 0) + n
            for b, s in seconds.items():
                time_in_bin[b] = time_in_bin.get(b, 0.0) + s
            print(f"[{k + 1}/{len(cases)}] {name}: {len(rows) // len(estimators)} loop episodes", flush=True)
        if scored == 0:
            raise BadInput(f"{args.eval_dir}: no complete scored case (run `scopekin evaluate` first)")
    except BadInput as e:
        print(f"alarm_speed: {e}", file=sys.stderr)
        return 2
    report = summarise(all_rows, false_by_bin, time_in_bin, estimators)
    try:
        write_outputs(args.out, all_rows, report, args, estimators)
    except OSError as e:
        print(f"alarm_speed: cannot write {args.out}: {e}", file=sys.stderr)
        return 3
    for e in estimators:
        print(f"{e}: latency vs speed, Spearman {report[e]['spearman_latency_vs_speed']}")
        for name, b in report[e]["bins"].items():
            lat = "n/a" if b["median_latency_s"] is None else f"{b['median_latency_s']:.2f} s"
            fa = "n/a" if b["false_alarms_per_10min"] is None else f"{b['false_alarms_per_10min']:.2f}"
            print(f"  {name:20s} {b['detected']:3d} of {b['episodes']:3d} within 0.5 s ({b['late']} late, "
                  f"{b['missed']} missed), median latency {lat}; {b['false_alarms']} false alarms in "
                  f"{b['seconds_at_speed']:.0f} s = {fa} per 10 min")
    return 0


if __name__ == "__main__":
    sys.exit(main())
