#!/usr/bin/env python3
"""Checks host_sim/evaluate/tune_tip_odometer.py on synthetic evaluations whose answer is known.

- exact_odometer: four patients whose slack (depth - tip) grows from 0 to 0, 50, 100 and 150 mm
  whatever the push, so the held-out handle (the other three patients' mean) is biased for the
  whole run, and whose EM tip sensor moves exactly along its own axis with the tip: the filter
  should lean on the odometry, so the longest correlation time must be chosen and its fused tip
  error must be below a fifth of the held-out handle's.
- drifting_odometer: the slack is a step in the push force (40 mm above 10 N), which the held-out
  handle learns, and the EM tip over-counts its advance by half: the shortest correlation time
  must be chosen.
- bad_input: a folder without cases and a bad --correlations exit 2 and write nothing.

usage: check_tune_tip_odometer.py CHECK SOURCE_DIR WORK_DIR"""
import json
import os
import subprocess
import sys

import numpy as np

from check_support import expect, failures, fresh_folder

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
TUNE = os.path.join(SOURCE, "host_sim", "evaluate", "tune_tip_odometer.py")
EM = [f"em_tip_{c}" for c in ("x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz")] + \
     [f"em_sigmoid_{c}" for c in ("x_mm", "y_mm", "z_mm")]


def write_case(root, name, seed, drifting):
    rng = np.random.default_rng(seed)
    n = 20000  # 100 s at the box's 5 ms
    t = 0.005 * np.arange(1, n + 1)
    depth = 20 + 10 * t + 5 * np.sin(t / 3)
    force = 10 + 8 * np.sin(t / (2 + seed)) + rng.normal(0, 0.3, n)
    if drifting:
        slack = np.where(force > 10, 40.0, 0.0)
    else:
        slack = 50.0 * (seed - 1) * (1 - np.exp(-t / 20))  # 0, 50, 100, 150 mm taken up
    tip = depth - slack
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump({"status": "complete"}, f)
    np.savetxt(os.path.join(folder, "truth.csv"),
               np.column_stack([t, tip, np.zeros(n), np.zeros(n)]), delimiter=",",
               header="time_s,tip_path_mm,scope_beyond_wall_mm,max_station_force_N", comments="", fmt="%.6f")
    np.savetxt(os.path.join(folder, "firmware.csv"), np.column_stack([t, depth, depth, np.zeros(n)]),
               delimiter=",", header="time_s,tip_path_mm,observer_tip_path_mm,max_contact_force_N",
               comments="", fmt="%.6f")
    # The tip sensor every 6th period (~33 Hz), on the x axis (identity orientation), no sigmoid.
    sensed = (1.5 if drifting else 1.0) * tip
    with open(os.path.join(folder, "recording.csv"), "w") as f:
        f.write(",".join(["time_s", "handle_force_N", "insertion_mm"] + EM) + "\n")
        for k in range(n):
            em = [f"{sensed[k]:.3f}", "0", "0", "1", "0", "0", "0", "", "", ""] if k % 6 == 0 else [""] * 10
            f.write(",".join([f"{t[k] - 0.001:.6f}", f"{force[k]:.4f}", f"{depth[k]:.4f}"] + em) + "\n")


def tune(*args):
    return subprocess.run(["/usr/bin/python3", TUNE, *args], capture_output=True, text=True)


fresh_folder(WORK)


if CHECK in ("exact_odometer", "drifting_odometer"):
    drifting = CHECK == "drifting_odometer"
    for k in range(4):
        write_case(WORK, f"p{k + 1}-synthetic-s1", k + 1, drifting)
    out, png = os.path.join(WORK, "tune.json"), os.path.join(WORK, "tune.png")
    p = tune(WORK, "--out", out, "--png", png, "--correlations", "2.5,10,40,120")
    expect(p.returncode == 0, f"the tuning exits 0 (got {p.returncode}: {p.stderr[-500:]})")
    r = json.load(open(out))
    grid = {g["correlation_s"]: g for g in r["grid"]}
    print(json.dumps({"handle": r["handle_held_out"], "grid": r["grid"]}, indent=1))
    expect(os.path.getsize(png) > 1000, "the picture is written")
    if drifting:
        expect(r["chosen_correlation_s"] == 2.5, f"an over-counting odometer: the shortest time ({r['chosen_correlation_s']})")
        expect(grid[2.5]["median_mm"] < grid[120]["median_mm"], "errors grow with the correlation time")
    else:
        expect(r["chosen_correlation_s"] == 120, f"an exact odometer: the longest time ({r['chosen_correlation_s']})")
        expect(grid[120]["median_mm"] < 0.2 * r["handle_held_out"]["median_mm"],
               f"the fused tip beats the held-out handle by 5x: {grid[120]['median_mm']:.1f} vs "
               f"{r['handle_held_out']['median_mm']:.1f} mm")
elif CHECK == "bad_input":
    out = os.path.join(WORK, "tune.json")
    os.makedirs(os.path.join(WORK, "empty"))
    p = tune(os.path.join(WORK, "empty"), "--out", out)
    expect(p.returncode == 2 and "need at least 2 patients" in p.stderr,
           f"no cases: exit 2 with a reason ({p.returncode}: {p.stderr.strip()[-200:]})")
    p = tune(os.path.join(WORK, "empty"), "--out", out, "--correlations", "5,-1")
    expect(p.returncode == 2 and "--correlations" in p.stderr,
           f"a negative correlation time: exit 2 ({p.returncode}: {p.stderr.strip()[-200:]})")
    expect(not os.path.exists(out), "nothing written")
else:
    sys.exit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
