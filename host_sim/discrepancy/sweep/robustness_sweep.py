#!/usr/bin/env python3
"""The discrepancy workflow's robustness sweep: every library effect at five sizes across its
plausible range, on procedures that differ in depth, speed and manoeuvres, plus null recordings at
1x and 2x the sensors' noise and pairs of unequal size. Each case is recorded with `scopekin
simulate`, given to `scopekin discrepancy` as a user would (the recording's CSV, the default model),
and judged: the right verdict, the right names, the parameters within 25 % and the most affected
output's held-out error at least halved (host_sim/discrepancy/README.md, "The robustness sweep").

usage:
  robustness_sweep.py list [--only REGEX]
  robustness_sweep.py run --scopekin BIN --out DIR [--shard I/N] [--jobs J] [--only REGEX] [--rerun]
  robustness_sweep.py truth --scopekin BIN --out DIR [--shard I/N] [--jobs J] [--only REGEX]
  robustness_sweep.py summarise DIR [--no-plot]

`run` writes DIR/cases/NAME/ (scenario.json, recorded/, discrepancy/, result.json) and skips a case
whose result.json exists unless --rerun; a case belongs to shard FNV-1a-64(its name) mod N, as in
`scopekin evaluate`. Beside each case `run` (and `truth` alone, without the search: seconds a
case) measures the truth's own reach, DIR/cases/NAME/truth_reach.json: the recording compared
(`scopekin discrepancy --compare-only`) with the model as given and with the true model, both driven
by the recording's encoder; where the true model does not halve the most affected output's held-out
error no search can pass the case (a recording the encoder's resolution cannot predict, e.g. a
stick-or-slip branch decided by 0.001 mm). Each result.json records the SHA-256 of the binary that
judged it; `summarise` lists them, so a count is known to be one code's. `summarise` reads every
result.json in DIR and writes DIR/sweep.json,
sweep.csv (one row per case), sweep.md (the success rate per effect x size x procedure, the
failures with their diagnosis) and heatmap.png. Exit status: 0 done, 1 a case could not be run,
2 bad usage."""
import argparse
import csv
import hashlib
import json
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import procedures  # noqa: E402

SWEPT_PROCEDURES = ["B", "C", "E"]  # short sigmoid-only (320 mm), mid (570 mm), deep (836 mm)
DIRECTION = {"direction": [0, 0.6, 0.8], "phase_rad": 0.7}
# Five sizes per effect across its plausible range (model/effects/EFFECTS.md; issue 22's ranges).
SIZES = {
    "ei_scale": [{"factor": f} for f in (0.7, 0.8, 0.9, 1.15, 1.3)],
    "ei_profile": [{"tip_factor": f, "handle_factor": 1.0} for f in (0.5, 0.6, 0.7, 0.8, 0.9)],
    "viscoadhesive_friction": [{"viscous_coefficient_s_per_mm": c} for c in (0.001, 0.002, 0.004, 0.006, 0.008)],
    # x0.5 .. x3 of the default 0.002 N/mm per mm
    "mesenteric_retraction": [{"stiffness_N_per_mm2": k} for k in (0.001, 0.002, 0.003, 0.004, 0.006)],
    "tissue_stiffening": [{"stiffening_per_N": b} for b in (0.2, 0.4, 0.7, 1.0, 1.5)],
    # amplitudes 0.002-0.012 N/mm, motility and breathing frequencies
    "sigmoid_mobility": [dict(amplitude_N_per_mm=a, frequency_Hz=f, **DIRECTION)
                         for a, f in ((0.002, 0.2), (0.004, 0.35), (0.006, 0.1), (0.008, 0.45), (0.012, 0.25))],
}
# Two effects hidden together, one dominant and one smaller.
PAIRS = [
    [{"name": "ei_scale", "factor": 0.85}, {"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0.001}],
    [{"name": "ei_profile", "tip_factor": 0.6, "handle_factor": 1.0},
     {"name": "mesenteric_retraction", "stiffness_N_per_mm2": 0.001}],
    [{"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0.006},
     {"name": "tissue_stiffening", "stiffening_per_N": 0.3}],
]
NOISE_FACTORS = [1, 2]


def fnv1a64(text):
    h = 0xcbf29ce484222325
    for b in text.encode():
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


LABEL_SKIP = {"phase_rad", "handle_factor"}  # the same in every size: not part of the case's name


def size_label(values):
    return "_".join(f"{v:g}" for k, v in values.items() if isinstance(v, (int, float)) and k not in LABEL_SKIP)


def plan():
    """Every case: name, cell (effect, size, procedure), hidden effects, sensors, seed."""
    cases = []

    def add(effect, size, procedure, effects, noise=1):
        name = f"{effect}-{size}-{procedure}"
        cases.append({"name": name, "effect": effect, "size": size, "procedure": procedure, "effects": effects,
                      "noise_factor": noise, "seed": fnv1a64(name) % 1_000_000 + 1})

    for procedure in SWEPT_PROCEDURES:
        for effect, sizes in SIZES.items():
            for values in sizes:
                add(effect, size_label(values), procedure, [dict(name=effect, **values)])
        for noise in NOISE_FACTORS:
            add("null", f"noise{noise}x", procedure, [], noise)
        for pair in PAIRS:
            label = "+".join(f"{e['name']}:{size_label({k: v for k, v in e.items() if k != 'name'})}" for e in pair)
            add("pair", label, procedure, pair)
    return cases


def select(cases, only, shard):
    chosen = [c for c in cases if only is None or re.search(only, c["name"])]
    index, count = shard
    return [c for c in chosen if fnv1a64(c["name"]) % count == index]


def compare_only(scopekin, recording, model, out):
    """`scopekin discrepancy --compare-only`'s report.json: the model (None: the default) driven by
    the recording's encoder and compared with it, one run, no search."""
    p = subprocess.run([scopekin, "discrepancy", recording, *(["--model", model] if model else []),
                        "--compare-only", "--out", out, "--no-plots", "--quiet"], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"scopekin discrepancy --compare-only: exit {p.returncode}: {p.stderr.strip()[-500:]}")
    return json.load(open(os.path.join(out, "report.json")))


def truth_reach(scopekin, work):
    """How far the true model itself gets on the case's recording (WORK/recorded, its scenario in
    WORK/scenario.json): its held-out RMS error of the output the model as given gets most wrong,
    against the model as given's, and its verdict (none: it explains the recording to its noise).
    `meets_bar`: it halves that error (the sweep's own bar), or, on a null recording, the model
    as given agrees with it. Writes WORK/truth_reach.json and returns it."""
    recording = os.path.join(work, "recorded", "recording.csv")
    scenario = json.load(open(os.path.join(work, "scenario.json")))
    model = {k: v for k, v in scenario.items()
             if k not in ("description", "procedure", "sensors", "initial_insertion_mm")}
    model_path = os.path.join(work, "truth_model.json")
    with open(model_path, "w") as f:
        json.dump(model, f, indent=1)
    given = compare_only(scopekin, recording, None, os.path.join(work, "truth_reach", "model_as_given"))
    true = compare_only(scopekin, recording, model_path, os.path.join(work, "truth_reach", "true_model"))
    output = given["most_affected_output"]["name"]
    before, after = given["rmse_before"][output], true["rmse_before"][output]
    reduction = 1.0 - after / before if before > 0 else 0.0
    reach = {"model_as_given_verdict": given["verdict"], "true_model_verdict": true["verdict"],
             "most_affected_output": output, "held_out_rmse_model_as_given": before,
             "held_out_rmse_true_model": after, "reduction": reduction,
             "meets_bar": given["verdict"] == "none" if not model.get("truth_effects") else reduction >= procedures.MIN_REDUCTION}
    with open(os.path.join(work, "truth_reach.json"), "w") as f:
        json.dump(reach, f, indent=1)
    return reach


def truth_reach_of(scopekin, work):
    """truth_reach.json if it is there, else measured (the recording must be there)."""
    path = os.path.join(work, "truth_reach.json")
    return json.load(open(path)) if os.path.isfile(path) else truth_reach(scopekin, work)


def binary_digest(path):
    """The first 12 hex digits of the binary's SHA-256: results with the same digest are one code's."""
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()[:12]


def run_case(case, scopekin, out, rerun):
    work = os.path.join(out, "cases", case["name"])
    result_path = os.path.join(work, "result.json")
    if os.path.isfile(result_path) and not rerun:
        result = json.load(open(result_path))
        if result.get("ran") and "truth_reach" not in result:  # a case run before truth_reach was
            result["truth_reach"] = truth_reach_of(scopekin, work)
            write_result(result_path, result)
        return result, True
    sensors = procedures.noise_times(case["noise_factor"]) if case["noise_factor"] != 1 else None
    result = {k: case[k] for k in ("name", "effect", "size", "procedure", "noise_factor", "seed")}
    result["hidden"] = case["effects"]
    result["scopekin_sha256"] = binary_digest(scopekin)
    t0 = time.monotonic()
    try:
        recording = procedures.record(scopekin, work, f"robustness sweep {case['name']}", case["procedure"],
                                      case["seed"], case["effects"], sensors)
    except RuntimeError as e:
        result.update(success=False, ran=False, why=str(e))
        return result, False
    t1 = time.monotonic()
    p = subprocess.run([scopekin, "discrepancy", recording, "--out", os.path.join(work, "discrepancy"), "--no-plots",
                        "--quiet"], capture_output=True, text=True)
    t2 = time.monotonic()
    result["wall_s"] = {"record": round(t1 - t0, 1), "discrepancy": round(t2 - t1, 1)}
    if p.returncode != 0:
        result.update(success=False, ran=False, why=f"scopekin discrepancy: exit {p.returncode}: {p.stderr.strip()[-500:]}")
    else:
        report = json.load(open(os.path.join(work, "discrepancy", "report.json")))
        result["ran"] = True
        result["model_runs"] = report.get("model_runs")
        result.update(procedures.judge(report, case["effects"]))
        result["truth_reach"] = truth_reach(scopekin, work)
    write_result(result_path, result)
    return result, False


def write_result(path, result):
    with open(path + ".part", "w") as f:
        json.dump(result, f, indent=1)
    os.replace(path + ".part", path)


def truth_case(case, scopekin, out):
    """`truth`: the case recorded (unless it is) and the truth's reach measured; no search."""
    work = os.path.join(out, "cases", case["name"])
    if not os.path.isfile(os.path.join(work, "recorded", "recording.csv")):
        sensors = procedures.noise_times(case["noise_factor"]) if case["noise_factor"] != 1 else None
        procedures.record(scopekin, work, f"robustness sweep {case['name']}", case["procedure"], case["seed"],
                          case["effects"], sensors)
    return truth_reach_of(scopekin, work)


def cmd_truth(args):
    cases = select(plan(), args.only, args.shard)
    if not cases:
        print("robustness_sweep.py: no case selected", file=sys.stderr)
        return 2
    print(f"{len(cases)} case(s): the truth's reach, {args.jobs} at a time", file=sys.stderr)
    done, failed, start = 0, 0, time.monotonic()

    def one(case):
        try:
            return case, truth_case(case, args.scopekin, args.out), None
        except RuntimeError as e:
            return case, None, str(e)

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for case, reach, error in pool.map(one, cases):
            done += 1
            failed += error is not None
            state = (f"FAILED: {error}" if error else
                     f"true model {reach['true_model_verdict']}, {reach['most_affected_output']} held-out "
                     f"{reach['held_out_rmse_model_as_given']:.3g} -> {reach['held_out_rmse_true_model']:.3g} "
                     f"({'meets' if reach['meets_bar'] else 'MISSES'} the bar)")
            print(f"[{done}/{len(cases)} {time.monotonic() - start:.0f} s] {case['name']}: {state}", file=sys.stderr,
                  flush=True)
    return 1 if failed else 0


def cmd_run(args):
    cases = select(plan(), args.only, args.shard)
    if not cases:
        print("robustness_sweep.py: no case selected", file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    print(f"{len(cases)} case(s) in shard {args.shard[0]}/{args.shard[1]}, {args.jobs} at a time", file=sys.stderr)
    done, failed, start = 0, 0, time.monotonic()

    def one(case):
        return case, run_case(case, args.scopekin, args.out, args.rerun)

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for case, (result, kept) in pool.map(one, cases):
            done += 1
            failed += not result.get("ran", False)
            state = "kept" if kept else ("ok" if result.get("success") else f"FAILED: {result.get('why')}")
            print(f"[{done}/{len(cases)} {time.monotonic() - start:.0f} s] {case['name']}: {state}", file=sys.stderr,
                  flush=True)
    return 1 if failed else 0


def load_results(out):
    folder = os.path.join(out, "cases")
    if not os.path.isdir(folder):
        raise SystemExit(f"robustness_sweep.py: {out}: no cases/ folder (run the sweep into it first)")
    results = []
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name, "result.json")
        if not os.path.isfile(path):
            continue
        r = json.load(open(path))
        report = os.path.join(folder, name, "discrepancy", "report.json")
        if r.get("ran") and os.path.isfile(report):  # judged again: the rule as it is now
            r.update(procedures.judge(json.load(open(report)), r["hidden"]))
        results.append(r)
    return results


def load_truth_reach(out):
    """Every case's truth_reach.json in DIR/cases (by name), judged or not."""
    folder = os.path.join(out, "cases")
    reach = {}
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name, "truth_reach.json")
        if os.path.isfile(path):
            reach[name] = json.load(open(path))
    return reach


def truth_summary(reach, results, cases):
    """How many cases the true model itself passes, which it does not (with their cells), and the
    success rate over the judged cases it passes."""
    missed = sorted(n for n, t in reach.items() if not t["meets_bar"])
    passable = [r for r in results if r["name"] in reach and reach[r["name"]]["meets_bar"]]
    return {"cases_measured": len(reach), "true_model_meets_bar": len(reach) - len(missed),
            "missed_by_true_model": [{"case": n, **{k: cases[n][k] for k in ("effect", "size", "procedure") if n in cases},
                                      "output": reach[n]["most_affected_output"],
                                      "reduction": reach[n]["reduction"],
                                      "true_model_verdict": reach[n]["true_model_verdict"]} for n in missed],
            "judged_where_true_model_meets_bar": len(passable), "success_rate_where_true_model_meets_bar": rate(passable)}


def rate(rows):
    return sum(r["success"] for r in rows) / len(rows) if rows else None


def short_why(why):
    """The first criterion a case missed, in a word or two (the heat map's cell text)."""
    for start, word in (("named", "wrong name"), ("verdict", "verdict"), ("parameters", "parameter"),
                        ("scopekin", "did not run")):
        if (why or "").startswith(start):
            return word
    return "error not halved" if "held-out error" in (why or "") else "failed"


def sd_coverage(results):
    """How often the reported SD covers the truth: |fitted - truth| within 1 and 2 SDs (a Gaussian
    68 and 95 %), over every compared parameter of a right name that came with an SD."""
    z = [abs(e["fitted"] - e["truth"]) / e["sd"] for r in results for e in r.get("parameters", [])
         if e.get("fitted") is not None and e.get("sd")]
    if not z:
        return {"parameters": 0}
    return {"parameters": len(z), "within_1_sd": sum(v <= 1 for v in z) / len(z),
            "within_2_sd": sum(v <= 2 for v in z) / len(z), "median_error_in_sd": sorted(z)[len(z) // 2]}


def profile_dips(costs):
    """Indices of a screening profile's dips: grid points whose training cost is below each
    neighbour's (an end counts against its one neighbour), as `profile_dips` in fit.cpp."""
    return [k for k, c in enumerate(costs)
            if (k == 0 or c < costs[k - 1]) and (k == len(costs) - 1 or c < costs[k + 1])]


def profile_shapes(out, results):
    """How many dips the hidden effect's screening profile has (its lowest training cost along each
    parameter's grid, on the capped objective), over every judged case with one hidden effect: the
    issue asks the objective to make it unimodal. Effects screened without a grid (the sigmoid
    motion, by its periodogram) have none."""
    profiles = []
    for r in results:
        if len(r.get("hidden", [])) != 1:
            continue
        path = os.path.join(out, "cases", r["name"], "discrepancy", "report.json")
        if not os.path.isfile(path):
            continue
        screened = (json.load(open(path)).get("screening") or {}).get("candidates", [])
        for c in screened:
            if c.get("effect") != r["hidden"][0]["name"]:
                continue
            for prof in (c.get("grid") or {}).get("profile", []):
                costs = prof["lowest_training_cost"]
                if len(costs) < 3 or not all(isinstance(v, (int, float)) for v in costs):
                    continue
                dips = profile_dips(costs)
                profiles.append({"case": r["name"], "parameter": prof["parameter"], "dips": len(dips),
                                 "at": [prof["values"][k] for k in dips]})
    single = [q for q in profiles if q["dips"] == 1]
    return {"profiles": len(profiles), "unimodal": len(single),
            "share_unimodal": len(single) / len(profiles) if profiles else None,
            "not_one_dip": [q for q in profiles if q["dips"] != 1]}


def cmd_summarise(args):
    results = load_results(args.out)
    reach = load_truth_reach(args.out)
    if not results and not reach:
        raise SystemExit(f"robustness_sweep.py: {args.out}/cases: no result.json or truth_reach.json yet")
    for r in results:
        r["true_model_meets_bar"] = reach[r["name"]]["meets_bar"] if r["name"] in reach else None
    planned = {c["name"] for c in plan()}
    cells = {}
    for r in results:
        cells.setdefault((r["effect"], r["size"], r["procedure"]), []).append(r)
    summary = {
        "cases_planned": len(planned), "cases_judged": len(results),
        "missing": sorted(planned - {r["name"] for r in results}),
        "success_rate": rate(results),
        "false_named_on_null": sum(1 for r in results if r["effect"] == "null" and r.get("verdict") == "named"),
        "by_effect": {e: rate([r for r in results if r["effect"] == e]) for e in sorted({r["effect"] for r in results})},
        "cells": [{"effect": e, "size": s, "procedure": p, "cases": len(rows), "success_rate": rate(rows),
                   "true_model_misses": any(r["true_model_meets_bar"] is False for r in rows),
                   "missed": [short_why(r["why"]) for r in rows if not r["success"]]}
                  for (e, s, p), rows in sorted(cells.items())],
        "failures": [{"case": r["name"], "why": r.get("why"),
                      "hidden_listed_as_equal": bool(r.get("hidden_listed_as_equal"))}
                     for r in results if not r["success"]],
        # Cases the workflow judged on the part of the recording its encoder decides (a branch).
        "judged_on_predictable_part": [{"case": r["name"], "until_s": r["judged_until_s"], "success": r["success"]}
                                       for r in results if r.get("judged_until_s") is not None],
        "sd_coverage": sd_coverage(results),
        "screening_profiles": profile_shapes(args.out, results),
        # Which binaries judged the cases (a count is one code's only with one digest).
        "binaries": {d: sum(1 for r in results if r.get("scopekin_sha256", "not recorded") == d)
                     for d in sorted({r.get("scopekin_sha256", "not recorded") for r in results})},
        "truth_reach": truth_summary(reach, results, {c["name"]: c for c in plan()}),
        "planned_cells": sorted({(c["effect"], c["size"], c["procedure"]) for c in plan()}),
    }
    with open(os.path.join(args.out, "sweep.json"), "w") as f:
        json.dump(summary, f, indent=1)
    keys = ["name", "effect", "size", "procedure", "noise_factor", "seed", "success", "verdict", "named",
            "most_affected_output", "reduction", "why", "true_model_meets_bar", "judged_until_s"]
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(keys + ["max_relative_parameter_error", "discrepancy_wall_s"])
        for r in results:
            errs = [abs(e["relative_error"]) for e in r.get("parameters", []) if e["relative_error"] is not None]
            w.writerow([";".join(r[k]) if isinstance(r.get(k), list) else r.get(k) for k in keys] +
                       [f"{max(errs):.4g}" if errs else "", (r.get("wall_s") or {}).get("discrepancy", "")])
    write_markdown(args.out, summary, results)
    print(open(os.path.join(args.out, "sweep.md")).read())
    if not args.no_plot:
        p = subprocess.run(["/usr/bin/python3", os.path.join(os.path.dirname(os.path.abspath(__file__)), "plot_sweep.py"),
                            os.path.join(args.out, "sweep.json"), os.path.join(args.out, "heatmap.png")],
                           capture_output=True, text=True)
        if p.returncode != 0:
            print(f"robustness_sweep.py: the heat map failed: {p.stderr.strip()}", file=sys.stderr)
            return 1
    return 0


def sd_line(c):
    if not c["parameters"]:
        return "No fitted parameter with an SD to compare."
    return (f"Reported SDs against the truth ({c['parameters']} parameters): within 1 SD {percent(c['within_1_sd'])}, "
            f"within 2 SD {percent(c['within_2_sd'])} (a Gaussian: 68 and 95 %); the median error is "
            f"{c['median_error_in_sd']:.3g} SDs.")


def profile_line(p):
    if not p["profiles"]:
        return "No screening profile of a hidden effect to look at."
    other = "; ".join(f"`{q['case']}` {q['parameter']}: {q['dips']} dips at " + ", ".join(f"{v:g}" for v in q["at"])
                      for q in p["not_one_dip"])
    return (f"The hidden effect's screening profile (its lowest training cost along each parameter's grid, "
            f"{p['profiles']} profile{'' if p['profiles'] == 1 else 's'} of single-effect cases): one dip in {p['unimodal']} "
            f"({percent(p['share_unimodal'])})" + (f"; otherwise: {other}." if other else "."))


def percent(x):
    return "–" if x is None else f"{100 * x:.0f} %"


def write_markdown(out, summary, results):
    procs = sorted({r["procedure"] for r in results})
    lines = [f"Robustness sweep: {summary['cases_judged']} of {summary['cases_planned']} cases judged, success "
             f"{percent(summary['success_rate'])}; false `named` on null recordings: {summary['false_named_on_null']}.", "",
             sd_line(summary["sd_coverage"]), "",
             profile_line(summary["screening_profiles"]), "",
             "Binaries (SHA-256, cases): " + ", ".join(f"{d} {n}" for d, n in summary["binaries"].items()) +
             ("" if len(summary["binaries"]) == 1 and "not recorded" not in summary["binaries"]
              else " — the cases may not all be one code's"), "",
             "| effect | size | " + " | ".join(f"procedure {p}" for p in procs) + " |",
             "|---|---|" + "---|" * len(procs)]
    rows = {}
    for c in summary["cells"]:
        rows.setdefault((c["effect"], c["size"]), {})[c["procedure"]] = c
    for (effect, size), by_proc in rows.items():
        cells = []
        for p in procs:
            c = by_proc.get(p)
            cells.append("" if c is None else ("pass" if c["success_rate"] == 1 else "FAIL") +
                         (" †" if c and c["true_model_misses"] else ""))
        lines.append(f"| {effect} | {size} | " + " | ".join(cells) + " |")
    lines += ["", "Per effect: " + ", ".join(f"{e} {percent(v)}" for e, v in summary["by_effect"].items()), ""]
    t = summary["truth_reach"]
    if t["cases_measured"]:
        lines += [f"The truth's own reach (†: the true model, driven by the recording's encoder, does not halve the "
                  f"most affected output's held-out error — no search can pass the case): measured on "
                  f"{t['cases_measured']} cases, met by the true model on {t['true_model_meets_bar']}; success on "
                  f"the judged cases it meets: {percent(t['success_rate_where_true_model_meets_bar'])} "
                  f"({t['judged_where_true_model_meets_bar']} cases).", ""]
        lines += [f"- `{m['case']}`: the true model's {m['output']} held-out error down {100 * m['reduction']:.0f} % "
                  f"(verdict {m['true_model_verdict']})" for m in t["missed_by_true_model"]]
        lines += [""]
    if summary["judged_on_predictable_part"]:
        lines += ["Judged on the recording's predictable part (the workflow's runs with the drive moved by half an "
                  "encoder count part there: report.json `predictability`):", ""]
        lines += [f"- `{j['case']}`: up to {j['until_s']:.2f} s, {'right' if j['success'] else 'wrong'}"
                  for j in summary["judged_on_predictable_part"]]
        lines += [""]
    if summary["failures"]:
        listed = sum(1 for f in summary["failures"] if f["hidden_listed_as_equal"])
        lines += [f"Failures (the first criterion missed; in {listed} of {len(summary['failures'])} the report lists the "
                  "hidden set beside the named one as explaining the recording as well):", ""]
        lines += [f"- `{f['case']}`: {f['why']}" +
                  ("; the report lists the hidden set as explaining the recording as well (not identifiable "
                   "on this recording)" if f["hidden_listed_as_equal"] else "") for f in summary["failures"]]
    if summary["missing"]:
        lines += ["", f"Not yet run: {len(summary['missing'])} case(s)."]
    with open(os.path.join(out, "sweep.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def shard_arg(text):
    m = re.fullmatch(r"(\d+)/(\d+)", text)
    if not m or int(m.group(2)) == 0 or int(m.group(1)) >= int(m.group(2)):
        raise argparse.ArgumentTypeError(f"'{text}' is not I/N with 0 <= I < N")
    return int(m.group(1)), int(m.group(2))


def add_case_options(parser, per_job):
    """The options `run` and `truth` share: the binary, the folder, the shard, the jobs, --only."""
    parser.add_argument("--scopekin", required=True, help="the scopekin binary")
    parser.add_argument("--out", required=True, help="output folder (cases/NAME/ per case)")
    parser.add_argument("--shard", type=shard_arg, default=(0, 1), help="I/N: this job's shard of N (default 0/1)")
    parser.add_argument("--jobs", type=int, default=1, help=f"cases at a time ({per_job})")
    parser.add_argument("--only", help="only cases whose name matches this regular expression")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    sub = ap.add_subparsers(dest="command", required=True)
    ls = sub.add_parser("list", help="print the planned cases")
    ls.add_argument("--only", help="only cases whose name matches this regular expression")
    run = sub.add_parser("run", help="record and judge the cases of one shard")
    add_case_options(run, "each discrepancy run uses 2 threads")
    run.add_argument("--rerun", action="store_true", help="run cases again that already have a result.json")
    tr = sub.add_parser("truth", help="record the cases (unless recorded) and measure the truth's own reach only")
    add_case_options(tr, "each run uses one thread")
    sm = sub.add_parser("summarise", help="combine every result.json in DIR into the sweep's tables and heat map")
    sm.add_argument("out", metavar="DIR")
    sm.add_argument("--no-plot", action="store_true", help="skip heatmap.png")
    args = ap.parse_args()
    if args.command == "list":
        for c in select(plan(), args.only, (0, 1)):
            print(c["name"], json.dumps(c["effects"]), f"noise x{c['noise_factor']}", f"seed {c['seed']}")
        return 0
    if args.command in ("run", "truth"):
        if args.jobs < 1:
            ap.error("--jobs must be at least 1")
        if not os.access(args.scopekin, os.X_OK):
            ap.error(f"--scopekin {args.scopekin}: not an executable file")
        return cmd_run(args) if args.command == "run" else cmd_truth(args)
    return cmd_summarise(args)


if __name__ == "__main__":
    sys.exit(main())
