#!/usr/bin/python3
"""Checks what scopekin-box did on the VM's vcan0 (files written by box_on_vcan.sh).

usage: check_box_run.py OUT_DIR DBC INPUT_SUMMARY_JSON

* nothing dropped: the box received every input frame canplayer sent (kernel drop counter 0,
  no rolling-counter gap, every sample taken), and no unknown identifier;
* its frames, decoded with python3-canmatrix from scopekin.dbc, are the protocol: a
  KineticEstimate, ContactSummary, Alarms and BoxCounters frame per period, a valid estimate that
  follows the advance;
* the force cell's 0.3 s silence: a BoxStatus with the stale bit within 3 periods (counted in
  KineticEstimate frames, i.e. box periods, not in wall time), InputsStale on the estimate, and
  the bits cleared within 3 periods of the cell's return;
* the injected error frames: counted, bus-off reported and recovered;
* the box's own --record log has the same frames as candump's view of the bus.
Prints a summary and writes OUT_DIR/check.json; exit status 1 on any failure.
"""
import gzip
import json
import os
import sys

import canmatrix.formats

FORCE_ID, ENCODER_ID = 0x110, 0x111
STATUS_ID, ESTIMATE_ID, SUMMARY_ID, ALARMS_ID, COUNTERS_ID, STATION_ID = 0x180, 0x181, 0x182, 0x183, 0x184, 0x190
KINETIC_FORCE_STALE, KINETIC_TORQUE_STALE = 1 << 3, 1 << 5
DRIVER_FORCE_STALE = 1 << 0


def read_candump(path):
    frames = []
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as log:
        for number, line in enumerate(log, 1):
            parts = line.split()
            if not parts:
                continue
            if len(parts) != 3 or "#" not in parts[2]:
                raise SystemExit(f"{path}:{number}: not a candump log line: {line!r}")
            stamp = float(parts[0].strip("()"))
            ident, data = parts[2].split("#", 1)
            frames.append((stamp, int(ident, 16), len(ident) == 8, bytes.fromhex(data.replace(".", ""))))
    return frames


def main():
    out_dir, dbc_path, summary_path = sys.argv[1:4]
    with open(summary_path) as f:
        sent = json.load(f)
    with open(os.path.join(out_dir, "box_stats.json")) as f:
        stats = json.load(f)
    db = canmatrix.formats.loadp_flat(dbc_path)
    failures = []

    def expect(condition, what):
        if not condition:
            failures.append(what)

    with open(os.path.join(out_dir, "exit_status.txt")) as f:
        expect(f.read().split() == ["canplayer=0", "scopekin-box=0"], "canplayer and scopekin-box exit 0")

    # --- nothing dropped -----------------------------------------------------------------------
    handle = stats["handle_sensors"]
    expect(stats["can"]["received"] == sent["total"],
           f"box received {stats['can']['received']} data frames, canplayer sent {sent['total']}")
    expect(stats["can"]["dropped"] == 0, f"kernel dropped {stats['can']['dropped']} frames")
    expect(handle["counter_gaps"] == 0, f"{handle['counter_gaps']} rolling-counter gaps")
    expect(handle["force_torque_samples"] == sent["frames"]["HandleForceTorque"], "every force/torque sample taken")
    expect(handle["insertion_roll_samples"] == sent["frames"]["InsertionRoll"], "every insertion/roll sample taken")
    for key in ("bad_length", "out_of_range", "sensor_status"):
        expect(handle[key] == 0, f"handle_sensors.{key} == 0")
    expect(stats["box"]["unknown_ids"] == 0, "no unknown identifiers")
    expect(stats["record"]["write_errors"] == 0, "record written without errors")

    # --- the bus as candump saw it ------------------------------------------------------------
    bus = read_candump(os.path.join(out_dir, "candump.log.gz"))
    inputs = [f for f in bus if f[1] in (FORCE_ID, ENCODER_ID) and not f[2]]
    expect(len(inputs) == sent["total"], f"candump saw {len(inputs)} input frames of {sent['total']}")
    decoded = []
    for stamp, ident, extended, data in bus:
        if extended or ident < STATUS_ID or ident > STATION_ID:
            continue
        frame = db.frame_by_id(canmatrix.ArbitrationId(ident))
        if frame is None:
            failures.append(f"box sent an unknown identifier 0x{ident:03X}")
            continue
        if len(data) != frame.size:
            failures.append(f"0x{ident:03X} with {len(data)} bytes, the DBC says {frame.size}")
            continue
        values = {name: float(signal.phys_value) for name, signal in frame.decode(data).items()}
        decoded.append((stamp, ident, values))
    estimates = [d for d in decoded if d[1] == ESTIMATE_ID]
    periods = stats["periods"]
    for ident, name in ((ESTIMATE_ID, "KineticEstimate"), (SUMMARY_ID, "ContactSummary"),
                        (ALARMS_ID, "Alarms"), (COUNTERS_ID, "BoxCounters")):
        count = sum(1 for d in decoded if d[1] == ident)
        expect(count == periods, f"{count} {name} frames for {periods} periods")
    expect(all(d[2]["EstimateValid"] == 1 for d in estimates), "every estimate valid")
    expect(all(d[2]["ContactForceLevel"] <= 2 and d[2]["AlarmsValid"] == 1 for d in decoded if d[1] == ALARMS_ID),
           "alarm frames valid")
    final_tip = estimates[-1][2]["TipPath"] if estimates else 0.0
    expect(final_tip > 300.0, f"final tip path {final_tip:.1f} mm follows the 100 -> 600 mm advance")

    # --- the force cell's silence --------------------------------------------------------------
    force_times = [f[0] for f in inputs if f[1] == FORCE_ID]
    gaps = [(a, b) for a, b in zip(force_times, force_times[1:]) if b - a > 0.1]
    expect(len(gaps) == 1, f"one silence of the force cell in the input ({len(gaps)} found)")
    stale_after = recovered_after = None
    if gaps:
        last_before, first_after = gaps[0]
        after = [d for d in decoded if d[0] > last_before]
        periods_seen = 0
        for stamp, ident, values in after:
            if ident == ESTIMATE_ID:
                periods_seen += 1
            if ident == STATUS_ID and int(values["KineticFaults"]) & KINETIC_FORCE_STALE:
                stale_after = periods_seen
                break
        expect(stale_after is not None and stale_after <= 3,
               f"BoxStatus with the force stale bit within 3 periods of the silence (after {stale_after})")
        expect(any(v["InputsStale"] == 1 for s, i, v in after if i == ESTIMATE_ID and s < first_after),
               "estimate flagged InputsStale (held) during the silence")
        back = [d for d in decoded if d[0] > first_after]
        periods_seen = 0
        for stamp, ident, values in back:
            if ident == ESTIMATE_ID:
                periods_seen += 1
            if ident == STATUS_ID and not (int(values["KineticFaults"]) & (KINETIC_FORCE_STALE | KINETIC_TORQUE_STALE)) \
                    and not (int(values["DriverFaults"]) & DRIVER_FORCE_STALE):
                recovered_after = periods_seen
                break
        expect(recovered_after is not None and recovered_after <= 3,
               f"BoxStatus with the stale bits cleared within 3 periods of the cell's return (after {recovered_after})")

    # --- error frames ----------------------------------------------------------------------------
    box = stats["box"]
    expect(box["can_error_frames"] == 2, f"2 error frames counted ({box['can_error_frames']})")
    expect(box["can_bus_off_events"] == 1, f"1 bus-off counted ({box['can_bus_off_events']})")
    expect(box["can_recoveries"] == 1, f"1 recovery counted ({box['can_recoveries']})")
    expect(any(d[1] == STATUS_ID and d[2]["CanState"] == 3 for d in decoded), "a BoxStatus reported bus-off")

    # --- the box's own record ---------------------------------------------------------------------
    record = read_candump(os.path.join(out_dir, "box_record.log.gz"))
    key = lambda f: (f[1], f[2], f[3])
    record_box = sorted(key(f) for f in record if STATUS_ID <= f[1] <= STATION_ID and not f[2])
    bus_box = sorted(key(f) for f in bus if STATUS_ID <= f[1] <= STATION_ID and not f[2])
    expect(record_box == bus_box, f"--record has the box's {len(bus_box)} frames as candump saw them ({len(record_box)})")
    record_inputs = sum(1 for f in record if f[1] in (FORCE_ID, ENCODER_ID) and not f[2])
    expect(record_inputs == sent["total"], f"--record has every input frame ({record_inputs})")

    result = {"input_frames_sent": sent["total"], "box_received": stats["can"]["received"],
              "kernel_dropped": stats["can"]["dropped"], "periods": periods,
              "period_overruns": stats["period_overruns"], "box_frames_decoded": len(decoded),
              "final_tip_path_mm": final_tip, "stale_reported_after_periods": stale_after,
              "recovered_after_periods": recovered_after, "error_frames": box["can_error_frames"],
              "failures": failures}
    with open(os.path.join(out_dir, "check.json"), "w") as f:
        json.dump(result, f, indent=2)
    print(json.dumps(result, indent=2))
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        return 1
    print("scopekin-box on vcan0: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
