#!/usr/bin/env python3
"""The discrepancy workflow's speed bound, measured: a 10-minute recording must take at most
2 minutes (issue 22; goal 30 s) on this 2-core machine. The recordings are the bench session
host_sim/scenarios/bench_session_10min.json (ten 60 s cycles of advance, hold, roll, withdrawal)
with each library effect hidden in turn, a pair and none, each simulated with its own seed, then
given to `scopekin discrepancy --no-plots` one at a time, as a user would.

usage:
  ten_minute_bench.py --scopekin BIN --out DIR [--only REGEX]

Writes DIR/NAME/ (scenario.json, recorded/, discrepancy/) and DIR/bench.json, bench.csv and
bench.md: per recording the verdict, the names and values fitted against the truth (judged by the
sweep's rule), the runs, the workflow's own wall time, the command's, and its CPU seconds per wall
second (how much of the two cores it had). Exit status: 0 every recording within 2 minutes, 1 one
was slower or could not be run, 2 bad usage."""
import argparse
import csv
import json
import os
import re
import resource
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import procedures  # noqa: E402

SCENARIO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenarios",
                        "bench_session_10min.json")
BOUND_S = 120.0  # issue 22: a 10-minute recording in at most 2 minutes
SIGMOID = {"name": "sigmoid_mobility", "amplitude_N_per_mm": 0.004, "frequency_Hz": 0.3, "direction": [0, 0.6, 0.8],
           "phase_rad": 0.7}
# name, hidden effects, simulation seed (the README's table: the scenario as committed with seed 5,
# the other effects swapped in with seeds 31-36).
RECORDINGS = [
    ("viscoadhesive_friction", [{"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0.003}], 5),
    ("mesenteric_retraction", [{"name": "mesenteric_retraction", "stiffness_N_per_mm2": 0.0025}], 31),
    ("ei_profile", [{"name": "ei_profile", "tip_factor": 0.75, "handle_factor": 1.15}], 32),
    ("tissue_stiffening", [{"name": "tissue_stiffening", "stiffening_per_N": 0.4}], 33),
    ("sigmoid_mobility", [SIGMOID], 34),
    ("pair", [{"name": "ei_scale", "factor": 0.88}, {"name": "viscoadhesive_friction",
                                                      "viscous_coefficient_s_per_mm": 0.003}], 35),
    ("none", [], 36),
]


def cpu_s():
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def run(cmd):
    """The command's wall time and CPU time (s); raises RuntimeError when it fails."""
    start, cpu = time.monotonic(), cpu_s()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[:2])}: exit {p.returncode}: {p.stderr.strip()[-500:]}")
    return time.monotonic() - start, cpu_s() - cpu


def bench_one(scopekin, out, name, effects, seed):
    work = os.path.join(out, name)
    os.makedirs(work, exist_ok=True)
    scenario = json.load(open(SCENARIO))
    scenario["truth_effects"] = effects
    scenario_path = os.path.join(work, "scenario.json")
    with open(scenario_path, "w") as f:
        json.dump(scenario, f, indent=1)
    run([scopekin, "simulate", scenario_path, "--out", os.path.join(work, "recorded"), "--seed", str(seed)])
    wall, cpu = run([scopekin, "discrepancy", os.path.join(work, "recorded", "recording.csv"), "--out",
                     os.path.join(work, "discrepancy"), "--no-plots", "--quiet"])
    report = json.load(open(os.path.join(work, "discrepancy", "report.json")))
    judged = procedures.judge(report, effects)
    return {"name": name, "seed": seed, "hidden": effects, "verdict": report["verdict"], "named": judged["named"],
            "success": judged["success"], "why": judged.get("why"), "parameters": judged.get("parameters", []),
            "model_runs": report.get("model_runs"), "simulated_s": report.get("simulated_s"),
            "workflow_wall_s": round(report.get("wall_time_s", 0.0), 1), "command_wall_s": round(wall, 1),
            "cpu_per_wall": round(cpu / wall, 2), "within_bound": wall <= BOUND_S}


def fitted_text(row):
    return "; ".join(f"{p['parameter']} {p['fitted']:.4g} (truth {p['truth']:.4g})" if p["fitted"] is not None
                     else f"{p['parameter']} not fitted" for p in row["parameters"]) or "-"


def write_tables(out, rows):
    with open(os.path.join(out, "bench.json"), "w") as f:
        json.dump({"bound_s": BOUND_S, "recordings": rows}, f, indent=1)
    with open(os.path.join(out, "bench.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["name", "seed", "verdict", "named", "success", "model_runs", "workflow_wall_s", "command_wall_s",
                    "cpu_per_wall", "within_bound"])
        for r in rows:
            w.writerow([r["name"], r["seed"], r["verdict"], "+".join(r["named"]), r["success"], r["model_runs"],
                        r["workflow_wall_s"], r["command_wall_s"], r["cpu_per_wall"], r["within_bound"]])
    lines = ["| hidden | verdict | named | fitted (truth) | right | runs | wall time (workflow) | CPU s per wall s |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['verdict']} | {', '.join(r['named']) or '-'} | {fitted_text(r)} | "
                     f"{'yes' if r['success'] else 'no'} | {r['model_runs']} | {r['command_wall_s']} s "
                     f"({r['workflow_wall_s']} s) | {r['cpu_per_wall']} |")
    with open(os.path.join(out, "bench.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scopekin", required=True, help="the scopekin binary")
    ap.add_argument("--out", required=True, help="folder for the recordings, the reports and bench.*")
    ap.add_argument("--only", help="only the recordings whose name matches this regular expression")
    args = ap.parse_args()
    if not os.access(args.scopekin, os.X_OK):
        ap.error(f"--scopekin {args.scopekin}: not an executable file")
    try:
        chosen = [r for r in RECORDINGS if args.only is None or re.search(args.only, r[0])]
    except re.error as e:
        ap.error(f"--only: {e}")
    if not chosen:
        ap.error("--only: no recording selected")
    os.makedirs(args.out, exist_ok=True)
    rows, failed = [], 0
    for i, (name, effects, seed) in enumerate(chosen, 1):
        print(f"[{i}/{len(chosen)}] {name}: simulating and running the workflow ...", file=sys.stderr, flush=True)
        try:
            row = bench_one(args.scopekin, args.out, name, effects, seed)
        except RuntimeError as e:
            print(f"[{i}/{len(chosen)}] {name}: FAILED: {e}", file=sys.stderr, flush=True)
            failed += 1
            continue
        rows.append(row)
        print(f"[{i}/{len(chosen)}] {name}: {row['verdict']} {'+'.join(row['named'])}, {row['model_runs']} runs, "
              f"{row['command_wall_s']} s ({row['cpu_per_wall']} CPU s per s)"
              f"{'' if row['within_bound'] else ' OVER THE BOUND'}", file=sys.stderr, flush=True)
        write_tables(args.out, rows)
    slow = sum(not r["within_bound"] for r in rows)
    print(f"{len(rows)} recording(s), {slow} over {BOUND_S:.0f} s, {failed} failed; {args.out}/bench.md",
          file=sys.stderr)
    return 1 if slow or failed else 0


if __name__ == "__main__":
    sys.exit(main())
