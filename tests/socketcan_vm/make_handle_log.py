#!/usr/bin/python3
"""Writes the handle sensors' traffic for the SocketCAN VM test as a candump log (canplayer input).

Both sensors at 1 kHz for DURATION s: the insertion encoder advances the scope from 100 mm at
--advance-mm-per-s (default 50: 100 -> 600 mm in 10 s), the force/torque cell reads 2 N.  The cell stops for GAP s from GAP_START (a sensor that
stops sending) and then returns.  The frames are encoded by python3-canmatrix from
firmware/protocol/scopekin.dbc, independently of the box's own encoders.

usage: make_handle_log.py DBC OUT.log [--duration S] [--gap-start S] [--gap S]
                          [--advance-mm-per-s V]
Prints one JSON line: frames per message, the gap's first missing and first returning frame times.
"""
import argparse
import decimal
import json
import sys

import canmatrix.formats


def encode_physical(frame, values):
    """canmatrix's Frame.encode packs RAW values: scale the physical ones with the DBC first."""
    raw = {}
    for signal in frame.signals:
        raw[signal.name] = int(signal.phys2raw(decimal.Decimal(str(values[signal.name]))))
    return bytes(frame.encode(raw))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dbc")
    parser.add_argument("out")
    parser.add_argument("--duration", type=float, default=10.0)
    parser.add_argument("--gap-start", type=float, default=6.0)
    parser.add_argument("--gap", type=float, default=0.3)
    parser.add_argument("--interface", default="vcan0")
    # mm/s from 100 mm; keep 100 + speed * duration inside the model's travel run (20..760 mm)
    parser.add_argument("--advance-mm-per-s", type=float, default=50.0)
    args = parser.parse_args()

    db = canmatrix.formats.loadp_flat(args.dbc)
    force = db.frame_by_name("HandleForceTorque")
    encoder = db.frame_by_name("InsertionRoll")
    steps = int(round(args.duration * 1000))
    gap_first = int(round(args.gap_start * 1000))
    gap_end = int(round((args.gap_start + args.gap) * 1000))
    counts = {"HandleForceTorque": 0, "InsertionRoll": 0}
    base_s = 1_000_000  # any origin: canplayer replays relative times
    with open(args.out, "w") as out:
        for k in range(steps):
            t_us = k * 1000
            stamp = f"({base_s + t_us // 1_000_000}.{t_us % 1_000_000:06d})"
            insertion = 100.0 + args.advance_mm_per_s * k / 1000.0
            data = encode_physical(encoder, {"Insertion": round(insertion, 2), "Roll": 0.0,
                                             "EncoderStatus": 0, "EncoderCounter": k % 16})
            out.write(f"{stamp} {args.interface} {encoder.arbitration_id.id:03X}#{data.hex().upper()}\n")
            counts["InsertionRoll"] += 1
            if gap_first <= k < gap_end:
                continue
            data = encode_physical(force, {"HandleForce": 2.0, "HandleTorque": 0.0,
                                           "CellStatus": 0, "CellCounter": k % 16})
            out.write(f"{stamp} {args.interface} {force.arbitration_id.id:03X}#{data.hex().upper()}\n")
            counts["HandleForceTorque"] += 1
    json.dump({"frames": counts, "total": sum(counts.values()),
               "gap_first_missing_ms": gap_first, "gap_first_returning_ms": gap_end}, sys.stdout)
    print()


if __name__ == "__main__":
    main()
