#!/usr/bin/env python3
"""End-to-end checks of the scopekin command line (tests/host_sim/cli/CMakeLists.txt).

usage: cli_checks.py CHECK SCOPEKIN WORK_DIR [SOURCE_DIR]
Every expectation is stated next to its check; a failure prints what differed and exits 1."""
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


def run(*args, expect_status=0):
    p = subprocess.run([SCOPEKIN, *args], capture_output=True, text=True)
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
    # The loop starts when the tip locks at the sigmoid-descending junction: 15.9 s in the reference
    # run at 20 mm/s (firmware/README.md, "Alarms"); the alarm must come within a second of it.
    expect(locks and 15.5 < locks[0]["raised_s"] < 17.0, f"self-lock alarm raised near 15.9 s: {locks[:1]}")
    expect(0 < s["peak_handle_force_N"]["true"] < 100, "peak handle force positive and below 100 N")
    expect(abs(s["peak_handle_force_N"]["measured"] - s["peak_handle_force_N"]["true"]) < 1.0,
           "measured peak handle force within 1 N of the true one (noise 0.05 N)")
    expect(s["peak_estimated_contact_force"]["force_N"] > 1.0, "the box estimates a contact force")
    expect(s["real_time_factor"] > 1.0, "faster than real time")
    eff = s["advance_efficiency_by_region"]
    expect(0.9 < eff["rectum"]["efficiency"] <= 1.05, f"the tip follows the hand in the rectum: {eff.get('rectum')}")
    expect(eff["sigmoid"]["efficiency"] < 0.95, "the sigmoid loop costs advance")
    # The demo's colonoscopy ends in the cecum (it starts ~1530 mm along the default colon).
    expect(s["final_tip"]["region"] == "cecum", f"the tip reaches the cecum: {s['final_tip']}")
    expect(s["peak_handle_force_N"]["true"] < 43.0, "peak handle force below the 43 N peak push measured in patients (firmware/fixed_point/RANGES.md [A])")
    # Past the reduced model's depth range (760 mm) the box holds its estimate and says so.
    first = s["firmware"]["fault_first_s"]
    expect("depth_outside_model" in first and 60.0 < first["depth_outside_model"] < 65.0,
           f"depth_outside_model flagged from ~62.7 s (20 + 25 * (t - 50.5) - 225 > 760): {first}")
    expect("fault flag depth_outside_model" in p.stdout, "the demo prints the fault flags it saw")
    world = rows(os.path.join(out, "world.csv"))
    firmware = rows(os.path.join(out, "firmware.csv"))
    # 100.2 s at 30 Hz: 3007 rows (one at t = 0); the box every 5 ms: 20040 periods.
    expect(len(world) == 3007, f"world.csv rows: {len(world)}")
    expect(len(firmware) == 20040, f"firmware.csv rows: {len(firmware)}")
    recording = rows(os.path.join(out, "recording.csv"))
    force_rows = sum(1 for r in recording if r["handle_force_N"] != "")
    # The force cell at 1 kHz (no dropouts by default): one sample per ms from 1 ms to 100.2 s.
    expect(force_rows == 100200, f"handle force samples: {force_rows}")
    snaps = json.load(open(os.path.join(out, "snapshots.json")))
    labels = [x["label"] for x in snaps["snapshots"]]
    expect(labels[0] == "self_lock alarm raised" and labels[-1] == "end" and len(labels) >= 4, f"snapshots: {labels}")
    checker = os.path.join(SOURCE, "host_sim", "plots", "check_pngs.py")
    c = subprocess.run(["/usr/bin/python3", checker] + [os.path.join(out, n) for n in
                                                       ["forces.png", "advance.png", "snapshots.png"]],
                       capture_output=True, text=True)
    print(c.stdout)
    expect(c.returncode == 0, "the PNGs are non-trivial: " + c.stdout + c.stderr)


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


CHECKS = {"replay_bad_log": check_replay_bad_log, "demo": check_demo, "simulate_run_identical": check_simulate_run_identical, "loop_free": check_loop_free,
          "bad_recordings": check_bad_recordings, "batch": check_batch}
os.makedirs(WORK, exist_ok=True)
CHECKS[CHECK]()
if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
