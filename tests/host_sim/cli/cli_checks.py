#!/usr/bin/env python3
"""End-to-end checks of the scopekin command line (tests/host_sim/cli/CMakeLists.txt).

usage: cli_checks.py CHECK SCOPEKIN WORK_DIR [SOURCE_DIR]
Every expectation is stated next to its check; a failure prints what differed and exits 1.
The output_order check needs SCOPEKIN_RENAME_PROBE (rename_probe.c, built by CMake) in the
environment."""
import bisect
import csv
import json
import os
import shutil
import subprocess
import sys

CHECK, SCOPEKIN, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
SOURCE = sys.argv[4] if len(sys.argv) > 4 else os.path.join(os.path.dirname(__file__), "..", "..", "..")
HERE = os.path.dirname(os.path.abspath(__file__))
failures = []


def expect(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(*args, expect_status=0, cwd=None, env=None, timeout=600):
    try:
        p = subprocess.run([SCOPEKIN, *args], capture_output=True, text=True, errors="replace", cwd=cwd,
                           env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise SystemExit(f"scopekin {' '.join(a[:80] for a in args)}: still running after {timeout} s")
    if expect_status is not None and p.returncode != expect_status:
        print(p.stdout[-3000:], p.stderr[-3000:])
        raise SystemExit(f"scopekin {' '.join(args)}: exit {p.returncode}, expected {expect_status}")
    return p


def fresh(name):
    d = os.path.join(WORK, name)
    shutil.rmtree(d, ignore_errors=True)
    return d


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def check_demo():
    out = fresh("demo")
    p = run("demo", "--out", out, "--quiet")
    for name in ["recording.csv", "world.csv", "firmware.csv", "snapshots.json", "summary.json", "forces.png",
                 "advance.png", "snapshots.png"]:
        expect(os.path.isfile(os.path.join(out, name)), f"demo wrote {name}")
    expect("Alarm timeline" in p.stdout and "Summary:" in p.stdout, "demo prints the alarm timeline and the summary")
    s = json.load(open(os.path.join(out, "summary.json")))
    expect(s["status"] == "complete", "the demo's simulation completes")
    locks = [a for a in s["alarms"] if a["kind"] == "self_lock"]
    # The tip locks in the sigmoid at ~16 s with static friction (the hand goes on, the tip stays at
    # 348 mm along the colon: world.csv); the alarm must come within a second of it.
    expect(locks and 15.5 < locks[0]["raised_s"] < 17.0, f"self-lock alarm raised near 16 s: {locks[:1]}")
    expect(0 < s["peak_handle_force_N"]["true"] < 100, "peak handle force positive and below 100 N")
    expect(abs(s["peak_handle_force_N"]["measured"] - s["peak_handle_force_N"]["true"]) < 1.0,
           "measured peak handle force within 1 N of the true one (noise 0.05 N)")
    expect(s["peak_estimated_contact_force"]["force_N"] > 1.0, "the box estimates a contact force")
    expect(s["real_time_factor"] > 1.0, "faster than real time")
    eff = s["advance_efficiency_by_region"]
    expect(0.9 < eff["rectum"]["efficiency"] <= 1.05, f"the tip follows the hand in the rectum: {eff.get('rectum')}")
    expect(eff["sigmoid"]["efficiency"] < 0.95, "the sigmoid loop costs advance")
    # The sigmoid pleats onto the scope on the withdrawal (telescoping), and the re-advance reaches
    # the cecum with less scope inserted than the 1,689 mm the same hands needed in a colon that
    # could not pleat (host_sim/README.md, "The main job").
    expect(s["final_tip"]["region"] == "cecum", f"the tip reaches the cecum: {s['final_tip']}")
    stretches = {k["region"]: k for k in s["world"]["telescoping"]}
    sigmoid = stretches.get("sigmoid", {})
    expect(abs(sigmoid.get("rest_length_mm", 0) - 402.0) < 5.0 and
           0.3 < sigmoid.get("peak_fraction", 0) <= sigmoid.get("max_fraction", 0),
           f"summary.json world.telescoping: the sigmoid (402 mm) pleated by more than 30 %: {s['world']['telescoping']}")
    expect(s["procedure"]["cecum_reached"] and s["procedure"]["insertion_at_cecum_mm"] < 1600.0,
           f"the cecum reached with less than 1,600 mm inserted: {s['procedure']}")
    expect(s["peak_handle_force_N"]["true"] < 43.0, "peak handle force below the 43 N peak push measured in patients (firmware/fixed_point/RANGES.md [A])")
    # The reduced model covers the whole run (its tables hold this job's re-advance to 1692 mm:
    # model/reduction/training.json), so the box never leaves it; the faults it did see are printed.
    first = s["firmware"]["fault_first_s"]
    expect("depth_outside_model" not in first, f"the whole run inside the reduced model: {first}")
    expect("fault flag contact_residual" in p.stdout, "the demo prints the fault flags it saw")
    world = rows(os.path.join(out, "world.csv"))
    firmware = rows(os.path.join(out, "firmware.csv"))
    # 99 s at 30 Hz: 2971 rows (one at t = 0); the box every 5 ms: 19800 periods.
    expect(len(world) == 2971, f"world.csv rows: {len(world)}")
    expect(len(firmware) == 19800, f"firmware.csv rows: {len(firmware)}")
    recording = rows(os.path.join(out, "recording.csv"))
    force_rows = sum(1 for r in recording if r["handle_force_N"] != "")
    # The force cell at 1 kHz (no dropouts by default): one sample per ms from 1 ms to 99 s.
    expect(force_rows == 99000, f"handle force samples: {force_rows}")
    snaps = json.load(open(os.path.join(out, "snapshots.json")))
    labels = [x["label"] for x in snaps["snapshots"]]
    expect(labels[0] == "self_lock alarm raised" and labels[-1] == "end" and len(labels) >= 4, f"snapshots: {labels}")
    checker = os.path.join(SOURCE, "host_sim", "plots", "check_pngs.py")
    c = subprocess.run(["/usr/bin/python3", checker] + [os.path.join(out, n) for n in
                                                       ["forces.png", "advance.png", "snapshots.png"]],
                       capture_output=True, text=True)
    print(c.stdout)
    expect(c.returncode == 0, "the PNGs are non-trivial: " + c.stdout + c.stderr)


def check_cycling_contacts():
    # A drawn patient (seed 1008) pushed into a loop, turned and withdrawn: at 31.33 s its contact
    # solve (36 contacts) cycles at omega = 1 (the change per sweep stays near 0.01 N after 20,000
    # sweeps) and the run used to stop there. World::step retries such a step under-relaxed.
    out = fresh("cycling")
    run("simulate", os.path.join(HERE, "data", "cycling_contacts.json"), "--out", out, "--quiet", "--seed", "1")
    s = json.load(open(os.path.join(out, "summary.json")))
    expect(s["status"] == "complete", f"the run completes: {s['message']}")
    expect(s["world"]["under_relaxed_steps"] > 0, f"steps solved under-relaxed: {s['world'].get('under_relaxed_steps')}")


def check_simulate_run_identical():
    sim = fresh("short_simulate")
    run("simulate", os.path.join(HERE, "data", "short_advance.json"), "--out", sim, "--quiet", "--seed", "7")
    rerun = fresh("short_run")
    run("run", os.path.join(sim, "recording.csv"), "--out", rerun, "--quiet")
    live = open(os.path.join(sim, "firmware.csv"), "rb").read()
    replayed = open(os.path.join(rerun, "firmware.csv"), "rb").read()
    expect(len(live) > 1000 and live == replayed,
           "run of simulate's recording gives bit-identical firmware.csv (%d vs %d bytes)" % (len(live), len(replayed)))
    s = json.load(open(os.path.join(sim, "summary.json")))
    expect(not any(a["kind"] == "self_lock" for a in s["alarms"]), "no self-lock alarm without a loop")
    # Another seed: other noise, so other rows.
    other = fresh("short_simulate_seed8")
    run("simulate", os.path.join(HERE, "data", "short_advance.json"), "--out", other, "--quiet", "--seed", "8")
    expect(open(os.path.join(other, "recording.csv"), "rb").read() != open(os.path.join(sim, "recording.csv"), "rb").read(),
           "another seed gives another recording")
    again = fresh("short_simulate_again")
    run("simulate", os.path.join(HERE, "data", "short_advance.json"), "--out", again, "--quiet", "--seed", "7")
    expect(open(os.path.join(again, "recording.csv"), "rb").read() == open(os.path.join(sim, "recording.csv"), "rb").read(),
           "the same seed gives the same recording")


def check_loop_free():
    out = fresh("straight")
    run("simulate", os.path.join(SOURCE, "model", "scenarios", "reference_straight_advance.json"), "--out", out, "--quiet")
    s = json.load(open(os.path.join(out, "summary.json")))
    expect(s["status"] == "complete", "the straight advance completes")
    expect(not any(a["kind"] == "self_lock" for a in s["alarms"]), f"no self-lock alarm on the straight advance: {s['alarms']}")


def write_lines(path, lines):
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def check_bad_recordings():
    sim = fresh("bad_base")
    run("simulate", os.path.join(HERE, "data", "short_advance.json"), "--out", sim, "--quiet")
    lines = open(os.path.join(sim, "recording.csv")).read().splitlines()
    header = lines[0].split(",")
    d = fresh("bad")
    os.makedirs(d)

    def refused(name, content, *needles):
        path = os.path.join(d, name + ".csv")
        write_lines(path, content)
        p = run("run", path, "--out", os.path.join(d, name), "--quiet", expect_status=2)
        for n in needles:
            expect(n in p.stderr, f"{name}: message names '{n}': {p.stderr.strip()}")

    # A missing column: dropping handle_torque_Nmm from the header and every row.
    k = header.index("handle_torque_Nmm")
    refused("missing_column", [",".join(c for i, c in enumerate(l.split(",")) if i != k) for l in lines],
            "handle_torque_Nmm")
    # Unsorted: rows 10 and 11 swapped (file lines 11 and 12).
    swapped = lines[:]
    swapped[10], swapped[11] = swapped[11], swapped[10]
    refused("unsorted", swapped, "line 12")
    refused("duplicate", lines[:11] + [lines[10]] + lines[11:], "line 12")
    cells = lines[20].split(",")
    cells[header.index("insertion_mm")] = "abc"
    refused("non_numeric", lines[:20] + [",".join(cells)] + lines[21:], "line 21", "insertion_mm", "abc")
    # A gap: 200 ms of rows removed is not refused; it is flagged, and the box says stale.
    times = [float(l.split(",")[0]) for l in lines[1:]]
    kept = [lines[0]] + [l for l, t in zip(lines[1:], times) if not (1.0 < t <= 1.2)]
    path = os.path.join(d, "gap.csv")
    write_lines(path, kept)
    p = run("run", path, "--out", os.path.join(d, "gap"), "--quiet")
    s = json.load(open(os.path.join(d, "gap", "summary.json")))
    expect(s["flagged"] and len(s["gaps"]) == 2 and abs(s["gaps"][0]["duration_s"] - 0.201) < 0.002,
           f"the gap is flagged: {s['gaps']}")
    expect("warning: gap" in p.stderr, "run warns about the gap")
    expect(s["firmware"]["fault_periods"]["insertion_stale"] >= 38, f"stale periods: {s['firmware']['fault_periods']}")


def check_batch():
    d = fresh("batch")
    os.makedirs(d)
    sim = os.path.join(d, "sim")
    run("simulate", os.path.join(HERE, "data", "short_advance.json"), "--out", sim, "--quiet")
    manifest = os.path.join(d, "manifest.txt")
    shutil.copy(os.path.join(HERE, "data", "short_advance.json"), os.path.join(d, "short_advance.json"))
    write_lines(manifest, ["# two entries", "short_advance.json", "sim/recording.csv"])
    summaries = []
    for i in range(2):
        run("batch", manifest, "--shard", f"{i}/2", "--out", os.path.join(d, f"shard{i}"), "--quiet")
        summaries.append(os.path.join(d, f"shard{i}", f"summary_shard_{i}_of_2.csv"))
    merged = os.path.join(d, "all.csv")
    run("batch-merge", *summaries, "--out", merged)
    r = rows(merged)
    expect(sorted(x["entry"] for x in r) == ["short_advance.json", "sim/recording.csv"], f"merged entries: {r}")
    expect(all(x["exit_status"] == "0" for x in r), "both entries ran")
    # The assignment is stable: the same manifest gives the same shards again.
    run("batch", manifest, "--shard", "0/2", "--out", os.path.join(d, "again"), "--quiet")
    expect(rows(os.path.join(d, "again", "summary_shard_0_of_2.csv"))[0:1] == rows(summaries[0])[0:1] or
           rows(summaries[0]) == [], "shard 0 holds the same entries again")
    p = run("batch", manifest, "--shard", "2/2", "--out", os.path.join(d, "bad"), expect_status=2)
    expect("0 <= I < N" in p.stderr, "a bad shard is refused")
    p = run("batch-merge", summaries[0], summaries[0], "--out", os.path.join(d, "twice.csv"), expect_status=None)
    expect(p.returncode == 2 or rows(summaries[0]) == [], "merging a shard twice is refused")


def check_replay_bad_log():
    d = fresh("replay_bad")
    os.makedirs(d)
    path = os.path.join(d, "bad.log")
    write_lines(path, ["(1700000000.000000) can0 110#0000000000", "(1700000000.001000) can0 11Z#00"])
    p = run("replay", path, "--out", os.path.join(d, "out"), expect_status=2)
    expect("line 2" in p.stderr, f"a malformed candump line is refused naming it: {p.stderr.strip()}")
    # A log of the handle sensors alone runs with a period every 5 ms: frames over 10 ms, periods at 5 and 10 ms.
    good = os.path.join(d, "sensors.log")
    write_lines(good, [f"(1700000000.{t:06d}) can0 110#0000000000" for t in range(0, 10001, 1000)])
    run("replay", good, "--out", os.path.join(d, "good"), "--quiet")
    s = json.load(open(os.path.join(d, "good", "summary.json")))
    expect(s["kind"] == "sensor_log" and s["periods"] == 2 and s["frames_fed"] == 11, f"sensor log replay: {s}")


SHORT = os.path.join(HERE, "data", "short_advance.json")


def line_of(text, marker):
    """The 1-based line of the first `marker` in `text`."""
    return text[:text.index(marker)].count("\n") + 1


def scenario_with(extra):
    """short_advance.json with `extra` (JSON members) added before its closing brace."""
    src = open(SHORT).read().rstrip()
    return src[:-1].rstrip() + ",\n  " + extra + "\n}\n"


def simulate_recording(name, procedure=None, seed=1):
    """A recording written by `scopekin simulate` (short_advance.json, or its procedure replaced)."""
    sim = fresh(name)
    scenario = SHORT
    if procedure is not None:
        d = json.load(open(SHORT))
        d["procedure"] = procedure
        scenario = os.path.join(WORK, name + ".json")
        json.dump(d, open(scenario, "w"))
    run("simulate", scenario, "--out", sim, "--quiet", "--seed", str(seed))
    return os.path.join(sim, "recording.csv")


# 13 s of hand motion (the discrepancy workflow needs at least 12 s): advance, then withdraw.
DISCREPANCY_PROCEDURE = [{"action": "advance", "start_s": 0, "end_s": 7, "speed_mm_per_s": 20},
                         {"action": "withdraw", "start_s": 7, "end_s": 13, "speed_mm_per_s": 10}]


def no_file_named(d, prefix):
    hits = [os.path.join(r, f) for r, ds, fs in os.walk(d) for f in fs + ds if f.startswith(prefix)]
    return hits == [], hits


def check_shell_injection():
    # An output folder whose name a shell would execute: the plot scripts get it as one argument
    # (no shell), so nothing runs and the plots are drawn into it.
    d = fresh("shell")
    os.makedirs(d)
    hostile = "x';touch PWNED;' $(touch PWNED2) `touch PWNED3` a b;c\"d"
    p = run("demo", "--scenario", SHORT, "--out", hostile, "--quiet", cwd=d, expect_status=None)
    expect(p.returncode == 0, f"demo into {hostile!r}: exit {p.returncode}: {p.stderr[-500:]}")
    for name in ["forces.png", "advance.png", "snapshots.png", "summary.json"]:
        expect(os.path.isfile(os.path.join(d, hostile, name)), f"demo wrote {name} into {hostile!r}")
    ok, hits = no_file_named(d, "PWNED")
    expect(ok, f"demo ran nothing from the folder name: {hits}")
    rec = simulate_recording("shell_recording", DISCREPANCY_PROCEDURE)
    hostile2 = "y';touch PWNED4;' $HOME"
    p = run("discrepancy", rec, "--out", hostile2, cwd=d, expect_status=None)
    expect(p.returncode == 0, f"discrepancy into {hostile2!r}: exit {p.returncode}: {p.stderr[-500:]}")
    # Off a terminal every stage gets a line when it starts, not only when a 10 % step is passed.
    stage_lines = [line for line in p.stderr.splitlines() if line.startswith("[")]
    expect(stage_lines[:1] == ["[          ]   0% the model as given"] and
           stage_lines[-1:] == ["[##########] 100% report"],
           f"discrepancy's progress names each stage as it starts: {stage_lines}")
    for name in ["outputs.png", "residuals.png", "candidates.png", "report.json"]:
        expect(os.path.isfile(os.path.join(d, hostile2, name)), f"discrepancy wrote {name} into {hostile2!r}")
    ok, hits = no_file_named(d, "PWNED")
    expect(ok, f"discrepancy ran nothing from the folder name: {hits}")
    # A folder name that starts with '-' is a folder, not an option of the plot script.
    p = run("demo", "--scenario", SHORT, "--out", "-h", "--quiet", cwd=d, expect_status=None)
    expect(p.returncode == 0 and os.path.isfile(os.path.join(d, "-h", "forces.png")),
           f"demo into '-h': exit {p.returncode}: {p.stderr[-300:]}")


def check_hostile_json():
    # Deep nesting, numbers beyond double, a key twice: exit 2 naming the file, line and field,
    # in a bounded message, nothing written; never a crash (exit 139) or exit 3.
    d = fresh("hostile_json")
    os.makedirs(d)

    def refused(name, text, needles, command="simulate", files=None):
        path = os.path.join(d, name + ".json")
        open(path, "w").write(text)
        for f, t in (files or {}).items():
            open(os.path.join(d, f), "w").write(t)
        out = os.path.join(d, name + "_out")
        args = [command, path] if command != "discrepancy" else [command, REC, "--model", path]
        if command != "static":
            args += ["--out", out, "--quiet"]
        p = run(*args, expect_status=None, timeout=120)
        expect(p.returncode == 2, f"{name}: exit {p.returncode}, expected 2: {p.stderr[-300:]}")
        for n in needles:
            expect(n in p.stderr, f"{name}: the message names '{n}': {p.stderr[-400:]}")
        expect(len(p.stderr) < 600, f"{name}: a bounded message ({len(p.stderr)} bytes)")
        expect(not os.path.exists(out), f"{name}: nothing written")

    REC = simulate_recording("hostile_json_recording", DISCREPANCY_PROCEDURE)
    deep = scenario_with('"gravity_mm_per_s2": ' + "[" * 60000 + "]" * 60000)
    refused("deep", deep, ["deep.json: line %d" % line_of(deep, "gravity"), "gravity_mm_per_s2[0][0]",
                           "nested deeper than 64 levels"])
    big = scenario_with('"gravity_mm_per_s2": [0, 1e400, 0]')
    refused("big", big, ["big.json: line %d" % line_of(big, "1e400"), "gravity_mm_per_s2[1]", "'1e400'",
                         "out of range"])
    # In a model file a scenario names: the model file is named.
    model = '{"colon": {"bundled": "default"},\n "scope": {"model": "cf_q160l", "length_mm": -1e999}}'
    with_model = json.load(open(SHORT))
    for k in ("colon", "scope"):
        del with_model[k]
    with_model["model"] = "big_model.json"
    refused("uses_big_model", json.dumps(with_model), ["big_model.json: line 2", "scope.length_mm", "out of range"],
            files={"big_model.json": model})
    dup = scenario_with('"initial_insertion_mm": 30')
    refused("duplicate", dup, ["duplicate.json: line %d" % line_of(dup, '"initial_insertion_mm": 30'),
                               "initial_insertion_mm: key given twice",
                               "first at line %d" % line_of(dup, '"initial_insertion_mm": 20')])
    problem = open(os.path.join(SOURCE, "model", "problems", "mattiasson_tip_load.json")).read()
    problem_dup = problem.replace('"static": {"load_steps": 10}', '"static": {"load_steps": 10, "load_steps": 11}')
    refused("beam_duplicate", problem_dup, ["beam_duplicate.json: line %d" % line_of(problem_dup, '"load_steps": 11'),
                                            "static.load_steps: key given twice"], command="static")
    model_dup = '{"colon": {"bundled": "default"},\n "colon": {"bundled": "default"}}'
    refused("model_duplicate", model_dup, ["model_duplicate.json: line 2", "colon: key given twice"],
            command="discrepancy")
    # A key of a megabyte is shown bounded.
    refused("long_key", scenario_with('"' + "k" * (1 << 20) + '": 1'), ["(1048576 bytes): unknown key"])


def check_time_gap():
    # A row far later than the one before is refused with its line, instead of the box stepping a
    # period every 5 ms across the gap (a row 10^9 s later once wrote 300 MB in 10 s).
    rec = simulate_recording("gap_base")
    lines = open(rec).read().splitlines()
    d = fresh("gap")
    os.makedirs(d)

    def with_time(line, t):
        cells = line.split(",")
        cells[0] = "%.6f" % t
        return ",".join(cells)

    last_t = float(lines[-1].split(",")[0])
    far = os.path.join(d, "far.csv")
    write_lines(far, lines[:-1] + [with_time(lines[-1], 999999999.0)])
    p = run("run", far, "--out", os.path.join(d, "far"), "--quiet", expect_status=2, timeout=60)
    expect(f"line {len(lines)}" in p.stderr and "--max-gap-s" in p.stderr,
           f"the gap is refused naming its line and the option: {p.stderr.strip()[:300]}")
    expect(not os.path.exists(os.path.join(d, "far")), "nothing written for the refused recording")
    # 100 s without a row: refused by default (60 s), run with --max-gap-s 200, every period stepped.
    hundred = os.path.join(d, "hundred.csv")
    write_lines(hundred, lines + [with_time(lines[-1], last_t + 100.0)])
    run("run", hundred, "--out", os.path.join(d, "hundred"), "--quiet", expect_status=2)
    run("run", hundred, "--out", os.path.join(d, "hundred"), "--quiet", "--max-gap-s", "200")
    s = json.load(open(os.path.join(d, "hundred", "summary.json")))
    expect(s["periods"] == round((last_t + 100.0) / 0.005), f"periods up to the last row: {s['periods']}")
    # A recording that starts late (a logger's clock): the box starts with the first row and runs
    # the periods of the recording only, not 100,000 empty ones from 0 s.
    late = os.path.join(d, "late.csv")
    write_lines(late, [lines[0]] + [with_time(l, float(l.split(",")[0]) + 500.0) for l in lines[1:]])
    run("run", late, "--out", os.path.join(d, "late"), "--quiet", timeout=60)
    s = json.load(open(os.path.join(d, "late", "summary.json")))
    expect(s["periods"] == round(last_t / 0.005), f"a late start runs the recording's periods only: {s['periods']}")
    fw = rows(os.path.join(d, "late", "firmware.csv"))
    expect(float(fw[0]["time_s"]) > 500.0, f"the first period after the first row: {fw[0]['time_s']}")
    # discrepancy: a 10^6 s gap is refused with its line, not looped over.
    drec = simulate_recording("gap_discrepancy", DISCREPANCY_PROCEDURE)
    dl = open(drec).read().splitlines()
    far_d = os.path.join(d, "far_discrepancy.csv")
    write_lines(far_d, dl + [with_time(dl[-1], float(dl[-1].split(",")[0]) + 1e6)])
    p = run("discrepancy", far_d, "--out", os.path.join(d, "far_discrepancy"), "--quiet", "--no-plots",
            expect_status=2, timeout=60)
    expect(f"line {len(dl) + 1}" in p.stderr and "--max-gap-s" in p.stderr,
           f"discrepancy refuses the gap naming its line: {p.stderr.strip()[:300]}")
    # The option is checked: a bound must be a positive, finite number of seconds.
    for bad in ["0", "-1", "nan", "inf"]:
        p = run("run", rec, "--out", os.path.join(d, "bad"), "--max-gap-s", bad, expect_status=2)
        expect("--max-gap-s" in p.stderr and len(p.stderr) < 300, f"--max-gap-s {bad}: {p.stderr.strip()}")


def check_option_ranges():
    # Integer options are not wrapped (-1 is not 2^64-1) and seconds are positive and finite,
    # refused with a short message naming the option.
    d = fresh("options")
    rec = simulate_recording("options_recording")
    cases = [
        (["simulate", SHORT, "--out", os.path.join(d, "s"), "--seed", "-1"], "--seed"),
        (["demo", "--scenario", SHORT, "--out", os.path.join(d, "demo"), "--seed", "-1"], "--seed"),
        (["demo", "--scenario", SHORT, "--out", os.path.join(d, "demo"), "--seed", "18446744073709551616"], "--seed"),
        (["batch", os.path.join(d, "manifest.txt"), "--out", os.path.join(d, "b"), "--seed", "-1"], "--seed"),
        (["run", rec, "--out", os.path.join(d, "r"), "--gap-s", "-1"], "--gap-s"),
        (["run", rec, "--out", os.path.join(d, "r"), "--gap-s", "nan"], "--gap-s"),
        (["run", rec, "--out", os.path.join(d, "r"), "--gap-s", "inf"], "--gap-s"),
        (["discrepancy", rec, "--out", os.path.join(d, "x"), "--fit-budget-s", "nan"], "--fit-budget-s"),
        (["discrepancy", rec, "--out", os.path.join(d, "x"), "--fit-budget-s", "-1"], "--fit-budget-s"),
        (["discrepancy", rec, "--out", os.path.join(d, "x"), "--threads", "-1"], "--threads"),
    ]
    os.makedirs(d, exist_ok=True)
    write_lines(os.path.join(d, "manifest.txt"), ["x.json"])
    open(os.path.join(d, "x.json"), "w").write("{}")
    for args, option in cases:
        p = run(*args, expect_status=None)
        expect(p.returncode == 2, f"{' '.join(args[-2:])}: exit {p.returncode}, expected 2")
        expect(option in p.stderr and len(p.stderr) < 300,
               f"{' '.join(args[-2:])}: a short message naming {option}: {p.stderr.strip()[:400]}")
    expect(not os.path.exists(os.path.join(d, "s")), "--seed -1: nothing simulated")


def check_bom_and_long_lines():
    # A UTF-8 byte-order mark before the header is skipped; a huge cell is quoted at most ~80
    # characters with its length; 1e309 is out of range, not "not a number".
    rec = simulate_recording("bom_base")
    lines = open(rec).read().splitlines()
    header = lines[0].split(",")
    d = fresh("bom")
    os.makedirs(d)
    bom = os.path.join(d, "bom.csv")
    write_lines(bom, ["\ufeff" + lines[0]] + lines[1:])
    run("run", bom, "--out", os.path.join(d, "bom"), "--quiet")
    plain = fresh("bom_plain")
    run("run", rec, "--out", plain, "--quiet")
    expect(open(os.path.join(d, "bom", "firmware.csv"), "rb").read() == open(os.path.join(plain, "firmware.csv"), "rb").read(),
           "a recording with a byte-order mark runs as the same recording without")
    cells = lines[5].split(",")
    cells[header.index("handle_force_N")] = "7" * (20 * 1024 * 1024)
    long_line = os.path.join(d, "long.csv")
    write_lines(long_line, lines[:5] + [",".join(cells)] + lines[6:])
    p = run("run", long_line, "--out", os.path.join(d, "long"), "--quiet", expect_status=2)
    expect(len(p.stderr) < 400, f"a 20 MB cell is not echoed whole ({len(p.stderr)} bytes of message)")
    expect("line 6, column handle_force_N" in p.stderr and "…' (20971520 bytes)" in p.stderr,
           f"the cell is quoted with its length: {p.stderr[:300]}")
    cells = lines[5].split(",")
    cells[header.index("handle_force_N")] = "1e309"
    huge = os.path.join(d, "huge.csv")
    write_lines(huge, lines[:5] + [",".join(cells)] + lines[6:])
    p = run("run", huge, "--out", os.path.join(d, "huge"), "--quiet", expect_status=2)
    expect("line 6, column handle_force_N: '1e309' is out of range" in p.stderr, f"1e309: {p.stderr.strip()}")
    # An unknown column of a megabyte in the header.
    wide = os.path.join(d, "wide.csv")
    write_lines(wide, [lines[0] + "," + "c" * (1 << 20)] + [l + "," for l in lines[1:]])
    p = run("run", wide, "--out", os.path.join(d, "wide"), "--quiet", expect_status=2)
    expect(len(p.stderr) < 400 and "(1048576 bytes)" in p.stderr, f"a long column name is bounded: {p.stderr[:300]}")


# firmware.csv's columns after the stations, in order (host_sim/README.md, "firmware.csv").
NEW_FIRMWARE_COLUMNS = ["box_faults", "tracker_faults", "tip_uncertainty_mm", "model_tip_path_mm",
                        "model_log_likelihood_ratio", "tip_from_model", "observer_tip_path_mm",
                        "max_contact_force_uncertainty_N", "model_max_contact_force_N",
                        "model_self_lock_alarm", "loop_score", "tip_from_tracker",
                        "model_contact_force_level"]


def check_box_faults():
    # The box's own faults and counters reach firmware.csv and summary.json: a candump log whose
    # handle force/torque frames skip one rolling counter value each (2,000 lost frames by the
    # counters) shows 2,000 counter gaps, the counter_gap bit in the periods that saw them, and no
    # such fault in a log without skips.
    d = fresh("box_faults")
    os.makedirs(d)

    def frame(counter):  # HandleForceTorque (0x110): force 0, torque 0, status 0, counter in byte 5
        return "110#00000000%02X%02X" % (0, counter & 0x0F)

    def write_log(path, step):
        write_lines(path, [f"({1700000000 + t // 1000000}.{t % 1000000:06d}) can0 {frame(k * step)}"
                           for k, t in enumerate(range(0, 2001 * 1000, 1000))])

    skipping = os.path.join(d, "skipping.log")
    write_log(skipping, 2)
    p = run("replay", skipping, "--out", os.path.join(d, "skipping"), "--quiet")
    s = json.load(open(os.path.join(d, "skipping", "summary.json")))
    box = s.get("box", {})
    expect(box.get("handle_sensors", {}).get("counter_gaps") == 2000,
           f"2,000 counter gaps counted: {json.dumps(box)[:600]}")
    expect(box.get("fault_periods", {}).get("counter_gap", 0) >= 399,
           f"counter_gap set in the periods that saw them (2 s / 5 ms): {box.get('fault_periods')}")
    # The first period (released 5 ms after the first frame) already saw a gap; its time is the
    # log's, exactly as firmware.csv prints it.
    expect(box.get("fault_first_s", {}).get("counter_gap") == 1700000000.005,
           f"first time of counter_gap: {box.get('fault_first_s')}")
    fw = rows(os.path.join(d, "skipping", "firmware.csv"))
    expect(fw and "box_faults" in fw[0] and "tracker_faults" in fw[0], "firmware.csv has box_faults, tracker_faults")
    with_gap = sum(1 for r in fw if int(r.get("box_faults", "0")) & (1 << 6))
    expect(with_gap == box.get("fault_periods", {}).get("counter_gap"),
           f"firmware.csv's counter_gap bit (1 << 6) in as many periods as summary.json says: {with_gap}")
    expect("counter_gap" in p.stdout, f"replay prints the box faults it saw: {p.stdout.strip()[-400:]}")
    steady = os.path.join(d, "steady.log")
    write_log(steady, 1)
    run("replay", steady, "--out", os.path.join(d, "steady"), "--quiet")
    s = json.load(open(os.path.join(d, "steady", "summary.json")))
    expect(s.get("box", {}).get("handle_sensors", {}).get("counter_gaps") == 0 and
           "counter_gap" not in s.get("box", {}).get("fault_first_s", {"counter_gap": 0}),
           f"no counter gap without skips: {json.dumps(s.get('box'))[:400]}")
    # A flood of handle frames (200 per period, above the 128 the box reads) builds a receive
    # backlog: the receive_backlog bit (1 << 14) reaches firmware.csv and the box section, with
    # the executive's backlog_periods and late_frames counters.
    flood = os.path.join(d, "flood.log")
    write_lines(flood, [f"({1700000000 + t // 1000000}.{t % 1000000:06d}) can0 {frame(k)}"
                        for k, t in enumerate(range(0, 200000, 25))])
    p = run("replay", flood, "--out", os.path.join(d, "flood"), "--quiet")
    box = json.load(open(os.path.join(d, "flood", "summary.json"))).get("box", {})
    counters = box.get("counters", {})
    expect(counters.get("backlog_periods", 0) > 0 and counters.get("late_frames", 0) > 0,
           f"the flood's backlog is counted: {counters}")
    expect(box.get("fault_periods", {}).get("receive_backlog") == counters.get("backlog_periods"),
           f"receive_backlog set in every backlog period: {box.get('fault_periods')} {counters}")
    fw = rows(os.path.join(d, "flood", "firmware.csv"))
    expect(sum(1 for r in fw if int(r.get("box_faults", "0")) & (1 << 14)) == counters.get("backlog_periods"),
           "firmware.csv's receive_backlog bit (1 << 14) in every backlog period")
    expect("receive_backlog" in p.stdout, f"replay prints the backlog: {p.stdout.strip()[-400:]}")
    # A box log (scopekin-box --record) also carries what the live box said about itself, which a
    # replay cannot reproduce (kernel drops, overruns): its BoxStatus bits and BoxCounters values
    # are reported under box.recorded. Here BoxStatus has receive_dropped (bit 9) and
    # period_overrun (bit 13) in periods 10..19 of 40, and BoxCounters says 19 frames dropped.
    def stamp(us):
        return f"({1700000000 + us // 1000000}.{us % 1000000:06d}) can0 "

    box_lines = []
    for k in range(40):
        t = k * 5000
        faults = (1 << 9) | (1 << 13) if 10 <= k < 20 else 0
        overruns = 3 if k >= 10 else 0
        box_lines.append(stamp(t + 100) + frame(k))
        box_lines.append(stamp(t) + "181#0000000000000000")
        box_lines.append(stamp(t) + "180#%02X01%04X%s%02X00" % (k & 0xFF, 0, faults.to_bytes(2, "little").hex().upper(),
                                                             overruns))
        box_lines.append(stamp(t) + "184#01000000%s" % (19 if k >= 20 else 0).to_bytes(4, "little").hex().upper())
    box_log = os.path.join(d, "box.log")
    write_lines(box_log, box_lines)
    p = run("replay", box_log, "--out", os.path.join(d, "box"), "--quiet", expect_status=1)  # outputs differ
    box = json.load(open(os.path.join(d, "box", "summary.json"))).get("box", {})
    recorded = box.get("recorded", {})
    expect(recorded.get("status_frames") == 40 and recorded.get("fault_frames") == {"receive_dropped": 10, "period_overrun": 10},
           f"the recorded BoxStatus bits: {recorded}")
    expect(recorded.get("fault_first_s", {}).get("receive_dropped") == 1700000000.05, f"first recorded drop: {recorded}")
    expect(recorded.get("counters_last", {}).get("can_dropped") == 19 and recorded.get("period_overruns_last") == 3,
           f"the recorded counters: {recorded}")
    expect(box.get("fault_periods", {}).get("receive_dropped") == 0, "the replayed box itself dropped nothing")
    expect("recorded box fault receive_dropped" in p.stdout, f"replay prints the recorded faults: {p.stdout[-400:]}")
    # run and simulate carry the same columns and section.
    rec = simulate_recording("box_faults_sim")
    sim_dir = os.path.dirname(rec)
    fw = rows(os.path.join(sim_dir, "firmware.csv"))
    header = open(os.path.join(sim_dir, "firmware.csv")).readline().strip().split(",")
    expect(header[-len(NEW_FIRMWARE_COLUMNS):] == NEW_FIRMWARE_COLUMNS,
           f"the new columns come last: {header[-len(NEW_FIRMWARE_COLUMNS):]}")
    expect(header[:13] == ["time_s", "step_index", "tip_path_mm", "tip_velocity_mm_per_s", "advance_efficiency",
                           "active_stations", "max_contact_force_N", "max_contact_station", "max_contact_path_mm",
                           "distal_sticking", "self_lock_alarm", "contact_force_level", "fault_flags"],
           f"the old columns keep their order: {header[:13]}")
    s = json.load(open(os.path.join(sim_dir, "summary.json")))
    expect("box" in s and s["box"]["counters"]["periods"] == len(fw), f"simulate's box section: {str(s.get('box'))[:300]}")
    expect(s["box"]["em_tracker"]["poses_ok"] > 0, "the EM tracker's poses are counted")
    run_dir = os.path.join(d, "run")
    run("run", rec, "--out", run_dir, "--quiet")
    header = open(os.path.join(run_dir, "firmware.csv")).readline().strip().split(",")
    expect(header[-len(NEW_FIRMWARE_COLUMNS):] == NEW_FIRMWARE_COLUMNS,
           f"run's firmware.csv ends with the new columns: {header[-len(NEW_FIRMWARE_COLUMNS):]}")
    s = json.load(open(os.path.join(run_dir, "summary.json")))
    expect(s.get("box", {}).get("counters", {}).get("periods") == len(rows(os.path.join(run_dir, "firmware.csv"))),
           f"run's box section counts its periods: {str(s.get('box'))[:300]}")
    expect(s["box"]["handle_sensors"]["counter_gaps"] == 0, "a recording numbers its frames without gaps")


def check_output_order():
    # Every output is written as NAME.part and renamed when complete, summary.json (report.json,
    # the shard summary) last of all: killed at any rename, a folder holds no summary, and every
    # file it holds under its final name is complete. rename_probe.c logs the renames (of scopekin
    # and of the plot scripts it starts) and kills scopekin at the N-th one.
    probe = os.environ.get("SCOPEKIN_RENAME_PROBE")
    if not probe or not os.path.isfile(probe):
        raise SystemExit("SCOPEKIN_RENAME_PROBE must name the rename_probe library")
    d = fresh("order")
    os.makedirs(d)
    rec = simulate_recording("order_recording")
    drec = simulate_recording("order_discrepancy_recording", DISCREPANCY_PROCEDURE)
    log_file = os.path.join(d, "sensors.log")
    write_lines(log_file, [f"(1700000000.{t:06d}) can0 110#000000000000" for t in range(0, 100001, 1000)])
    manifest = os.path.join(d, "manifest.txt")
    shutil.copy(SHORT, os.path.join(d, "short_advance.json"))
    write_lines(manifest, ["short_advance.json"])
    commands = {
        "simulate": (lambda out: ["simulate", SHORT, "--out", out, "--quiet"], "summary.json"),
        "run": (lambda out: ["run", rec, "--out", out, "--quiet"], "summary.json"),
        "replay": (lambda out: ["replay", log_file, "--out", out, "--quiet"], "summary.json"),
        "demo": (lambda out: ["demo", "--scenario", SHORT, "--out", out, "--quiet"], "summary.json"),
        "discrepancy": (lambda out: ["discrepancy", drec, "--out", out, "--quiet"], "report.json"),
        "batch": (lambda out: ["batch", manifest, "--out", out, "--quiet"], "summary_shard_0_of_1.csv"),
    }
    for name, (args, summary) in commands.items():
        log = os.path.join(d, name + ".log")

        def probed(out, kill_at=None):
            shutil.rmtree(out, ignore_errors=True)
            if os.path.exists(log):
                os.remove(log)
            env = dict(os.environ, LD_PRELOAD=probe, SCOPEKIN_RENAME_LOG=log,
                       ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":verify_asan_link_order=0")
            if kill_at is not None:
                env["SCOPEKIN_RENAME_KILL_AT"] = str(kill_at)
            p = subprocess.run([SCOPEKIN, *args(out)], capture_output=True, text=True, env=env)
            renames = [l.split("\t") for l in open(log).read().splitlines()] if os.path.exists(log) else []
            return p, renames

        full = os.path.join(d, name + "_full")
        p, renames = probed(full)
        expect(p.returncode == 0, f"{name}: exit {p.returncode}: {p.stderr[-300:]}")
        renamed = [os.path.relpath(to, full) for _, to in renames]
        expect(renamed and renamed[-1] == summary, f"{name}: {summary} renamed last: {renamed}")
        expect(all(f == t + ".part" for f, t in renames), f"{name}: every rename is NAME.part -> NAME: {renames}")
        finals = sorted(os.path.relpath(os.path.join(r, f), full) for r, _, fs in os.walk(full) for f in fs)
        expect(sorted(renamed) == finals, f"{name}: every output came by a rename: {finals} vs {sorted(renamed)}")
        complete = {f: open(os.path.join(full, f), "rb").read() for f in finals}
        # Killed at each rename scopekin itself makes (the plot scripts' are theirs): no summary,
        # and every CSV under its final name is the complete one (the runs are deterministic).
        own = [i + 1 for i, (_, t) in enumerate(renames) if not t.endswith(".png")]
        for k in own:
            out = os.path.join(d, f"{name}_killed_{k}")
            p, _ = probed(out, kill_at=k)
            expect(p.returncode == -9, f"{name} killed at rename {k}: exit {p.returncode}")
            there = sorted(os.path.relpath(os.path.join(r, f), out) for r, _, fs in os.walk(out) for f in fs)
            expect(summary not in there, f"{name} killed at rename {k}: no {summary}: {there}")
            for f in there:
                if f.endswith(".csv") and not f.startswith("summary_shard"):
                    expect(open(os.path.join(out, f), "rb").read() == complete.get(f),
                           f"{name} killed at rename {k}: {f} is complete")
                elif f.endswith(".json"):
                    json.load(open(os.path.join(out, f)))  # complete JSON (a truncated one raises)
            shutil.rmtree(out, ignore_errors=True)


def check_patients():
    # One patient: JSON on stdout, the same for the same seed, another for another seed.
    a = json.loads(run("patient", "--seed", "3").stdout)
    expect(a["seed"] == 3 and set(a) >= {"colon", "mechanics", "scope", "derived"}, f"patient JSON: {sorted(a)}")
    expect(run("patient", "--seed", "3").stdout == run("patient", "--seed", "3").stdout, "same seed, same patient")
    expect(run("patient", "--seed", "4").stdout != run("patient", "--seed", "3").stdout, "another seed, another patient")
    lengths = a["colon"]["region_lengths_mm"]
    expect(abs(sum(lengths.values()) - a["derived"]["total_length_mm"]) < 1e-6, "total length is the regions' sum")
    d = fresh("patients")
    os.makedirs(d)
    out = os.path.join(d, "p3.json")
    run("patient", "--seed", "3", "--out", out)
    expect(json.load(open(out)) == a, "--out writes the same JSON")
    # Bad seeds: usage errors, exit 2, naming the option.
    for bad in ["-1", "1e30", "x", "18446744073709551616"]:
        p = run("patient", "--seed", bad, expect_status=2)
        expect("--seed" in p.stderr and "whole number" in p.stderr, f"--seed {bad}: {p.stderr[-300:]}")
    run("patient", expect_status=2)
    run("patients", "--count", "0", "--out", d, expect_status=2)
    run("patients", "--count", "2", "--seed", "18446744073709551615", "--out", d, expect_status=2)
    # A scenario with the saved patient runs (a second of advance).
    scenario = os.path.join(d, "s.json")
    with open(scenario, "w") as f:
        json.dump({"patient": {"file": "p3.json"}, "scope": {"model": "cf_q160l"}, "initial_insertion_mm": 20,
                   "procedure": [{"action": "advance", "start_s": 0, "end_s": 1, "speed_mm_per_s": 25}]}, f)
    run("simulate", scenario, "--out", os.path.join(d, "run"), "--quiet")
    s = json.load(open(os.path.join(d, "run", "summary.json")))
    expect(s["status"] == "complete" and s["patient"]["seed"] == 3, "simulate with a patient file completes")
    with open(scenario, "w") as f:
        json.dump({"patient": {"seed": 3}, "colon": {"bundled": "default"}, "scope": {"model": "cf_q160l"},
                   "procedure": [{"action": "hold", "start_s": 0, "end_s": 1}]}, f)
    p = run("simulate", scenario, "--out", os.path.join(d, "run2"), "--quiet", expect_status=2)
    expect("s.json: patient: a scenario takes either 'patient'" in p.stderr, f"patient and colon refused: {p.stderr}")
    # A gallery: the four files, one CSV row and one panel per patient, a real PNG.
    g = os.path.join(d, "gallery")
    p = run("patients", "--count", "6", "--seed", "10", "--out", g, "--quiet")
    for name in ["patients.json", "patients.csv", "centerlines.csv", "gallery.png"]:
        expect(os.path.isfile(os.path.join(g, name)), f"patients wrote {name}")
    table = rows(os.path.join(g, "patients.csv"))
    expect([r["seed"] for r in table] == [str(s) for s in range(10, 16)], "one CSV row per seed")
    listed = json.load(open(os.path.join(g, "patients.json")))
    expect(listed["count"] == 6 and [x["seed"] for x in listed["patients"]] == list(range(10, 16)),
           "patients.json lists the six")
    expect(listed["redraws"] == sum(int(r["redraws"]) for r in table), "redraws add up")
    # The straightened path: shorter than the colon (every patient has a mobile sigmoid), printed.
    expect(all(0 < float(r["straightened_path_mm"]) < float(r["total_length_mm"]) for r in table),
           "straightened_path_mm is shorter than the colon in every row")
    expect("straightened path to the cecum" in p.stdout and "of 6 under 1330 mm" in p.stdout,
           f"patients prints the straightened path's distribution: {p.stdout}")
    checker = os.path.join(SOURCE, "host_sim", "plots", "check_pngs.py")
    c = subprocess.run(["/usr/bin/python3", checker, os.path.join(g, "gallery.png")], capture_output=True, text=True)
    expect(c.returncode == 0, "the gallery is a non-trivial PNG: " + c.stdout + c.stderr)


def check_truth():
    # truth.csv beside world.csv: one row per box period, joined to firmware.csv by time_s (the
    # same text) and period (its row number); h = 10 ms here, so half the rows are blended
    # between world steps. A 20 -> 80 mm advance in the rectum: no loop, no force episode, the tip
    # at the hand's pace (model/truth/README.md).
    d = fresh("truth")
    run("simulate", SHORT, "--out", d, "--quiet")
    truth = rows(os.path.join(d, "truth.csv"))
    fw = rows(os.path.join(d, "firmware.csv"))
    expect(len(truth) == len(fw) == 600, f"truth.csv and firmware.csv: one row per 5 ms period of 3 s: {len(truth)}, {len(fw)}")
    expect([r["time_s"] for r in truth] == [r["time_s"] for r in fw], "truth.csv's time_s is firmware.csv's, row by row")
    expect([r["period"] for r in truth] == [str(i) for i in range(len(truth))], "period counts the rows from 0")
    header = open(os.path.join(d, "truth.csv")).readline().strip().split(",")
    for column in ["insertion_mm", "tip_path_mm", "tip_displaced_path_mm", "tip_region", "station_11_side_N",
                   "max_station_force_N", "max_wall_force_N", "max_wall_path_mm", "advance_efficiency",
                   "loop_excess_mm", "loop_episode", "loop_type", "loop_region", "force_level",
                   "force_warning_episode", "force_critical_episode"]:
        expect(column in header, f"truth.csv has {column}")
    # The hand advances 20 mm/s from 20 mm: at 2 s, 60 mm (blended between world steps at 2.005 s).
    at = {r["time_s"]: r for r in truth}
    expect(abs(float(at["2.000000"]["insertion_mm"]) - 60.0) < 1e-3 and abs(float(at["2.005000"]["insertion_mm"]) - 60.1) < 1e-3,
           f"insertion at 2 and 2.005 s: {at['2.000000']['insertion_mm']}, {at['2.005000']['insertion_mm']}")
    expect(all(r["loop_episode"] == "0" and r["force_level"] == "0" for r in truth), "no loop or force episode")
    eff = [float(r["advance_efficiency"]) for r in truth[100:] if r["advance_efficiency"]]
    expect(eff and all(0.8 < e < 1.2 for e in eff), f"the tip keeps the hand's pace in the rectum: {min(eff)}..{max(eff)}")
    expect(abs(float(truth[-1]["tip_path_mm"]) - 80.0) < 3.0, f"tip near 80 mm at the end: {truth[-1]['tip_path_mm']}")
    s = json.load(open(os.path.join(d, "summary.json")))
    expect(s["files"].get("truth") == "truth.csv", f"summary lists truth.csv: {s['files']}")
    t = s.get("truth", {})
    expect(t.get("periods") == 600 and t.get("loop_episodes") == [] and t.get("force_episodes", {}).get("warning_10N") == []
           and t.get("definitions", {}).get("loop_onset_excess_mm") == 20.0, f"summary.json truth: {str(t)[:300]}")


def independent_rms(fw_rows, truth_rows, fw_col, truth_col):
    """RMS of firmware - truth over the periods where both are numbers (the scorer's rule)."""
    total, n = 0.0, 0
    for a, b in zip(fw_rows, truth_rows):
        if a[fw_col] != "" and b[truth_col] != "":
            total += (float(a[fw_col]) - float(b[truth_col])) ** 2
            n += 1
    return (total / n) ** 0.5 if n else None


def independent_detections(times, up, episodes, early=1.0, within=0.5):
    """The detection rule of host_sim/evaluate/README.md, written again: episodes detected by a rise
    from 1 s before their onset to 0.5 s after it, and rises outside every episode (false alarms)."""
    rises = [t for k, t in enumerate(times) if up[k] and (k == 0 or not up[k - 1])]
    end_of_run = times[-1] + 0.005
    used, detected, false_alarms = set(), 0, 0
    for e in episodes:
        hit = [i for i, r in enumerate(rises) if i not in used and e["onset_s"] - early <= r <= e["onset_s"] + within]
        if hit:
            used.add(hit[0])
            detected += 1
        else:
            end = e["end_s"] if e["end_s"] is not None else end_of_run
            late = [i for i, r in enumerate(rises) if i not in used and e["onset_s"] + within < r <= end]
            if late:
                used.add(late[0])
    for r in rises:
        inside = any(e["onset_s"] - early <= r <= max(e["end_s"] if e["end_s"] is not None else end_of_run,
                                                       e["onset_s"] + within) for e in episodes)
        false_alarms += 0 if inside else 1
    return detected, false_alarms


def check_evaluate():
    # The CI's small evaluation: three short scripted cases, run with two jobs, scored for today's
    # estimator and the handle force monitor baseline (host_sim/evaluate/README.md).
    manifest = os.path.join(SOURCE, "model", "scenarios", "evaluation", "ci_smoke.json")
    d = fresh("evaluate")
    p = run("evaluate", manifest, "--out", d, "--jobs", "2", "--quiet")
    for name in ["scorecard.json", "scorecard.csv", "scorecard.md", "scorecard_shard_0_of_1.json",
                 "distributions.png", "worst_cases.png"]:
        expect(os.path.isfile(os.path.join(d, name)), f"evaluate wrote {name}")
    expect("| tip position error, RMS [mm] |" in p.stdout, "evaluate prints the scorecard's table")
    names = [c["name"] for c in json.load(open(manifest))["cases"]]
    for name in names:
        for f in ["scenario.json", "simulate.log", "firmware.csv", "truth.csv", "recording.csv", "summary.json",
                  "score.json", "estimates.csv"]:
            expect(os.path.isfile(os.path.join(d, "cases", name, f)), f"case {name} has {f}")
    card = json.load(open(os.path.join(d, "scorecard.json")))
    expect(card["overall"]["scored"] == len(names), f"every case scored: {card['overall']['not_scored']}")
    table = rows(os.path.join(d, "scorecard.csv"))
    expect(sorted((r["case"], r["estimator"]) for r in table) ==
           sorted((n, e) for n in names for e in ["box", "depth_replay", "force_monitor", "insertion_depth",
                                                         "definitions_confirmation"]),
           "one CSV row per case x estimator")
    # The scores against the run's own files, computed again here: the tip error of the box
    # (firmware.csv's published tip against truth.csv, joined row by row) and of the depth replay
    # (firmware.csv's model_tip_path_mm), the box's tip within its stated SD, its loop alarm
    # against the true loop episodes of summary.json.
    episodes_seen = 0
    for name in names:
        case = os.path.join(d, "cases", name)
        fw, truth = rows(os.path.join(case, "firmware.csv")), rows(os.path.join(case, "truth.csv"))
        summary = json.load(open(os.path.join(case, "summary.json")))
        score = json.load(open(os.path.join(case, "score.json")))["estimators"]
        rms = independent_rms(fw, truth, "tip_path_mm", "tip_path_mm")
        got = score["box"]["tip_error_mm"]["rms"]
        expect(abs(got - rms) < 1e-6 * max(1.0, rms), f"{name}: tip error RMS {got} vs {rms} computed here")
        rms = independent_rms(fw, truth, "model_tip_path_mm", "tip_path_mm")
        got = score["depth_replay"]["tip_error_mm"]["rms"]
        expect(abs(got - rms) < 1e-6 * max(1.0, rms), f"{name}: replay tip error RMS {got} vs {rms} computed here")
        within = [abs(float(f["tip_path_mm"]) - float(t["tip_path_mm"])) <= float(f["tip_uncertainty_mm"])
                  for f, t in zip(fw, truth)]
        w = score["box"]["tip_within_sd"]
        expect(w["periods"] == len(fw) and w["within_1_sd"] == sum(within),
               f"{name}: tip within 1 SD {w} vs {sum(within)} of {len(fw)} computed here")
        expect(score["depth_replay"]["tip_within_sd"] is None, f"{name}: the replay states no uncertainty")
        force = independent_rms(fw, truth, "max_contact_force_N", "max_station_force_N")
        expect(abs(score["box"]["force_error_N"]["rms"] - force) < 1e-6 * max(1.0, force),
               f"{name}: force error RMS")
        expect(score["force_monitor"]["tip_error_mm"] is None, f"{name}: the force monitor has no tip estimate")
        # The insertion-depth baseline: the tip at the last insertion sample at or before each period.
        rec = rows(os.path.join(case, "recording.csv"))
        rec_t = [float(r["time_s"]) for r in rec]
        depth = [float(rec[max(0, bisect.bisect_right(rec_t, float(r["time_s"]) + 1e-9) - 1)]["insertion_mm"])
                 for r in fw]
        rms = independent_rms([{"d": str(d_mm)} for d_mm in depth], truth, "d", "tip_path_mm")
        got = score["insertion_depth"]["tip_error_mm"]["rms"]
        expect(abs(got - rms) < 1e-3 * max(1.0, rms), f"{name}: insertion-depth tip error {got} vs {rms} here")
        expect(score["insertion_depth"]["loop_alarm"]["false_alarms"] == 0, f"{name}: the depth baseline never alarms")
        times = [float(r["time_s"]) for r in fw]
        loops = summary["truth"]["loop_episodes"]
        episodes_seen += len(loops)
        detected, false_alarms = independent_detections(times, [r["self_lock_alarm"] == "1" for r in fw], loops)
        a = score["box"]["loop_alarm"]
        expect((a["episodes"], a["detected"], a["false_alarms"]) == (len(loops), detected, false_alarms),
               f"{name}: loop alarm {a['episodes']}, {a['detected']}, {a['false_alarms']} vs "
               f"{len(loops)}, {detected}, {false_alarms} computed here")
        warnings = summary["truth"]["force_episodes"]["warning_10N"]
        detected, false_alarms = independent_detections(times, [r["contact_force_level"] in ("1", "2") for r in fw],
                                                        warnings)
        a = score["box"]["warning_alarm"]
        expect((a["episodes"], a["detected"], a["false_alarms"]) == (len(warnings), detected, false_alarms),
               f"{name}: 10 N alarm vs computed here")
    expect(episodes_seen >= 1, "the smoke set has at least one true loop episode")
    checker = os.path.join(SOURCE, "host_sim", "plots", "check_pngs.py")
    c = subprocess.run(["/usr/bin/python3", checker, os.path.join(d, "distributions.png"),
                        os.path.join(d, "worst_cases.png")], capture_output=True, text=True)
    expect(c.returncode == 0, "the plots are non-trivial PNGs: " + c.stdout + c.stderr)
    # Re-scoring without running gives the same scorecard; so do two shards merged.
    before = open(os.path.join(d, "scorecard.csv")).read()
    run("evaluate", manifest, "--out", d, "--score-only", "--no-plots", "--quiet")
    expect(open(os.path.join(d, "scorecard.csv")).read() == before, "--score-only scores the same")
    shards = []
    for i in range(2):
        run("evaluate", manifest, "--out", d, "--shard", f"{i}/2", "--score-only", "--quiet")
        shards.append(os.path.join(d, f"scorecard_shard_{i}_of_2.json"))
    merged = os.path.join(d, "merged")
    run("evaluate-merge", *shards, "--out", merged, "--no-plots")
    expect(sorted(open(os.path.join(merged, "scorecard.csv")).read().splitlines()) == sorted(before.splitlines()),
           "two shards merged give the unsharded scorecard")
    p = run("evaluate-merge", shards[0], "--out", os.path.join(d, "half"), "--no-plots", expect_status=1)
    expect("shards missing: 1 of 2" in p.stderr, f"a missing shard is named: {p.stderr}")
    p = run("evaluate-merge", shards[0], shards[0], "--out", os.path.join(d, "twice"), expect_status=2)
    expect("given twice" in p.stderr, f"a shard merged twice is refused: {p.stderr}")
    # Tuning the baseline on this set (not on a set named validation).
    tuned = os.path.join(d, "thresholds.json")
    run("evaluate-tune", d, "--out", tuned)
    t = json.load(open(tuned))
    expect(t["tuned_on"]["manifest"] == "ci_smoke" and "loop" in t and "warning" in t, f"tuned: {str(t)[:200]}")
    run("evaluate", manifest, "--out", d, "--score-only", "--no-plots", "--quiet", "--thresholds", tuned)
    v = json.load(open(os.path.join(d, "scorecard.json")))
    v["manifest"] = "validation"
    os.makedirs(os.path.join(d, "as_validation"), exist_ok=True)
    json.dump(v, open(os.path.join(d, "as_validation", "scorecard.json"), "w"))
    p = run("evaluate-tune", os.path.join(d, "as_validation"), "--out", tuned, expect_status=2)
    expect("never tuned on" in p.stderr, f"tuning on the validation set is refused: {p.stderr}")
    p = run("evaluate-tune", d, os.path.join(d, "as_validation"), "--out", tuned, expect_status=2)
    expect("never tuned on" in p.stderr, f"... also beside a development set: {p.stderr}")
    # Two development sets pool their cases (here the set split in two by its case folders).
    halves = [os.path.join(d, "half_a"), os.path.join(d, "half_b")]
    for k, half in enumerate(halves):
        h = json.load(open(os.path.join(d, "scorecard.json")))
        h["manifest"], h["cases"] = f"ci_smoke_{'ab'[k]}", h["cases"][k::2]
        h["cases"] = [dict(c, folder=os.path.relpath(os.path.join(d, c["folder"]), half)) for c in h["cases"]]
        os.makedirs(half, exist_ok=True)
        json.dump(h, open(os.path.join(half, "scorecard.json"), "w"))
    pooled = os.path.join(d, "thresholds_pooled.json")
    run("evaluate-tune", *halves, "--out", pooled)
    tp = json.load(open(pooled))
    expect(tp["tuned_on"]["manifest"] == "ci_smoke_a+ci_smoke_b" and sorted(tp["tuned_on"]["cases"]) ==
           sorted(t["tuned_on"]["cases"]) and tp["loop"] == t["loop"],
           f"two halves pooled tune as the whole set: {str(tp)[:300]}")
    p = run("evaluate-tune", d, d, "--out", pooled, expect_status=2)
    expect("given twice" in p.stderr, f"a set given twice is refused: {p.stderr}")
    # A scope that went through the colon wall (truth.csv scope_beyond_wall_mm above 40 mm; none
    # here, so one is written in): the case is scored only before that moment, and the scorecard
    # says so.
    for name in names:
        beyond = [float(r["scope_beyond_wall_mm"]) for r in rows(os.path.join(d, "cases", name, "truth.csv"))]
        expect(max(beyond) < 40.0, f"{name}: the scope stays inside the colon: {max(beyond)} mm beyond the wall")
    cut = os.path.join(d, "cut")
    shutil.copytree(os.path.join(d, "cases"), os.path.join(cut, "cases"))
    case = os.path.join(cut, "cases", names[0])
    lines = open(os.path.join(case, "truth.csv")).read().splitlines()
    header = lines[0].split(",")
    column = header.index("scope_beyond_wall_mm")
    half = len(lines) // 2
    lost_s = float(lines[half].split(",")[0])
    for k in range(half, len(lines)):
        cells = lines[k].split(",")
        cells[column] = "55"
        lines[k] = ",".join(cells)
    open(os.path.join(case, "truth.csv"), "w").write("\n".join(lines) + "\n")
    run("evaluate", manifest, "--out", cut, "--score-only", "--no-plots", "--quiet")
    score = json.load(open(os.path.join(case, "score.json")))
    fw, truth = rows(os.path.join(case, "firmware.csv")), rows(os.path.join(case, "truth.csv"))
    kept = [k for k, r in enumerate(truth) if float(r["time_s"]) < lost_s - 1e-9]
    expect(abs(score["scope_through_wall_s"] - lost_s) < 1e-9 and score["periods"] == len(kept),
           f"the cut case is scored on {score['periods']} periods, {len(kept)} before {lost_s} s")
    rms = independent_rms([fw[k] for k in kept], [truth[k] for k in kept], "tip_path_mm", "tip_path_mm")
    got = score["estimators"]["box"]["tip_error_mm"]["rms"]
    expect(abs(got - rms) < 1e-6 * max(1.0, rms), f"cut case: tip error RMS {got} vs {rms} before the cut")
    md = open(os.path.join(cut, "scorecard.md")).read()
    expect("scored only up to where the scope went through the colon wall" in md and names[0] in md,
           "the scorecard names the case cut short")


def check_evaluate_bad_input():
    # Bad manifests and options: exit 2, the file and the field named, nothing run.
    d = fresh("evaluate_bad")
    os.makedirs(d)
    smoke = json.load(open(os.path.join(SOURCE, "model", "scenarios", "evaluation", "ci_smoke.json")))
    one = dict(smoke["cases"][0])

    def manifest(name, text):
        path = os.path.join(d, name)
        with open(path, "w") as f:
            f.write(text if isinstance(text, str) else json.dumps(text, indent=1))
        return path

    cases = [
        ("missing.json", None, "missing.json"),
        ("syntax.json", '{"name": "x",\n "cases": [\n', "syntax.json: not valid JSON: parse error at line 3"),
        ("unknown.json", {"name": "x", "cases": [one], "shards": 2}, "unknown.json: shards: unknown key"),
        ("duplicate.json", {"name": "x", "cases": [one, one]},
         "duplicate.json: cases[1].name: 'default-push-40' is also the name of cases[0]"),
        ("unsafe.json", {"name": "x", "cases": [dict(one, name="../../etc")]}, "is not a file-safe name"),
        ("badkey.json", {"name": "x", "cases": [dict(one, procedur=[])]},
         "badkey.json: cases[0] 'default-push-40': procedur: unknown key"),
        ("long.json", {"name": "x", "cases": [dict(one, name="y" * 5000)]}, "(5000 bytes)"),
    ]
    for name, text, says in cases:
        path = os.path.join(d, name) if text is None else manifest(name, text)
        p = run("evaluate", path, "--out", os.path.join(d, "out"), expect_status=2)
        expect(says in p.stderr, f"{name}: expected '{says}' in: {p.stderr[-400:]}")
        expect(len(p.stderr) < 600, f"{name}: a short message ({len(p.stderr)} bytes)")
        expect(not os.path.isdir(os.path.join(d, "out", "cases")), f"{name}: nothing run")
    ok = manifest("ok.json", {"name": "x", "cases": [one]})
    for option, value, says in [("--shard", "2/2", "0 <= I < N"), ("--shard", "-1/2", "0 <= I < N"),
                                ("--shard", "x", "0 <= I < N"), ("--jobs", "0", "--jobs"),
                                ("--jobs", "-3", "--jobs")]:
        p = run("evaluate", ok, "--out", os.path.join(d, "out"), option, value, expect_status=2)
        expect(says in p.stderr, f"{option} {value}: {p.stderr[-300:]}")
    p = run("evaluate", ok, expect_status=2)
    expect("--out" in p.stderr, "--out is required")
    p = run("evaluate", ok, "--list")
    expect("default-push-40" in p.stdout, "--list names the cases")


def check_evaluate_manifests():
    # The committed manifests (model/scenarios/evaluation/): the validation set has >= 40 cases,
    # >= 20 patients each with both styles, and no patient of the development sets (development_extra
    # adds patients, none of development's); the scripted
    # sets are accepted as they are (the physician sets are checked by evaluate_physician_manifests).
    folder = os.path.join(SOURCE, "model", "scenarios", "evaluation")
    sets = {n: json.load(open(os.path.join(folder, n + ".json")))
            for n in ["ci_smoke", "development_scripted", "development", "development_extra", "validation"]}
    for n, m in sets.items():
        expect(m["name"] == n, f"{n}.json is named {m['name']}")
    val = sets["validation"]["cases"]
    expect(len(val) >= 40, f"validation has {len(val)} cases")
    styles = {}
    for c in val:
        styles.setdefault(c["patient"]["seed"], set()).add(c["physician"]["style"])
    expect(len(styles) >= 20 and all(s >= {"careful_expert", "hurried_trainee"} for s in styles.values()),
           f"validation: >= 20 patients, each with both styles: {styles}")
    dev_patients = {c["patient"]["seed"] for n in ["development", "development_scripted", "development_extra"]
                    for c in sets[n]["cases"] if "patient" in c}
    extra = {c["patient"]["seed"] for c in sets["development_extra"]["cases"]}
    first = {c["patient"]["seed"] for c in sets["development"]["cases"]}
    expect(not (extra & first), f"development_extra repeats development's patients: {extra & first}")
    expect(not (dev_patients & set(styles)), f"development and validation share patients: {dev_patients & set(styles)}")
    for n in ["ci_smoke", "development_scripted"]:
        run("evaluate", os.path.join(folder, n + ".json"), "--list")


def check_evaluate_physician_manifests():
    # development.json, development_extra.json and validation.json need the physicians' generator (scenario key
    # "physician"): until it is merged, the scenario reader refuses the key and this check is
    # skipped (exit 77), not failed.
    folder = os.path.join(SOURCE, "model", "scenarios", "evaluation")
    for n in ["development", "development_extra", "validation"]:
        p = run("evaluate", os.path.join(folder, n + ".json"), "--list", expect_status=None)
        if p.returncode == 2 and "physician: unknown key" in p.stderr:
            print(f"SKIPPED: {n}.json needs the physicians' procedure generator (not merged yet)")
            sys.exit(77)
        expect(p.returncode == 0, f"{n}.json is accepted: {p.stderr[-400:]}")


def check_physician():
    # A physician instead of a procedure: the bench operator pushes a 400 mm scope through a
    # 200 mm straight tube and stops within 30 mm of its end; simulate writes procedure.csv (one
    # row per world.csv row, the same time_s) and summary.json "procedure" with the documented
    # keys. A scripted run gets {"kind": "scripted", ...}. Bad physician keys: exit 2 naming them.
    d = fresh("physician")
    os.makedirs(d)
    scenario = os.path.join(d, "s.json")
    base = {"colon": {"bundled": "straight_tube", "length_mm": 200, "inner_radius_mm": 15, "region": "rectum"},
            "scope": {"model": "cf_q160l", "length_mm": 400, "elements": 40}, "initial_insertion_mm": 20}
    with open(scenario, "w") as f:
        json.dump(dict(base, physician={"style": "bench_operator", "seed": 3, "max_duration_s": 60}), f)
    out = os.path.join(d, "run")
    p = run("simulate", scenario, "--out", out, "--quiet")
    expect("physician bench_operator (seed 3): cecum_reached" in p.stdout, f"simulate says how it went: {p.stdout}")
    s = json.load(open(os.path.join(out, "summary.json")))
    proc = s.get("procedure", {})
    expect(list(proc.keys()) == ["kind", "style", "seed", "cecum_reached", "cecum_time_s", "insertion_at_cecum_mm",
                                 "loop_reductions", "abdominal_pressure_s", "duration_s", "end_reason"],
           f"summary.json procedure keys: {list(proc.keys())}")
    expect(proc.get("kind") == "physician" and proc.get("style") == "bench_operator" and proc.get("seed") == 3
           and proc.get("cecum_reached") is True and proc.get("end_reason") == "cecum_reached"
           and proc.get("loop_reductions") == 0 and proc.get("abdominal_pressure_s") == 0,
           f"summary.json procedure: {proc}")
    expect(abs(proc["insertion_at_cecum_mm"] - 170.0) < 5.0, f"the tip 30 mm short of 200 mm: {proc}")
    expect(abs(s["duration_s"] - proc["duration_s"]) < 1e-9 and s["duration_s"] < 60, "the run stops at the cecum")
    expect(s["files"].get("procedure") == "procedure.csv", f"summary lists procedure.csv: {s['files']}")
    hand = rows(os.path.join(out, "procedure.csv"))
    world = rows(os.path.join(out, "world.csv"))
    expect(len(hand) == len(world) and [r["time_s"] for r in hand] == [r["time_s"] for r in world],
           "procedure.csv has world.csv's rows")
    expect(list(hand[0].keys()) == ["time_s", "state", "speed_mm_per_s", "roll_deg", "steering", "pressure"],
           f"procedure.csv columns: {list(hand[0].keys())}")
    advancing = [float(r["speed_mm_per_s"]) for r in hand if r["state"] == "advance"]
    expect(advancing and all(8.0 - 1e-6 <= v <= 10.0 + 1e-6 for v in advancing), "the bench pushes at 8-10 mm/s")
    expect({r["state"] for r in hand} <= {"hold", "advance", "pause"}, f"bench states: {({r['state'] for r in hand})}")
    # Scripted: the same tube, 7 s at 25 mm/s from 20 mm (the tip passes 170 mm at 6 s); the run
    # goes on to the procedure's end.
    with open(scenario, "w") as f:
        json.dump(dict(base, procedure=[{"action": "advance", "start_s": 0, "end_s": 7, "speed_mm_per_s": 25}]), f)
    out2 = os.path.join(d, "scripted")
    run("simulate", scenario, "--out", out2, "--quiet")
    proc = json.load(open(os.path.join(out2, "summary.json")))["procedure"]
    expect(proc.get("kind") == "scripted" and "style" not in proc and proc.get("end_reason") == "end_of_procedure"
           and proc.get("cecum_reached") is True, f"scripted procedure: {proc}")
    hand = rows(os.path.join(out2, "procedure.csv"))
    expect(all(r["state"] == "advance" and abs(float(r["speed_mm_per_s"]) - 25.0) < 1e-6 for r in hand[1:]),
           "scripted procedure.csv: advance at 25 mm/s")
    # Refusals, nothing written.
    for extra, message in [
            ({"physician": {"style": "surgeon", "seed": 1}}, "s.json: physician.style: unknown style 'surgeon'"),
            ({"physician": {"style": "careful_expert", "seed": -1}}, "s.json: physician.seed: expected a whole number"),
            ({"physician": {"style": "careful_expert", "seed": 1, "max_duration_s": 0}},
             "s.json: physician.max_duration_s: 0 s must be in (0, 3600]"),
            ({"physician": {"style": "careful_expert", "seed": 1}, "procedure": [{"action": "hold", "start_s": 0, "end_s": 1}]},
             "s.json: physician: a scenario takes either 'procedure'"),
            ({"physician": {"style": "careful_expert", "seed": 1}, "steering": [{"start_s": 0, "end_s": 1}]},
             "s.json: steering: the physician decides"),
            ({}, "s.json: procedure: missing; give 'procedure'")]:
        with open(scenario, "w") as f:
            json.dump(dict(base, **extra), f)
        bad = os.path.join(d, "bad")
        p = run("simulate", scenario, "--out", bad, "--quiet", expect_status=2)
        expect(message in p.stderr and not os.path.exists(bad), f"refused naming the path: {p.stderr}")


CHECKS = {"physician": check_physician, "patients": check_patients, "replay_bad_log": check_replay_bad_log, "demo": check_demo, "simulate_run_identical": check_simulate_run_identical, "loop_free": check_loop_free,
          "bad_recordings": check_bad_recordings, "batch": check_batch, "shell_injection": check_shell_injection,
          "hostile_json": check_hostile_json, "time_gap": check_time_gap, "option_ranges": check_option_ranges,
          "bom_and_long_lines": check_bom_and_long_lines, "box_faults": check_box_faults,
          "output_order": check_output_order, "truth": check_truth, "evaluate": check_evaluate,
          "evaluate_bad_input": check_evaluate_bad_input, "evaluate_manifests": check_evaluate_manifests,
          "evaluate_physician_manifests": check_evaluate_physician_manifests,
          "cycling_contacts": check_cycling_contacts}
os.makedirs(WORK, exist_ok=True)
CHECKS[CHECK]()
if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
