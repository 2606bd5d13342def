#!/usr/bin/env python3
"""Fits the box's slack regressor (firmware/kinetics/slack_regressor.hpp) on an evaluation of the
development set and writes its trees as the firmware's C++ source.

usage: fit_slack_regressor.py EVAL_DIR [EVAL_DIR ...] --out slack_trees.cpp [--report fit.json]
                              [--target slack | contact_force]

--target slack (the default) fits depth - the true tip; --target contact_force fits the truth's
largest station force [N] (truth.csv max_station_force_N) on the same features: the box's largest
contact force outside the model evidence's trust (default_contact_force_trees()).

EVAL_DIR is the output of `scopekin evaluate model/scenarios/evaluation/development.json` (each
case's truth.csv, recording.csv, firmware.csv and summary.json). Only complete cases are used, each
up to where its scope went through the wall (the scorer's rule, host_sim/evaluate/README.md). The
features are the firmware's, computed here in double from the same inputs (the Q16.16 averages
differ from these by rounding only); the target is depth - the true tip along the colon.

Model: gradient-boosted regression trees (Friedman 2001), squared error, 100 trees of depth 4,
learning rate 0.05, half the rows per tree, at least 100 rows per leaf, on every 20th period (the
rows of one case are strongly correlated; more rows change nothing but the time). Before the
final fit, each patient is left out in turn (leave-one-patient-out; with more than 12 patients,
e.g. development and development_extra together, 12 groups of patients dealt round-robin by
name are left out in turn, patient_folds): the report gives those
held-out errors per case beside the tip observer's, and the uncertainty law (one SD:
floor + a * |slack| + b * depth [m]) is fitted to the held-out errors and scaled so that 68 % of
held-out periods lie within it. Needs Debian's python3-sklearn and python3-numpy.
"""
import argparse
import glob
import json
import os
import sys

import numpy as np
from sklearn.ensemble import GradientBoostingRegressor

PERIOD_S = 0.005
TAUS_S = [1.0, 5.0, 20.0, 60.0]
TREES, DEPTH, RATE = 100, 4, 0.05
EVERY = 20
FEATURES = ["depth_mm", "handle_force_N", "advanced_mm", "withdrawn_mm", "below_deepest_mm",
            "observer_slack_mm"] + [f"force_N_ema_{t:g}s" for t in TAUS_S] + \
           [f"speed_mm_per_s_ema_{t:g}s" for t in TAUS_S]


def q16(x):
    return round(x * 65536) / 65536


def columns(path, names):
    with open(path) as f:
        header = f.readline().strip().split(",")
    missing = [n for n in names if n not in header]
    if missing:
        print(f"{os.path.basename(sys.argv[0])}: {path}: no column {missing}", file=sys.stderr)
        sys.exit(2)
    a = np.genfromtxt(path, delimiter=",", skip_header=1, usecols=[header.index(n) for n in names])
    a = a.reshape(-1, len(names))
    return {n: a[:, i] for i, n in enumerate(names)}


def ema(x, alpha, first):
    out, s = np.empty_like(x), first
    for i, v in enumerate(x):
        s += alpha * (v - s)
        out[i] = s
    return out


def load_case(folder):
    """Features, target and the observer's slack at the box's periods, or None if not usable."""
    summary = json.load(open(os.path.join(folder, "summary.json")))
    if summary.get("status") != "complete":
        return None
    truth = columns(os.path.join(folder, "truth.csv"), ["time_s", "tip_path_mm", "scope_beyond_wall_mm"])
    with open(os.path.join(folder, "firmware.csv")) as f:
        header = f.readline().strip().split(",")
    observer = "observer_tip_path_mm" if "observer_tip_path_mm" in header else "tip_path_mm"
    fw = columns(os.path.join(folder, "firmware.csv"), [observer])
    model_force = "model_max_contact_force_N" if "model_max_contact_force_N" in header else "max_contact_force_N"
    fw_force = columns(os.path.join(folder, "firmware.csv"), [model_force])[model_force]
    force_truth = columns(os.path.join(folder, "truth.csv"), ["max_station_force_N"])
    rec = columns(os.path.join(folder, "recording.csv"), ["time_s", "handle_force_N", "insertion_mm"])
    t = truth["time_s"]
    n = min(t.size, fw[observer].size)
    lost = np.where(truth["scope_beyond_wall_mm"][:n] > 40.0)[0]
    if lost.size:
        n = lost[0]
    at = np.clip(np.searchsorted(rec["time_s"], t[:n] + 1e-9) - 1, 0, rec["time_s"].size - 1)
    depth = np.nan_to_num(rec["insertion_mm"][at], nan=20.0)
    force = np.nan_to_num(rec["handle_force_N"][at], nan=0.0)
    moved = np.diff(depth, prepend=depth[0])
    speed = moved / q16(PERIOD_S)
    cols = [depth, force, np.cumsum(np.clip(moved, 0, None)), np.cumsum(np.clip(-moved, 0, None)),
            np.maximum.accumulate(depth) - depth, depth - fw[observer][:n]]
    alphas = [q16(q16(PERIOD_S) / tau) for tau in TAUS_S]
    cols += [ema(force, a, force[0]) for a in alphas]
    cols += [ema(speed, a, 0.0) for a in alphas]
    return {"name": os.path.basename(folder.rstrip("/")), "X": np.column_stack(cols), "time_s": t[:n],
            "y": depth - truth["tip_path_mm"][:n], "depth": depth,
            "force_N": np.nan_to_num(force_truth["max_station_force_N"][:n], nan=0.0),
            "model_force_N": fw_force[:n]}


def model(rate=RATE):
    return GradientBoostingRegressor(n_estimators=TREES, max_depth=DEPTH, learning_rate=rate,
                                     subsample=0.5, min_samples_leaf=100, random_state=1)


def complete_tree(tree, rate=RATE):
    """(features, thresholds, leaves) of a depth-DEPTH complete tree equal to sklearn's `tree`:
    a leaf above the last level becomes a node that always goes left, its value in every leaf."""
    internal = 2 ** DEPTH - 1
    feature, threshold, leaf = [0] * internal, [2 ** 31 - 1] * internal, [0.0] * (internal + 1)
    t = tree.tree_

    def fill(node, slot, level):
        if level == DEPTH:
            leaf[slot - internal] = t.value[node][0][0] * rate
            return
        if t.children_left[node] == -1:  # a leaf above the last level
            feature[slot], threshold[slot] = 0, 2 ** 31 - 1
            fill(node, 2 * slot + 1, level + 1)
            fill(node, 2 * slot + 2, level + 1)
            return
        feature[slot] = int(t.feature[node])
        threshold[slot] = int(np.floor(t.threshold[node] * 65536))
        fill(t.children_left[node], 2 * slot + 1, level + 1)
        fill(t.children_right[node], 2 * slot + 2, level + 1)

    fill(0, 0, 0)
    return feature, threshold, [int(round(v * 65536)) for v in leaf]


def firmware_predict(trees, base_raw, X):
    """The firmware's integer evaluation (slack_regressor.cpp), for the fit's own check."""
    raw = np.floor(X * 65536).astype(np.int64)
    total = np.full(X.shape[0], base_raw, dtype=np.int64)
    for feature, threshold, leaf in trees:
        node = np.zeros(X.shape[0], dtype=np.int64)
        for _ in range(DEPTH):
            f = np.array(feature)[node]
            go_left = raw[np.arange(X.shape[0]), f] <= np.array(threshold)[node]
            node = np.where(go_left, 2 * node + 1, 2 * node + 2)
        total += np.array(leaf)[node - (2 ** DEPTH - 1)]
    return total / 65536


def rms(e):
    return float(np.sqrt(np.mean(np.square(e))))


# What each target fits: its truth column, the baseline it is compared with in the report, the
# report's key for the held-out errors, and the C++ function the source defines.
TARGETS = {
    "slack": {"y": "y", "baseline": "observer", "unit": "mm", "errors": "held_out_tip_rms_mm",
              "function": "default_slack_trees", "what": "the slack regressor's trees",
              "law": ("floor_mm", "per_slack", "per_metre_mm")},
    "contact_force": {"y": "force_N", "baseline": "model", "unit": "N",
                      "errors": "held_out_force_rms_N", "function": "default_contact_force_trees",
                      "what": "the largest contact force's trees (same features)",
                      "law": ("floor_N", "per_newton", "per_metre_N")},
}


def read_cases(eval_dirs, load=None):
    """Every complete case of one evaluation or several (a folder or a list of folders), read by
    `load` (default load_case), with progress."""
    load = load or load_case
    eval_dirs = [eval_dirs] if isinstance(eval_dirs, str) else eval_dirs
    found = [f for d in eval_dirs for f in sorted(glob.glob(os.path.join(d, "cases", "*", "summary.json")))]
    cases = []
    for f in found:
        c = load(os.path.dirname(f))
        print(f"fit: {'read' if c else 'skipped (not complete)'} {os.path.dirname(f)}", file=sys.stderr)
        if c:
            cases.append(c)
    return cases


FOLDS = 12  # patients held out together: one each up to 12 patients, then 12 groups


def patient_of(case):
    return case["name"].split("-")[0]


def patient_folds(cases):
    """The held-out groups: each patient alone when there are at most FOLDS, else FOLDS groups of
    patients dealt round-robin in name order (so a fit's held-out errors stay held out by patient
    while the number of fits stays bounded)."""
    patients = sorted({patient_of(c) for c in cases})
    k = min(FOLDS, len(patients))
    return [set(patients[i::k]) for i in range(k)]


def baseline(c, target):
    """What the box published before the fit: the observer's slack, the reduced model's force."""
    return c["X"][:, 5] if target == "slack" else c["model_force_N"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                 epilog="Exit status: 0 written, 2 bad input.")
    ap.add_argument("eval_dir", nargs="+", help="one or more evaluation folders (`scopekin evaluate --out`), e.g. development and development_extra")
    ap.add_argument("--out", required=True, help="the C++ source to write")
    ap.add_argument("--report", help="JSON: held-out errors per case, the uncertainty law")
    ap.add_argument("--target", choices=sorted(TARGETS), default="slack",
                    help="slack: depth - tip [mm] (default); contact_force: the largest station force [N]")
    a = ap.parse_args()
    spec = TARGETS[a.target]
    cases = read_cases(a.eval_dir)
    if len(cases) < 4:
        print(f"fit_slack_regressor.py: {' '.join(a.eval_dir)}: {len(cases)} complete cases (cases/*/summary.json "
              "with status complete), need at least 4", file=sys.stderr)
        sys.exit(2)
    target = lambda c: c[spec["y"]]
    patient = patient_of
    patients = sorted({patient(c) for c in cases})
    held_out, per_case = [], []
    folds = patient_folds(cases)
    for k, p in enumerate(folds):
        print(f"fit: leaving out patients {' '.join(sorted(p))} ({k + 1} of {len(folds)})", file=sys.stderr)
        train = [c for c in cases if patient(c) not in p]
        m = model().fit(np.vstack([c["X"][::EVERY] for c in train]),
                        np.concatenate([target(c)[::EVERY] for c in train]))
        for c in (c for c in cases if patient(c) in p):
            pred = m.predict(c["X"])
            held_out.append((pred, target(c), c["depth"]))
            per_case.append({"case": c["name"],
                             "rms_regressor": rms(pred - target(c)),
                             f"rms_{spec['baseline']}": rms(baseline(c, a.target) - target(c))})
    # Uncertainty: |error| ~ floor + a |prediction| + b depth[m], least squares, non-negative,
    # then scaled so that 68 % of the held-out periods lie within one SD.
    pred = np.concatenate([h[0] for h in held_out]); y = np.concatenate([h[1] for h in held_out])
    depth = np.concatenate([h[2] for h in held_out])
    A = np.column_stack([np.ones_like(pred), np.abs(pred), depth / 1000])
    coef = np.clip(np.linalg.lstsq(A, np.abs(pred - y), rcond=None)[0], 0, None)
    sigma = A @ coef
    scale = np.quantile(np.abs(pred - y) / np.maximum(sigma, 1e-6), 0.68)
    coef = coef * scale
    within = float(np.mean(np.abs(pred - y) <= A @ coef))
    within2 = float(np.mean(np.abs(pred - y) <= 2 * (A @ coef)))

    print("fit: the final fit on every case", file=sys.stderr)
    final = model().fit(np.vstack([c["X"][::EVERY] for c in cases]),
                        np.concatenate([target(c)[::EVERY] for c in cases]))
    trees = [complete_tree(e[0]) for e in final.estimators_]
    base_raw = int(round(float(final.init_.constant_.ravel()[0]) * 65536))
    X = np.vstack([c["X"][::EVERY] for c in cases])
    mismatch = float(np.max(np.abs(firmware_predict(trees, base_raw, X) - final.predict(X))))

    spread = lambda v: {"median": float(np.median(v)), "p90": float(np.percentile(v, 90)), "worst": float(np.max(v))}
    summary = {"target": a.target, "unit": spec["unit"], "cases": len(cases), "patients": len(patients),
               "features": FEATURES, "trees": TREES, "depth": DEPTH, "learning_rate": RATE,
               "every_nth_period": EVERY,
               spec["errors"]: {"regressor": spread([c["rms_regressor"] for c in per_case]),
                                spec["baseline"]: spread([c[f"rms_{spec['baseline']}"] for c in per_case])},
               "uncertainty": dict(zip(spec["law"], map(float, coef)),
                                   held_out_within_1sd=within, held_out_within_2sd=within2),
               "firmware_vs_sklearn_max_abs": mismatch, "per_case": per_case}
    print(json.dumps({k: v for k, v in summary.items() if k != "per_case"}, indent=1), file=sys.stderr)
    if a.report:
        with open(a.report, "w") as f:
            json.dump(summary, f, indent=1)
    write_source(a.out, trees, base_raw, coef, summary, spec)


def write_source(path, trees, base_raw, coef, summary, spec, extra=""):
    """The C++ source: the trees as SlackTrees returned by spec["function"](), then `extra` (more
    C++ inside the namespace, e.g. an alarm's settings)."""
    flat = lambda key: [v for t in trees for v in t[key]]
    def rows(values, per_line=12):
        return "\n".join("    " + ", ".join(str(v) for v in values[i:i + per_line]) + ","
                         for i in range(0, len(values), per_line))
    if "source" in spec:  # another fit's own description (fit_loop_alarm.py)
        source = spec["source"]
    else:
        h, unit = summary[spec["errors"]], spec["unit"]
        source = (f"fitted by host_sim/evaluate/fit_slack_regressor.py on {summary['cases']} development cases "
                  f"({summary['patients']} patients); held-out RMS median {h['regressor']['median']:.1f} {unit}, "
                  f"p90 {h['regressor']['p90']:.1f} {unit}")
    generator = spec.get("generator", f"host_sim/evaluate/fit_slack_regressor.py --target {summary['target']}")
    text = f"""// Generated by {generator} (do not edit):
// {spec['what']} ({spec.get('header', 'firmware/kinetics/slack_regressor.hpp')}), {source}.
// {TREES} trees of depth {DEPTH}, features {", ".join(FEATURES)}.
#include <cstdint>

#include "{spec.get('header', 'kinetics/slack_regressor.hpp')}"

namespace scopekin::kinetics {{
namespace {{

constexpr std::uint8_t kFeature[] = {{
{rows(flat(0), 24)}
}};
constexpr std::int32_t kThresholdRaw[] = {{
{rows(flat(1))}
}};
constexpr std::int32_t kLeafRaw[] = {{
{rows(flat(2))}
}};

}}  // namespace

const SlackTrees& {spec['function']}() noexcept {{
    static constexpr SlackTrees trees{{
        {TREES}U, {DEPTH}U, kFeature, kThresholdRaw, kLeafRaw, {base_raw},
        {{{", ".join(str(int(round(t * 65536))) for t in TAUS_S)}}},
        {int(round(coef[0] * 65536))}, {int(round(coef[1] * 65536))}, {int(round(coef[2] * 65536))},
        "{source}"}};
    return trees;
}}
{extra}
}}  // namespace scopekin::kinetics
"""
    tmp = path + ".part"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)
    print(f"fit: wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
