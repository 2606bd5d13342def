#!/usr/bin/python3
"""How much does the handle tell? A ceiling study for the box's estimates from its handle alone.

Trains learned estimators on the handle signals the box receives (force, torque, insertion, roll:
recording.csv at the box's 5 ms periods) against the ground truth, leaving whole patients out
(grouped cross-validation), and scores them as the scorecard does (host_sim/evaluate/README.md):
  * the loop alarm: a classifier of "within [onset - 1 s, onset + 0.5 s] of a true loop episode"
    (periods later inside an episode left out), its debounced alarm scored with the scorecard's
    rule (a rise within [onset - 1 s, onset + 0.5 s] detects; a rise outside every
    [onset - 1 s, end] is a false alarm); sweeping its threshold gives the trade-off between
    onsets found and false alarms per 10 minutes;
  * the tip's place along the colon: a regression of the scope taken up between the handle and
    the tip (insertion - true tip path), the tip estimated as insertion - it; per-case RMS beside
    the insertion-depth baseline (the tip at the insertion);
  * the largest station force: a regression of the truth's max_station_force_N; per-case RMS
    beside a constant (the training cases' median).
What a flexible learner with every window of the handle's history finds on patients it was not
trained on is what any causal estimator using these signals is up against. A model-based
estimator adds structure, not information: one that claims far more on the same cases deserves
suspicion; one far below leaves evidence unused.

The learner: gradient-boosted trees (scikit-learn's HistGradientBoostingClassifier and
...Regressor; Friedman 2001, Ann. Statist. 29(5)) on causal window features (force, insertion,
their changes and the force-per-insertion slope over 0.25-2 s, force and insertion above their
1-5 s minima, |torque|, roll change). The alarm rises when the score has stayed above the
threshold for 50 ms and falls when it has stayed 0.2 below it for 1 s (debounce and hysteresis,
against chatter).

Usage:
  handle_evidence.py DEV_DIR [--test DIR ...] --out OUT [--folds 6]
DEV_DIR is an evaluated development set (`scopekin evaluate ... --out DEV_DIR`); without --test the
figures are the cross-validated ones on DEV_DIR's patients; with --test the learners are trained on
all of DEV_DIR and scored on each test folder (report only: never tune on it). Writes OUT/
handle_evidence.json, handle_evidence_loop.csv (one row per set x style x threshold),
handle_evidence_errors.csv (one row per set x case) and handle_evidence.png (one per test set,
handle_evidence_NAME.png). Cases whose run stopped (summary.json status other than "complete")
are skipped with a message, as the scorecard leaves them unscored. Exit 0 done, 2 bad input (a
folder without evaluated cases, a case without its files, too few patients for the folds).
"""
import argparse
import csv
import glob
import json
import os
import sys

import numpy as np

SUBSAMPLE = 5          # train and score at 40 Hz (every 5th 5-ms period)
PERIOD_S = 0.005
EARLY_S, WITHIN_S = 1.0, 0.5  # the scorecard's detection window
LATE_S = 2.0  # also counted: onsets found within 2 s (how late the handle tells)
HYSTERESIS = 0.2
ON_PERIODS = 10    # 50 ms above the threshold to rise
OFF_PERIODS = 200  # 1 s below threshold - hysteresis to fall
THRESHOLDS = [round(v, 2) for v in np.arange(0.30, 0.96, 0.05)]
BUDGETS_PER_10MIN = [2.0, 0.5]  # issue 21's bound and goal for false loop alarms


def fail(message):
    print(f"handle_evidence: {message}", file=sys.stderr)
    sys.exit(2)


def case_status(folder):
    """The run's status from its summary.json ("complete", "failed", ...; None without one or
    without the field)."""
    try:
        return json.load(open(os.path.join(folder, "summary.json"))).get("status")
    except (OSError, ValueError):
        return None


def read_case(folder):
    """The handle signals at the box's periods, the true tip path and largest station force
    (estimates.csv) and the true loop episodes of one case."""
    need = ["estimates.csv", "recording.csv", "summary.json"]
    for name in need:
        if not os.path.isfile(os.path.join(folder, name)):
            fail(f"{folder}: no {name} (run `scopekin evaluate` on it first)")
    est = np.genfromtxt(os.path.join(folder, "estimates.csv"), delimiter=",", names=True,
                        usecols=(0, 1, 2))
    times = est["time_s"]
    rec = np.genfromtxt(os.path.join(folder, "recording.csv"), delimiter=",", names=True,
                        usecols=(0, 1, 2, 3, 4))
    if times.size < 2 or rec.size < 2:
        fail(f"{folder}: fewer than two periods")
    # The last sample at or before each period (what the box had; the scorecard's rule).
    at = np.clip(np.searchsorted(rec["time_s"], times + 1e-9) - 1, 0, rec.size - 1)
    truth = json.load(open(os.path.join(folder, "summary.json"))).get("truth", {})
    episodes = [(e["onset_s"], e["end_s"] if e["end_s"] is not None else np.inf)
                for e in truth.get("loop_episodes", [])]
    return {"time_s": times, "force_N": rec["handle_force_N"][at],
            "torque_Nmm": rec["handle_torque_Nmm"][at], "insertion_mm": rec["insertion_mm"][at],
            "roll_rad": rec["roll_rad"][at], "episodes": episodes,
            "true_tip_path_mm": np.nan_to_num(est["true_tip_path_mm"]),
            "true_max_force_N": np.nan_to_num(est["true_max_station_force_N"])}


def lagged(a, n):
    out = np.empty_like(a)
    out[:n] = a[0]
    out[n:] = a[:-n]
    return out


def running_min(a, n):
    """Causal minimum over the last n samples (the window starts at the first sample)."""
    padded = np.concatenate([np.full(n - 1, a[0]), a])
    return np.lib.stride_tricks.sliding_window_view(padded, n).min(axis=1)


def features(case):
    """Causal features at every period, from the handle signals alone."""
    f, x = case["force_N"], case["insertion_mm"]
    columns = [f, x / 1000.0]
    for n in (50, 100, 200, 400):  # 0.25, 0.5, 1, 2 s
        df, dx = f - lagged(f, n), x - lagged(x, n)
        columns += [df, dx / 10.0, df / np.maximum(np.abs(dx), 2.0) * np.sign(dx + 1e-9)]
    for n in (200, 400, 1000):  # 1, 2, 5 s
        columns += [f - running_min(f, n), (x - running_min(x, n)) / 10.0]
    columns += [np.abs(case["torque_Nmm"]) / 100.0,
                np.abs(case["roll_rad"] - lagged(case["roll_rad"], 100))]
    return np.column_stack(columns)


def labels(case):
    """1 in a detection window, 0 outside every episode, -1 later inside an episode (unused)."""
    t = case["time_s"]
    y = np.zeros(t.size)
    for onset, end in case["episodes"]:
        y[(t > onset + WITHIN_S) & (t <= end)] = -1
    for onset, _ in case["episodes"]:
        y[(t >= onset - EARLY_S) & (t <= onset + WITHIN_S)] = 1
    return y


def alarm(score, threshold):
    """Rises after the score has stayed above threshold for ON_PERIODS; falls after it has stayed
    below threshold - HYSTERESIS for OFF_PERIODS (a debounced alarm, as the firmware's monitors)."""
    up = np.zeros(score.size, dtype=bool)
    state, run = False, 0
    for k, s in enumerate(score):
        if not state:
            run = run + 1 if s > threshold else 0
            if run >= ON_PERIODS:
                state, run = True, 0
        else:
            run = run + 1 if s < threshold - HYSTERESIS else 0
            if run >= OFF_PERIODS:
                state, run = False, 0
        up[k] = state
    return up


def score_alarm(t, up, episodes, within_s=WITHIN_S):
    """The scorecard's rule (host_sim/evaluate/README.md): detected, false alarms, scored s."""
    rises = [t[k] for k in range(t.size) if up[k] and (k == 0 or not up[k - 1])]
    used = [False] * len(rises)
    inside = [False] * len(rises)
    detected = 0
    for onset, end in episodes:
        for i, r in enumerate(rises):
            if onset - EARLY_S <= r <= max(end, onset + within_s):
                inside[i] = True
        for i, r in enumerate(rises):
            if not used[i] and onset - EARLY_S <= r <= onset + within_s:
                used[i] = True
                detected += 1
                break
    false_alarms = sum(1 for i in range(len(rises)) if not inside[i])
    return detected, false_alarms, t[-1] - t[0] + PERIOD_S


def load_set(folder):
    cases = sorted(glob.glob(os.path.join(folder, "cases", "*")))
    if not cases:
        fail(f"{folder}: no cases/ (not an evaluated set)")
    out = []
    for i, c in enumerate(cases):
        print(f"handle_evidence: reading {folder} [{i + 1}/{len(cases)}]", file=sys.stderr, end="\r")
        status = case_status(c)
        if status not in (None, "complete"):  # a run that stopped has no estimates: not scored
            print(f"\nhandle_evidence: {c}: skipped (status {status})", file=sys.stderr)
            continue
        case = read_case(c)
        name = os.path.basename(c)
        case.update(name=name, patient=name.split("-")[0],
                    style=name.split("-")[1] if "-" in name else "?",
                    X=features(case), y=labels(case))
        out.append(case)
    print(file=sys.stderr)
    return out


def training_rows(cases):
    X = np.vstack([c["X"][::SUBSAMPLE] for c in cases])
    pick = lambda key: np.concatenate([c[key][::SUBSAMPLE] for c in cases])
    return X, pick


def train(cases):
    """The three learners on these cases: loop-onset classifier, slack and force regressions."""
    from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor
    X, pick = training_rows(cases)
    y = pick("y")
    keep = y >= 0
    settings = dict(max_iter=150, learning_rate=0.05, max_leaf_nodes=15, l2_regularization=1.0,
                    min_samples_leaf=200, random_state=0)
    onset = HistGradientBoostingClassifier(**settings).fit(X[keep], y[keep])
    slack = HistGradientBoostingRegressor(**settings).fit(
        X, pick("insertion_mm") - pick("true_tip_path_mm"))
    force = HistGradientBoostingRegressor(**settings).fit(X, pick("true_max_force_N"))
    return {"onset": onset, "slack": slack, "force": force,
            "force_constant_N": float(np.median(pick("true_max_force_N")))}


def apply(learners, case):
    """The learners' outputs on one case: alarm score, tip estimate, force estimate."""
    case["score"] = learners["onset"].predict_proba(case["X"])[:, 1]
    case["tip_mm"] = case["insertion_mm"] - learners["slack"].predict(case["X"])
    case["force_est_N"] = learners["force"].predict(case["X"])
    case["force_constant_N"] = learners["force_constant_N"]


def rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


def case_errors(c):
    """Per-case RMS: learned tip and force beside their baselines."""
    return {"case": c["name"], "style": c["style"],
            "tip_learned_rms_mm": rms(c["tip_mm"] - c["true_tip_path_mm"]),
            "tip_insertion_rms_mm": rms(c["insertion_mm"] - c["true_tip_path_mm"]),
            "force_learned_rms_N": rms(c["force_est_N"] - c["true_max_force_N"]),
            "force_constant_rms_N": rms(c["force_constant_N"] - c["true_max_force_N"])}


def distribution(values):
    v = np.asarray(values, dtype=float)
    return {"median": float(np.median(v)), "p90": float(np.percentile(v, 90)),
            "worst": float(v.max())}


def curve(cases):
    """Per style and threshold: pooled detections, episodes, false alarms, per 10 min."""
    rows = []
    for style in sorted({c["style"] for c in cases}) + ["all"]:
        chosen = [c for c in cases if style in ("all", c["style"])]
        episodes = sum(len(c["episodes"]) for c in chosen)
        for thr in THRESHOLDS:
            detected = detected_late = false_alarms = 0
            seconds = 0.0
            for c in chosen:
                up = alarm(c["score"], thr)
                d, f, s = score_alarm(c["time_s"], up, c["episodes"])
                detected, false_alarms, seconds = detected + d, false_alarms + f, seconds + s
                detected_late += score_alarm(c["time_s"], up, c["episodes"], LATE_S)[0]
            rows.append({"style": style, "threshold": thr, "episodes": episodes,
                         "detected": detected,
                         "detected_share": detected / episodes if episodes else None,
                         f"detected_within_{LATE_S:g}_s": detected_late,
                         "false_alarms": false_alarms,
                         "false_alarms_per_10min": false_alarms * 600.0 / seconds})
    return rows


def at_budget(rows, style, budget):
    """The best detection share with false alarms within the budget (None: never within it)."""
    ok = [r for r in rows if r["style"] == style and r["false_alarms_per_10min"] <= budget]
    return max(ok, key=lambda r: (r["detected_share"] or 0.0)) if ok else None


def plot(rows, errors, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), gridspec_kw={"width_ratios": [1.4, 1, 1]})
    ax = axes[0]
    for style in sorted({r["style"] for r in rows}):
        pts = [r for r in rows if r["style"] == style]
        ax.plot([r["false_alarms_per_10min"] for r in pts],
                [100 * (r["detected_share"] or 0) for r in pts], "o-", ms=3, label=style)
    ax.axhline(90, color="k", ls="--", lw=0.8)
    ax.axvline(2, color="k", ls="--", lw=0.8)
    ax.text(2.1, 91, "issue 21's bound", fontsize=7)
    ax.set_xscale("symlog", linthresh=1)
    ax.set_xlim(left=0)
    ax.set_xlabel("false loop alarms per 10 min")
    ax.set_ylabel("loop onsets detected within 0.5 s [%]")
    ax.set_ylim(0, 100)
    ax.set_title("loop alarm", fontsize=9)
    ax.legend(fontsize=8)
    for ax, (learned, base, unit, bound, what) in zip(axes[1:], [
            ("tip_learned_rms_mm", "tip_insertion_rms_mm", "mm", 20, "tip: insertion"),
            ("force_learned_rms_N", "force_constant_rms_N", "N", 1.5, "force: constant")]):
        data = [[e[base] for e in errors], [e[learned] for e in errors]]
        ax.boxplot(data, labels=[what, "learned"], showfliers=False)
        for i, d in enumerate(data):
            ax.plot(np.full(len(d), i + 1) + np.linspace(-0.1, 0.1, len(d)), d, ".", ms=4,
                    color="tab:blue")
        ax.axhline(bound, color="k", ls="--", lw=0.8)
        ax.text(0.55, bound, "issue 21's median bound", fontsize=7, va="bottom")
        ax.set_yscale("log")
        ax.set_ylabel(f"RMS per case [{unit}]")
        ax.set_title(f"{learned.split('_')[0]} error per case", fontsize=9)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dev", help="the folder of an evaluated development set (the --out of scopekin evaluate: cases/ inside)")
    parser.add_argument("--test", nargs="*", default=[], help="folders of evaluated sets to score on (report only, never tuned on)")
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--folds", type=int, default=6, help="patient folds for cross-validation")
    args = parser.parse_args()
    if args.folds < 2:
        fail("--folds must be at least 2")
    dev = load_set(args.dev)
    report = {"rule": "host_sim/evaluate/README.md: alarms against episodes (1 s early, 0.5 s); "
                      "errors as RMS per case over its periods",
              "features": "handle force, torque, insertion, roll at the box's periods (causal)",
              "sets": {}}
    patients = sorted({c["patient"] for c in dev})
    if len(patients) < args.folds:
        fail(f"{args.dev}: {len(patients)} patients, fewer than --folds {args.folds}")
    folds = [patients[i::args.folds] for i in range(args.folds)]
    for i, held in enumerate(folds):
        print(f"handle_evidence: fold {i + 1}/{args.folds} (leaving out {', '.join(held)})",
              file=sys.stderr)
        learners = train([c for c in dev if c["patient"] not in held])
        for c in dev:
            if c["patient"] in held:
                apply(learners, c)
    sets = [("development (patients left out)", dev)]
    if args.test:
        print("handle_evidence: training on all of the development set", file=sys.stderr)
        learners = train(dev)
        for folder in args.test:
            cases = load_set(folder)
            for c in cases:
                apply(learners, c)
            sets.append((os.path.basename(os.path.normpath(folder)), cases))
    os.makedirs(args.out, exist_ok=True)
    all_rows, all_errors = [], []
    for name, cases in sets:
        rows = curve(cases)
        errors = [case_errors(c) for c in cases]
        all_errors += [{"set": name, **e} for e in errors]
        error_summary = {}
        for style in sorted({e["style"] for e in errors}) + ["all"]:
            chosen = [e for e in errors if style in ("all", e["style"])]
            error_summary[style] = {k: distribution([e[k] for e in chosen])
                                    for k in errors[0] if k.endswith(("_mm", "_N"))}
        summary = {}
        for style in sorted({r["style"] for r in rows}):
            summary[style] = {f"within_{b:g}_per_10min": at_budget(rows, style, b)
                              for b in BUDGETS_PER_10MIN}
        report["sets"][name] = {"cases": len(cases), "curve": rows, "best_within_budget": summary,
                                "errors": errors, "error_distributions": error_summary}
        for r in rows:
            all_rows.append({"set": name, **r})
        for style, s in summary.items():
            b = s["within_2_per_10min"]
            text = "none within 2 per 10 min" if b is None else (
                f"{b['detected']} of {b['episodes']} ({100 * b['detected_share']:.0f} %) at "
                f"{b['false_alarms_per_10min']:.2f} false per 10 min (threshold {b['threshold']}; "
                f"within {LATE_S:g} s: {b[f'detected_within_{LATE_S:g}_s']})")
            print(f"{name}: {style}: loop onsets {text}")
        for style, d in error_summary.items():
            f = lambda k: "{median:.3g} / {p90:.3g} / {worst:.3g}".format(**d[k])
            print(f"{name}: {style}: tip RMS [mm] learned {f('tip_learned_rms_mm')}, insertion "
                  f"{f('tip_insertion_rms_mm')}; largest force RMS [N] learned "
                  f"{f('force_learned_rms_N')}, constant {f('force_constant_rms_N')} "
                  "(median / p90 / worst case)")
        plot(rows, errors, os.path.join(args.out, "handle_evidence.png" if name == sets[0][0]
                                        else f"handle_evidence_{name}.png"),
             f"What the handle alone tells: {name}, {len(cases)} cases (learned on other patients)")
    with open(os.path.join(args.out, "handle_evidence.json"), "w") as out:
        json.dump(report, out, indent=1)
    for suffix, table in (("loop", all_rows), ("errors", all_errors)):
        with open(os.path.join(args.out, f"handle_evidence_{suffix}.csv"), "w", newline="") as out:
            w = csv.DictWriter(out, fieldnames=list(table[0].keys()))
            w.writeheader()
            w.writerows(table)
    print(f"handle_evidence: wrote {args.out}/handle_evidence.json, _loop.csv, _errors.csv, .png",
          file=sys.stderr)


if __name__ == "__main__":
    main()
