#!/usr/bin/python3
"""Checks of host_sim/evaluate/alarm_speed.py (an alarm's timing against the hand's speed).

  synthetic  one case of 120 s whose hand advances at 10, then 20, then 40 mm/s (40 s each), with
             a 5 s loop episode in the middle of each stretch (onsets 20, 60, 100 s). The box's
             alarm rises 0.2 s after the first onset (detected), 2 s after the second (late) and
             not for the third (missed), and once more at 90 s (a false alarm, hand at 40 mm/s);
             the force monitor's never rises. The study must file them under slow, middle and
             fast with those outcomes and latencies, 1 false alarm in the ~39 s the hand spent
             at >= 30 mm/s, and none for the force monitor;
  bad_input  a folder with no cases, a case without the estimator's column: exit 2, a message.
Usage: check_alarm_speed.py CHECK SOURCE_DIR WORK_DIR
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_support import expect, failures, fresh_folder, run_script  # noqa: E402

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SCRIPT = os.path.join(SOURCE, "host_sim", "evaluate", "alarm_speed.py")
fresh_folder(WORK)
ONSETS = (20.0, 60.0, 100.0)
BOX_RISES = (20.2, 62.0, 90.0)


def insertion(t):
    if t < 40:
        return 10 * t
    if t < 80:
        return 400 + 20 * (t - 40)
    return 1200 + 40 * (t - 80)


def write_case(root, name, box_column="box_loop_alarm"):
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    times = [k * 0.005 for k in range(1, 24001)]
    with open(os.path.join(folder, "truth.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", "insertion_mm"])
        for t in times:
            w.writerow([f"{t:.3f}", f"{insertion(t):.3f}"])
    with open(os.path.join(folder, "estimates.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", box_column, "force_monitor_loop_alarm"])
        for t in times:
            up = any(r <= t + 1e-9 < r + 1.0 for r in BOX_RISES)  # each rise up for 1 s
            w.writerow([f"{t:.3f}", 1 if up else 0, 0])
    json.dump({"status": "complete",
               "truth": {"scope_through_wall_s": None,
                         "loop_episodes": [{"onset_s": o, "end_s": o + 5.0} for o in ONSETS]}},
              open(os.path.join(folder, "summary.json"), "w"))


def run(*args):
    return run_script(SCRIPT, *args)


if CHECK == "synthetic":
    evaluation = os.path.join(WORK, "evaluation")
    write_case(evaluation, "c1")
    out = os.path.join(WORK, "study")
    p = run(evaluation, "--out", out, "--estimators", "box,force_monitor")
    expect(p.returncode == 0, f"the study runs (exit {p.returncode}: {p.stderr.strip()[-300:]})")
    report = json.load(open(os.path.join(out, "alarm_speed.json")))["estimators"]
    box = report["box"]["bins"]
    slow, middle, fast = box["slow (5..15)"], box["middle (15..30)"], box["fast (>= 30)"]
    expect(slow["detected"] == 1 and abs(slow["median_latency_s"] - 0.2) < 1e-6,
           f"slow: detected 0.2 s after the onset ({slow})")
    expect(middle["late"] == 1 and abs(middle["median_latency_s"] - 2.0) < 1e-6, f"middle: late by 2 s ({middle})")
    expect(fast["missed"] == 1 and fast["false_alarms"] == 1, f"fast: missed, one false alarm ({fast})")
    expect(38.0 <= fast["seconds_at_speed"] <= 40.0 and
           abs(fast["false_alarms_per_10min"] - 600.0 / fast["seconds_at_speed"]) < 1e-9,
           f"fast: per 10 min of the time at that speed ({fast['seconds_at_speed']} s)")
    monitor = report["force_monitor"]["bins"]
    expect(sum(b["missed"] for b in monitor.values()) == 3 and
           sum(b["false_alarms"] for b in monitor.values()) == 0, "the silent monitor misses all three")
    rows = list(csv.DictReader(open(os.path.join(out, "alarm_speed_episodes.csv"))))
    expect(len(rows) == 6 and {r["outcome"] for r in rows if r["estimator"] == "box"} ==
           {"detected", "late", "missed"}, "one row per episode and estimator")
    expect(os.path.isfile(os.path.join(out, "alarm_speed.png")), "the picture is drawn")
elif CHECK == "bad_input":
    empty = os.path.join(WORK, "empty")
    os.makedirs(os.path.join(empty, "cases"))
    p = run(empty, "--out", os.path.join(WORK, "o1"))
    expect(p.returncode == 2 and "no complete scored case" in p.stderr, f"no case: exit 2 ({p.stderr.strip()})")
    other = os.path.join(WORK, "other")
    write_case(other, "c1", box_column="another_loop_alarm")
    p = run(other, "--out", os.path.join(WORK, "o2"), "--estimators", "box")
    expect(p.returncode == 2 and "no column box_loop_alarm" in p.stderr,
           f"an estimator the evaluation lacks: exit 2 ({p.stderr.strip()})")
else:
    sys.exit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
