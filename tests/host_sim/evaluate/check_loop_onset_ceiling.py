#!/usr/bin/python3
"""Checks of host_sim/evaluate/loop_onset_ceiling.py (loop alarms on the true tip).

  synthetic  one case of 120 s whose hand advances at 20 mm/s. The tip keeps pace except in three
             loop episodes (onsets 20, 60, 100 s), where it stops dead for 3 s and then catches up,
             and in two normal stalls of 0.14 s (40 and 80 s: 2.8 mm taken up, then given back).
             By hand: an excess alarm at 2 mm rings in both stalls (2 false alarms in 2 min, 10 per
             10 min: over the budget); at 3-10 mm it finds the three onsets within 0.5 s (latency
             T / 20 mm/s) with no false alarm, so the chosen setting finds 3 of 3; at 15 and 20 mm it
             is late (0.75 and 1 s). 0.5 s after each onset the scope has taken up 10 mm. A --test
             set is scored with the setting chosen on the first;
  bad_input  a folder with no complete case, a truth.csv without loop_excess_mm, a budget of 0:
             exit 2 and a message, nothing written.
Usage: check_loop_onset_ceiling.py CHECK SOURCE_DIR WORK_DIR
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_support import expect, failures, fresh_folder, run_script  # noqa: E402

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SCRIPT = os.path.join(SOURCE, "host_sim", "evaluate", "loop_onset_ceiling.py")
fresh_folder(WORK)
SPEED = 20.0  # mm/s
LOOPS = (20.0, 60.0, 100.0)  # onsets; the tip stops for 3 s
STALLS = (40.0, 80.0)  # the tip stops for 0.14 s
LOOP_S, STALL_S = 3.0, 0.14


def taken_up(t):
    """The truth's excess: the scope taken up since the tip last kept pace [mm]."""
    for start, length in [(o, LOOP_S) for o in LOOPS] + [(s, STALL_S) for s in STALLS]:
        if start <= t < start + length:
            return SPEED * (t - start)
    return 0.0


def write_case(root, name, excess_column="loop_excess_mm"):
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    with open(os.path.join(folder, "truth.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", "insertion_mm", "tip_path_mm", excess_column])
        for k in range(1, 24001):
            t = k * 0.005
            w.writerow([f"{t:.3f}", f"{SPEED * t:.4f}", f"{SPEED * t - taken_up(t):.4f}", f"{taken_up(t):.4f}"])
    json.dump({"status": "complete",
               "truth": {"scope_through_wall_s": None,
                         "loop_episodes": [{"onset_s": o, "end_s": o + LOOP_S} for o in LOOPS]}},
              open(os.path.join(folder, "summary.json"), "w"))


def row(rows, set_name, setting):
    return next(r for r in rows if r["set"] == set_name and r["setting"] == setting)


if CHECK == "synthetic":
    dev, val = os.path.join(WORK, "dev"), os.path.join(WORK, "val")
    write_case(dev, "c1")
    write_case(val, "c1")
    out = os.path.join(WORK, "study")
    p = run_script(SCRIPT, dev, "--test", val, "--out", out)
    expect(p.returncode == 0, f"the study runs (exit {p.returncode}: {p.stderr.strip()[-300:]})")
    rows = list(csv.DictReader(open(os.path.join(out, "loop_onset_ceiling.csv"))))
    two = row(rows, "dev", "T=2 mm")
    expect(two["detected"] == "3" and two["false_alarms"] == "2" and abs(float(two["false_alarms_per_10min"]) - 10.0) < 0.01,
           f"T = 2 mm rings in both stalls: 2 false alarms in 2 min ({two})")
    for t in ("3", "5", "10"):
        r = row(rows, "dev", f"T={t} mm")
        expect(r["detected"] == "3" and r["false_alarms"] == "0" and
               abs(float(r["median_latency_s"]) - float(t) / SPEED) < 0.011,
               f"T = {t} mm finds the three onsets {float(t) / SPEED:g} s after them ({r})")
    for t, latency in (("15", 0.75), ("20", 1.0)):
        r = row(rows, "dev", f"T={t} mm")
        expect(r["late"] == "3" and abs(float(r["median_latency_s"]) - latency) < 0.011, f"T = {t} mm is late ({r})")
    report = json.load(open(os.path.join(out, "loop_onset_ceiling.json")))
    excess = report["families"]["excess"]
    expect(excess["setting"] == "T=3 mm" and excess["scores"]["val"]["detected"] == 3 and
           excess["scores"]["val"]["false_alarms"] == 0,
           f"chosen on the first set within the budget, scored on the test set ({excess['setting']})")
    stall = report["families"]["stall"]
    expect(stall["setting"] is not None and stall["scores"]["dev"]["detected"] == 3,
           f"a stall alarm finds the dead stops ({stall['setting']})")
    take_up = report["take_up_0_5s_after_onset"]["dev"]
    expect(take_up["episodes"] == 3 and abs(take_up["median_mm"] - 10.0) < 0.2,
           f"10 mm taken up 0.5 s after each onset ({take_up})")
    expect(os.path.isfile(os.path.join(out, "loop_onset_ceiling.png")) and
           os.path.isfile(os.path.join(out, "loop_onset_ceiling_episodes.csv")), "the picture and the episodes' table")
elif CHECK == "bad_input":
    empty = os.path.join(WORK, "empty")
    os.makedirs(os.path.join(empty, "cases"))
    p = run_script(SCRIPT, empty, "--out", os.path.join(WORK, "o1"))
    expect(p.returncode == 2 and "no complete case" in p.stderr, f"no case: exit 2 ({p.stderr.strip()})")
    other = os.path.join(WORK, "other")
    write_case(other, "c1", excess_column="another_column")
    p = run_script(SCRIPT, other, "--out", os.path.join(WORK, "o2"))
    expect(p.returncode == 2 and "no column loop_excess_mm" in p.stderr, f"no excess column: exit 2 ({p.stderr.strip()})")
    p = run_script(SCRIPT, other, "--out", os.path.join(WORK, "o3"), "--budget", "0")
    expect(p.returncode == 2 and "--budget must be > 0" in p.stderr, f"a budget of 0: exit 2 ({p.stderr.strip()})")
    expect(not any(os.path.exists(os.path.join(WORK, o)) for o in ("o1", "o2", "o3")), "nothing written")
else:
    sys.exit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
