#!/usr/bin/env python3
"""Chooses the persistence of the box's published contact-force level (kinetics::Config::
contact_force, kPublishedContactForceConfig) on evaluations of the development set.

usage: tune_contact_level.py EVAL_DIR [EVAL_DIR ...] [--report level.json]

The level reads the published largest contact force (firmware.csv max_contact_force_N: the contact
force trees' while the handle's evidence does not trust the reduced model, the model's while it
does). The monitor (firmware/monitors/contact_force_monitor.hpp) raises the warning at 10 N and the
critical level at 14 N after PERSISTENCE consecutive periods at or above them and clears each below
90 % of its threshold. For every persistence tried, both levels are scored with the scorecard's
rule against the truth's >= 10 N and >= 14 N episodes (detected within 0.5 s of the onset, a rise
up to 1 s early counts; every other rise a false alarm: host_sim/evaluate/README.md, "Alarms
against episodes"), each case up to where the scope went through the wall (as the scorecard).
The choice: the persistence with the most detections of both levels together whose false alarms
stay within BUDGET_PER_10MIN per 10 minutes for each level with a margin: the 90th percentile over
sets of 20 patients drawn with replacement from the development patients (fit_loop_alarm.py's
patient bootstrap; Efron & Tibshirani 1993, ch. 6). The budget is the handle force monitor's (3 per
10 min: `scopekin evaluate-tune`'s default, a stated guess). Ties: fewer false alarms, then the
shorter persistence. The reduced model's own level (model_max_contact_force_N, raised on its
first period) is scored beside it. A set named "...validation..." is refused: the choice is made
on development only. Exit status 0 done, 2 bad input.
"""
import argparse
import glob
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_loop_alarm as alarm  # noqa: E402  (the scorecard's rule, the patient bootstrap)
from fit_slack_regressor import columns  # noqa: E402  (a case's columns; exit 2 naming a missing one)

PERSISTENCES = [1, 2, 5, 10, 20, 40]
LEVELS = {"warning_10N": 10.0, "critical_14N": 14.0}
CLEAR_FRACTION = 0.9
BUDGET_PER_10MIN = 3.0
LOST_BEYOND_WALL_MM = 40.0  # the scorecard scores a case up to here


def load(folder):
    """One complete case: times, the published and the model's force, episodes per level."""
    summary = json.load(open(os.path.join(folder, "summary.json")))
    if summary.get("status") != "complete":
        return None
    fw = columns(os.path.join(folder, "firmware.csv"),
                 ["time_s", "max_contact_force_N", "model_max_contact_force_N"])
    beyond = columns(os.path.join(folder, "truth.csv"), ["scope_beyond_wall_mm"])["scope_beyond_wall_mm"]
    n = min(fw["time_s"].size, beyond.size)
    lost = np.where(beyond[:n] > LOST_BEYOND_WALL_MM)[0]
    lost_s = fw["time_s"][lost[0]] if lost.size else np.inf
    n = lost[0] if lost.size else n
    t = fw["time_s"][:n]
    episodes = {}
    for kind in LEVELS:  # as the scorecard cuts them (case_run.cpp)
        found = summary.get("truth", {}).get("force_episodes", {}).get(kind, [])
        episodes[kind] = [(e["onset_s"], np.inf if e["end_s"] is None or e["end_s"] >= lost_s else e["end_s"])
                          for e in found if e["onset_s"] < lost_s]
    return {"name": os.path.basename(folder.rstrip("/")), "time_s": t,
            "published_N": fw["max_contact_force_N"][:n], "model_N": fw["model_max_contact_force_N"][:n],
            "episodes": episodes}


def level_up(force_N, threshold_N, persistence):
    """The monitor's detector on the Q16.16 grid: up after `persistence` periods >= threshold,
    down at once below the clear level (contact_force_monitor.hpp)."""
    f = alarm.q16_raw(force_N)
    on = int(alarm.q16_raw(threshold_N))
    off = int(np.floor(on * alarm.q16_raw(CLEAR_FRACTION) / 65536.0 + 0.5))
    up = np.zeros(f.size, dtype=bool)
    state, run = False, 0
    for k, v in enumerate(f):
        if not state:
            run = run + 1 if v >= on else 0
            if run >= persistence:
                state, run = True, 0
        elif v < off:
            state = False
        up[k] = state
    return up


def pooled(cases, kind, up_of):
    detected = false_alarms = episodes = 0
    seconds = 0.0
    per_patient = {}
    for c in cases:
        d, f, s = alarm.score_alarm(c["time_s"], up_of(c), c["episodes"][kind])
        detected, false_alarms, seconds = detected + d, false_alarms + f, seconds + s
        episodes += len(c["episodes"][kind])
        tally = per_patient.setdefault(c["name"].split("-")[0], [0, 0.0])
        tally[0], tally[1] = tally[0] + f, tally[1] + s
    return {"episodes": episodes, "detected": detected, "false_alarms": false_alarms,
            "false_alarms_per_10min": false_alarms * 600.0 / seconds if seconds else None,
            "false_alarms_per_10min_resampled": alarm.resampled_false_alarm_rate(list(per_patient.values()))}


def score(cases, force_key, persistence):
    return {kind: pooled(cases, kind, lambda c, th=th: level_up(c[force_key], th, persistence))
            for kind, th in LEVELS.items()}


def choose(rows):
    ok = [r for r in rows
          if all(r[k]["false_alarms_per_10min_resampled"] <= BUDGET_PER_10MIN for k in LEVELS)]
    key = lambda r: (sum(r[k]["detected"] for k in LEVELS), -sum(r[k]["false_alarms"] for k in LEVELS),
                     -r["persistence"])
    return max(ok, key=key) if ok else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                 epilog="Exit status: 0 done, 2 bad input.")
    ap.add_argument("eval_dir", nargs="+", help="evaluation folders of the development set (`scopekin evaluate --out`)")
    ap.add_argument("--report", help="JSON: every persistence's detections and false alarms per level")
    a = ap.parse_args()
    if any("validation" in os.path.basename(os.path.normpath(d)) for d in a.eval_dir):
        print("tune_contact_level.py: a validation set is not tuned on", file=sys.stderr)
        sys.exit(2)
    cases = []
    try:
        for d in a.eval_dir:
            for f in sorted(glob.glob(os.path.join(d, "cases", "*", "summary.json"))):
                c = load(os.path.dirname(f))
                if c is not None and c["time_s"].size > 1:
                    cases.append(c)
    except (ValueError, KeyError, json.JSONDecodeError) as e:
        print(f"tune_contact_level.py: {e}", file=sys.stderr)
        sys.exit(2)
    patients = {c["name"].split("-")[0] for c in cases}
    if len(patients) < 2 or not any(c["episodes"]["critical_14N"] for c in cases):
        print(f"tune_contact_level.py: {' '.join(a.eval_dir)}: {len(cases)} complete cases of {len(patients)} "
              "patients; need at least 2 patients and one >= 14 N episode", file=sys.stderr)
        sys.exit(2)
    rows = []
    for p in PERSISTENCES:
        row = {"persistence": p, **score(cases, "published_N", p)}
        rows.append(row)
        print(f"persistence {p:3d}: " + "; ".join(
            f"{k} {row[k]['detected']} of {row[k]['episodes']}, {row[k]['false_alarms_per_10min']:.2f} per 10 min "
            f"(p90 {row[k]['false_alarms_per_10min_resampled']:.2f})" for k in LEVELS), file=sys.stderr)
    chosen = choose(rows)
    model = {"persistence": 1, **score(cases, "model_N", 1)}
    report = {"cases": len(cases), "patients": len(patients), "budget_false_alarms_per_10min": BUDGET_PER_10MIN,
              "budget_rule": {**alarm.budget_rule(), "false_alarms_per_10min": BUDGET_PER_10MIN},
              "chosen": chosen, "by_persistence": rows, "reduced_model_level": model}
    print(json.dumps({"chosen_persistence": chosen["persistence"] if chosen else None,
                      "chosen": chosen, "reduced_model_level": model}, indent=1))
    if a.report:
        with open(a.report, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
