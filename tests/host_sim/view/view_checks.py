#!/usr/bin/env python3
"""`scopekin view` without a browser: its page's data against the run's own files, bad input.

view_checks.py CHECK SCOPEKIN RUN_DIR WORK
  export      the exported page embeds the run: its alarms are firmware.csv's self_lock_alarm /
              contact_force_level intervals, its frames frames.jsonl's lines, no NaN
  snapshots   without frames.jsonl the snapshots' key moments are the frames
  no_run      a folder without a run, a missing folder: exit 2, the message says why
  truncated   firmware.csv cut in the middle of a line, frames.jsonl cut: exit 2, file and line named
  port_in_use a port another program holds: exit 2, the message names the port
  served      the served page is the exported file, byte for byte, sent uncompressed to a client
              that accepts brotli and gzip (a browser: httplib's brotli took 0.83 s of CPU);
              SIGTERM ends the server with 0
  unwritable  --export into a folder that does not exist: exit 3
  help        --help lists --port, --no-browser and --export
  discrepancy a discrepancy report (written here, by hand: the view shows what the report says)
              exported: the report as it is, series.csv grouped by output; a cut series.csv: exit 2
  evaluation  (RUN_DIR an evaluation) the page embeds the scorecard and each case's replay; a case
              whose files are gone is listed without one, with a warning, exit 0
Exit status 0 passed, 1 a check failed.
"""
import csv
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import urllib.request

CHECK, SCOPEKIN, RUN, WORK = sys.argv[1:5]
failures = 0


def expect(condition, message):
    global failures
    print(("ok   " if condition else "FAIL ") + message)
    if not condition:
        failures += 1


def view(*args, timeout=120):
    return subprocess.run([SCOPEKIN, "view", *args], capture_output=True, text=True, timeout=timeout)


def fresh(name):
    d = os.path.join(WORK, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


def copy_run(name):
    d = os.path.join(WORK, name)
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(RUN, d)
    return d


def embedded_data(html_path):
    text = open(html_path, encoding="utf-8").read()
    m = re.search(r'<script id="scopekin-data" type="application/json">(.*?)</script>', text, re.S)
    expect(m is not None, "the page embeds its data")
    return json.loads(m.group(1).replace("<\\/", "</"))


def intervals(times, up):
    """[start, end) of the periods where up holds; end None: up at the end."""
    out, start = [], None
    for t, u in zip(times, up):
        if u and start is None:
            start = t
        if not u and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, None))
    return out


def check_export():
    out = os.path.join(fresh("export"), "view.html")
    p = view(RUN, "--export", out)
    expect(p.returncode == 0, f"--export exits 0 ({p.returncode}): {p.stderr.strip()}")
    data = embedded_data(out)
    fw = list(csv.DictReader(open(os.path.join(RUN, "firmware.csv"))))
    times = [float(r["time_s"]) for r in fw]
    want = {
        "self_lock": intervals(times, [r["self_lock_alarm"] != "0" for r in fw]),
        "contact_force_warning": intervals(times, [r["contact_force_level"] == "1" for r in fw]),
        "contact_force_critical": intervals(times, [int(r["contact_force_level"]) >= 2 for r in fw]),
    }
    got = {k: [(a["start_s"], a["end_s"]) for a in data["alarms"] if a["kind"] == k] for k in want}
    for kind in want:
        same = len(want[kind]) == len(got[kind]) and all(
            abs(a[0] - b[0]) < 1e-9 and ((a[1] is None) == (b[1] is None)) and (a[1] is None or abs(a[1] - b[1]) < 1e-9)
            for a, b in zip(want[kind], got[kind]))
        expect(same, f"{kind}: the page's {len(got[kind])} intervals are firmware.csv's {len(want[kind])}")
    expect(len(data["alarms"]) > 0, f"the run has alarms to step through ({len(data['alarms'])})")
    lines = [ln for ln in open(os.path.join(RUN, "frames.jsonl")) if ln.strip()]
    expect(data["frames_source"] == "frames.jsonl" and len(data["frames"]) == len(lines),
           f"the frames are frames.jsonl's {len(lines)} lines ({len(data['frames'])})")
    colon_points = len(data["colon"]["centerline_mm"])
    expect(all(len(f["colon_mm"]) == colon_points for f in data["frames"]),
           f"every frame carries the displaced colon's {colon_points} points")
    s = data["series"]
    expect(len(s["time_s"]) <= 8000 and len(s["time_s"]) * s["stride_periods"] >= len(fw),
           f"the timeline keeps every {s['stride_periods']}-th of {len(fw)} periods")
    text = open(out, encoding="utf-8").read()
    embedded = text[text.index('id="scopekin-data"'):]
    embedded = embedded[: embedded.index("</script>")]
    expect("NaN" not in embedded, "no NaN in the embedded JSON (null instead)")


def check_snapshots():
    d = copy_run("no_frames")
    os.remove(os.path.join(d, "frames.jsonl"))
    out = os.path.join(d, "view.html")
    p = view(d, "--export", out)
    expect(p.returncode == 0, f"without frames.jsonl --export exits 0 ({p.returncode}): {p.stderr.strip()}")
    data = embedded_data(out)
    snaps = json.load(open(os.path.join(d, "snapshots.json")))["snapshots"]
    expect(data["frames_source"] == "snapshots.json" and len(data["frames"]) == len(snaps),
           f"the snapshots' {len(snaps)} key moments are the frames ({len(data['frames'])})")


def check_no_run():
    empty = fresh("empty")
    p = view(empty, "--export", os.path.join(WORK, "x.html"))
    expect(p.returncode == 2 and "summary.json" in p.stderr, f"a folder without a run: exit 2 ({p.returncode}), {p.stderr.strip()}")
    p = view(os.path.join(WORK, "does-not-exist"), "--no-browser")
    expect(p.returncode == 2 and "not a folder" in p.stderr, f"a missing folder: exit 2 ({p.returncode}), {p.stderr.strip()}")


def check_truncated():
    d = copy_run("truncated_csv")
    fw = os.path.join(d, "firmware.csv")
    text = open(fw).read()
    cut = text[: len(text) // 2]
    cut = cut[: cut.rfind("\n") + 1] + cut[cut.rfind("\n") + 1:][:20]  # a last line cut short
    open(fw, "w").write(cut)
    p = view(d, "--export", os.path.join(d, "x.html"))
    expect(p.returncode == 2 and "firmware.csv" in p.stderr and "line" in p.stderr,
           f"firmware.csv cut short: exit 2 ({p.returncode}), {p.stderr.strip()}")
    d = copy_run("truncated_frames")
    fr = os.path.join(d, "frames.jsonl")
    text = open(fr).read()
    open(fr, "w").write(text[: len(text) // 2])
    p = view(d, "--export", os.path.join(d, "x.html"))
    expect(p.returncode == 2 and "frames.jsonl: line" in p.stderr,
           f"frames.jsonl cut short: exit 2 ({p.returncode}), {p.stderr.strip()}")


def check_port_in_use():
    holder = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    holder.bind(("127.0.0.1", 0))
    holder.listen(1)
    port = holder.getsockname()[1]
    try:
        p = view(RUN, "--no-browser", "--port", str(port), timeout=120)
    finally:
        holder.close()
    expect(p.returncode == 2 and f"port {port}" in p.stderr, f"port {port} in use: exit 2 ({p.returncode}), {p.stderr.strip()}")


def check_served():
    exported = os.path.join(fresh("served"), "view.html")
    p = view(RUN, "--export", exported)
    expect(p.returncode == 0, f"--export exits 0 ({p.returncode})")
    server = subprocess.Popen([SCOPEKIN, "view", RUN, "--no-browser", "--port", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()
        m = re.search(r"(http://127\.0\.0\.1:\d+/)", line)
        expect(m is not None, f"the server prints its address ({line.strip()})")
        request = urllib.request.Request(m.group(1), headers={"Accept-Encoding": "br, gzip, deflate"})
        with urllib.request.urlopen(request, timeout=60) as answer:
            encoding = answer.headers.get("Content-Encoding")
            body = answer.read()
        expect(encoding is None, f"the page is sent uncompressed to a client that accepts br and gzip (Content-Encoding: {encoding})")
        expect(body == open(exported, "rb").read(), f"the served page is the exported file ({len(body)} bytes)")
    finally:
        server.terminate()
        status = server.wait(timeout=60)
    expect(status == 0, f"SIGTERM ends the server with exit status 0 ({status})")


def check_unwritable():
    p = view(RUN, "--export", os.path.join(WORK, "no-such-folder", "sub", "view.html"))
    expect(p.returncode == 3, f"--export into a missing folder: exit 3 ({p.returncode}), {p.stderr.strip()}")


def check_help():
    p = subprocess.run([SCOPEKIN, "view", "--help"], capture_output=True, text=True)
    expect(p.returncode == 0 and all(o in p.stdout for o in ["--port", "--no-browser", "--export"]),
           "--help lists --port, --no-browser and --export")


def write_discrepancy(d):
    """A small discrepancy report: one effect named, two outputs, 100 samples each."""
    report = {
        "recording": "recording.csv", "model": "default model", "verdict": "single",
        "effects": [{"name": "ei_scale", "parameters": [{"name": "factor", "value": 0.85, "sd": 0.01}],
                     "where": {"acts": "scope", "regions_where_it_closes_the_gap": ["sigmoid"]},
                     "share_explained": 0.93, "entry": {}}],
        "rmse_before": {"handle_force_N": 0.8, "tip_position_mm": 6.0},
        "rmse_after": {"handle_force_N": 0.1, "tip_position_mm": 1.5},
        "most_affected_output": {"name": "handle_force_N", "held_out_rmse_before": 0.8,
                                 "held_out_rmse_after": 0.1, "reduction": 0.875},
        "rmse_by_region": {"sigmoid": {"handle_force_N": {"samples": 100, "before": 0.8, "after": 0.1},
                                       "tip_position_mm": {"samples": 100, "before": 6.0, "after": 1.5}}},
    }
    json.dump(report, open(os.path.join(d, "report.json"), "w"))
    with open(os.path.join(d, "series.csv"), "w") as f:
        f.write("output,component,time_s,held_out,measured,before,after\n")
        for output, component, scale in [("handle_force_N", "x", 1.0), ("tip_position_mm", "y", 10.0)]:
            for k in range(100):
                t = 0.1 * k
                f.write(f"{output},{component},{t:.1f},{1 if 30 <= k < 40 else 0},{scale * t:.3f},{scale * 1.2 * t:.3f},{scale * 1.01 * t:.3f}\n")
    return report


def check_discrepancy():
    d = fresh("discrepancy")
    report = write_discrepancy(d)
    out = os.path.join(d, "view.html")
    p = view(d, "--export", out)
    expect(p.returncode == 0, f"--export of a discrepancy report exits 0 ({p.returncode}): {p.stderr.strip()}")
    data = embedded_data(out)
    expect(data["kind"] == "discrepancy" and data["report"] == report, "the page embeds report.json as it is")
    s = data["series"]
    expect(sorted(s) == ["handle_force_N/x", "tip_position_mm/y"], f"series.csv grouped by output and component ({sorted(s)})")
    f = s["handle_force_N/x"]
    expect(len(f["time_s"]) == 100 and sum(f["held_out"]) == 10 and abs(f["before"][50] - 1.2 * 5.0) < 1e-9,
           "each group's samples as series.csv has them (100, 10 held out, before(5 s) = 6)")
    text = open(os.path.join(d, "series.csv")).read().splitlines()
    text[40] = ",".join(text[40].split(",")[:5])
    open(os.path.join(d, "series.csv"), "w").write("\n".join(text) + "\n")
    p = view(d, "--export", os.path.join(d, "cut.html"))
    expect(p.returncode == 2 and "series.csv: line 41" in p.stderr, f"a row cut short: exit 2, its line named ({p.returncode}): {p.stderr.strip()}")
    write_discrepancy(d)  # whole again, for the browser test


def check_evaluation():
    out = os.path.join(fresh("evaluation"), "view.html")
    p = view(RUN, "--export", out)
    expect(p.returncode == 0, f"--export of an evaluation exits 0 ({p.returncode}): {p.stderr.strip()[-300:]}")
    data = embedded_data(out)
    scorecard = json.load(open(os.path.join(RUN, "scorecard.json")))
    complete = [c["case"] for c in scorecard["cases"] if c["status"] == "complete"]
    expect(data["kind"] == "evaluation" and data["scorecard"]["overall"] == scorecard["overall"],
           "the page embeds the scorecard as scorecard.json has it")
    expect(sorted(data["case_views"]) == sorted(complete), f"each complete case has its replay ({len(data['case_views'])} of {len(complete)})")
    expect(all(len(v["series"]["time_s"]) <= 2000 for v in data["case_views"].values()),
           "each case's timeline keeps at most 2000 points")
    d = os.path.join(WORK, "evaluation_broken")
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(RUN, d)
    broken = scorecard["cases"][0]
    os.remove(os.path.join(d, broken["folder"], "truth.csv"))
    p = view(d, "--export", os.path.join(d, "view.html"))
    data = embedded_data(os.path.join(d, "view.html"))
    expect(p.returncode == 0 and broken["case"] in p.stderr and "truth.csv" in data["case_errors"].get(broken["case"], ""),
           f"a case without truth.csv: listed without its replay, a warning, exit 0 ({p.returncode}): {data['case_errors']}")


os.makedirs(WORK, exist_ok=True)
globals()["check_" + CHECK]()
sys.exit(1 if failures else 0)
