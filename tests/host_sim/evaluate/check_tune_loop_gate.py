#!/usr/bin/env python3
"""Checks host_sim/evaluate/tune_loop_gate.py's bad input: a folder without cases, and cases
without EM tracker columns, exit 2 with the reason and write nothing. (The gate's rule itself is
checked in the firmware, tests/firmware/kinetics/test_slack_excess.cpp, whose closed-form cases
the script's excess_at_poses is checked against here.)

usage: check_tune_loop_gate.py bad_input SOURCE_DIR WORK_DIR"""
import json
import os
import subprocess
import sys

import numpy as np

from check_support import expect, failures, fresh_folder

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
TUNE = os.path.join(SOURCE, "host_sim", "evaluate", "tune_loop_gate.py")
fresh_folder(WORK)


def tune(*args):
    return subprocess.run(["/usr/bin/python3", TUNE, *args], capture_output=True, text=True)


if CHECK != "bad_input":
    sys.exit(f"unknown check {CHECK}")
out = os.path.join(WORK, "gate.json")
os.makedirs(os.path.join(WORK, "empty"))
p = tune(os.path.join(WORK, "empty"), "--out", out)
expect(p.returncode == 2 and "need at least 2 patients" in p.stderr,
       f"no cases: exit 2 with a reason ({p.returncode}: {p.stderr.strip()[-200:]})")
# A complete case without the tracker's columns is skipped, so again too few patients.
folder = os.path.join(WORK, "no_tracker", "cases", "p1-synthetic-s1")
os.makedirs(folder)
with open(os.path.join(folder, "summary.json"), "w") as f:
    json.dump({"status": "complete", "truth": {"loop_episodes": []}}, f)
t = 0.005 * np.arange(1, 401)
np.savetxt(os.path.join(folder, "truth.csv"), np.column_stack([t, 20 + t, np.zeros(t.size), np.zeros(t.size)]),
           delimiter=",", header="time_s,tip_path_mm,scope_beyond_wall_mm,max_station_force_N", comments="")
np.savetxt(os.path.join(folder, "recording.csv"), np.column_stack([t, np.zeros(t.size), 20 + t]),
           delimiter=",", header="time_s,handle_force_N,insertion_mm", comments="")
np.savetxt(os.path.join(folder, "firmware.csv"), np.column_stack([t, 20 + t, 20 + t, np.zeros(t.size), np.zeros(t.size)]),
           delimiter=",", header="time_s,tip_path_mm,observer_tip_path_mm,max_contact_force_N,self_lock_alarm",
           comments="")
p = tune(os.path.join(WORK, "no_tracker"), "--out", out)
expect(p.returncode == 2 and "EM tracker" in p.stderr,
       f"no tracker columns: exit 2 naming the tracker ({p.returncode}: {p.stderr.strip()[-200:]})")
expect(not os.path.exists(out), "nothing written")

# The script's excess against the firmware test's closed form: 60 poses at pace (1 mm each,
# every 6 periods), then 30 with the tip still: 30 mm taken up.
sys.path.insert(0, os.path.join(SOURCE, "host_sim", "evaluate"))
import tune_loop_gate  # noqa: E402
k = np.arange(91)
excess = tune_loop_gate.excess_at_poses(6 * k, k.astype(float), np.minimum(k, 60).astype(float))
expect(excess[-1] == 30 and excess[65] == 5 and excess[60] == 0,
       f"the excess of a tip that stops dead: {excess[60]}, {excess[65]}, {excess[-1]} (0, 5, 30 mm)")
sys.exit(1 if failures else 0)
