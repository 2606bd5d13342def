#!/usr/bin/env python3
"""Checks host_sim/evaluate/tune_contact_level.py on synthetic evaluations whose answers are known,
and on bad input.

synthetic: three patients, each a 60 s case whose published force rises to 16 N at the onset of a
true >= 14 N episode (and so past 10 N at the >= 10 N episode's onset) and holds it for 2 s, and
twice per case jumps to 16 N for 50 ms (10 periods) where the truth has no episode. A persistence of
up to 10 periods raises the level on both jumps (two false alarms per case and level); 20 and 40
periods raise it only in the episodes, still within 0.5 s of the onsets (20 periods = 0.1 s). So
20 is chosen (the most detections within the budget; 20 and 40 tie, the shorter wins), with every
episode found and no false alarm; the model's force, a flat 12 N, finds no >= 14 N episode.
bad_input: a folder without cases, a validation set, a case without its columns: exit 2.

usage: check_tune_contact_level.py synthetic|bad_input SOURCE_DIR WORK_DIR"""
import json
import os
import sys

import numpy as np

from check_support import expect, failures, fresh_folder, run_script

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
TUNE = os.path.join(SOURCE, "host_sim", "evaluate", "tune_contact_level.py")
fresh_folder(WORK)
PERIOD_S = 0.005


def write_case(eval_dir, name, onset_s, spikes_s, columns=True):
    folder = os.path.join(eval_dir, "cases", name)
    os.makedirs(folder)
    t = PERIOD_S * np.arange(1, int(60 / PERIOD_S) + 1)
    published = np.full(t.size, 2.0)
    published[(t >= onset_s) & (t < onset_s + 2.0)] = 16.0
    for s in spikes_s:
        published[(t >= s - 1e-9) & (t < s + 0.05 - 1e-9)] = 16.0
    model = np.full(t.size, 12.0)
    names = "time_s,max_contact_force_N,model_max_contact_force_N" if columns else "time_s,other"
    data = np.column_stack([t, published, model]) if columns else np.column_stack([t, published])
    np.savetxt(os.path.join(folder, "firmware.csv"), data, delimiter=",", header=names, comments="", fmt="%.5f")
    np.savetxt(os.path.join(folder, "truth.csv"), np.column_stack([t, np.zeros(t.size)]), delimiter=",",
               header="time_s,scope_beyond_wall_mm", comments="", fmt="%.5f")
    episode = {"onset_s": onset_s, "end_s": onset_s + 2.0}
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump({"status": "complete", "truth": {"force_episodes": {
            "warning_10N": [episode], "critical_14N": [episode]}}}, f)


if CHECK == "synthetic":
    dev = os.path.join(WORK, "development")
    for k in range(3):
        write_case(dev, f"p{k + 1}-synthetic-s1", 20.0 + k, [5.0, 45.0])
    report = os.path.join(WORK, "level.json")
    p = run_script(TUNE, dev, "--report", report)
    expect(p.returncode == 0, f"runs ({p.returncode}: {p.stderr.strip()[-300:]})")
    r = json.load(open(report)) if os.path.exists(report) else {}
    rows = {row["persistence"]: row for row in r.get("by_persistence", [])}
    expect(all(rows[q]["critical_14N"]["false_alarms"] == 6 and rows[q]["warning_10N"]["false_alarms"] == 6
               for q in (1, 2, 5, 10) if q in rows) and len(rows) == 6,
           "up to 10 periods: both 50 ms jumps per case are false alarms, each level")
    expect(all(rows[q][k]["false_alarms"] == 0 and rows[q][k]["detected"] == 3
               for q in (20, 40) for k in ("critical_14N", "warning_10N")),
           "20 and 40 periods: no false alarm, every episode found within 0.5 s")
    expect((r.get("chosen") or {}).get("persistence") == 20, f"20 periods chosen ({(r.get('chosen') or {}).get('persistence')})")
    expect(r.get("reduced_model_level", {}).get("critical_14N", {}).get("detected") == 0,
           "the model's flat 12 N finds no >= 14 N episode")
elif CHECK == "bad_input":
    os.makedirs(os.path.join(WORK, "empty"))
    p = run_script(TUNE, os.path.join(WORK, "empty"))
    expect(p.returncode == 2 and "need at least 2 patients" in p.stderr, f"no cases: exit 2 ({p.returncode}: {p.stderr.strip()[-200:]})")
    val = os.path.join(WORK, "validation")
    write_case(val, "p1-synthetic-s1", 20.0, [])
    p = run_script(TUNE, val)
    expect(p.returncode == 2 and "not tuned on" in p.stderr, f"a validation set: exit 2 ({p.returncode}: {p.stderr.strip()[-200:]})")
    bad = os.path.join(WORK, "no_columns")
    write_case(bad, "p1-synthetic-s1", 20.0, [], columns=False)
    p = run_script(TUNE, bad)
    expect(p.returncode == 2 and "no column" in p.stderr, f"a case without its columns: exit 2 ({p.returncode}: {p.stderr.strip()[-200:]})")
else:
    sys.exit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
