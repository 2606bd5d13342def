#!/usr/bin/env python3
"""Checks host_sim/evaluate/friction_evidence.py on synthetic case folders whose answer is known:
handle forces made by Coulomb's law from the stations' normal forces, mu = 0.1-0.4, the hand
going back and forth. The fit must give each mu back (within 0.01) and rank them perfectly; a load
proportional to the normal forces that does not reverse with the hand must fit as no friction
(the negative control); a case that only advances is not scored. Bad input: no cases, a firmware.csv without the stations'
normal forces, exit 2 with the reason.

usage: check_friction_evidence.py synthetic|bad_input SOURCE_DIR WORK_DIR"""
import csv
import json
import os
import subprocess
import sys

import numpy as np

from check_support import expect, failures, fresh_folder

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SCRIPT = os.path.join(SOURCE, "host_sim", "evaluate", "friction_evidence.py")
fresh_folder(WORK)


def run(*args):
    return subprocess.run(["/usr/bin/python3", SCRIPT, *args], capture_output=True, text=True)


def write_case(root, name, mu, back_and_forth=True, stations=True, seed=0, coulomb=True, style="hurried_trainee",
               start_mm=100.0):
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    t = 0.005 * np.arange(1, 6001)  # 30 s
    if back_and_forth:  # 20 mm/s for 2 s, then back for 1 s: a triangle wave on an advance
        phase = np.mod(t, 3.0)
        speed = np.where(phase < 2.0, 20.0, -20.0)
    else:
        speed = np.full(t.size, 20.0)
    depth = start_mm + np.cumsum(speed) * 0.005
    normal0 = 10.0 + 5.0 * np.sin(t)  # N: the model's station forces, varying with the depth
    normal1 = 4.0 + 0.02 * depth
    rng = np.random.default_rng(seed)
    if coulomb:
        force = mu * np.sign(speed) * (normal0 + normal1) + 2.0 + rng.normal(0, 0.05, t.size)
    else:  # a load that grows with the contact forces but does not reverse with the hand
        force = mu * (normal0 + normal1) + rng.normal(0, 0.05, t.size)
    json.dump({"status": "complete", "procedure": {"style": style},
               "patient": {"mechanics": {"friction_coefficient": mu}}, "truth": {}},
              open(os.path.join(folder, "summary.json"), "w"))
    with open(os.path.join(folder, "recording.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", "handle_force_N", "insertion_mm"])
        w.writerows(zip(t, force, depth))
    with open(os.path.join(folder, "firmware.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        names = [f"station_{i}_normal_N" for i in range(12)] if stations else []
        w.writerow(["time_s"] + names)
        for k in range(t.size):
            w.writerow([t[k]] + ([normal0[k], normal1[k]] + [0.0] * 10 if stations else []))
    # The advancing push index's closed form: Coulomb's push, mu N + 2 N, over the advancing periods
    # (the script's speed, smoothed over 0.1 s, is above 3 mm/s on all but the reversals' edges).
    advancing = speed > 0
    return float(np.mean(mu * (normal0 + normal1)[advancing] + 2.0))


if CHECK == "synthetic":
    root = os.path.join(WORK, "eval")
    mus = [0.1, 0.2, 0.3, 0.4]
    pushes = {}
    for i, mu in enumerate(mus):  # from 400 mm: inside the push index's 300-900 mm
        pushes[f"p{i}-trainee-s1"] = write_case(root, f"p{i}-trainee-s1", mu, seed=i, start_mm=400.0)
    write_case(root, "p9-trainee-s1", 0.25, back_and_forth=False)
    write_case(root, "p8-expert-s1", 0.3, coulomb=False, style="careful_expert")
    out = os.path.join(WORK, "out")
    p = run(root, "--out", out)
    expect(p.returncode == 0, f"exit 0 ({p.returncode}: {p.stderr.strip()[-300:]})")
    rows = list(csv.DictReader(open(os.path.join(out, "friction_evidence.csv"))))
    fitted = {r["case"]: float(r["mu_hat"]) for r in rows}
    for i, mu in enumerate(mus):
        got = fitted.get(f"p{i}-trainee-s1")
        expect(got is not None and abs(got - mu) < 0.01, f"mu {mu} fitted back within 0.01: {got}")
    expect("p9-trainee-s1" not in fitted, "a case that only advances is not scored")
    index = {r["case"]: r["advancing_push_N"] for r in rows}
    for name, expected in pushes.items():
        got = float(index[name]) if index.get(name) else None
        expect(got is not None and abs(got - expected) < 0.1,
               f"{name}: advancing push {got} N, Coulomb's {expected:.2f} N")
    expect(index.get("p8-expert-s1") == "", "no push index below 300 mm")
    got = fitted.get("p8-expert-s1")
    expect(got is not None and abs(got) < 0.01,
           f"a load that does not reverse with the hand is not friction: fitted {got}")
    report = json.load(open(os.path.join(out, "friction_evidence.json")))
    expect(abs(report["by_style"]["hurried_trainee"]["spearman"] - 1.0) < 1e-9, "ranked perfectly")
    expect(abs(report["by_style"]["hurried_trainee"]["spearman_advancing_push"] - 1.0) < 1e-9,
           "the push index ranks them perfectly too")
    expect(os.path.isfile(os.path.join(out, "friction_evidence.png")), "the picture is drawn")
elif CHECK == "bad_input":
    os.makedirs(os.path.join(WORK, "empty", "cases"))
    p = run(os.path.join(WORK, "empty"), "--out", os.path.join(WORK, "out"))
    expect(p.returncode == 2 and "need at least 3" in p.stderr, f"no cases: exit 2 ({p.returncode}: {p.stderr.strip()})")
    root = os.path.join(WORK, "no_stations")
    write_case(root, "p0-trainee-s1", 0.2, stations=False)
    p = run(root, "--out", os.path.join(WORK, "out"))
    expect(p.returncode == 2 and "station_0_normal_N" in p.stderr,
           f"no station forces: exit 2 naming the column ({p.returncode}: {p.stderr.strip()})")
    p = run(root, "--out", os.path.join(WORK, "out"), "--min-speed", "0")
    expect(p.returncode == 2 and "--min-speed" in p.stderr, f"--min-speed 0: exit 2 ({p.returncode})")
    expect(not os.path.exists(os.path.join(WORK, "out")), "nothing written")
else:
    sys.exit(f"unknown check {CHECK}")

if failures:
    sys.exit(f"{len(failures)} check(s) failed")
