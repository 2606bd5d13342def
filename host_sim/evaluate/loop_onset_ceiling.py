#!/usr/bin/env python3
"""How early can a loop alarm be, knowing the true tip? A ceiling for issue 21's loop bound.

usage: loop_onset_ceiling.py EVAL_DIR [--test EVAL_DIR ...] --out DIR [--budget 2.0]

Issue 21 asks the box to find >= 90 % of the truth's loop episodes within 0.5 s of their onset at
<= 2 false alarms per 10 min. The truth dates an onset back to the knee where the scope began to
be taken up (model/truth/README.md, "Loop episodes": an episode is confirmed at 20 mm of excess,
its onset is the knee before it). This study asks what a causal detector could do if it knew the
true tip exactly (a tracker without error, a perfect estimator): it reads truth.csv's
`insertion_mm`, `tip_path_mm` and `loop_excess_mm` (the excess as the truth computes it, causally:
the scope taken up since the tip last kept pace) and runs two families of alarms on them:
- `excess`: up when the excess reaches T mm, down when it falls to T / 2;
- `stall`: up while, over the trailing W s, the hand advanced >= 1 mm and the tip less than F of
  it (the truth's own pace test at other windows and fractions).
Every setting is scored by the scorecard's rule (host_sim/evaluate/README.md, "The scoring
rules"; alarm_speed.py's implementation, whose pooled counts equal the scorecard's) up to where
the scope went through the wall. On EVAL_DIR (the set one may tune on) each family's setting
that finds the most onsets within 0.5 s at <= BUDGET false alarms per 10 min (pooled) is chosen
and then scored on each --test set (reported only). Beside it, per episode, how much scope the
truth had taken up 0.5 s after the onset (`take_up_at_0_5s_mm`): an excess alarm at T can find
an episode within 0.5 s only where that is >= T.

Each evaluation is named by its folder. Writes DIR/loop_onset_ceiling.csv (one row per set,
family and setting), DIR/loop_onset_ceiling_
episodes.csv (one row per set and episode: onset, hand speed, take-up 0.5 s after the onset),
DIR/loop_onset_ceiling.json (the chosen settings and their scores per set) and DIR/
loop_onset_ceiling.png (onsets found against false alarms per family and set; the take-up's
distribution). Prints the table. Exit status 2 for bad input (no complete case, a missing
column), 3 if an output cannot be written.
"""
import argparse
import json
import os
import sys

import numpy as np

from alarm_speed import hand_speed, rises, score_episodes
from case_columns import BadInput, case_folders, columns, complete_summary, write_rows

WITHIN_S = 0.5  # the scorecard's "within 0.5 s of the onset"
EXCESS_T_MM = [2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0]
STALL_W_S = [0.1, 0.2, 0.3, 0.5]
STALL_F = [0.1, 0.25, 0.5]
PACE_MIN_HANDLE_MM = 1.0  # model/truth/truth_definitions.hpp kPaceMinHandle_mm


def settings():
    """(family, label, parameters) of every alarm tried."""
    out = [("excess", f"T={t:g} mm", {"T_mm": t}) for t in EXCESS_T_MM]
    out += [("stall", f"W={w:g} s F={f:g}", {"W_s": w, "F": f}) for w in STALL_W_S for f in STALL_F]
    return out


def excess_alarm(excess, threshold):
    """Up from where the excess reaches the threshold until it falls to half of it."""
    decided = (excess >= threshold) | (excess <= threshold / 2)  # else: keeps its state
    last = np.maximum.accumulate(np.where(decided, np.arange(len(excess)), -1))
    return np.where(last >= 0, excess[np.maximum(last, 0)] >= threshold, False)


def stall_alarm(t, insertion, tip, window_s, fraction):
    """Up while, over the trailing window, the hand advanced >= 1 mm and the tip < fraction of it."""
    start = np.searchsorted(t, t - window_s + 1e-9)
    start = np.maximum(start - 1, 0)  # the sample at or before the window's start
    hand = insertion - insertion[start]
    moved = tip - tip[start]
    return (hand >= PACE_MIN_HANDLE_MM) & (moved < fraction * hand)


def read_case(folder):
    """The case's series up to the wall and its episodes, or None if the case is not complete."""
    summary = complete_summary(folder)
    if summary is None:
        return None
    truth = summary.get("truth") or {}
    c = columns(os.path.join(folder, "truth.csv"),
                ["time_s", "insertion_mm", "tip_path_mm", "loop_excess_mm"])
    if len(c["time_s"]) < 2:
        raise BadInput(f"{folder}/truth.csv: no periods")
    cut = truth.get("scope_through_wall_s")
    keep = c["time_s"] <= cut if cut is not None else np.ones(len(c["time_s"]), bool)
    c = {k: v[keep] for k, v in c.items()}
    for k, v in c.items():
        if np.isnan(v).any():
            raise BadInput(f"{folder}/truth.csv: empty cells in {k}")
    end_s = float(c["time_s"][-1])
    episodes = [(float(e["onset_s"]), e.get("end_s")) for e in truth.get("loop_episodes", [])
                if float(e["onset_s"]) <= end_s]
    return c, episodes, end_s


def read_set(eval_dir):
    cases = []
    folders = case_folders(eval_dir)
    for k, (name, folder) in enumerate(folders):
        case = read_case(folder)
        print(f"[{k + 1}/{len(folders)}] {name}: " +
              ("not complete, skipped" if case is None else f"{len(case[1])} loop episodes"), flush=True)
        if case is not None:
            cases.append((name, *case))
    if not cases:
        raise BadInput(f"{eval_dir}: no complete case (run `scopekin evaluate` first)")
    return cases


def alarm_of(family, p, c):
    if family == "excess":
        return excess_alarm(c["loop_excess_mm"], p["T_mm"])
    return stall_alarm(c["time_s"], c["insertion_mm"], c["tip_path_mm"], p["W_s"], p["F"])


def score_setting(cases, family, p):
    """Pooled episodes, detected within 0.5 s, late, missed, false alarms, scored seconds."""
    total = {"episodes": 0, "detected": 0, "late": 0, "missed": 0, "false_alarms": 0, "scored_s": 0.0,
             "latencies_s": []}
    for _, c, episodes, end_s in cases:
        t = c["time_s"]
        outcomes, false = score_episodes(rises(t, alarm_of(family, p, c).astype(float)), episodes, end_s)
        total["episodes"] += len(episodes)
        for outcome, latency in outcomes:
            total[outcome] += 1
            if latency is not None:
                total["latencies_s"].append(latency)
        total["false_alarms"] += len(false)
        total["scored_s"] += end_s - float(t[0])
    total["detected_share"] = total["detected"] / total["episodes"] if total["episodes"] else None
    total["false_alarms_per_10min"] = total["false_alarms"] * 600.0 / total["scored_s"]
    lat = total.pop("latencies_s")
    total["median_latency_s"] = float(np.median(lat)) if lat else None
    return total


def take_up_rows(set_name, cases):
    """Per episode: the hand's speed before the onset and the truth's excess 0.5 s after it."""
    rows = []
    for name, c, episodes, _ in cases:
        t = c["time_s"]
        for onset, _end in episodes:
            at = min(onset + WITHIN_S, float(t[-1]))
            before = float(np.interp(onset, t, c["insertion_mm"] - c["tip_path_mm"]))
            after = float(np.interp(at, t, c["insertion_mm"] - c["tip_path_mm"]))
            rows.append({"set": set_name, "case": name, "onset_s": onset,
                         "speed_mm_per_s": hand_speed(t, c["insertion_mm"], onset),
                         "take_up_at_0_5s_mm": after - before})
    return rows


def choose(rows, family, budget):
    """The family's setting with the most onsets within 0.5 s at <= budget false alarms per 10 min."""
    ok = [r for r in rows if r["family"] == family and r["false_alarms_per_10min"] <= budget]
    if not ok:
        return None
    return max(ok, key=lambda r: (r["detected"], -r["false_alarms_per_10min"]))


def draw(out, rows, episode_rows, sets, budget):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("note: no python3-matplotlib, loop_onset_ceiling.png not drawn", file=sys.stderr)
        return
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for s in sets:
        for family, marker in (("excess", "o"), ("stall", "s")):
            pts = [r for r in rows if r["set"] == s and r["family"] == family and r["episodes"]]
            axes[0].scatter([r["false_alarms_per_10min"] for r in pts],
                            [100.0 * r["detected_share"] for r in pts], marker=marker, label=f"{s}: {family}")
    axes[0].axvline(budget, color="grey", ls="--", lw=1)
    axes[0].axhline(90, color="red", ls=":", lw=1)
    axes[0].set_xscale("symlog", linthresh=1)
    axes[0].set_xlim(left=0)
    axes[0].set_ylim(0, 100)
    axes[0].set_xlabel("false loop alarms per 10 min")
    axes[0].set_ylabel("loop onsets found within 0.5 s [%]")
    axes[0].set_title("alarms on the true tip (issue 21: >= 90 % at <= 2)", fontsize=9)
    axes[0].legend(fontsize=7)
    for s in sets:
        v = np.sort([r["take_up_at_0_5s_mm"] for r in episode_rows if r["set"] == s])
        if len(v):
            axes[1].plot(v, np.arange(1, len(v) + 1) / len(v) * 100.0, label=s)
    axes[1].set_xlabel("scope taken up 0.5 s after the onset [mm]")
    axes[1].set_ylabel("episodes at or below [%]")
    axes[1].set_xlim(left=-5, right=30)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "loop_onset_ceiling.png"), dpi=110)
    plt.close(fig)


def write_outputs(out, rows, episode_rows, report, sets, budget):
    os.makedirs(out, exist_ok=True)
    fields = ["set", "family", "setting", "episodes", "detected", "late", "missed", "false_alarms",
              "scored_s", "detected_share", "false_alarms_per_10min", "median_latency_s"]
    write_rows(os.path.join(out, "loop_onset_ceiling.csv"), fields, rows)
    write_rows(os.path.join(out, "loop_onset_ceiling_episodes.csv"),
               ["set", "case", "onset_s", "speed_mm_per_s", "take_up_at_0_5s_mm"], episode_rows)
    with open(os.path.join(out, "loop_onset_ceiling.json"), "w") as f:
        json.dump(report, f, indent=1)
    draw(out, rows, episode_rows, sets, budget)


def take_up_summary(episode_rows, set_name):
    v = np.array([r["take_up_at_0_5s_mm"] for r in episode_rows if r["set"] == set_name])
    if not len(v):
        return None
    return {"episodes": int(len(v)), "median_mm": float(np.median(v)),
            "p10_mm": float(np.percentile(v, 10)), "p90_mm": float(np.percentile(v, 90)),
            "share_at_least_mm": {f"{t:g}": float(np.mean(v >= t)) for t in EXCESS_T_MM}}


def set_names(folders):
    """(name, folder) per evaluation: the folder's own name, numbered where two share one."""
    names = []
    for d in folders:
        base = os.path.basename(os.path.normpath(d)) or "evaluation"
        name, k = base, 2
        while name in [n for n, _ in names]:
            name, k = f"{base}_{k}", k + 1
        names.append((name, d))
    return names


def report_of(rows, episode_rows, sets, budget):
    """Each family's setting chosen on the first set, its scores on every set, the take-up."""
    tuned_on = sets[0][0]
    report = {"budget_false_alarms_per_10min": budget, "sets": dict(sets), "families": {}}
    for family in ("excess", "stall"):
        best = choose([r for r in rows if r["set"] == tuned_on], family, budget)
        entry = {"chosen_on": tuned_on, "setting": None if best is None else best["setting"], "scores": {}}
        if best is not None:
            entry["scores"] = {r["set"]: r for r in rows if r["family"] == family and r["setting"] == best["setting"]}
        report["families"][family] = entry
    report["take_up_0_5s_after_onset"] = {s: take_up_summary(episode_rows, s) for s, _ in sets}
    return report


def print_summary(report, tuned_on_dir, budget):
    for family, entry in report["families"].items():
        if entry["setting"] is None:
            print(f"{family}: no setting within {budget:g} false alarms per 10 min on {tuned_on_dir}")
            continue
        for set_name, s in entry["scores"].items():
            share = "n/a" if s["detected_share"] is None else f"{100.0 * s['detected_share']:.0f} %"
            print(f"{family} {entry['setting']} on {set_name}: {s['detected']} of {s['episodes']} onsets within "
                  f"0.5 s ({share}; {s['late']} late, {s['missed']} missed), "
                  f"{s['false_alarms_per_10min']:.2f} false alarms per 10 min")
    for set_name, s in report["take_up_0_5s_after_onset"].items():
        if s is None:
            print(f"{set_name}: no loop episode")
            continue
        print(f"{set_name}: scope taken up 0.5 s after the onset, median {s['median_mm']:.1f} mm "
              f"(10th percentile {s['p10_mm']:.1f}, 90th {s['p90_mm']:.1f})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("eval_dir", help="the evaluation the settings are chosen on (development)")
    parser.add_argument("--test", action="append", default=[], help="an evaluation reported only")
    parser.add_argument("--out", required=True)
    parser.add_argument("--budget", type=float, default=2.0, help="false alarms per 10 min (default 2)")
    args = parser.parse_args()
    if not args.budget > 0:
        print(f"loop_onset_ceiling: --budget must be > 0 (got {args.budget})", file=sys.stderr)
        return 2
    sets = set_names([args.eval_dir] + args.test)
    rows, episode_rows, data = [], [], {}
    try:
        for set_name, d in sets:
            print(f"{set_name}: {d}", flush=True)
            data[set_name] = read_set(d)
    except BadInput as e:
        print(f"loop_onset_ceiling: {e}", file=sys.stderr)
        return 2
    for set_name, _ in sets:
        cases = data[set_name]
        episode_rows += take_up_rows(set_name, cases)
        for family, label, p in settings():
            rows.append({"set": set_name, "family": family, "setting": label, "parameters": p,
                         **score_setting(cases, family, p)})
    report = report_of(rows, episode_rows, sets, args.budget)
    try:
        write_outputs(args.out, rows, episode_rows, report, [s for s, _ in sets], args.budget)
    except OSError as e:
        print(f"loop_onset_ceiling: cannot write {args.out}: {e}", file=sys.stderr)
        return 3
    print_summary(report, args.eval_dir, args.budget)
    return 0


if __name__ == "__main__":
    sys.exit(main())
