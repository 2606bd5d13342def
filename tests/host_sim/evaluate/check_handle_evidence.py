#!/usr/bin/python3
"""Checks of host_sim/evaluate/handle_evidence.py (what the handle alone tells).

  rules      the alarm scoring against episodes, on traces whose answers are known by hand (the
             scorecard's rule, host_sim/evaluate/README.md), and the alarm's debounce;
  positive   a synthetic evaluated set whose handle force ramps at 10 N/s from 0.5 s before each
             loop's onset, whose tip lags the insertion by 2 mm per N of push above 5 N and whose
             largest station force is half the push: on patients it was not trained on the study
             must find >= 90 % of the onsets within 0.5 s at <= 2 false alarms per 10 min, and
             its tip and force errors must be under a fifth of their baselines' (it finds what is
             there);
  negative   the same set with the ramps 7 s away from every onset and the tip lag and station
             force drawn independently of the handle: it must claim no more than 20 % of the
             onsets, and its errors must stay above 0.8 of the baselines' (it does not invent what
             is not there);
  bad_input  a folder with no cases: exit 2 and a message.
Usage: check_handle_evidence.py CHECK SOURCE_DIR WORK_DIR
"""
import csv
import importlib.util
import json
import os
import shutil
import subprocess
import sys

import numpy as np

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SCRIPT = os.path.join(SOURCE, "host_sim", "evaluate", "handle_evidence.py")
failures = []


def expect(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def module():
    spec = importlib.util.spec_from_file_location("handle_evidence", SCRIPT)
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def make_set(folder, related):
    """Four patients x one 80 s case: insertion at 20 mm/s, force 5 N + noise; a loop episode
    every 20 s (onset 10 + 20 k s + 1.3 s x patient, 5 s long) and a 10 N/s force ramp from
    0.5 s before (onset, or onset + 7 s when not related) to 5.5 s later. Related: the tip lags
    the insertion by 2 mm/N x (force - 5 N)+ and the largest station force is force / 2;
    otherwise both are slow random walks of the same size, independent of the handle."""
    rng = np.random.default_rng(7)
    period = 0.005
    t = np.round(np.arange(1, 16001) * period, 6)
    for p in range(4):
        case = os.path.join(folder, "cases", f"p90{p:02d}-expert-s1")
        os.makedirs(case, exist_ok=True)
        onsets = [10.0 + 20 * k + 1.3 * p for k in range(4)]
        force = 5 + 0.3 * rng.standard_normal(t.size)
        for o in onsets:
            start = o + (0.0 if related else 7.0) - 0.5
            on = (t >= start) & (t <= start + 5.5)
            force[on] += 10.0 * (t[on] - start)
        if related:
            lag_mm, station_N = 2.0 * np.maximum(force - 5.0, 0.0), force / 2.0
        else:
            walk = lambda scale: scale * np.abs(np.cumsum(rng.standard_normal(t.size)) / 40.0)
            lag_mm, station_N = walk(20.0), 2.5 + walk(5.0)
        tip = 20 * t - lag_mm
        with open(os.path.join(case, "estimates.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["time_s", "true_tip_path_mm", "true_max_station_force_N"])
            w.writerows([[f"{v:.6f}", f"{a:.3f}", f"{b:.3f}"] for v, a, b in zip(t, tip, station_N)])
        with open(os.path.join(case, "recording.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["time_s", "handle_force_N", "handle_torque_Nmm", "insertion_mm", "roll_rad"])
            w.writerows([[f"{v:.6f}", f"{fv:.3f}", "0.0", f"{20 * v:.2f}", "0.0"]
                         for v, fv in zip(t, force)])
        episodes = [{"onset_s": o, "end_s": o + 5.0} for o in onsets]
        with open(os.path.join(case, "summary.json"), "w") as f:
            json.dump({"truth": {"loop_episodes": episodes}}, f)


def run_study(folder, out):
    p = subprocess.run(["/usr/bin/python3", SCRIPT, folder, "--out", out, "--folds", "2"],
                       capture_output=True, text=True)
    expect(p.returncode == 0, f"the study runs: {p.stderr[-500:]}")
    report = json.load(open(os.path.join(out, "handle_evidence.json")))
    for name in ["handle_evidence_loop.csv", "handle_evidence_errors.csv", "handle_evidence.png"]:
        expect(os.path.getsize(os.path.join(out, name)) > 0, f"wrote {name}")
    found = report["sets"]["development (patients left out)"]
    errors = found["error_distributions"]["expert"]
    ratio = lambda a, b: errors[a]["median"] / errors[b]["median"]
    return (found["best_within_budget"]["expert"]["within_2_per_10min"],
            ratio("tip_learned_rms_mm", "tip_insertion_rms_mm"),
            ratio("force_learned_rms_N", "force_constant_rms_N"))


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
if CHECK == "rules":
    m = module()
    t = np.round(np.arange(0, 4000) * 0.005, 6)  # 0 .. 19.995 s
    episodes = [(10.0, 15.0)]

    def rises(*at):
        up = np.zeros(t.size, dtype=bool)
        for a, b in at:
            up[(t >= a) & (t < b)] = True
        return up
    # A rise 0.8 s early detects; 0.4 s after the onset detects; 0.6 s after is late (not a
    # detection, not a false alarm: inside the episode); at 17 s, after the end, a false alarm.
    expect(m.score_alarm(t, rises((9.2, 9.5)), episodes)[:2] == (1, 0), "a rise 0.8 s early detects")
    expect(m.score_alarm(t, rises((10.4, 11)), episodes)[:2] == (1, 0), "a rise 0.4 s late detects")
    expect(m.score_alarm(t, rises((10.6, 11)), episodes)[:2] == (0, 0), "0.6 s late: not detected, not false")
    expect(m.score_alarm(t, rises((8.5, 9)), episodes)[:2] == (0, 1), "1.5 s early: a false alarm")
    expect(m.score_alarm(t, rises((10.2, 10.3), (17, 18)), episodes)[:2] == (1, 1), "after the end: false")
    expect(m.score_alarm(t, rises((10.6, 11)), episodes, 2.0)[:2] == (1, 0), "within 2 s: 0.6 s detects")
    on, off = m.ON_PERIODS, m.OFF_PERIODS
    score = np.array([0.8] * (on - 1) + [0.2] + [0.8] * on + [0.55] * off + [0.45] * off + [0.2])
    up = m.alarm(score, 0.7)
    expect(not up[:2 * on - 1].any() and up[2 * on - 1], "rises after ON_PERIODS above the threshold")
    expect(up[2 * on:2 * on + off].all(), "stays up above threshold - hysteresis")
    expect(up[2 * on + 2 * off - 2] and not up[2 * on + 2 * off - 1], "falls after OFF_PERIODS below it")
elif CHECK in ("positive", "negative"):
    make_set(os.path.join(WORK, "set"), CHECK == "positive")
    best, tip_ratio, force_ratio = run_study(os.path.join(WORK, "set"), os.path.join(WORK, "out"))
    share = 0.0 if best is None else best["detected_share"]
    print(f"{CHECK}: onsets {share:.2f}, tip error / insertion's {tip_ratio:.2f}, "
          f"force error / constant's {force_ratio:.2f}")
    if CHECK == "positive":
        expect(share >= 0.9, f"a 10 N/s ramp at each onset: {share:.2f} of the onsets found (>= 0.9)")
        expect(tip_ratio < 0.2, f"tip lag 2 mm/N: learned / insertion error {tip_ratio:.2f} (< 0.2)")
        expect(force_ratio < 0.2, f"station force F / 2: learned / constant {force_ratio:.2f} (< 0.2)")
    else:
        expect(share <= 0.2, f"ramps 7 s away from the onsets: {share:.2f} claimed (<= 0.2)")
        expect(tip_ratio > 0.8, f"tip lag unrelated: learned / insertion {tip_ratio:.2f} (> 0.8)")
        expect(force_ratio > 0.8, f"force unrelated: learned / constant {force_ratio:.2f} (> 0.8)")
elif CHECK == "bad_input":
    os.makedirs(os.path.join(WORK, "empty"))
    p = subprocess.run(["/usr/bin/python3", SCRIPT, os.path.join(WORK, "empty"), "--out",
                        os.path.join(WORK, "out")], capture_output=True, text=True)
    expect(p.returncode == 2 and "no cases/" in p.stderr, f"no cases: exit {p.returncode}, {p.stderr}")
else:
    sys.exit(f"unknown check {CHECK}")
print(f"{len(failures)} check(s) failed" if failures else f"{CHECK}: all checks passed")
sys.exit(1 if failures else 0)
