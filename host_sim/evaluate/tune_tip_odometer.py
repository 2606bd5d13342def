#!/usr/bin/env python3
"""Chooses the tip odometer's correlation time (firmware/kinetics/tip_odometer.hpp) on an
evaluation of the development set, with the handle's tip held out.

usage: tune_tip_odometer.py EVAL_DIR [EVAL_DIR ...] --out tune.json [--png tune.png] [--correlations 5,10,20]
                            [--sigmoid-reach MM]

The filter pulls the EM tracker's odometry towards the handle's tip, the slack regressor's. In
the development set's own firmware that tip is in-sample (its trees were fitted on those very
cases: 27.6 mm RMS in the median case against 48.4 held out), so a filter tuned on it trusts the
handle more than a new patient deserves. Here each patient's handle tip comes from trees fitted
with that patient left out (fit_slack_regressor.py's leave-one-patient-out fit), with the
uncertainty law fitted the same way as the firmware's (floor + a |slack| + b depth, scaled to 68 %
of the held-out periods). The filter runs in floating point as tip_odometer.cpp runs it: at each
fresh tip pose the advance along the mid-interval axis, less the sigmoid sensor's displacement
within --sigmoid-reach (100 mm, the firmware's); every UPDATE_STEPS periods the update with gain r / (r + c / T); the
bounds 600 mm behind and 400 mm ahead of the depth (TipObserver). The model-evidence trust rule
is left out (a held-out patient is not the training patient). Scored like the scorecard: per case
RMS over the case's periods up to where the scope goes through the wall; median, 90th
percentile, worst; the share of periods within 1 and 2 stated SDs. The chosen correlation time
has the least median + 90th percentile.

The filter's estimate depends on q and c only through q / c; q (Q_MM2_PER_MM) then sets the
width of the stated SD and is not varied here. Needs Debian's python3-sklearn, python3-numpy and
python3-matplotlib (the picture only).
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_slack_regressor as slack  # noqa: E402  (cases, features and the trees' learner)

PERIOD_S = 0.005
UPDATE_STEPS = 20
Q_MM2_PER_MM = 0.5
SIGMOID_REACH_MM = 100.0
MAX_SLACK_MM, MAX_AHEAD_MM = 600.0, 400.0
MAX_VARIANCE_MM2 = 30000.0
CORRELATIONS_S = [2.5, 5, 10, 15, 20, 30, 40, 60, 120]


def scope_axis(q):
    """R(q) e_x for unit quaternions (w, x, y, z), row-wise."""
    w, x, y, z = q.T
    return np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], 1)


def read_tracker(folder, sigmoid_reach_mm):
    """The tip's and the sigmoid's poses at the tip sensor's samples: times and advances [mm]."""
    path = os.path.join(folder, "recording.csv")
    with open(path) as f:
        header = f.readline().strip().split(",")
        names = ["time_s"] + [f"em_tip_{c}" for c in ("x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz")] + \
                [f"em_sigmoid_{c}" for c in ("x_mm", "y_mm", "z_mm")]
        if any(n not in header for n in names):
            return None
        at = [header.index(n) for n in names]
        rows = []
        for line in f:
            cells = line.rstrip("\r\n").split(",")
            if cells[at[1]] == "":
                continue
            rows.append([float(cells[i]) if cells[i] != "" else np.nan for i in at])
    if len(rows) < 2:
        return None
    d = np.array(rows)
    tip, sigmoid = d[:, 1:4], d[:, 8:11]
    axis = scope_axis(d[:, 4:8])
    mid = axis[1:] + axis[:-1]
    mid /= np.linalg.norm(mid, axis=1)[:, None]
    step = np.diff(tip, axis=0)
    sigmoid_step = np.diff(sigmoid, axis=0)
    near = np.isfinite(sigmoid_step[:, 0]) & np.isfinite(sigmoid[:-1, 0]) & \
        (np.linalg.norm(tip[1:] - np.nan_to_num(sigmoid[1:]), axis=1) < sigmoid_reach_mm)
    step[near] -= sigmoid_step[near]
    return {"time_s": d[:, 0], "advance_mm": np.einsum("ij,ij->i", step, mid)}


def held_out_handle(cases):
    """Each case's slack predicted by trees fitted without its patient."""
    patient = slack.patient_of
    folds = slack.patient_folds(cases)
    for k, p in enumerate(folds):
        print(f"tune: the handle's trees without patients {' '.join(sorted(p))} ({k + 1} of {len(folds)})",
              file=sys.stderr)
        train = [c for c in cases if patient(c) not in p]
        m = slack.model().fit(np.vstack([c["X"][::slack.EVERY] for c in train]),
                              np.concatenate([c["y"][::slack.EVERY] for c in train]))
        for c in cases:
            if patient(c) in p:
                c["slack_mm"] = m.predict(c["X"])


def uncertainty_law(cases):
    """fit_slack_regressor.py's law on the held-out slack: SD = A @ coef."""
    pred = np.concatenate([c["slack_mm"] for c in cases])
    y = np.concatenate([c["y"] for c in cases])
    depth = np.concatenate([c["depth"] for c in cases])
    A = np.column_stack([np.ones_like(pred), np.abs(pred), depth / 1000])
    coef = np.clip(np.linalg.lstsq(A, np.abs(pred - y), rcond=None)[0], 0, None)
    scale = np.quantile(np.abs(pred - y) / np.maximum(A @ coef, 1e-6), 0.68)
    return coef * scale


def fused(c, correlation_s, law):
    """tip_odometer.cpp's filter on one case: the fused tip and its variance at every period."""
    depth, slack_mm = c["depth"], c["slack_mm"]
    handle = depth - slack_mm
    sd = np.maximum(law[0] + law[1] * np.abs(slack_mm) + law[2] * depth / 1000, 1.0)
    handle_var = np.minimum(sd * sd, MAX_VARIANCE_MM2)
    arrived = np.searchsorted(c["tracker"]["time_s"], c["time_s"] + 1e-9) - 1
    advance = c["tracker"]["advance_mm"]
    n = depth.size
    tip, var = handle.copy(), handle_var.copy()
    x = p = None
    last = since = 0
    for k in range(n):  # noqa: the filter is sequential
        if x is None:
            if arrived[k] >= 0:
                x, p, last, since = handle[k], handle_var[k], arrived[k], 0
            continue
        while last < arrived[k]:
            x += advance[last]
            p = min(p + Q_MM2_PER_MM * abs(advance[last]), MAX_VARIANCE_MM2)
            last += 1
        since += 1
        if since >= UPDATE_STEPS:
            since = 0
            r = p / handle_var[k]
            gain = r / (r + correlation_s / (UPDATE_STEPS * PERIOD_S))
            x += gain * (handle[k] - x)
            p *= 1 - gain
        x = min(max(x, max(0.0, depth[k] - MAX_SLACK_MM)), depth[k] + MAX_AHEAD_MM)
        tip[k], var[k] = x, p
    return tip, var


def score(cases, tips):
    rms = np.array([np.sqrt(np.mean((tip - (c["depth"] - c["y"])) ** 2)) for c, (tip, _) in zip(cases, tips)])
    err = np.concatenate([np.abs(tip - (c["depth"] - c["y"])) for c, (tip, _) in zip(cases, tips)])
    sd = np.sqrt(np.concatenate([var for _, var in tips]))
    return {"median_mm": float(np.median(rms)), "p90_mm": float(np.percentile(rms, 90)),
            "worst_mm": float(rms.max()), "within_1_sd": float(np.mean(err <= sd)),
            "within_2_sd": float(np.mean(err <= 2 * sd))}


def load(folder, sigmoid_reach_mm):
    c = slack.load_case(folder)
    if c is None:
        return None
    c["tracker"] = read_tracker(folder, sigmoid_reach_mm)
    return c if c["tracker"] is not None else None


def read_tracker_cases(eval_dir, load, script):
    """The complete cases with the tracker's samples (`load` returns None for the others); with
    fewer than 2 patients the script exits 2 saying so."""
    cases = slack.read_cases(eval_dir, load)
    if len({slack.patient_of(c) for c in cases}) < 2:
        print(f"{script}: {' '.join([eval_dir] if isinstance(eval_dir, str) else eval_dir)}: {len(cases)} complete cases with EM tracker samples "
              "(cases/*/summary.json with status complete, recording.csv with em_tip_*), need at "
              "least 2 patients", file=sys.stderr)
        sys.exit(2)
    return cases


def plot(path, rows, handle):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    cs = [r["correlation_s"] for r in rows]
    ax.semilogx(cs, [r["median_mm"] for r in rows], "o-", label="fused, median case")
    ax.semilogx(cs, [r["p90_mm"] for r in rows], "s-", label="fused, 90th percentile case")
    ax.axhline(handle["median_mm"], ls="--", c="grey", label="handle alone (held out), median")
    ax.set_xlabel("correlation time of the handle's error [s]")
    ax.set_ylabel("tip error, per case RMS [mm]")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                 epilog="Exit status: 0 written, 2 bad input.")
    ap.add_argument("eval_dir", nargs="+", help="one or more evaluation folders (`scopekin evaluate --out`), e.g. development and development_extra")
    ap.add_argument("--out", required=True, help="the JSON report to write")
    ap.add_argument("--png", help="a picture of the errors against the correlation time")
    ap.add_argument("--sigmoid-reach", type=float, default=SIGMOID_REACH_MM, metavar="MM",
                    help="the tip's distance from the sigmoid sensor within which its displacement is "
                         "taken off (default: %(default)g, the firmware's; 0: no sigmoid correction)")
    ap.add_argument("--correlations", help="comma-separated correlation times [s] (default: %s)" %
                    ",".join(f"{c:g}" for c in CORRELATIONS_S))
    a = ap.parse_args()
    try:
        grid = [float(v) for v in a.correlations.split(",")] if a.correlations else CORRELATIONS_S
    except ValueError:
        grid = []
    if not grid or any(not np.isfinite(v) or v <= 0 for v in grid):
        print(f"tune_tip_odometer.py: --correlations {a.correlations!r}: need positive numbers, "
              "comma-separated", file=sys.stderr)
        sys.exit(2)
    if not (np.isfinite(a.sigmoid_reach) and a.sigmoid_reach >= 0):
        print(f"tune_tip_odometer.py: --sigmoid-reach {a.sigmoid_reach:g}: need a distance >= 0 mm", file=sys.stderr)
        sys.exit(2)
    cases = read_tracker_cases(a.eval_dir, lambda folder: load(folder, a.sigmoid_reach),
                               "tune_tip_odometer.py")
    held_out_handle(cases)
    law = uncertainty_law(cases)
    handle_rms = np.array([np.sqrt(np.mean((c["slack_mm"] - c["y"]) ** 2)) for c in cases])
    handle = {"median_mm": float(np.median(handle_rms)), "p90_mm": float(np.percentile(handle_rms, 90)),
              "worst_mm": float(handle_rms.max())}
    rows = []
    for k, correlation_s in enumerate(grid):
        print(f"tune: correlation {correlation_s:g} s ({k + 1} of {len(grid)})", file=sys.stderr)
        rows.append({"correlation_s": correlation_s, **score(cases, [fused(c, correlation_s, law) for c in cases])})
    best = min(rows, key=lambda r: r["median_mm"] + r["p90_mm"])
    report = {"eval_dir": a.eval_dir, "cases": len(cases), "q_mm2_per_mm": Q_MM2_PER_MM,
              "update_steps": UPDATE_STEPS, "sigmoid_reach_mm": a.sigmoid_reach,
              "uncertainty_law": {"floor_mm": law[0], "per_slack": law[1], "per_metre_mm": law[2]},
              "handle_held_out": handle, "grid": rows, "chosen_correlation_s": best["correlation_s"]}
    with open(a.out, "w") as f:
        json.dump(report, f, indent=1)
    for r in rows:
        print(f"correlation {r['correlation_s']:6g} s: tip RMS {r['median_mm']:.1f} / {r['p90_mm']:.1f} / "
              f"{r['worst_mm']:.1f} mm, within 1 / 2 SD {100 * r['within_1_sd']:.0f} / {100 * r['within_2_sd']:.0f} %")
    print(f"handle alone (held out): {handle['median_mm']:.1f} / {handle['p90_mm']:.1f} / {handle['worst_mm']:.1f} mm; "
          f"chosen: {best['correlation_s']:g} s; written {a.out}")
    if a.png:
        plot(a.png, rows, handle)


if __name__ == "__main__":
    main()
