#!/usr/bin/python3
"""Checks of host_sim/evaluate/stale_force_study.py (the estimate while the force cell is silent).

  synthetic  one case of 60 s whose truth tip is the insertion, whose largest force is 2 N and
             whose loop episode covers the first half of the silent window, run through a stand-in
             box (this script, as `fake_box run`) that publishes the insertion as the tip and 2 N
             while the force cell speaks, and the insertion + 10 mm, 3 N and a raised alarm while
             it is silent: the study must find 10 mm and 1 N RMS in the window, 0 after it, the
             loop alarmed for half the window and raised without a loop for the other half, and
             0 / 0 N for the case's own (working) firmware.csv;
  bad_input  a folder with no cases, and a box that refuses the recording: exit 2 and a message.
Usage: check_stale_force_study.py CHECK SOURCE_DIR WORK_DIR
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_support import expect, failures, fresh_folder, run_script  # noqa: E402


def fake_box(recording, out):
    """The stand-in box: one row per 5 ms period, from the recording's last sample."""
    os.makedirs(out, exist_ok=True)
    with open(recording, newline="") as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(out, "firmware.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", "tip_path_mm", "tip_uncertainty_mm", "max_contact_force_N",
                    "self_lock_alarm"])
        for row in rows[4::5]:
            silent = row["handle_force_N"] == ""
            depth = float(row["insertion_mm"])
            w.writerow([row["time_s"], depth + (10 if silent else 0), 5, 3 if silent else 2,
                        1 if silent else 0])


if len(sys.argv) > 1 and sys.argv[1] == "fake_box":  # called by the study as its `BIN run`
    if "refuse" in sys.argv[3]:
        print("line 2: not a recording", file=sys.stderr)
        sys.exit(2)
    fake_box(sys.argv[3], sys.argv[sys.argv.index("--out") + 1])
    sys.exit(0)

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SCRIPT = os.path.join(SOURCE, "host_sim", "evaluate", "stale_force_study.py")
fresh_folder(WORK)
box = os.path.join(WORK, "fake_box")
with open(box, "w") as f:
    f.write(f"#!/bin/sh\nexec {sys.executable} {os.path.abspath(__file__)} fake_box \"$@\"\n")
os.chmod(box, 0o755)


def write_case(root, name):
    """60 s at 1 kHz, insertion 10 mm/s; silent window (at 0.4, 20 s) is 24..44 s."""
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    with open(os.path.join(folder, "recording.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", "handle_force_N", "handle_torque_Nmm", "insertion_mm", "roll_rad", "region"])
        for k in range(1, 60001):
            w.writerow([f"{k / 1000:.3f}", "2.0", "0.0", f"{k / 100:.3f}", "0", "rectum"])
    with open(os.path.join(folder, "truth.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", "tip_path_mm", "max_station_force_N", "loop_episode"])
        for k in range(1, 12001):
            t = k * 0.005
            w.writerow([f"{t:.3f}", f"{t * 10:.3f}", "2", 1 if 24.0 <= t < 34.0 else 0])
    json.dump({"status": "complete", "truth": {"scope_through_wall_s": None}},
              open(os.path.join(folder, "summary.json"), "w"))
    fake_box(os.path.join(folder, "recording.csv"), folder)  # the case's own run: the cell working
    return folder


def run(*args):
    return run_script(SCRIPT, *args)


if CHECK == "synthetic":
    evaluation = os.path.join(WORK, "evaluation")
    write_case(evaluation, "c1")
    out = os.path.join(WORK, "study")
    p = run(evaluation, "--scopekin", box, "--out", out)
    expect(p.returncode == 0, f"the study runs (exit {p.returncode}: {p.stderr.strip()[-300:]})")
    expect("[1/1] c1" in p.stdout, "progress names the case")
    s = json.load(open(os.path.join(out, "stale_force.json")))["runs"]
    silent, working = s["silent"], s["working"]
    expect(abs(silent["tip_rms_mm"]["median"] - 10.0) < 0.01, f"tip 10 mm RMS while silent: {silent['tip_rms_mm']}")
    expect(abs(silent["force_rms_N"]["median"] - 1.0) < 1e-6, f"force 1 N RMS while silent: {silent['force_rms_N']}")
    expect(abs(silent["tip_rms_after_mm"]["median"]) < 1e-9, "no tip error after the window")
    expect(abs(silent["loop_alarmed_s"] - 10.0) < 0.02 and abs(silent["loop_s"] - 10.0) < 0.02,
           f"the loop half of the window alarmed: {silent['loop_alarmed_s']} of {silent['loop_s']} s")
    expect(abs(silent["alarm_without_loop_s"] - 10.0) < 0.02,
           f"the loop-free half raised without a loop: {silent['alarm_without_loop_s']} s")
    expect(working["tip_rms_mm"]["median"] < 1e-9 and working["force_rms_N"]["median"] < 1e-9
           and working["loop_alarmed_s"] == 0.0, "the working run: no error, no alarm")
    with open(os.path.join(out, "cases", "c1", "recording.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    empty = [float(r["time_s"]) for r in rows if r["handle_force_N"] == ""]
    expect(len(empty) == 20000 and abs(min(empty) - 24.0) < 1e-9 and abs(max(empty) - 43.999) < 1e-9,
           f"20 s silenced from 40 % of the run: {len(empty)} rows")
    rows = list(csv.DictReader(open(os.path.join(out, "stale_force.csv"))))
    expect([r["run"] for r in rows] == ["silent", "working"], "the CSV has a row per run")
    expect(os.path.isfile(os.path.join(out, "stale_force.png")), "the picture is drawn")
elif CHECK == "bad_input":
    empty = os.path.join(WORK, "empty")
    os.makedirs(os.path.join(empty, "cases"))
    p = run(empty, "--scopekin", box, "--out", os.path.join(WORK, "o1"))
    expect(p.returncode == 2 and "no complete case" in p.stderr, f"no case: exit 2 ({p.returncode}, {p.stderr.strip()})")
    p = run(WORK, "--scopekin", box, "--out", os.path.join(WORK, "o2"))
    expect(p.returncode == 2 and "no cases/ folder" in p.stderr, f"not an evaluation: exit 2 ({p.stderr.strip()})")
    write_case(os.path.join(WORK, "refuse"), "c1")
    p = run(os.path.join(WORK, "refuse"), "--scopekin", box, "--out", os.path.join(WORK, "refuse_out"))
    expect(p.returncode == 2 and "exited 2" in p.stderr and "not a recording" in p.stderr,
           f"a refused recording: exit 2, the box's message ({p.stderr.strip()})")
    p = run(empty, "--scopekin", box, "--out", os.path.join(WORK, "o3"), "--at", "1.5")
    expect(p.returncode == 2 and "--at" in p.stderr, f"--at outside [0, 1): exit 2 ({p.stderr.strip()})")
else:
    sys.exit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
