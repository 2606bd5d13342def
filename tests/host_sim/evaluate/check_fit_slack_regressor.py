#!/usr/bin/env python3
"""Checks host_sim/evaluate/fit_slack_regressor.py on a synthetic evaluation whose answer is known:
four patients whose slack is a step function of the push force (40 mm above 10 N, else 0), with
the observer's tip at the depth (its slack always 0). The cases are in two evaluation folders read
together; leaving each patient out, the trees must learn the step (held-out tip error below a quarter of the observer's), the written source must hold
100 trees of depth 4 (15 nodes, 16 leaves each) and the uncertainty law, and bad input must exit 2.
With --target contact_force the truth's largest station force is a step in the push force too
(12 N above 10 N of push, else 2 N) where the reduced model said 0 N: the trees must learn it.

usage: check_fit_slack_regressor.py CHECK SOURCE_DIR WORK_DIR   (CHECK: synthetic | bad_input)"""
import json
import os
import re
import subprocess
import sys

import numpy as np

from check_support import expect, failures, fresh_folder

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
FIT = os.path.join(SOURCE, "host_sim", "evaluate", "fit_slack_regressor.py")


def write_case(root, name, seed):
    rng = np.random.default_rng(seed)
    n = 20000  # 100 s at the box's 5 ms
    t = 0.005 * np.arange(1, n + 1)
    depth = 20 + 10 * t + 5 * np.sin(t / 3)
    force = 10 + 8 * np.sin(t / (2 + seed)) + rng.normal(0, 0.3, n)
    slack = np.where(force > 10, 40.0, 0.0)
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump({"status": "complete"}, f)
    wall_force = np.where(force > 10, 12.0, 2.0)
    np.savetxt(os.path.join(folder, "truth.csv"),
               np.column_stack([t, depth - slack, np.zeros(n), wall_force]), delimiter=",",
               header="time_s,tip_path_mm,scope_beyond_wall_mm,max_station_force_N", comments="", fmt="%.6f")
    np.savetxt(os.path.join(folder, "recording.csv"), np.column_stack([t - 0.001, force, depth]),
               delimiter=",", header="time_s,handle_force_N,insertion_mm", comments="", fmt="%.6f")
    np.savetxt(os.path.join(folder, "firmware.csv"), np.column_stack([t, depth, depth, np.zeros(n)]),
               delimiter=",", header="time_s,tip_path_mm,observer_tip_path_mm,max_contact_force_N",
               comments="", fmt="%.6f")


def fit(*args):
    return subprocess.run(["/usr/bin/python3", FIT, *args], capture_output=True, text=True)


fresh_folder(WORK)


def check_patient_folds():
    """Up to 12 patients each is its own fold; beyond, 12 disjoint groups that cover them all."""
    sys.path.insert(0, os.path.dirname(FIT))
    import fit_slack_regressor as fitter
    few = [{"name": f"p{k}-expert-s1"} for k in range(1, 5)] + [{"name": "p1-trainee-s1"}]
    expect(sorted(map(sorted, fitter.patient_folds(few))) == [["p1"], ["p2"], ["p3"], ["p4"]],
           f"four patients, four folds: {fitter.patient_folds(few)}")
    many = [{"name": f"p{1000 + k}-trainee-s1"} for k in range(36)]
    folds = fitter.patient_folds(many)
    covered = [p for f in folds for p in f]
    expect(len(folds) == 12 and len(covered) == 36 and len(set(covered)) == 36
           and all(len(f) == 3 for f in folds), f"36 patients, 12 disjoint folds of 3: {folds}")


if CHECK == "synthetic":
    check_patient_folds()
    # Two evaluation folders (as development and development_extra), two patients each.
    for k in range(4):
        write_case(os.path.join(WORK, "a" if k < 2 else "b"), f"p{k + 1}-synthetic-s1", k + 1)
    out, report = os.path.join(WORK, "trees.cpp"), os.path.join(WORK, "fit.json")
    p = fit(os.path.join(WORK, "a"), os.path.join(WORK, "b"), "--out", out, "--report", report)
    expect(p.returncode == 0, f"the fit exits 0 (got {p.returncode}: {p.stderr[-500:]})")
    r = json.load(open(report))
    expect(r["cases"] == 4 and r["patients"] == 4, f"both folders read: {r['cases']} cases, {r['patients']} patients")
    held = r["held_out_tip_rms_mm"]
    expect(held["observer"]["median"] > 15, f"the observer misses the slack: {held['observer']}")
    expect(held["regressor"]["median"] < 0.25 * held["observer"]["median"],
           f"the trees learn the step on held-out patients: {held['regressor']} vs {held['observer']}")
    u = r["uncertainty"]
    expect(abs(u["held_out_within_1sd"] - 0.68) < 0.02, f"the law holds 68 % of held-out periods: {u}")
    text = open(out).read()
    arrays = {name: re.search(name + r"\[\] = \{([^}]*)\}", text).group(1) for name in
              ["kFeature", "kThresholdRaw", "kLeafRaw"]}
    counts = {k: len([v for v in a.replace("\n", " ").split(",") if v.strip()]) for k, a in arrays.items()}
    expect(counts == {"kFeature": 1500, "kThresholdRaw": 1500, "kLeafRaw": 1600},
           f"100 complete trees of depth 4: {counts}")
    expect("default_slack_trees()" in text and "100U, 4U" in text, "the source defines default_slack_trees()")
    expect(r["firmware_vs_sklearn_max_abs"] < 1e-3,
           f"the firmware's integer evaluation matches the learner's: {r['firmware_vs_sklearn_max_abs']}")
    force_out, force_report = os.path.join(WORK, "force_trees.cpp"), os.path.join(WORK, "force_fit.json")
    p = fit(os.path.join(WORK, "a"), os.path.join(WORK, "b"), "--target", "contact_force", "--out", force_out,
            "--report", force_report)
    expect(p.returncode == 0, f"the force fit exits 0 (got {p.returncode}: {p.stderr[-500:]})")
    held = json.load(open(force_report))["held_out_force_rms_N"]
    expect(held["model"]["median"] > 5, f"the model's 0 N misses the wall force: {held['model']}")
    expect(held["regressor"]["median"] < 0.25 * held["model"]["median"],
           f"the force trees learn the step on held-out patients: {held['regressor']} vs {held['model']}")
    expect("default_contact_force_trees()" in open(force_out).read(),
           "the source defines default_contact_force_trees()")
elif CHECK == "bad_input":
    p = fit(os.path.join(WORK, "missing"), "--out", os.path.join(WORK, "x.cpp"))
    expect(p.returncode == 2 and "complete cases" in p.stderr, f"no evaluation: exit 2 ({p.returncode}, {p.stderr.strip()})")
    write_case(WORK, "p1-a-s1", 1)
    os.remove(os.path.join(WORK, "cases", "p1-a-s1", "firmware.csv"))
    with open(os.path.join(WORK, "cases", "p1-a-s1", "firmware.csv"), "w") as f:
        f.write("time_s,step_index\n0.005,0\n")
    p = fit(WORK, "--out", os.path.join(WORK, "x.cpp"))
    expect(p.returncode == 2 and "no column" in p.stderr, f"a firmware.csv without the tip: exit 2 ({p.returncode}, {p.stderr.strip()[-200:]})")
    expect(not os.path.exists(os.path.join(WORK, "x.cpp")), "nothing written")
else:
    raise SystemExit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
