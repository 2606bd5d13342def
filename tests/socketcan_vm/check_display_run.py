#!/usr/bin/python3
"""Checks what display_on_vcan.sh wrote: `scopekin display --can vcan0` beside scopekin-box on a real
kernel's CAN stack heard the box's periods, served its page, and streamed rows that follow the handle
log (the insertion advancing from 100 mm at 50 mm/s, the force 2 N) with the box's tip.  With
box-view the box started the display itself (`scopekin-box --view`) and stopped it: its statistics
say how the display ended, and a display program that is not there was refused (exit 2, the reason).

usage: check_display_run.py OUT_DIR DURATION_S [display|box-view]"""
import gzip
import json
import re
import sys

out, duration = sys.argv[1], float(sys.argv[2])
mode = sys.argv[3] if len(sys.argv) > 3 else "display"
failures = 0


def expect(ok, what):
    global failures
    print(("ok   " if ok else "FAIL ") + what)
    failures += 0 if ok else 1


status = open(f"{out}/exit_status.txt").read().strip()
expect(status == "canplayer=0 page=0 scopekin-display=0 scopekin-box=0", f"every program ended with 0 ({status})")
said = open(f"{out}/display.txt").read()
m = re.search(r"heard (\d+) box periods \((\d+) frames refused", said)
periods = int(m.group(1)) if m else 0
expect(m is not None and periods >= 0.8 * duration / 0.005 and m.group(2) == "0",
       f"the display heard the box's periods ({m.group(0) if m else said[-200:]}; {duration / 0.005:.0f} in the log's time)")
page = gzip.open(f"{out}/page.html.gz", "rt", encoding="utf-8").read()
expect('id="scopekin-data"' in page and '"box_only":true' in page.replace(" ", ""),
       f"the page is the box's ({len(page)} characters)")
rows = []
for line in gzip.open(f"{out}/events.txt.gz", "rt", encoding="utf-8"):
    if line.startswith("data: "):
        rows += json.loads(line[6:]).get("rows", [])
times = [r["time_s"] for r in rows]
expect(len(rows) >= 0.8 * duration / 0.02 and all(b > a for a, b in zip(times, times[1:])),
       f"a row every 20 ms in time order ({len(rows)} rows over {times[-1] if times else 0:.2f} s)")
insertion = [r["insertion_mm"] for r in rows]
expect(rows and abs(max(insertion) - (100 + 50 * duration)) < 10 and min(insertion) < 120,
       f"the handle's insertion heard on the bus: {min(insertion) if rows else None} -> {max(insertion) if rows else None} mm")
# The box and its display start before the traffic: the handle's rows from its first frames on.
heard = [r for r in rows if r["insertion_mm"] > 0]
expect(len(heard) > 100 and all(abs(r["handle_force_N"] - 2.0) < 0.01 for r in heard[5:]),
       f"the handle force, 2 N, in the {len(heard)} rows since the handle's first frames")
tips = [r["box_tip_path_mm"] for r in rows]
expect(rows and tips[-1] > tips[0] + 0.5 * 50 * duration, f"the box's tip advances ({tips[0] if rows else None} -> {tips[-1] if rows else None} mm)")
if mode == "box-view":
    refusal = open(f"{out}/refusal.txt").read().strip()
    statuses = open(f"{out}/refusal_status.txt").read().split()
    expect(statuses[0] == "refusal=2" and "cannot start the display '/nonexistent/scopekin'" in refusal,
           f"a display program that is not there: exit 2 ({refusal})")
    busy = json.load(open(f"{out}/box_stats_busy.json"))
    said = open(f"{out}/busy_stderr.log").read()
    expect(statuses[1] == "busy=0" and busy["display"]["ended_on_its_own"] and busy["display"]["exit_status"] == 2
           and "the display ended (exit status 2); the box goes on without it" in said and busy["periods"] >= 400,
           f"a display that ends on its own (port taken): the box goes on, exit 0, {busy['periods']} periods "
           f"({said.strip()[-300:]})")
    shown = json.load(open(f"{out}/box_stats.json"))["display"]
    expect(shown["program"] == "scopekin" and shown["port"] == 8765 and not shown["ended_on_its_own"]
           and shown["exit_status"] == 0, f"the box stopped its display, which ended with 0 ({shown})")
sys.exit(1 if failures else 0)
