#!/usr/bin/env python3
"""Fits the box's slack regressor (firmware/kinetics/slack_regressor.hpp) on an evaluation of the
development set and writes its trees as the firmware's C++ source.

usage: fit_slack_regressor.py EVAL_DIR --out slack_trees.cpp [--report fit.json]

EVAL_DIR is the output of `scopekin evaluate model/scenarios/evaluation/development.json` (each
case's truth.csv, recording.csv, firmware.csv and summary.json). Only complete cases are used, each
up to where its scope went through the wall (the scorer's rule, host_sim/evaluate/README.md). The
features are the firmware's, computed here in double from the same inputs (the Q16.16 averages
differ from these by rounding only); the target is depth - the true tip along the colon.

Model: gradient-boosted regression trees (Friedman 2001), squared error, 100 trees of depth 4,
learning rate 0.05, half the rows per tree, at least 100 rows per leaf, on every 20th period (the
rows of one case are strongly correlated; more rows change nothing but the time). Before the
final fit, each patient is left out in turn (leave-one-patient-out): the report gives those
held-out errors per case beside the tip observer's, and the uncertainty law (one SD:
floor + a * |slack| + b * depth [m]) is fitted to the held-out errors and scaled so that 68 % of
held-out periods lie within it. Needs Debian's python3-sklearn and python3-numpy.
"""
import argparse
import csv
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
        print(f"fit_slack_regressor.py: {path}: no column {missing}", file=sys.stderr)
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
    return {"name": os.path.basename(folder.rstrip("/")), "X": np.column_stack(cols),
            "y": depth - truth["tip_path_mm"][:n], "depth": depth}


def model():
    return GradientBoostingRegressor(n_estimators=TREES, max_depth=DEPTH, learning_rate=RATE,
                                     subsample=0.5, min_samples_leaf=100, random_state=1)


def complete_tree(tree):
    """(features, thresholds, leaves) of a depth-DEPTH complete tree equal to sklearn's `tree`:
    a leaf above the last level becomes a node that always goes left, its value in every leaf."""
    internal = 2 ** DEPTH - 1
    feature, threshold, leaf = [0] * internal, [2 ** 31 - 1] * internal, [0.0] * (internal + 1)
    t = tree.tree_

    def fill(node, slot, level):
        if level == DEPTH:
            leaf[slot - internal] = t.value[node][0][0] * RATE
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "),
                                 epilog="Exit status: 0 written, 2 bad input.")
    ap.add_argument("eval_dir")
    ap.add_argument("--out", required=True, help="the C++ source to write")
    ap.add_argument("--report", help="JSON: held-out errors per case, the uncertainty law")
    a = ap.parse_args()
    cases = []
    for f in sorted(glob.glob(os.path.join(a.eval_dir, "cases", "*", "summary.json"))):
        c = load_case(os.path.dirname(f))
        print(f"fit: {'read' if c else 'skipped (not complete)'} {os.path.dirname(f)}", file=sys.stderr)
        if c:
            cases.append(c)
    if len(cases) < 4:
        print(f"fit_slack_regressor.py: {a.eval_dir}: {len(cases)} complete cases (cases/*/summary.json "
              "with status complete), need at least 4", file=sys.stderr)
        sys.exit(2)
    patient = lambda c: c["name"].split("-")[0]
    patients = sorted({patient(c) for c in cases})
    held_out, per_case = [], []
    for k, p in enumerate(patients):
        print(f"fit: leaving out patient {p} ({k + 1} of {len(patients)})", file=sys.stderr)
        train = [c for c in cases if patient(c) != p]
        m = model().fit(np.vstack([c["X"][::EVERY] for c in train]),
                        np.concatenate([c["y"][::EVERY] for c in train]))
        for c in (c for c in cases if patient(c) == p):
            pred = m.predict(c["X"])
            held_out.append((pred, c["y"], c["depth"]))
            per_case.append({"case": c["name"], "tip_rms_mm_regressor": rms(pred - c["y"]),
                             "tip_rms_mm_observer": rms(c["X"][:, 5] - c["y"])})
    # Uncertainty: |error| ~ floor + a |slack| + b depth[m], least squares, non-negative, then scaled.
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
                        np.concatenate([c["y"][::EVERY] for c in cases]))
    trees = [complete_tree(e[0]) for e in final.estimators_]
    base_raw = int(round(float(final.init_.constant_.ravel()[0]) * 65536))
    X = np.vstack([c["X"][::EVERY] for c in cases])
    mismatch = float(np.max(np.abs(firmware_predict(trees, base_raw, X) - final.predict(X))))

    r = [c["tip_rms_mm_regressor"] for c in per_case]; o = [c["tip_rms_mm_observer"] for c in per_case]
    summary = {"cases": len(cases), "patients": len(patients), "features": FEATURES,
               "trees": TREES, "depth": DEPTH, "learning_rate": RATE, "every_nth_period": EVERY,
               "held_out_tip_rms_mm": {"regressor": {"median": float(np.median(r)), "p90": float(np.percentile(r, 90)), "worst": float(np.max(r))},
                                       "observer": {"median": float(np.median(o)), "p90": float(np.percentile(o, 90)), "worst": float(np.max(o))}},
               "uncertainty": {"floor_mm": float(coef[0]), "per_slack": float(coef[1]), "per_metre_mm": float(coef[2]),
                               "held_out_within_1sd": within, "held_out_within_2sd": within2},
               "firmware_vs_sklearn_max_abs_mm": mismatch, "per_case": per_case}
    print(json.dumps({k: v for k, v in summary.items() if k != "per_case"}, indent=1), file=sys.stderr)
    if a.report:
        with open(a.report, "w") as f:
            json.dump(summary, f, indent=1)
    write_source(a.out, trees, base_raw, coef, summary, a.eval_dir)


def write_source(path, trees, base_raw, coef, summary, eval_dir):
    flat = lambda key: [v for t in trees for v in t[key]]
    def rows(values, per_line=12):
        return "\n".join("    " + ", ".join(str(v) for v in values[i:i + per_line]) + ","
                         for i in range(0, len(values), per_line))
    h = summary["held_out_tip_rms_mm"]
    source = (f"fitted by host_sim/evaluate/fit_slack_regressor.py on {summary['cases']} development cases "
              f"({summary['patients']} patients); held-out tip RMS median {h['regressor']['median']:.1f} mm, "
              f"p90 {h['regressor']['p90']:.1f} mm")
    text = f"""// Generated by host_sim/evaluate/fit_slack_regressor.py (do not edit): the slack regressor's trees
// (firmware/kinetics/slack_regressor.hpp), {source}.
// {TREES} trees of depth {DEPTH}, features {", ".join(FEATURES)}.
#include <cstdint>

#include "kinetics/slack_regressor.hpp"

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

const SlackTrees& default_slack_trees() noexcept {{
    static constexpr SlackTrees trees{{
        {TREES}U, {DEPTH}U, kFeature, kThresholdRaw, kLeafRaw, {base_raw},
        {{{", ".join(str(int(round(t * 65536))) for t in TAUS_S)}}},
        {int(round(coef[0] * 65536))}, {int(round(coef[1] * 65536))}, {int(round(coef[2] * 65536))},
        "{source}"}};
    return trees;
}}

}}  // namespace scopekin::kinetics
"""
    tmp = path + ".part"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)
    print(f"fit: wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
