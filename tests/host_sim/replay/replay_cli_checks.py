#!/usr/bin/env python3
"""End-to-end checks of `scopekin replay` on hostile candump logs (tests/host_sim/replay).

usage: replay_cli_checks.py CHECK SCOPEKIN WORK_DIR
The logs are written here: both handle sensors at 1 kHz (insertion 100 mm + 50 mm/s, 2 N), packed
by hand from firmware/protocol/scopekin.dbc's layouts (little-endian, 0.01 mm, 0.005 N).  Every
expectation is stated next to its check; a failure prints what differed and exits 1."""
import json
import os
import shutil
import subprocess
import sys

CHECK, SCOPEKIN, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
failures = []


def expect(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(*args, timeout=60):
    try:
        return subprocess.run([SCOPEKIN, *args], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise SystemExit(f"scopekin {' '.join(args)}: still running after {timeout} s")


def fresh(name):
    d = os.path.join(WORK, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


def le(value, size):
    return (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")


def sensor_lines(ms, foreign_per_ms=0, base_s=1_000_000):
    lines = []
    for k in range(ms):
        t = k * 1000
        stamp = f"({base_s + t // 1_000_000}.{t % 1_000_000:06d})"
        encoder = le(round((100.0 + 0.05 * k) / 0.01), 3) + le(0, 3) + bytes([(k % 16) << 4])
        lines.append(f"{stamp} can0 111#{encoder.hex().upper()}")
        force = le(round(2.0 / 0.005), 2) + le(0, 2) + bytes([0, k % 16])
        lines.append(f"{stamp} can0 110#{force.hex().upper()}")
        for j in range(foreign_per_ms):
            lines.append(f"{stamp} can0 {0x300 + j % 0x100:03X}#0011223344556677")
    return lines


def write(d, name, lines):
    path = os.path.join(d, name)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return path


def check_backwards():
    d = fresh("backwards")
    # A reversed log: every step back is 1 ms (the old reader refused only steps back over 1 s).
    p = run("replay", write(d, "reversed.log", list(reversed(sensor_lines(2000)))), "--out",
            os.path.join(d, "out"))
    expect(p.returncode == 2, f"reversed log: exit 2, got {p.returncode}")
    expect("line 3: " in p.stderr and "s before line 2's" in p.stderr,
           f"reversed log: the message names lines 3 and 2: {p.stderr.strip()[:300]}")
    expect(not os.path.exists(os.path.join(d, "out", "firmware.csv")), "reversed log: no output")
    # Two lines swapped in an otherwise good log.
    lines = sensor_lines(100)
    lines[100], lines[102] = lines[102], lines[100]
    p = run("replay", write(d, "swapped.log", lines), "--out", os.path.join(d, "out"))
    expect(p.returncode == 2 and "line 102: " in p.stderr,
           f"swapped lines: exit 2 naming line 102: {p.returncode} {p.stderr.strip()[:300]}")


def check_gap():
    d = fresh("gap")
    # One frame 10^9 s after the rest: a period every 5 ms across it would never end.
    lines = sensor_lines(100) + ["(1001000000.000000) can0 110#900100000000"]
    p = run("replay", write(d, "gap.log", lines), "--out", os.path.join(d, "out"), timeout=30)
    expect(p.returncode == 2, f"gap of 10^9 s: exit 2, got {p.returncode}")
    expect("line 201: " in p.stderr and "--max-gap-s 60 s" in p.stderr,
           f"gap: the message names line 201 and the bound: {p.stderr.strip()[:300]}")
    # A 90 s gap: refused by default, replayed with --max-gap-s 120 (18,000 periods more).
    lines = sensor_lines(100) + ["(1000090.099000) can0 110#900100000000"]
    path = write(d, "gap90.log", lines)
    p = run("replay", path, "--out", os.path.join(d, "out"), "--quiet")
    expect(p.returncode == 2 and "line 201: " in p.stderr, f"90 s gap refused by default: {p.stderr.strip()[:300]}")
    p = run("replay", path, "--out", os.path.join(d, "out"), "--quiet", "--max-gap-s", "120")
    expect(p.returncode == 0, f"90 s gap with --max-gap-s 120: exit 0, got {p.returncode} {p.stderr[-300:]}")
    if p.returncode == 0:
        s = json.load(open(os.path.join(d, "out", "summary.json")))
        expect(s["periods"] == 90_099_000 // 5000 + 1, f"one period every 5 ms up to the last frame: {s['periods']}")
    # The bound itself is validated: a readable refusal, exit 2.
    for bad in ["-1", "0", "nan", "inf", "1e400", "3601", "x" * 5000]:
        p = run("replay", path, "--out", os.path.join(d, "out"), "--max-gap-s", bad)
        expect(p.returncode == 2 and "--max-gap-s" in p.stderr and len(p.stderr) < 400,
               f"--max-gap-s {bad[:20]}: exit 2 with a short message, got {p.returncode} ({len(p.stderr)} chars)")


CHECKS = {"backwards": check_backwards, "gap": check_gap}

if __name__ == "__main__":
    os.makedirs(WORK, exist_ok=True)
    CHECKS[CHECK]()
    if failures:
        sys.exit(f"{len(failures)} expectation(s) failed")
    print(f"replay check {CHECK}: ok")
