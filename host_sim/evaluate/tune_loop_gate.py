#!/usr/bin/env python3
"""Chooses the loop alarm's tracker gate (firmware/kinetics/slack_excess.hpp) and the raise level
that goes with it, on an evaluation of the development set, with the alarm's trees held out.

usage: tune_loop_gate.py EVAL_DIR [EVAL_DIR ...] --out gate.json [--png gate.png]

With the bench's EM tracker, the box's loop alarm from evidence counts a period's score only when
the scope taken up since the tip last kept pace (the truth's pace rule on the tracker's odometry:
model/truth/README.md, "Loop episodes") is at least the gate, and debounces it at its own raise
level (clear 0.1 below, 10 periods up, 100 down: as without the tracker). The scores come from
trees fitted with the case's patient left out (fit_loop_alarm.py's fit), so the choice is not
flattered by the development set's in-sample trees; the excess is computed as the firmware does:
at each fresh tip pose (the period whose time reaches the sample's), on the odometer's travel
(tune_tip_odometer.py's advances, sigmoid-corrected within 100 mm) and the insertion at that
period, held between poses; before the first pose the alarm is the one without the tracker, its
raise level read from the generated loop_alarm.cpp (run fit_loop_alarm.py first). Scored with the scorecard's rule; kept: the most
onsets within 0.5 s whose false alarms meet issue 21's bound (2 per 10 minutes) at the 90th
percentile over resampled sets of 20 patients (fit_loop_alarm.py's margin rule), ties to fewer
false alarms. Needs Debian's python3-sklearn, python3-numpy and python3-matplotlib (the picture
only).
"""
import argparse
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_loop_alarm as loop  # noqa: E402  (features, trees, debounce and scoring rule)
import tune_tip_odometer as odometer  # noqa: E402  (the tracker's advances)

GATES_MM = [0, 2, 4, 6, 8, 10, 12]
LEVELS = [round(v, 3) for v in np.arange(0.50, 0.801, 0.025)]
WINDOW_S, MIN_HAND_MM, PACE_FRACTION = 0.5, 1.0, 0.5
LOOP_ALARM_SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "firmware",
                                 "kinetics", "generated", "loop_alarm.cpp")


def level_without_tracker(source=LOOP_ALARM_SOURCE):
    """The raise level fit_loop_alarm.py wrote (EvidenceAlarm::Config{raise_raw, ...})."""
    with open(source) as f:
        found = re.search(r"EvidenceAlarm::Config\{(\d+),", f.read())
    if found is None:
        sys.exit(f"tune_loop_gate.py: {source}: no EvidenceAlarm::Config{{raise, ...}} found")
    return int(found.group(1)) / 65536.0


def excess_at_poses(pose_step, insertion, travel):
    """slack_excess.cpp: the excess at each pose (steps are period indices)."""
    window = int(round(WINDOW_S / loop.PERIOD_S))
    excess = np.zeros(pose_step.size)
    taken = insertion - travel
    base, first = taken[0], 0
    for k in range(pose_step.size):  # noqa: sequential, like the firmware
        while pose_step[k] - pose_step[first] > window:
            first += 1
        hand = insertion[k] - insertion[first]
        keeps_pace = hand >= MIN_HAND_MM and travel[k] - travel[first] >= PACE_FRACTION * hand
        base = taken[first:k + 1].min() if keeps_pace else min(base, taken[k])
        excess[k] = taken[k] - base
    return excess


def excess_at_periods(c):
    """The excess held between poses; NaN before the first pose (the tracker not yet valid)."""
    tr = c["tracker"]
    t = c["time_s"]
    pose_step = np.searchsorted(t, tr["time_s"] - 1e-9)  # the period whose time reaches it
    keep = pose_step < t.size
    pose_step = pose_step[keep]
    travel = np.r_[0.0, np.cumsum(tr["advance_mm"])][keep]
    ex = excess_at_poses(pose_step, c["depth"][pose_step], travel)
    out = np.full(t.size, np.nan)
    at = np.searchsorted(pose_step, np.arange(t.size), side="right") - 1
    has = at >= 0
    out[has] = ex[at[has]]
    return out


def alarm(score, excess, gate_mm, level, without_level):
    """evidence_alarm.cpp's debounce, with the tracker's settings where the excess is valid."""
    raw = loop.q16_raw(score)
    with_tracker = (int(loop.q16_raw(level)), int(loop.q16_raw(level - loop.HYSTERESIS)))
    without = (int(loop.q16_raw(without_level)), int(loop.q16_raw(without_level - loop.HYSTERESIS)))
    valid = ~np.isnan(excess)
    counted = np.where(valid & ~(np.nan_to_num(excess) >= gate_mm), 0, raw)
    up = np.zeros(raw.size, dtype=bool)
    state, run = False, 0
    for k in range(raw.size):  # noqa: sequential, like the firmware
        rise, clear = with_tracker if valid[k] else without
        v = counted[k]
        toward = v < clear if state else v > rise
        run = run + 1 if toward else 0
        if run >= (loop.CLEAR_STEPS if state else loop.RAISE_STEPS):
            state, run = not state, 0
        up[k] = state
    return up


def load(folder):
    c = loop.load(folder)
    if c is None:
        return None
    c["tracker"] = odometer.read_tracker(folder, odometer.SIGMOID_REACH_MM)
    return c if c["tracker"] is not None else None


def plot(path, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for gate in sorted({r["gate_mm"] for r in rows}):
        rs = [r for r in rows if r["gate_mm"] == gate]
        ax.plot([r["false_alarms_per_10min"] for r in rs], [100 * r["detected_share"] for r in rs],
                "o-", label=f"gate {gate:g} mm")
    ax.axvline(loop.BUDGET_PER_10MIN, ls="--", c="grey")
    ax.set_xlabel("false loop alarms per 10 min (held out)")
    ax.set_ylabel("loop onsets detected within 0.5 s [%]")
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                 epilog="Exit status: 0 written, 2 bad input.")
    ap.add_argument("eval_dir", nargs="+", help="one or more evaluation folders (`scopekin evaluate --out`), e.g. development and development_extra")
    ap.add_argument("--out", required=True, help="the JSON report to write")
    ap.add_argument("--png", help="a picture: detections against false alarms per gate")
    a = ap.parse_args()
    without_level = level_without_tracker()
    cases = odometer.read_tracker_cases(a.eval_dir, load, "tune_loop_gate.py")
    patient = loop.features.patient_of
    folds = loop.features.patient_folds(cases)
    for k, p in enumerate(folds):
        print(f"tune: the loop alarm's trees without patients {' '.join(sorted(p))} ({k + 1} of {len(folds)})",
              file=sys.stderr)
        trees = loop.fit([c for c in cases if patient(c) not in p])
        for c in cases:
            if patient(c) in p:
                c["score"] = trees.predict(c["X"])
                c["excess"] = excess_at_periods(c)
    rows = []
    for gate in GATES_MM:
        for level in LEVELS:
            r = loop.pooled(cases, lambda c: alarm(c["score"], c["excess"], gate, level, without_level))
            r.update(gate_mm=gate, level=level, detected_share=r["detected"] / max(r["episodes"], 1))
            rows.append(r)
            print(f"gate {gate:4g} mm, level {level:.3f}: {r['detected']} of {r['episodes']} within 0.5 s, "
                  f"{r['false_alarms_per_10min']:.2f} false alarms per 10 min "
                  f"(resampled p90 {r['false_alarms_per_10min_resampled']:.2f})", flush=True)
    without = loop.pooled(cases, lambda c: loop.debounced(c["score"], without_level))
    best = loop.best_within_budget(rows)
    report = {"eval_dir": a.eval_dir, "cases": len(cases), "level_without_tracker": without_level,
              "without_tracker": without,
              "budget_rule": loop.budget_rule(),
              "grid": rows, "chosen": best}
    with open(a.out, "w") as f:
        json.dump(report, f, indent=1)
    print(f"without the tracker (level {without_level:.3f}): {without['detected']} of {without['episodes']}, "
          f"{without['false_alarms_per_10min']:.2f} per 10 min "
          f"(resampled p90 {without['false_alarms_per_10min_resampled']:.2f})")
    print("chosen: " + (f"gate {best['gate_mm']:g} mm, level {best['level']:.3f}: {best['detected']} of "
                        f"{best['episodes']}, {best['false_alarms_per_10min']:.2f} per 10 min "
                        f"(resampled p90 {best['false_alarms_per_10min_resampled']:.2f})" if best
                        else "none within the false-alarm budget") + f"; written {a.out}")
    if a.png:
        plot(a.png, rows)


if __name__ == "__main__":
    main()
