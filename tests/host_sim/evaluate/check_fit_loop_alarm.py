#!/usr/bin/env python3
"""Checks host_sim/evaluate/fit_loop_alarm.py on a synthetic evaluation whose answer is known:
four patients whose loops start 0.3 s into each hard push (the push force steps from 5 to 20 N
for 3 s at random times), where the reduced model's alarm never rises. Leaving each patient out,
the chosen raise level must find at least 90 % of the onsets within 0.5 s at no more than 2 false
alarms per 10 minutes; the source must hold 100 complete trees of depth 4 and the alarm's
settings; bad input must exit 2 and write nothing. The margin rule's resampled rate is checked
against closed forms: patients all at one rate give that rate, and one patient in ten with 20 false
alarms per 10 min (the rest none) gives the binomial quantile: the 90th percentile of
Binomial(20, 0.1) heavy patients in 20 is 4, so 4 per 10 min where the pooled rate is 2.

usage: check_fit_loop_alarm.py CHECK SOURCE_DIR WORK_DIR   (CHECK: synthetic | bad_input)"""
import json
import os
import re
import subprocess
import sys

import numpy as np

from check_support import expect, failures, fresh_folder

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
FIT = os.path.join(SOURCE, "host_sim", "evaluate", "fit_loop_alarm.py")


def write_case(root, name, seed):
    rng = np.random.default_rng(seed)
    n = 24000  # 120 s at the box's 5 ms
    t = 0.005 * np.arange(1, n + 1)
    pushes = np.cumsum(rng.uniform(10.0, 18.0, 8))
    pushes = pushes[pushes < 115.0]
    force = 5.0 + rng.normal(0, 0.2, n)
    for p in pushes:
        force[(t >= p) & (t < p + 3.0)] += 15.0
    depth = 20 + 10 * t
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    episodes = [{"onset_s": float(p + 0.3), "end_s": float(p + 3.0)} for p in pushes]
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump({"status": "complete", "truth": {"loop_episodes": episodes}}, f)
    zeros = np.zeros(n)
    np.savetxt(os.path.join(folder, "truth.csv"), np.column_stack([t, depth, zeros, zeros]),
               delimiter=",", header="time_s,tip_path_mm,scope_beyond_wall_mm,max_station_force_N",
               comments="", fmt="%.6f")
    np.savetxt(os.path.join(folder, "recording.csv"), np.column_stack([t - 0.001, force, depth]),
               delimiter=",", header="time_s,handle_force_N,insertion_mm", comments="", fmt="%.6f")
    np.savetxt(os.path.join(folder, "firmware.csv"), np.column_stack([t, depth, depth, zeros, zeros]),
               delimiter=",", header="time_s,tip_path_mm,observer_tip_path_mm,max_contact_force_N,self_lock_alarm",
               comments="", fmt="%.6f")


def fit(*args):
    return subprocess.run(["/usr/bin/python3", FIT, *args], capture_output=True, text=True)


fresh_folder(WORK)
if CHECK == "synthetic":
    for k in range(4):
        write_case(WORK, f"p{k + 1}-synthetic-s1", k + 1)
    out, report = os.path.join(WORK, "loop_alarm.cpp"), os.path.join(WORK, "fit.json")
    p = fit(WORK, "--out", out, "--report", report)
    expect(p.returncode == 0, f"the fit exits 0 (got {p.returncode}: {p.stderr[-500:]})")
    r = json.load(open(report))
    chosen, model = r["chosen"], r["reduced_model_self_lock"]
    expect(model["detected"] == 0, f"the model's alarm finds nothing: {model}")
    expect(chosen["detected"] >= 0.9 * chosen["episodes"] and chosen["false_alarms_per_10min"] <= 2.0,
           f"held out, the chosen level finds >= 90 % within 0.5 s at <= 2 per 10 min: {chosen}")
    text = open(out).read()
    arrays = {name: re.search(name + r"\[\] = \{([^}]*)\}", text).group(1) for name in
              ["kFeature", "kThresholdRaw", "kLeafRaw"]}
    counts = {k: len([v for v in a.replace("\n", " ").split(",") if v.strip()]) for k, a in arrays.items()}
    expect(counts == {"kFeature": 1500, "kThresholdRaw": 1500, "kLeafRaw": 1600},
           f"100 complete trees of depth 4: {counts}")
    raise_raw = int(np.floor(chosen["raise_level"] * 65536))
    expect(f"EvidenceAlarm::Config{{{raise_raw}," in text and "10U, 100U}" in text,
           "the source defines default_loop_alarm() with the chosen level and the debounce")
    expect(chosen["false_alarms_per_10min_resampled"] <= 2.0,
           f"the chosen level meets the budget at the resampled 90th percentile: {chosen}")
    sys.path.insert(0, os.path.dirname(FIT))
    import fit_loop_alarm
    same = fit_loop_alarm.resampled_false_alarm_rate([[3, 900.0]] * 7)
    expect(abs(same - 2.0) < 1e-9, f"patients all at 2 per 10 min: the quantile is 2 ({same})")
    one_heavy = fit_loop_alarm.resampled_false_alarm_rate([[0, 600.0]] * 9 + [[20, 600.0]])
    expect(abs(one_heavy - 4.0) < 1e-9, f"one patient in ten at 20 per 10 min: p90 4 ({one_heavy})")
    expect(r["firmware_vs_sklearn_max_abs"] < 0.1,  # a feature at a float32 threshold: one leaf
           f"the firmware's integer evaluation matches the learner's: {r['firmware_vs_sklearn_max_abs']}")
elif CHECK == "bad_input":
    p = fit(os.path.join(WORK, "missing"), "--out", os.path.join(WORK, "x.cpp"))
    expect(p.returncode == 2 and "need at least 2 patients" in p.stderr,
           f"no evaluation: exit 2 ({p.returncode}, {p.stderr.strip()[-200:]})")
    write_case(WORK, "p1-a-s1", 1)
    with open(os.path.join(WORK, "cases", "p1-a-s1", "firmware.csv"), "w") as f:
        f.write("time_s,step_index\n0.005,0\n")
    p = fit(WORK, "--out", os.path.join(WORK, "x.cpp"))
    expect(p.returncode == 2 and "no column" in p.stderr,
           f"a firmware.csv without the box's columns: exit 2 ({p.returncode}, {p.stderr.strip()[-200:]})")
    expect(not os.path.exists(os.path.join(WORK, "x.cpp")), "nothing written")
else:
    raise SystemExit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
