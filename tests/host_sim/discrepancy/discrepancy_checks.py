#!/usr/bin/env python3
"""The discrepancy workflow proven on data with a hidden effect: each check must name the effect
hidden in a synthetic recording, fit its parameters within 25 % and halve the most affected
output's held-out error (host_sim/discrepancy/README.md). Each check writes a scenario, records it
with `scopekin simulate` (the test bed's sensor noise, its own seed), and gives only the recording's
CSV to `scopekin discrepancy` with the default model. Procedures, seeds and parameter values differ
between checks; the procedures are host_sim/discrepancy/sweep/procedures.py's, which the
robustness sweep also records.

usage: discrepancy_checks.py CHECK SCOPEKIN WORK_DIR SOURCE_DIR
A failure prints what differed and exits 1."""
import csv
import json
import os
import shutil
import subprocess
import sys

CHECK, SCOPEKIN, WORK, SOURCE = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
# The procedures, the recording and the compared parameters, shared with the robustness sweep.
sys.path.insert(0, os.path.join(SOURCE, "host_sim", "discrepancy", "sweep"))
import procedures  # noqa: E402
from procedures import COMPARED, truth_value  # noqa: E402
from robustness_sweep import profile_dips  # noqa: E402
# One check also draws the report's plots and has them checked (the others skip them for time).
PLOTTED = "ei_scale"
SECOND_PASS = "ei_scale"  # then run again on its own model.json (check_second_pass)
# Every library effect but viscoadhesive friction at its neutral value (model/effects/EFFECTS.md).
NEUTRAL = {"ei_scale": {"factor": 1.0}, "ei_profile": {"tip_factor": 1.0, "handle_factor": 1.0},
           "mesenteric_retraction": {"stiffness_N_per_mm2": 0.0}, "sigmoid_mobility": {"amplitude_N_per_mm": 0.0},
           "tissue_stiffening": {"stiffening_per_N": 0.0}}
failures = []

# check -> (procedure, seed, hidden truth effects, sensors, expected verdict, fitted keys to compare)
CHECKS = {
    "viscoadhesive_friction": ("B", 11, [{"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0.003}], None),
    "mesenteric_retraction": ("A", 12, [{"name": "mesenteric_retraction", "stiffness_N_per_mm2": 0.0025}], None),
    # On B (320 mm, the sigmoid only): a model run there costs 0.4 of one on C (1.3 s against
    # 3.2 s), and this check was the CI's longest (1,141 s on C). The handle factor is the harder
    # of the two to see (only the inserted shaft bends): on B it comes out 6 % low (1.128 for 1.2).
    # C's junction stays in the checks (tissue_stiffening, none) and in the sweep's ei_profile cells.
    "ei_profile": ("B", 13, [{"name": "ei_profile", "tip_factor": 0.7, "handle_factor": 1.2}], None),
    "ei_scale": ("B", 14, [{"name": "ei_scale", "factor": 1.12}], None),
    "sigmoid_mobility": ("A", 15, [{"name": "sigmoid_mobility", "amplitude_N_per_mm": 0.004, "frequency_Hz": 0.35,
                                    "direction": [0, 0.6, 0.8], "phase_rad": 0.7}], None),
    "tissue_stiffening": ("C", 16, [{"name": "tissue_stiffening", "reference_force_N": 2}], None),
    "none": ("C", 17, [], None),
    # Outside the library: the EM tracker's samples arrive 99 ms late (a latency the model lacks).
    "unexplained": ("A", 18, [], {"em_tracker": {"latency_s": 0.099}}),
    "two_effects": ("A", 19, [{"name": "ei_scale", "factor": 0.85},
                              {"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0.003}], None),
}
# Checks that fit on windows, with the budget they give (recording seconds per fit run).
WINDOWED = {"windowed": ("D", 22, [{"name": "ei_scale", "factor": 1.15}], None)}
FIT_BUDGET_S = "80"
CHECKS.update(WINDOWED)


def expect(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)
    else:
        print("ok:", message)


def run(*args, expect_status=0):
    p = subprocess.run([SCOPEKIN, *args], capture_output=True, text=True)
    if expect_status is not None and p.returncode != expect_status:
        print(p.stdout[-3000:], p.stderr[-3000:])
        raise SystemExit(f"scopekin {' '.join(args)}: exit {p.returncode}, expected {expect_status}")
    return p


def record(name, procedure, seed, effects, sensors):
    work = os.path.join(WORK, name)
    shutil.rmtree(work, ignore_errors=True)
    procedures.record(SCOPEKIN, work, f"discrepancy check {name}", procedure, seed, effects, sensors)
    return work


def check_hidden(name):
    procedure, seed, effects, sensors = CHECKS[name]
    work = record(name, procedure, seed, effects, sensors)
    out = os.path.join(work, "discrepancy")
    plots = [] if name == PLOTTED else ["--no-plots"]
    budget = ["--fit-budget-s", FIT_BUDGET_S] if name in WINDOWED else []
    p = run("discrepancy", os.path.join(work, "recorded", "recording.csv"), "--out", out, *plots, *budget, "--quiet")
    print(p.stdout)
    for f in ["report.json", "report.md", "model.json", "series.csv"]:
        expect(os.path.isfile(os.path.join(out, f)), f"wrote {f}")
    if name == PLOTTED:
        pngs = [os.path.join(out, n) for n in ["outputs.png", "residuals.png", "candidates.png", "profiles.png"]]
        c = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "host_sim", "plots", "check_pngs.py"), *pngs],
                           capture_output=True, text=True)
        expect(c.returncode == 0, f"the report's PNGs are non-trivial: {c.stdout.strip()} {c.stderr.strip()}")
    r = json.load(open(os.path.join(out, "report.json")))
    named = [e["name"] for e in r["effects"]]
    windows = r["fit_windows"]
    expect(windows["windowed"] == (name in WINDOWED), f"fitted on windows: {windows['windowed']}")
    if name in WINDOWED:
        spans = [(w["start_s"], w["scored_from_s"], w["end_s"]) for w in windows["windows"]]
        expect(len(spans) == 10 and all(abs(e - s0 - 8.0) < 1e-6 and abs(f - s0 - 3.0) < 1e-6 for s0, f, e in spans),
               f"one 8 s window per block (80 s budget), 3 s spin-up first: {spans}")
        expect(windows["confirmation"] and windows["confirmation"]["holds"],
               f"the named effect holds over the whole recording: {windows['confirmation']}")
    if name == "none":
        expect(r["verdict"] == "none", f"no hidden effect: verdict none (got {r['verdict']}, {named})")
        return
    if name == "unexplained":
        expect(r["verdict"] == "unexplained", f"an effect outside the library: verdict unexplained (got {r['verdict']}, {named})")
        # A late tracker is no stick-or-slip branch: the encoder decides the prediction to the end.
        test = r.get("predictability") or {}
        expect(test.get("runs_ok") is True and test.get("until_s") is None and test.get("judged_again") is False,
               f"the best candidate run with the drive moved by half an encoder count never parts: {test}")
        return
    expect(r["verdict"] == "named", f"verdict named (got {r['verdict']})")
    expect(sorted(named) == sorted(e["name"] for e in effects), f"named {named}, hidden {[e['name'] for e in effects]}")
    if len(effects) == 1:
        best = r["candidates"][0]["effects"]
        expect(best == [effects[0]["name"]], f"top-ranked candidate {best}")
    unexplained_sd = [(e["name"], q["name"]) for e in r["effects"] for q in e["parameters"]
                      if q.get("fitted") and q.get("sd") is None and not q.get("sd_unavailable")]
    expect(not unexplained_sd, f"every fitted parameter has an SD or says why not: {unexplained_sd}")
    for effect in effects:
        fitted = next((e for e in r["effects"] if e["name"] == effect["name"]), None)
        if fitted is None:
            continue
        values = {p["name"]: p["value"] for p in fitted["parameters"]}
        for truth_key, report_key in COMPARED[effect["name"]]:
            truth = truth_value(effect, truth_key)
            got = values.get(report_key)
            expect(got is not None and abs(got - truth) <= 0.25 * abs(truth),
                   f"{effect['name']}.{report_key} = {got} within 25 % of the truth {truth}")
    most = r["most_affected_output"]
    expect(most["reduction"] >= 0.5,
           f"held-out RMS error of the most affected output ({most['name']}) down by >= 50 %: "
           f"{most['held_out_rmse_before']:.4g} -> {most['held_out_rmse_after']:.4g}")
    model = json.load(open(os.path.join(out, "model.json")))
    expect(sorted(e["name"] for e in model.get("truth_effects", [])) == sorted(named), "model.json carries the named effects")
    if name == SECOND_PASS:
        check_second_pass(work, out)


def check_second_pass(work, first):
    """The workflow run again with a --model that carries library effects. On the model it wrote
    (model.json) it completes and finds nothing left. On a model that carries the hidden effect at
    its neutral value (ei_scale 1.0) the residual is still there: the effects the model carries
    are not screened again (a run holds an effect once; before, this exited 2), the others are.
    That model carries every library effect at its neutral value (model/effects/EFFECTS.md) but
    one, viscoadhesive friction, so that the pass screens one candidate (33 runs, not 193 with
    only the hidden effect carried: the CI's time)."""
    recording = os.path.join(work, "recorded", "recording.csv")
    out = os.path.join(work, "second_pass")
    run("discrepancy", recording, "--model", os.path.join(first, "model.json"), "--out", out, "--no-plots", "--quiet")
    r = json.load(open(os.path.join(out, "report.json")))
    expect(r["verdict"] == "none", f"second pass on model.json: verdict none (got {r['verdict']})")
    # --compare-only: one model run, no search; the model as given disagrees, the written model
    # agrees within the noise.
    for model, verdict in ((None, "disagrees"), (os.path.join(first, "model.json"), "none")):
        out = os.path.join(work, f"compare_only_{verdict}")
        run("discrepancy", recording, *(["--model", model] if model else []), "--compare-only", "--out", out,
            "--no-plots", "--quiet")
        r = json.load(open(os.path.join(out, "report.json")))
        expect(r["verdict"] == verdict and r["compare_only"] and r["model_runs"] == 1 and not r["candidates"],
               f"--compare-only with {model or 'the default model'}: verdict {verdict} from one run, no candidate "
               f"(got {r['verdict']}, {r['model_runs']} runs, {len(r['candidates'])} candidates)")
    neutral = json.load(open(os.path.join(first, "model.json")))
    neutral["truth_effects"] = [{"name": n, **v} for n, v in NEUTRAL.items()]
    carried = sorted(NEUTRAL)
    neutral_path = os.path.join(work, "neutral_model.json")
    with open(neutral_path, "w") as f:
        json.dump(neutral, f, indent=1)
    out = os.path.join(work, "neutral_pass")
    run("discrepancy", recording, "--model", neutral_path, "--out", out, "--no-plots", "--quiet")
    r = json.load(open(os.path.join(out, "report.json")))
    screened = (r.get("screening") or {}).get("candidates", [])
    skipped = sorted(c["effect"] for c in screened if "skipped" in c)
    expect(skipped == carried, f"a model carrying {carried}: they are not screened again: {skipped}")
    expect(len(screened) == 6 and [c["effect"] for c in screened if "skipped" not in c] == ["viscoadhesive_friction"]
           and all("gauss_newton_step" in c for c in screened if "skipped" not in c),
           f"... and the other library effect is: {[c['effect'] for c in screened]}")
    again = [e["name"] for e in r["effects"]]
    expect(not set(again) & set(carried), f"... none of them is named again: {again} (verdict {r['verdict']})")


def write_rows(path, header, rows_):
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows_)


def check_bad_input(_name):
    work = record("bad_input", "B", 21, [], None)
    src = os.path.join(work, "recorded", "recording.csv")
    with open(src, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        rows_ = list(reader)
    col = {name: i for i, name in enumerate(header)}

    def refused(label, rows_variant, fragment):
        path = os.path.join(work, f"{label}.csv")
        write_rows(path, header, rows_variant)
        p = run("discrepancy", path, "--out", os.path.join(work, f"out_{label}"), "--no-plots", "--quiet", expect_status=2)
        expect(fragment in p.stderr, f"{label}: exit 2 saying '{fragment}': {p.stderr.strip()[:300]}")

    # No handle motion: the encoder's cells are empty.
    blank = [list(r) for r in rows_]
    for r in blank:
        r[col["insertion_mm"]] = ""
        r[col["roll_rad"]] = ""
    refused("no_handle", [r for r in blank if any(c for c in r[1:])], "no handle motion")
    # Insertion in metres.
    metres = [list(r) for r in rows_]
    for r in metres:
        if r[col["insertion_mm"]]:
            r[col["insertion_mm"]] = f"{float(r[col['insertion_mm']]) / 1000:.5f}"
    refused("metres", metres, "metres instead of millimetres")
    # Too short to hold data out: the first 8 s.
    refused("short", [r for r in rows_ if float(r[col["time_s"]]) <= 8.0], "too short to hold data out")
    # No measured output: the EM and tip force cells are empty.
    stripped = [list(r) for r in rows_]
    for r in stripped:
        for name, i in col.items():
            if name.startswith("em_") or name.startswith("tip_force"):
                r[i] = ""
    refused("no_outputs", stripped, "no measured output to compare with")
    # Handle force in millinewtons.
    milli = [list(r) for r in rows_]
    for r in milli:
        if r[col["handle_force_N"]]:
            r[col["handle_force_N"]] = f"{float(r[col['handle_force_N']]) * 1000:.3f}"
    refused_milli = os.path.join(work, "milli.csv")
    write_rows(refused_milli, header, milli)
    q = run("discrepancy", refused_milli, "--out", os.path.join(work, "out_milli"), "--no-plots", "--quiet", expect_status=None)
    expect(q.returncode == 2 and ("newtons" in q.stderr or "RecordingError" in q.stderr or "line" in q.stderr),
           f"handle force in mN: refused (exit {q.returncode}): {q.stderr.strip()[:300]}")


def check_thesis_cantilever(_name):
    out = os.path.join(WORK, "thesis_cantilever")
    shutil.rmtree(out, ignore_errors=True)
    p = run("discrepancy", "--thesis-cantilever", "--out", out, "--quiet")
    print(p.stdout)
    r = json.load(open(os.path.join(out, "report.json")))
    given = r["model_as_given"]["rms_mm"]
    # The thesis's own models reach 5.5-6.1 mm RMS against these points (model/PHYSICS.md §2.6); the
    # model at its chapter-5 EI with a horizontal clamp is worse, and every fit must do better.
    expect(8.0 < given < 12.0, f"model as given: RMS {given:.2f} mm (350 N cm^2, clamp horizontal)")
    names = sorted(c["name"] for c in r["candidates"])
    expect(names == sorted(["ei_scale", "ei_profile", "ei_scale + clamp_pitch", "ei_profile + clamp_pitch"]), f"candidates {names}")
    for c in r["candidates"]:
        expect(c["rms_held_out_mm"] < given, f"{c['name']}: held-out RMS {c['rms_held_out_mm']:.2f} mm below the model as given")
    scale = next(c for c in r["candidates"] if c["name"] == "ei_scale")
    expect(5.0 < scale["rms_all_points_mm"] < 6.1, f"one EI: RMS {scale['rms_all_points_mm']:.2f} mm within the thesis's 5.5-6.1 mm band")
    expect(isinstance(r["ei_profile_explains_better_than_one_ei"], bool), "the report answers the EI-profile question")
    expect("EI / w" in r["not_identifiable"], "the report says EI and weight are not separable")


def check_sweep(_name):
    """A small part of the robustness sweep (host_sim/discrepancy/sweep/robustness_sweep.py): two
    cases run, judged and summarised into its tables and heat map; and its rule on made-up reports
    (a parameter 24 % off passes, 26 % off fails; a null recording named fails)."""
    sweep = os.path.join(SOURCE, "host_sim", "discrepancy", "sweep", "robustness_sweep.py")
    out = os.path.join(WORK, "sweep")
    shutil.rmtree(out, ignore_errors=True)
    cases = ["ei_scale-1.3-B", "null-noise2x-B"]
    p = subprocess.run(["/usr/bin/python3", sweep, "run", "--scopekin", SCOPEKIN, "--out", out,
                        "--only", "^(" + "|".join(cases) + ")$"], capture_output=True, text=True)
    print(p.stderr)
    expect(p.returncode == 0, f"the sweep's two cases ran (exit {p.returncode})")
    p = subprocess.run(["/usr/bin/python3", sweep, "summarise", out], capture_output=True, text=True)
    print(p.stdout, p.stderr)
    expect(p.returncode == 0, f"summarised (exit {p.returncode})")
    for f in ["sweep.json", "sweep.csv", "sweep.md", "heatmap.png"]:
        expect(os.path.isfile(os.path.join(out, f)), f"wrote {f}")
    s = json.load(open(os.path.join(out, "sweep.json")))
    expect(s["cases_judged"] == 2 and s["cases_planned"] >= 100, f"2 of {s['cases_planned']} planned cases judged")
    expect(s["success_rate"] == 1.0, f"both judged right: {s['failures']}")
    expect(s["false_named_on_null"] == 0, "no effect named on the null recording")
    expect(len(s["binaries"]) == 1 and list(s["binaries"].values()) == [2] and "not recorded" not in s["binaries"],
           f"one binary judged both cases, its digest recorded: {s['binaries']}")
    # The truth's own reach: the true ei_scale 1.3 explains its recording (the handle force's error
    # at least halved), and the null recording's model as given is its true model.
    reach = {n: json.load(open(os.path.join(out, "cases", n, "truth_reach.json"))) for n in cases}
    expect(reach["ei_scale-1.3-B"]["meets_bar"] and reach["ei_scale-1.3-B"]["true_model_verdict"] == "none" and
           reach["ei_scale-1.3-B"]["model_as_given_verdict"] == "disagrees",
           f"the true ei_scale 1.3 explains its recording, the model as given does not: {reach['ei_scale-1.3-B']}")
    expect(reach["null-noise2x-B"]["meets_bar"] and reach["null-noise2x-B"]["model_as_given_verdict"] == "none",
           f"the null recording: the model as given agrees: {reach['null-noise2x-B']}")
    # The hidden ei_scale's screening profile has one dip; dips counted as fit.cpp's profile_dips does.
    shapes = s["screening_profiles"]
    expect(shapes["profiles"] == 1 and shapes["unimodal"] == 1, f"one screening profile, one dip: {shapes}")
    expect(profile_dips([3, 1, 2, 0.5, 4]) == [1, 3] and profile_dips([1, 2, 3]) == [0] and profile_dips([2, 2, 2]) == [],
           "the profile's dips: below each neighbour, an end against its one")
    t = s["truth_reach"]
    expect(t["cases_measured"] == 2 and t["true_model_meets_bar"] == 2 and t["success_rate_where_true_model_meets_bar"] == 1.0,
           f"summarised: the true model meets the bar on both, both right: {t}")
    c = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "host_sim", "plots", "check_pngs.py"),
                        os.path.join(out, "heatmap.png")], capture_output=True, text=True)
    expect(c.returncode == 0, f"the heat map is non-trivial: {c.stdout.strip()} {c.stderr.strip()}")
    # The 10-minute bench (too slow for CI: seven 2-minute runs) refuses bad usage with exit 2.
    bench = os.path.join(SOURCE, "host_sim", "discrepancy", "sweep", "ten_minute_bench.py")
    for args, fragment in ((["--scopekin", os.path.join(out, "no-such-binary")], "not an executable"),
                           (["--scopekin", SCOPEKIN, "--only", "no-such-recording"], "no recording selected"),
                           (["--scopekin", SCOPEKIN, "--only", "("], "--only:")):
        b = subprocess.run(["/usr/bin/python3", bench, *args, "--out", os.path.join(out, "bench")],
                           capture_output=True, text=True)
        expect(b.returncode == 2 and fragment in b.stderr, f"the bench refuses {args}: exit {b.returncode}, "
               f"'{fragment}' in {b.stderr.strip()[-200:]}")
    hidden = [{"name": "ei_scale", "factor": 0.8}]

    def report(value, reduction=0.9, verdict="named"):
        return {"verdict": verdict, "effects": [{"name": "ei_scale", "parameters": [{"name": "factor", "value": value}]}],
                "most_affected_output": {"name": "handle_force_N", "reduction": reduction}}
    expect(procedures.judge(report(0.8 * 1.24), hidden)["success"], "the rule: 24 % off passes")
    late = procedures.judge(report(0.8 * 1.26), hidden)
    expect(not late["success"] and "factor" in late["why"], f"the rule: 26 % off fails ({late['why']})")
    weak = procedures.judge(report(0.8, reduction=0.4), hidden)
    expect(not weak["success"] and "down 40 %" in weak["why"], f"the rule: the error down 40 % fails ({weak['why']})")
    expect(not procedures.judge(report(0.8), [])["success"], "the rule: an effect named on a null recording fails")
    # ei_scale named where ei_profile was hidden, ei_profile listed as explaining it as well: still a
    # failure, and the summary says the recording could not tell them apart.
    equal = report(0.8)
    equal["equally_consistent"] = {"sets": [{"effects": ["ei_profile"]}]}
    listed = procedures.judge(equal, [{"name": "ei_profile", "tip_factor": 0.8, "handle_factor": 1.0}])
    expect(not listed["success"] and listed["hidden_listed_as_equal"],
           f"the rule: the hidden set listed as equal is a failure, marked ({listed})")
    expect(not procedures.judge(report(0.8), hidden)["hidden_listed_as_equal"], "the rule: right names are not marked")
    # Judged on the recording's predictable part: the case says up to where (sweep.md lists it).
    part = report(0.8)
    part["predictability"] = {"judged_again": True, "until_s": 25.1}
    expect(procedures.judge(part, hidden)["judged_until_s"] == 25.1 and
           procedures.judge(report(0.8), hidden)["judged_until_s"] is None,
           "the rule: a case judged on its predictable part says up to where; the others do not")


if CHECK == "bad_input":
    check_bad_input(CHECK)
elif CHECK == "sweep":
    check_sweep(CHECK)
elif CHECK == "thesis_cantilever":
    check_thesis_cantilever(CHECK)
elif CHECK in CHECKS:
    check_hidden(CHECK)
else:
    raise SystemExit(f"unknown check {CHECK}")
if failures:
    print(f"{len(failures)} failure(s)")
    sys.exit(1)
