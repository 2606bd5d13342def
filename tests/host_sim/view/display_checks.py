#!/usr/bin/env python3
"""`scopekin display` without a browser: the box's page from its CAN frames, against the box's
own outputs, and bad input.

display_checks.py CHECK SCOPEKIN DBC MAKE_HANDLE_LOG WORK
  box_log  a handle-sensor log (10 s, the force cell silent 6.0-6.3 s; made by python3-canmatrix
           from the DBC) through `scopekin replay --record`: the record is a box log, and
           `scopekin replay` of it compares every output frame equal
  stream   `scopekin display` of that box log (--pace 0): every period of the box arrives on
           /events, and each row's tip, largest contact force, alarms and fault flags equal the
           replay's firmware.csv at the same time to the CAN signals' resolution (0.1 mm,
           0.001 N; the SD in 10 mm steps)
  refusals a log of the handle sensors alone, a missing file, an interface that cannot be opened,
           neither a log nor --can, both: exit 2 with a message that says why
Exit status 0 passed, 1 a check failed.
"""
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import time
import urllib.request

CHECK, SCOPEKIN, DBC, MAKE_LOG, WORK = sys.argv[1:6]
failures = 0


def expect(condition, message):
    global failures
    print(("ok   " if condition else "FAIL ") + message)
    if not condition:
        failures += 1


def path(*names):
    return os.path.join(WORK, *names)


def check_box_log():
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    made = subprocess.run(["/usr/bin/python3", MAKE_LOG, DBC, path("handle.log"), "--duration", "10",
                           "--gap-start", "6", "--gap", "0.3", "--interface", "can0"],
                          capture_output=True, text=True)
    expect(made.returncode == 0, f"the handle log is written ({made.stderr.strip()[-200:]})")
    r = subprocess.run([SCOPEKIN, "replay", path("handle.log"), "--out", path("replay"),
                        "--record", path("box.log"), "--quiet"], capture_output=True, text=True)
    expect(r.returncode == 0 and os.path.exists(path("box.log")),
           f"replay --record writes the box log (exit {r.returncode})")
    again = subprocess.run([SCOPEKIN, "replay", path("box.log"), "--out", path("again"), "--quiet"],
                           capture_output=True, text=True)
    m = re.search(r"(\d+) recorded frames compared, (\d+) differ", again.stdout)
    expect(again.returncode == 0 and m is not None and int(m.group(1)) > 0 and m.group(2) == "0",
           f"the record replays as a box log to the same frames ({m.group(0) if m else again.stdout[-300:]})")


def read_events(url, timeout_s=120):
    """Every message of /events until the display says it is done."""
    messages = []
    with urllib.request.urlopen(url + "events", timeout=timeout_s) as stream:
        for raw in stream:
            line = raw.decode("utf-8").rstrip("\n")
            if line.startswith("data: "):
                messages.append(json.loads(line[6:]))
                if messages[-1].get("done"):
                    break
    return messages


def check_stream():
    display = subprocess.Popen([SCOPEKIN, "display", path("box.log"), "--pace", "0", "--no-browser",
                                "--port", "0", "--quiet"], stdout=subprocess.PIPE, text=True)
    try:
        url = None
        for line in display.stdout:
            m = re.search(r"view at (http://127\.0\.0\.1:\d+/)", line)
            if m:
                url = m.group(1)
                break
        expect(url is not None, f"display prints its address ({url})")
        messages = read_events(url)
        rows = [row for m in messages for row in m.get("rows", [])]
        expect(messages and messages[-1].get("done") is True, f"the stream ends with done ({len(messages)} messages)")
        with open(path("replay", "firmware.csv"), newline="") as f:
            periods = list(csv.DictReader(f))
        first_s = float(open(path("box.log")).readline().split(")")[0][1:])
        by_time = {round(float(p["time_s"]) - first_s, 6): p for p in periods}
        # The page keeps a row every 20 ms (LiveView); each must be one of the box's periods.
        expect(len(rows) >= len(periods) // 4 - 1,
               f"a row every 20 ms of the box's {len(periods)} periods ({len(rows)} rows)")
        worst = {"tip": 0.0, "force": 0.0, "sd": 0.0}
        unmatched = alarms_differ = faults_differ = 0
        for row in rows:
            p = by_time.get(round(row["time_s"], 6))
            if p is None:
                unmatched += 1
                continue
            worst["tip"] = max(worst["tip"], abs(row["box_tip_path_mm"] - float(p["tip_path_mm"])))
            worst["force"] = max(worst["force"], abs(row["box_max_force_N"] - float(p["max_contact_force_N"])))
            alarms_differ += (row["self_lock"] != int(p["self_lock_alarm"]) or
                              row["contact_level"] != int(p["contact_force_level"]))
            faults_differ += row["fault_flags"] != int(p["fault_flags"])
        expect(unmatched == 0, f"every row is a period of the box ({unmatched} not)")
        expect(worst["tip"] <= 0.05 + 1e-6, f"the tip as firmware.csv's to 0.1 mm steps (worst {worst['tip']:.4f} mm)")
        expect(worst["force"] <= 0.0005 + 1e-6, f"the largest force as firmware.csv's to 1 mN steps (worst {worst['force']:.5f} N)")
        expect(alarms_differ == 0, f"the alarms as firmware.csv's ({alarms_differ} rows differ)")
        expect(faults_differ == 0, f"the fault flags as firmware.csv's ({faults_differ} rows differ)")
        stale = [r["time_s"] for r in rows if r["fault_flags"] & (1 << 3)]
        expect(stale and 6.0 <= min(stale) <= 6.02,
               f"the silent force cell shows as the force-stale flag from 6.0 s ({min(stale) if stale else None})")
        expect(all(len(r["stations"]) <= 12 for r in rows) and any(r["stations"] for r in rows),
               "the stations' positions and forces arrive")
    finally:
        display.terminate()
        code = display.wait(timeout=30)
    expect(code == 0, f"display ends with 0 on SIGTERM after the log ({code})")


def refused(args, pattern, what):
    r = subprocess.run([SCOPEKIN, "display", *args, "--no-browser", "--port", "0"],
                       capture_output=True, text=True, timeout=60)
    expect(r.returncode == 2 and re.search(pattern, r.stderr) is not None,
           f"{what}: exit 2 ({r.returncode}), says why ({r.stderr.strip()[:160]})")


def check_refusals():
    refused([path("handle.log")], r"no frame of the box.*--record", "a log of the handle sensors alone")
    refused([path("missing.log")], r"missing\.log", "a missing file")
    refused(["--can", "scopekin_none0"], r"scopekin_none0", "an interface that cannot be opened")
    refused([], r"give a box log or --can", "neither a log nor --can")
    refused([path("box.log"), "--can", "vcan0"], r"excludes", "both a log and --can")


{"box_log": check_box_log, "stream": check_stream, "refusals": check_refusals}[CHECK]()
sys.exit(1 if failures else 0)
