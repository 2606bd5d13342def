#!/usr/bin/env python3
"""What the box's estimate is worth while the handle's force cell is silent: a fault study.

usage: stale_force_study.py EVAL_DIR --scopekin BIN --out DIR [--at FRACTION] [--silence-s S]
                            [--after-s S]

For each complete case of an evaluation (EVAL_DIR/cases/NAME with recording.csv, truth.csv and
summary.json, as `scopekin evaluate` writes them), the case's recording is copied with the force
cell silent (handle_force_N and handle_torque_Nmm emptied: one sensor, no sample) for --silence-s
seconds (default 20) from --at of the recording's duration (default 0.4), and run through the
firmware with `BIN run` (BIN: the scopekin CLI). Inside the silent window (cut where the truth's
scope went through the wall) and over --after-s seconds after it (default 20) the study measures,
against truth.csv:
  * tip error RMS [mm] (firmware tip_path_mm - truth tip_path_mm), and the fraction of the
    window's periods within one published standard deviation (tip_uncertainty_mm);
  * largest contact force error RMS [N] (max_contact_force_N - truth max_station_force_N);
  * the loop alarm: seconds of the truth's loop episodes with self_lock_alarm raised, and seconds
    without a loop with it raised.
The case's own firmware.csv in EVAL_DIR (the cell working) is scored over the same windows beside
it, when it is there.

Writes DIR/stale_force.csv (a row per case and run: "silent" and "working"), DIR/stale_force.json
(per run: median / 90th percentile / worst of the cases' RMS, pooled loop seconds) and
DIR/stale_force.png (the cases' tip and force RMS, silent against working; needs
python3-matplotlib, skipped with a note without it), and DIR/cases/NAME/ (the silent recording
and the firmware's outputs on it). Prints one line per case. Exit status 2 for bad input (no
complete case, a missing column, the firmware refusing a recording), 3 if an output cannot be
written.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

import numpy as np

from case_columns import BadInput, case_folders, columns, complete_summary

PERIOD_S = 0.005  # the box's period
SILENCED = ("handle_force_N", "handle_torque_Nmm")


def silence_recording(source, target, at, silence_s):
    """Copies the recording with the force cell's columns emptied in the window; returns it."""
    with open(source, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        raise BadInput(f"{source}: no rows")
    header = rows[0]
    missing = [n for n in ("time_s",) + SILENCED if n not in header]
    if missing:
        raise BadInput(f"{source}: no column {', '.join(missing)}")
    try:
        end_s = float(rows[-1][0])
    except ValueError:
        raise BadInput(f"{source}: last row has no time")
    start, stop = at * end_s, at * end_s + silence_s
    columns = [header.index(n) for n in SILENCED]
    with open(target, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(header)
        for row in rows[1:]:
            if start <= float(row[0]) < stop:
                for c in columns:
                    row[c] = ""
            if any(cell != "" for cell in row[1:-1]):  # a row left with no sample at all is dropped
                writer.writerow(row)
    return start, stop


def score(firmware_csv, truth, start, stop, after_s, cut_s):
    """The window's and the after-window's measures of one firmware run (None if it is empty)."""
    fw = columns(firmware_csv, ["time_s", "tip_path_mm", "tip_uncertainty_mm",
                                   "max_contact_force_N", "self_lock_alarm"])
    t = fw["time_s"]
    tip = np.interp(t, truth["time_s"], truth["tip_path_mm"])
    force = np.interp(t, truth["time_s"], truth["max_station_force_N"])
    loop = np.interp(t, truth["time_s"], truth["loop_episode"]) > 0.5
    error = fw["tip_path_mm"] - tip
    inside = (t >= start) & (t < stop) & (t < cut_s)
    after = (t >= stop) & (t < stop + after_s) & (t < cut_s)
    if not inside.any():
        return None
    alarm = fw["self_lock_alarm"][inside] > 0.5
    return {
        "tip_rms_mm": float(np.sqrt(np.mean(error[inside] ** 2))),
        "tip_rms_after_mm": float(np.sqrt(np.mean(error[after] ** 2))) if after.any() else None,
        "tip_within_1sd": float(np.mean(np.abs(error[inside]) <= fw["tip_uncertainty_mm"][inside])),
        "force_rms_N": float(np.sqrt(np.mean((fw["max_contact_force_N"][inside] - force[inside]) ** 2))),
        "loop_s": float(loop[inside].sum() * PERIOD_S),
        "loop_alarmed_s": float((alarm & loop[inside]).sum() * PERIOD_S),
        "loop_free_s": float((~loop[inside]).sum() * PERIOD_S),
        "alarm_without_loop_s": float((alarm & ~loop[inside]).sum() * PERIOD_S),
    }


def study_case(folder, out_folder, args):
    """(name, window, {run: measures}) of a complete case, None if it is not one."""
    summary = complete_summary(folder)
    if summary is None:
        return None
    name = os.path.basename(folder.rstrip("/"))
    cut_s = (summary.get("truth") or {}).get("scope_through_wall_s") or float("inf")
    truth = columns(os.path.join(folder, "truth.csv"),
                    ["time_s", "tip_path_mm", "max_station_force_N", "loop_episode"])
    if len(truth["time_s"]) == 0:
        raise BadInput(f"{name}: truth.csv has no rows")
    os.makedirs(out_folder, exist_ok=True)
    silent = os.path.join(out_folder, "recording.csv")
    start, stop = silence_recording(os.path.join(folder, "recording.csv"), silent, args.at, args.silence_s)
    run = subprocess.run([args.scopekin, "run", silent, "--out", out_folder, "--quiet"],
                         capture_output=True, text=True)
    if run.returncode != 0:
        raise BadInput(f"{name}: `{args.scopekin} run` exited {run.returncode}: {run.stderr.strip()[:300]}")
    measures = {"silent": score(os.path.join(out_folder, "firmware.csv"), truth, start, stop,
                                args.after_s, cut_s)}
    working = os.path.join(folder, "firmware.csv")
    if os.path.isfile(working):
        measures["working"] = score(working, truth, start, stop, args.after_s, cut_s)
    if measures["silent"] is None:
        return None
    return name, (start, stop), measures


def spread(values):
    values = [v for v in values if v is not None]
    if not values:
        return None
    return {"median": float(np.median(values)), "p90": float(np.percentile(values, 90)),
            "worst": float(np.max(values)), "cases": len(values)}


def summarise(results):
    runs = {}
    for run in ("silent", "working"):
        rows = [m[run] for _, _, m in results if m.get(run) is not None]
        if not rows:
            continue
        runs[run] = {key: spread([r[key] for r in rows])
                     for key in ("tip_rms_mm", "tip_rms_after_mm", "tip_within_1sd", "force_rms_N")}
        for key in ("loop_s", "loop_alarmed_s", "loop_free_s", "alarm_without_loop_s"):
            runs[run][key] = float(sum(r[key] for r in rows))
    return runs


def write_outputs(out, results, summary, args):
    keys = ["tip_rms_mm", "tip_rms_after_mm", "tip_within_1sd", "force_rms_N", "loop_s",
            "loop_alarmed_s", "loop_free_s", "alarm_without_loop_s"]
    with open(os.path.join(out, "stale_force.csv"), "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(["case", "run", "silent_from_s", "silent_to_s"] + keys)
        for name, (start, stop), measures in results:
            for run, m in measures.items():
                if m is not None:
                    writer.writerow([name, run, f"{start:.3f}", f"{stop:.3f}"] +
                                    ["" if m[k] is None else f"{m[k]:.6g}" for k in keys])
    with open(os.path.join(out, "stale_force.json"), "w") as f:
        json.dump({"eval_dir": args.eval_dir, "at_fraction": args.at, "silence_s": args.silence_s,
                   "after_s": args.after_s, "runs": summary}, f, indent=1)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("note: no python3-matplotlib, stale_force.png not drawn", file=sys.stderr)
        return
    pairs = [(m["working"], m["silent"]) for _, _, m in results if m.get("working") and m["silent"]]
    if not pairs:
        return
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for ax, key, unit in ((axes[0], "tip_rms_mm", "tip error RMS [mm]"),
                          (axes[1], "force_rms_N", "largest force error RMS [N]")):
        x = [w[key] for w, _ in pairs]
        y = [s[key] for _, s in pairs]
        top = max(x + y) * 1.05
        ax.plot([0, top], [0, top], color="grey", lw=0.8)
        ax.scatter(x, y, s=14)
        ax.set_xlabel(f"cell working: {unit}")
        ax.set_ylabel(f"cell silent: {unit}")
    fig.suptitle(f"{args.silence_s:g} s without the force cell, per case")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "stale_force.png"), dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("eval_dir")
    parser.add_argument("--scopekin", required=True, help="the scopekin CLI")
    parser.add_argument("--out", required=True)
    parser.add_argument("--at", type=float, default=0.4, help="silence from this fraction of the run")
    parser.add_argument("--silence-s", type=float, default=20.0)
    parser.add_argument("--after-s", type=float, default=20.0)
    args = parser.parse_args()
    try:
        if not 0.0 <= args.at < 1.0 or not args.silence_s > 0 or not args.after_s >= 0:
            raise BadInput("--at must be in [0, 1), --silence-s > 0, --after-s >= 0")
        results = []
        cases = case_folders(args.eval_dir)
        for k, (name, folder) in enumerate(cases):
            result = study_case(folder, os.path.join(args.out, "cases", name), args)
            if result is None:
                print(f"[{k + 1}/{len(cases)}] {name}: not a complete case, skipped", flush=True)
                continue
            results.append(result)
            m = result[2]["silent"]
            print(f"[{k + 1}/{len(cases)}] {name}: tip {m['tip_rms_mm']:.1f} mm, force "
                  f"{m['force_rms_N']:.2f} N RMS while silent", flush=True)
        if not results:
            raise BadInput(f"{args.eval_dir}: no complete case")
    except BadInput as e:
        print(f"stale_force_study: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"stale_force_study: cannot write under {args.out}: {e}", file=sys.stderr)
        return 3
    summary = summarise(results)
    try:
        write_outputs(args.out, results, summary, args)
    except OSError as e:
        print(f"stale_force_study: cannot write {args.out}: {e}", file=sys.stderr)
        return 3
    for run, s in summary.items():
        tip, force = s["tip_rms_mm"], s["force_rms_N"]
        print(f"{run}: tip {tip['median']:.1f} / {tip['p90']:.1f} / {tip['worst']:.1f} mm, force "
              f"{force['median']:.2f} / {force['p90']:.2f} / {force['worst']:.2f} N (median / p90 / "
              f"worst of {tip['cases']} cases); loop alarmed {s['loop_alarmed_s']:.0f} of "
              f"{s['loop_s']:.0f} s, without a loop {s['alarm_without_loop_s']:.0f} of {s['loop_free_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
