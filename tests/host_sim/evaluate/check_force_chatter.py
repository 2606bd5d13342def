#!/usr/bin/python3
"""Checks of host_sim/evaluate/force_chatter.py (period-2 chatter of the truth's contact force).

  synthetic  three cases of 10 s at 10 ms world steps, truth.csv at the box's 5 ms periods (the
             periods between steps interpolated, as the truth does): an expert whose force goes
             0, 18, 0, 18 N from step to step for its first 2 s and is steady at 5 N after (steps
             1 to 999 at 0.01 to 9.99 s, 997 with two neighbours; chattering: 2 to 199 and 200,
             where 18 N falls to 5 N, 199); a trainee whose force rises 20 N in 100 ms and falls again (a
             fast but smooth force: no chatter) and who goes through the wall at 5 s, after which
             it chatters (not counted); a bench case that fails (skipped). The study must give
             199 of 997 and 0 of 497 and skip the failed case;
  bad_input  a folder with no cases, a case without max_station_force_N: exit 2, a message.
Usage: check_force_chatter.py CHECK SOURCE_DIR WORK_DIR
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_support import expect, failures, fresh_folder, run_script  # noqa: E402

CHECK, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SCRIPT = os.path.join(SOURCE, "host_sim", "evaluate", "force_chatter.py")
fresh_folder(WORK)


def write_case(root, name, force_at_step, through_wall_s=None, status="complete",
               column="max_station_force_N"):
    """A case of 10 s: force_at_step(k) at world step k (10 ms), interpolated at the 5 ms periods."""
    folder = os.path.join(root, "cases", name)
    os.makedirs(folder)
    with open(os.path.join(folder, "truth.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time_s", column])
        for period in range(1, 2000):
            k, odd = divmod(period, 2)
            force = force_at_step(k) if not odd else 0.5 * (force_at_step(k) + force_at_step(k + 1))
            w.writerow([f"{0.005 * period:.3f}", f"{force:.4f}"])
    json.dump({"status": status, "time_step_s": 0.01,
               "truth": {"scope_through_wall_s": through_wall_s}},
              open(os.path.join(folder, "summary.json"), "w"))


def expert(k):
    return (18.0 if k % 2 else 0.0) if k < 200 else 5.0


def trainee(k):
    if k >= 500:
        return 18.0 if k % 2 else 0.0  # through the wall: not counted
    rise = min(max(k - 300, 0), 10) - min(max(k - 320, 0), 10)
    return 2.0 * rise  # 0 -> 20 N in 100 ms and back


def run(*args):
    return run_script(SCRIPT, *args)


if CHECK == "synthetic":
    evaluation = os.path.join(WORK, "evaluation")
    write_case(evaluation, "p1-expert-s1", expert)
    write_case(evaluation, "p1-trainee-s1", trainee, through_wall_s=5.0)
    write_case(evaluation, "p1-bench-s1", expert, status="failed")
    out = os.path.join(WORK, "study")
    p = run(evaluation, "--out", out)
    expect(p.returncode == 0, f"the study runs (exit {p.returncode}: {p.stderr.strip()[-300:]})")
    rows = {r["case"]: r for r in csv.DictReader(open(os.path.join(out, "force_chatter.csv")))}
    expect(set(rows) == {"p1-expert-s1", "p1-trainee-s1"}, f"the failed case is skipped ({sorted(rows)})")
    e = rows.get("p1-expert-s1", {})
    expect(e.get("chattering") == "199" and e.get("steps") == "997",
           f"the expert chatters in 199 of 997 steps ({e})")
    t = rows.get("p1-trainee-s1", {})
    expect(t.get("chattering") == "0" and t.get("steps") == "497",
           f"the trainee's fast smooth force is no chatter; its steps end at the wall ({t})")
    report = json.load(open(os.path.join(out, "force_chatter.json")))
    expect(abs(report["styles"]["expert"]["worst"] - 199 / 997) < 1e-12 and
           report["all"]["cases_above_10_percent"] == 1, f"the summary ({report['all']})")
    expect(os.path.isfile(os.path.join(out, "force_chatter.png")), "the picture is drawn")
elif CHECK == "bad_input":
    empty = os.path.join(WORK, "empty")
    os.makedirs(os.path.join(empty, "cases"))
    p = run(empty, "--out", os.path.join(WORK, "o1"))
    expect(p.returncode == 2 and "no complete case" in p.stderr, f"no case: exit 2 ({p.stderr.strip()})")
    other = os.path.join(WORK, "other")
    write_case(other, "p1-expert-s1", expert, column="another_force_N")
    p = run(other, "--out", os.path.join(WORK, "o2"))
    expect(p.returncode == 2 and "no column max_station_force_N" in p.stderr,
           f"a truth without the force: exit 2 ({p.stderr.strip()})")
else:
    sys.exit(f"unknown check {CHECK}")
sys.exit(1 if failures else 0)
