#!/usr/bin/env python3
"""How much the handle tells about the patient's friction: a study, not the box (issue 21 asks the
box to identify the patient; it does not yet). Run on an evaluation's case folders.

usage: friction_evidence.py EVAL_DIR --out DIR [--min-speed MM_PER_S]

Why it can work. Pushing or pulling a scope through the colon costs Coulomb friction at every
contact, mu times its normal force, against the motion (thesis ch. 2, Coulomb's law); so the
handle force jumps by about 2 mu N_total when the hand reverses, with N_total the sum of the
normal forces along the scope. The box's reduced model publishes its stations' normal forces
(firmware.csv `station_I_normal_N`, the training patient's shape at that depth). Per case, over
the periods where the hand moves faster than --min-speed (default 3 mm/s, the insertion's
derivative smoothed over 0.1 s), a least-squares fit of

    handle_force_N = mu_hat * sign(speed) * sum_i station_i_normal_N + c

gives mu_hat (c takes up what does not reverse with the motion: elastic loads, the loop's push).
mu_hat is not the patient's mu: the normal forces are the model's, not the patient's. What the
study asks is whether it ranks the patients by their friction (Spearman's rank correlation against
summary.json patient.mechanics.friction_coefficient, per physician style), which is what an
identifier in the box would have to build on. Cases cut short where the scope went through the
wall are fitted before that time only; a case needs at least 1 s of moving each way (advancing
only, friction cannot be told from a load that grows with depth).

Beside mu_hat, a model-free index: the mean handle force while the hand advances faster than
--min-speed at depths of 300-900 mm (the sigmoid to the transverse colon), where sliding friction
along the inserted scope makes most of the push. It needs a second of such advance; its rank
correlation with the true friction is reported beside mu_hat's.

Writes DIR/friction_evidence.csv (a row per case), DIR/friction_evidence.json (per style and over
all: cases, Spearman and Pearson correlation of mu_hat, Spearman of the advancing push) and DIR/friction_evidence.png (true against fitted,
per style; needs python3-matplotlib). Prints one line per case. Exit status 2 for bad input (no
scorable case, a missing column), 3 if an output cannot be written.
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

from case_columns import BadInput, columns, complete_summary

STATIONS = 12  # firmware/kinetics: the reduced model's stations
SMOOTH_S = 0.1
MIN_EACH_WAY_S = 1.0
PUSH_BAND_MM = (300.0, 900.0)  # the advancing push index's depths (sigmoid to transverse)


def fit_case(folder, min_speed):
    """(style, true mu, mu_hat, c, seconds used) of a complete case, or None if it is not one."""
    summary = complete_summary(folder)
    if summary is None:
        return None
    summary_path = os.path.join(folder, "summary.json")
    try:
        mu = float(summary["patient"]["mechanics"]["friction_coefficient"])
    except (KeyError, TypeError, ValueError):
        raise BadInput(f"{summary_path}: no patient.mechanics.friction_coefficient")
    style = (summary.get("procedure") or {}).get("style") or "scripted"
    normals = [f"station_{i}_normal_N" for i in range(STATIONS)]
    fw = columns(os.path.join(folder, "firmware.csv"), ["time_s"] + normals)
    rec = columns(os.path.join(folder, "recording.csv"), ["time_s", "handle_force_N", "insertion_mm"])
    ok = np.isfinite(rec["handle_force_N"]) & np.isfinite(rec["insertion_mm"])
    if ok.sum() < 2:
        return None
    t = fw["time_s"]
    force = np.interp(t, rec["time_s"][ok], rec["handle_force_N"][ok])
    depth = np.interp(t, rec["time_s"][ok], rec["insertion_mm"][ok])
    window = max(1, int(round(SMOOTH_S / np.median(np.diff(t)))))
    speed = np.convolve(np.gradient(depth, t), np.ones(window) / window, "same")
    normal = np.nansum(np.stack([fw[n] for n in normals]), axis=0)
    until = (summary.get("truth") or {}).get("scope_through_wall_s")
    use = (np.abs(speed) > min_speed) & (normal > 0.5) & np.isfinite(force)
    if until is not None:
        use &= t < until
    period = float(np.median(np.diff(t)))
    # Both directions, a second of each at least: advancing only, the fit cannot tell friction
    # from a load that grows with depth.
    if min((use & (speed > 0)).sum(), (use & (speed < 0)).sum()) * period < MIN_EACH_WAY_S:
        return None
    design = np.column_stack([np.sign(speed[use]) * normal[use], np.ones(use.sum())])
    (mu_hat, c), *_ = np.linalg.lstsq(design, force[use], rcond=None)
    # The model-free index: the mean push while advancing through PUSH_BAND_MM.
    band = (speed > min_speed) & (depth >= PUSH_BAND_MM[0]) & (depth < PUSH_BAND_MM[1]) & np.isfinite(force)
    if until is not None:
        band &= t < until
    push = float(np.mean(force[band])) if band.sum() * period >= MIN_EACH_WAY_S else None
    return style, mu, float(mu_hat), float(c), float(use.sum() * period), push


def rank_correlation(a, b):
    ra = np.argsort(np.argsort(a)).astype(float)
    rb = np.argsort(np.argsort(b)).astype(float)
    return float(np.corrcoef(ra, rb)[0, 1])


def correlations(rows):
    if len(rows) < 3:
        return {"cases": len(rows), "spearman": None, "pearson": None,
                "spearman_advancing_push": None, "cases_advancing_push": None}
    mu = np.array([r["true_mu"] for r in rows])
    hat = np.array([r["mu_hat"] for r in rows])
    pushed = [r for r in rows if r["advancing_push_N"] is not None]
    push = None
    if len(pushed) >= 3:
        push = rank_correlation(np.array([r["true_mu"] for r in pushed]),
                                np.array([r["advancing_push_N"] for r in pushed]))
    return {"cases": len(rows), "spearman": rank_correlation(mu, hat),
            "pearson": float(np.corrcoef(mu, hat)[0, 1]), "spearman_advancing_push": push,
            "cases_advancing_push": len(pushed)}


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for style in sorted({r["style"] for r in rows}):
        mine = [r for r in rows if r["style"] == style]
        ax.plot([r["true_mu"] for r in mine], [r["mu_hat"] for r in mine], "o", label=style)
    ax.set_xlabel("the patient's friction coefficient (truth)")
    ax.set_ylabel("fitted from the handle (mu_hat)")
    ax.set_title("Friction from the handle force and the model's normal forces")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path + ".part.png", dpi=110)
    plt.close(fig)
    os.replace(path + ".part.png", path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("eval_dir")
    parser.add_argument("--out", required=True)
    parser.add_argument("--min-speed", type=float, default=3.0, help="mm/s (default 3)")
    a = parser.parse_args()
    if not a.min_speed > 0:
        print("friction_evidence.py: --min-speed must be > 0", file=sys.stderr)
        return 2
    cases_dir = os.path.join(a.eval_dir, "cases")
    names = sorted(os.listdir(cases_dir)) if os.path.isdir(cases_dir) else []
    rows = []
    try:
        for k, name in enumerate(names):
            fit = fit_case(os.path.join(cases_dir, name), a.min_speed)
            if fit is None:
                print(f"[{k + 1}/{len(names)}] {name}: not scored (not complete, or under 1 s of moving "
                      "each way)")
                continue
            style, mu, hat, c, used, push = fit
            rows.append({"case": name, "style": style, "true_mu": mu, "mu_hat": hat, "offset_N": c,
                         "moving_s": used, "advancing_push_N": push})
            print(f"[{k + 1}/{len(names)}] {name}: mu {mu:.3f}, fitted {hat:.3f} ({used:.0f} s moving)",
                  flush=True)
    except BadInput as e:
        print(f"friction_evidence.py: {e}", file=sys.stderr)
        return 2
    if len(rows) < 3:
        print(f"friction_evidence.py: {a.eval_dir}: need at least 3 complete cases with a patient, "
              f"found {len(rows)}", file=sys.stderr)
        return 2
    report = {"eval_dir": os.path.abspath(a.eval_dir), "min_speed_mm_per_s": a.min_speed,
              "all": correlations(rows),
              "by_style": {s: correlations([r for r in rows if r["style"] == s])
                           for s in sorted({r["style"] for r in rows})}}
    try:
        os.makedirs(a.out, exist_ok=True)
        base = os.path.join(a.out, "friction_evidence")
        with open(base + ".csv.part", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
            w.writeheader()
            w.writerows(rows)
        os.replace(base + ".csv.part", base + ".csv")
        plot(rows, base + ".png")
        with open(base + ".json.part", "w") as f:
            json.dump(report, f, indent=1)
        os.replace(base + ".json.part", base + ".json")
    except OSError as e:
        print(f"friction_evidence.py: cannot write {a.out}: {e}", file=sys.stderr)
        return 3
    for style, r in report["by_style"].items():
        s = "n/a" if r["spearman"] is None else f"{r['spearman']:.2f}"
        p = "n/a" if r["spearman_advancing_push"] is None else f"{r['spearman_advancing_push']:.2f}"
        print(f"{style}: {r['cases']} cases, rank correlation with the true friction: fitted {s}, "
              f"advancing push {p}")
    print(f"wrote {base}.csv, .json, .png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
