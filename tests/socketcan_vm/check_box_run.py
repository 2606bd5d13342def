#!/usr/bin/python3
"""Checks what scopekin-box did on the VM's vcan0 (files written by box_on_vcan.sh).

usage: check_box_run.py OUT_DIR DBC INPUT_SUMMARY_JSON

The machine may be slow or busy (TCG, sanitizers, other jobs): what is checked at any speed, and
what only where the box kept its deadline.

At any speed:
* nothing crashed (every program exit 0), every input frame accounted for: received by the box or
  counted as dropped by the kernel (SO_RXQ_OVFL), every received frame taken as a valid sample,
  no unknown identifier, bad length, range or status fault;
* every drop and every overrun flagged: in the box's fault log each growth of the drop count comes
  with kBoxFaultReceiveDropped (DriverFaults bit 9) and each overrun with kBoxFaultPeriodOverrun
  (bit 13); the bits reach the bus in a BoxStatus, the counts in BoxCounters; after the last drop
  the bit clears (the box recovers);
* the protocol: a KineticEstimate, ContactSummary, Alarms, EstimateEvidence and BoxCounters frame
  per period, a valid estimate that follows the advance;
* the force cell's 0.3 s silence (found by frame count: a starved canplayer leaves other pauses,
  counted): the stale bit in a BoxStatus, InputsStale on the estimate, the cell reported lost
  (KineticFaults bit 14, protocol 1.4) in the 20th force-stale period in a row and in no other
  period by the box's own fault log (from the first period with every input fresh: the estimator
  counts from its first insertion sample), and on the bus in a BoxStatus after the silence began; the
  bits cleared after the cell's return.  Where the box ran no late period within 20 periods of
  the silence's edges (a box that fell behind reads the returning samples late: rightly not
  fresh, flagged as a backlog): stale and cleared within 3 periods each (counted in
  KineticEstimate frames, i.e. box periods, not in wall time), and, where the silence lasted
  0.15 s or more on the bus, 20 stale periods reached;
* the EM tracker on the serial line (--serial): every frame it wrote taken as a valid sample,
  counted in BoxCounters.serial_frames, no serial fault from the first clear period until the
  tracker paused (fault log and BoxStatus.TrackerFaults; a stale bit only where the guest
  starved the tracker, by its own report);
* the injected error frames: counted, bus-off reported and recovered;
* the box's own --record log has the frames it received and sent as candump saw them.

Only where the box kept its deadline: nothing dropped at all (kernel drop counter 0, no
rolling-counter gap, every frame canplayer sent received).  The box kept its deadline if it was
built without sanitizers and never fell more than MAX_LAG_PERIODS periods (50 ms, 100 input
frames) behind its schedule at a time: the socket's receive buffer (~425 KB: ~475 frames,
0.24 s of both sensors) cannot fill then.  A period or two lost now and then (TCG translating
the code of the first periods, another process starting) is not a missed deadline in this sense;
a box that reports longer overruns, or runs under AddressSanitizer, may drop, and then the
checks above say whether it counted, flagged and reported every drop.

Prints a summary and writes OUT_DIR/check.json; exit status 1 on any failure.
"""
import json
import os
import sys

import canmatrix.formats

from box_logs import (
    COUNTER_INDEX, COUNTERS_ID, DRIVER_FORCE_STALE, DRIVER_PERIOD_OVERRUN, DRIVER_RECEIVE_DROPPED,
    ENCODER_ID, ESTIMATE_ID, FORCE_ID, KINETIC_FORCE_BLIND, KINETIC_FORCE_STALE, KINETIC_STALE, KINETIC_TORQUE_STALE, STATION_ID,
    STATUS_ID, SUMMARY_ID, ALARMS_ID, EVIDENCE_ID, TRACKER_STALE, FORCE_BLIND_AFTER_PERIODS, FaultLog, bit_runs,
    check_flags_account, decode_box_frames,
    longest_lag_periods, read_candump, read_marks)

PERIOD_US = 5000
MAX_LAG_PERIODS = 10


def main():
    out_dir, dbc_path, summary_path = sys.argv[1:4]
    with open(summary_path) as f:
        sent = json.load(f)
    with open(os.path.join(out_dir, "box_stats.json")) as f:
        stats = json.load(f)
    with open(os.path.join(out_dir, "tracker.json")) as f:
        tracker_report = json.load(f)
    db = canmatrix.formats.loadp_flat(dbc_path)
    log = FaultLog(os.path.join(out_dir, "box_faults.csv"), PERIOD_US)
    marks = read_marks(os.path.join(out_dir, "marks.txt"))
    failures = []

    def expect(condition, what):
        if not condition:
            failures.append(what)

    sanitized = stats["build"]["address_sanitizer"]
    overruns = stats["period_overruns"]
    lag = longest_lag_periods(log)
    kept_deadline = not sanitized and lag <= MAX_LAG_PERIODS
    handle = stats["handle_sensors"]
    can = stats["can"]
    received, dropped = can["received"], can["dropped"]

    with open(os.path.join(out_dir, "exit_status.txt")) as f:
        expect(f.read().split() == ["canplayer=0", "scopekin-box=0"], "canplayer and scopekin-box exit 0")

    # --- every input frame accounted for (any speed) -------------------------------------------
    expect(received + dropped == sent["total"],
           f"box received {received} + kernel dropped {dropped} = {received + dropped} frames, "
           f"canplayer sent {sent['total']}")
    expect(handle["force_torque_samples"] + handle["insertion_roll_samples"] == received,
           "every received frame taken as a valid sample")
    expect(handle["force_torque_samples"] <= sent["frames"]["HandleForceTorque"]
           and handle["insertion_roll_samples"] <= sent["frames"]["InsertionRoll"],
           "no sample counted twice")
    for key in ("bad_length", "out_of_range", "sensor_status"):
        expect(handle[key] == 0, f"handle_sensors.{key} == 0")
    expect(stats["box"]["unknown_ids"] == 0, "no unknown identifiers")
    expect(stats["box"]["send_failures"] == 0, f"{stats['box']['send_failures']} send failures")
    expect(stats["record"]["write_errors"] == 0, "record written without errors")

    # --- nothing dropped, where the box kept its deadline --------------------------------------
    if kept_deadline:
        expect(received == sent["total"], f"box received {received} data frames, canplayer sent {sent['total']}")
        expect(dropped == 0, f"kernel dropped {dropped} frames")
        expect(handle["counter_gaps"] == 0, f"{handle['counter_gaps']} rolling-counter gaps")

    # --- every drop and overrun flagged and reported (any speed) ---------------------------------
    check_flags_account(log, expect)
    expect(log.rows[-1]["can_dropped"] == dropped and log.rows[-1]["period_overruns"] == overruns,
           "the fault log's last row has the final drop and overrun counts")
    bus, observer_drops = read_candump(os.path.join(out_dir, "candump.log.gz"))
    expect(observer_drops == 0, f"candump (the observer, not the box) lost {observer_drops} frames")
    decoded = decode_box_frames(db, bus, failures)
    statuses = [d for d in decoded if d[1] == STATUS_ID]
    counters = {}
    for _, ident, values in decoded:
        if ident == COUNTERS_ID:
            counters.setdefault(int(values["CounterIndex"]), []).append(int(values["CounterValue"]))
    if dropped > 0:
        expect(any(int(v["DriverFaults"]) & DRIVER_RECEIVE_DROPPED for _, _, v in statuses),
               "a BoxStatus reported the drops (DriverFaults bit 9)")
        last_drop = max(r["period"] for r in log.rows if r["driver_faults"] & DRIVER_RECEIVE_DROPPED)
        expect(any(r["period"] > last_drop and not r["driver_faults"] & DRIVER_RECEIVE_DROPPED
                   for r in log.rows), "kBoxFaultReceiveDropped cleared after the last drop")
    expect(counters.get(COUNTER_INDEX["can_dropped"], [0])[-1] == dropped,
           f"BoxCounters can_dropped ends at the box's count {dropped} "
           f"({counters.get(COUNTER_INDEX['can_dropped'], [None])[-1]})")
    if overruns > 0:
        expect(any(int(v["DriverFaults"]) & DRIVER_PERIOD_OVERRUN and v["PeriodOverruns"] > 0
                   for _, _, v in statuses),
               "a BoxStatus reported an overrun (DriverFaults bit 13, PeriodOverruns)")
        reported = counters.get(COUNTER_INDEX["period_overruns"], [0])
        expect(0 < reported[-1] <= overruns, f"BoxCounters period_overruns reported ({reported[-1]} of {overruns})")

    # --- the protocol ---------------------------------------------------------------------------
    estimates = [d for d in decoded if d[1] == ESTIMATE_ID]
    periods = stats["periods"]
    for ident, name in ((ESTIMATE_ID, "KineticEstimate"), (SUMMARY_ID, "ContactSummary"),
                        (ALARMS_ID, "Alarms"), (EVIDENCE_ID, "EstimateEvidence"),
                        (COUNTERS_ID, "BoxCounters")):
        count = sum(1 for d in decoded if d[1] == ident)
        expect(count == periods, f"{count} {name} frames for {periods} periods")
    expect(all(d[2]["EstimateValid"] == 1 for d in estimates), "every estimate valid")
    expect(all(d[2]["ContactForceLevel"] <= 2 and d[2]["AlarmsValid"] == 1 for d in decoded if d[1] == ALARMS_ID),
           "alarm frames valid")
    final_tip = estimates[-1][2]["TipPath"] if estimates else 0.0
    expect(final_tip > 300.0, f"final tip path {final_tip:.1f} mm follows the 100 -> 600 mm advance")

    # --- the force cell's silence ----------------------------------------------------------------
    inputs = [(i, f) for i, f in enumerate(bus) if f[1] in (FORCE_ID, ENCODER_ID) and not f[2]]
    expect(len(inputs) == sent["total"], f"candump saw {len(inputs)} input frames of {sent['total']}")
    force = [(i, f[0]) for i, f in inputs if f[1] == FORCE_ID]
    # The intended silence by frame count (the log has a force frame every ms before it), not by
    # time: a player the guest starved leaves other pauses in the bus (counted, not failed).
    before = sent["gap_first_missing_ms"]
    expect(len(force) == sent["frames"]["HandleForceTorque"] and 0 < before < len(force),
           f"candump saw {len(force)} force frames of {sent['frames']['HandleForceTorque']}")
    starved_pauses = sum(1 for a, b in zip(force, force[1:]) if b[1] - a[1] > 0.1) - 1
    stale_after = recovered_after = silence_on_bus_s = None
    silence_judged = True
    if 0 < before < len(force):
        (last_before, _), (first_after, _) = force[before - 1], force[before]
        # 0.3 s in the log; on the bus shorter if canplayer was starved just before it.
        silence_on_bus_s = force[before][1] - force[before - 1][1]
        periods_seen = 0
        for index, ident, values in decoded:
            if index < last_before:
                continue
            if ident == ESTIMATE_ID:
                periods_seen += 1
            if ident == STATUS_ID and int(values["KineticFaults"]) & KINETIC_FORCE_STALE:
                stale_after = periods_seen
                break
        expect(any(v["InputsStale"] == 1 for i, d, v in decoded if d == ESTIMATE_ID and last_before < i < first_after),
               "estimate flagged InputsStale (held) during the silence")
        # Lost in the 20th stale period in a row, by the box's own count (its fault log has every
        # period it ran, whatever its speed): bit 14 in exactly those periods, and the silence's
        # run of stale periods, where it reached 20, reported in a BoxStatus after the silence began.
        # The estimator counts from its first insertion sample on (kinetics.cpp: no estimate
        # before it): a run that began before the box first had all its inputs fresh (the start,
        # longer under AddressSanitizer) is only checked not to report the loss too early.
        last_period = stats["periods"]
        stale_runs = bit_runs(log, "kinetic_faults", KINETIC_FORCE_STALE, last_period)
        blind_runs = bit_runs(log, "kinetic_faults", KINETIC_FORCE_BLIND, last_period)
        ready = next((r["period"] for r in log.rows if not r["kinetic_faults"] & KINETIC_STALE), last_period + 1)
        expected_blind = [(first + FORCE_BLIND_AFTER_PERIODS - 1, last) for first, last in stale_runs
                          if last - first + 1 >= FORCE_BLIND_AFTER_PERIODS and first >= ready]
        judged_blind = [run for run in blind_runs if run[0] >= ready]
        early_blind = [(a, b) for a, b in blind_runs if a < ready
                       and not any(a >= first + FORCE_BLIND_AFTER_PERIODS - 1 and b <= last
                                   for first, last in stale_runs)]
        expect(judged_blind == expected_blind and not early_blind,
               f"KineticFaults bit 14 in the periods {blind_runs[:4]}, from the 20th of each run of force-stale "
               f"periods {expected_blind[:4]} (inputs all fresh first in period {ready})")
        # The box's period at an edge of the silence: its KineticEstimate frames before it on the
        # bus (one per period, checked above).
        edges = [sum(1 for i, d, _ in decoded if d == ESTIMATE_ID and i < edge)
                 for edge in (last_before, first_after)]
        silent_periods = edges[1] - edges[0]
        silence_blind = any(first <= edges[1] and last >= edges[0] for first, last in expected_blind)
        if silence_blind:
            expect(any(int(v["KineticFaults"]) & KINETIC_FORCE_BLIND
                       for i, d, v in decoded if d == STATUS_ID and i > last_before),
                   f"the force cell reported lost (KineticFaults bit 14) on the bus after {silent_periods} "
                   f"periods of silence")
        periods_seen = 0
        for index, ident, values in decoded:
            if index < first_after:
                continue
            if ident == ESTIMATE_ID:
                periods_seen += 1
            if ident == STATUS_ID and not (int(values["KineticFaults"]) & (KINETIC_FORCE_STALE | KINETIC_TORQUE_STALE)) \
                    and not (int(values["DriverFaults"]) & DRIVER_FORCE_STALE):
                recovered_after = periods_seen
                break
        # "Within 3 periods" holds where the box kept its schedule around the silence's edges;
        # a box that fell behind there reads the returning samples late (a backlog: rightly not
        # fresh, kBoxFaultReceiveBacklog) and must only recover.
        lagging = [r["period"] for r in log.rows
                   if any(edge <= r["period"] <= edge + 20 for edge in edges)
                   and r["driver_faults"] & DRIVER_PERIOD_OVERRUN]
        silence_judged = not lagging
        # 20 periods are 0.1 s: judged where the silence lasted 0.15 s or more on the bus (a player
        # starved just before it shortens it) and the box kept its schedule at its edges.
        expect(silence_blind or not silence_judged or silence_on_bus_s < 0.15,
               f"the silence ({silent_periods} box periods, {silence_on_bus_s:.2f} s on the bus) reached "
               f"20 force-stale periods in a row")
        expect(stale_after is not None and (stale_after <= 3 or not silence_judged),
               f"BoxStatus with the force stale bit within 3 periods of the silence (after {stale_after})")
        expect(recovered_after is not None and (recovered_after <= 3 or not silence_judged),
               f"BoxStatus with the stale bits cleared within 3 periods of the cell's return (after {recovered_after})")

    # --- the EM tracker on the serial line -------------------------------------------------------
    tracker = stats["em_tracker"]
    serial = stats["serial"]
    written = tracker_report["frames"]
    # The box opens the line, then flushes it: a frame written in between is lost to the box.
    expect(written - 1 <= tracker["frames_ok"] <= written,
           f"the box took {tracker['frames_ok']} valid tracker frames of the {written} written")
    expect(tracker["poses_ok"] + tracker["tip_forces_ok"] == tracker["frames_ok"],
           "every tracker frame a valid sample")
    for key in ("bad_checksum", "bad_length", "unknown_type", "bytes_discarded", "buffer_overflows",
                "unknown_sensor", "out_of_range", "quaternion_norm", "timestamp_backwards",
                "device_status", "samples_dropped", "serial_closed", "serial_errors"):
        expect(tracker[key] == 0, f"em_tracker.{key} == 0 ({tracker[key]})")

    expect(serial["hangups"] == 0 and serial["device_open"], "the serial line stayed up")
    reported_serial = counters.get(COUNTER_INDEX["serial_frames"], [0])
    expect(0 < reported_serial[-1] <= tracker["frames_ok"],
           f"BoxCounters serial_frames reported ({reported_serial[-1]} of {tracker['frames_ok']})")
    clear = [r for r in log.rows if r["tracker_faults"] == 0]
    first_clear = clear[0]["period"] if clear else None
    expect(first_clear is not None and first_clear <= 30,
           f"every tracker source fresh within 30 periods of the start (period {first_clear}; "
           f"the tracker writes 50 ms after the box opened the line, a cycle takes 33 ms)")
    pause = marks["tracker_pause"]
    # A source is stale after 100 ms without a sample; a tracker the guest starved (late by 60 ms
    # or more: a source's gap reached 33 + 60 ms) may rightly be flagged stale for a while.
    starved = [(due, end + 100_000 + 2 * PERIOD_US)
               for due, end, late in tracker_report.get("late_episodes", []) if late >= 60_000]
    # A period runs between its release and the next row's (it may run late: an overrun).
    runs = [(r, r["monotonic_us"], n["monotonic_us"] if n else r["monotonic_us"] + PERIOD_US)
            for r, n in zip(log.rows, log.rows[1:] + [None])]
    tracker_faulty = [r["period"] for r, run_from, run_to in runs
                      if first_clear is not None and r["period"] > first_clear
                      and r["monotonic_us"] < pause and r["tracker_faults"] != 0
                      and not (r["tracker_faults"] == TRACKER_STALE
                               and any(run_from <= b and a <= run_to for a, b in starved))]
    expect(not tracker_faulty, f"no serial fault while the tracker streamed (periods {tracker_faulty[:5]})")
    measured_tracker_starved_ms = max((late for *_, late in tracker_report.get("late_episodes", [])), default=0) // 1000
    # On the bus: TrackerFaults non-zero only before the first clear BoxStatus and after the pause
    # (then only the stale bit): the pattern nonzero* zero+ stale*.
    pattern = "".join("z" if int(v["TrackerFaults"]) == 0 else
                      ("s" if int(v["TrackerFaults"]) == 1 else "x") for _, _, v in statuses)
    stripped = pattern.lstrip("sx").rstrip("s")
    expect(stripped and set(stripped) <= ({"z", "s"} if starved else {"z"}),
           f"BoxStatus.TrackerFaults clear while the tracker streamed ({pattern[:12]}...{pattern[-12:]})")

    # --- error frames ----------------------------------------------------------------------------
    box = stats["box"]
    expect(box["can_error_frames"] == 2, f"2 error frames counted ({box['can_error_frames']})")
    expect(box["can_bus_off_events"] == 1, f"1 bus-off counted ({box['can_bus_off_events']})")
    expect(box["can_recoveries"] == 1, f"1 recovery counted ({box['can_recoveries']})")
    expect(any(v["CanState"] == 3 for _, _, v in statuses), "a BoxStatus reported bus-off")

    # --- the box's own record ---------------------------------------------------------------------
    record, _ = read_candump(os.path.join(out_dir, "box_record.log.gz"))
    key = lambda f: (f[1], f[2], f[3])
    record_box = sorted(key(f) for f in record if STATUS_ID <= f[1] <= STATION_ID and not f[2])
    bus_box = sorted(key(f) for f in bus if STATUS_ID <= f[1] <= STATION_ID and not f[2])
    expect(record_box == bus_box, f"--record has the box's {len(bus_box)} frames as candump saw them ({len(record_box)})")
    record_inputs = sum(1 for f in record if f[1] in (FORCE_ID, ENCODER_ID) and not f[2])
    expect(record_inputs == received, f"--record has every input frame the box received ({record_inputs} of {received})")

    result = {"box_build": stats["build"], "kept_deadline": kept_deadline,
              "input_frames_sent": sent["total"], "box_received": received,
              "kernel_dropped": dropped, "counter_gaps": handle["counter_gaps"], "periods": periods,
              "period_overruns": overruns, "longest_lag_periods": lag,
              "box_frames_decoded": len(decoded),
              "final_tip_path_mm": final_tip, "stale_reported_after_periods": stale_after,
              "recovered_after_periods": recovered_after, "silence_timing_judged": silence_judged,
              "silence_on_bus_s": silence_on_bus_s,
              "player_starved_pauses": starved_pauses, "error_frames": box["can_error_frames"],
              "tracker_frames_written": written, "tracker_frames_taken": tracker["frames_ok"],
              "tracker_late_max_ms": measured_tracker_starved_ms,
              "fault_log_rows": len(log.rows), "failures": failures}
    with open(os.path.join(out_dir, "check.json"), "w") as f:
        json.dump(result, f, indent=2)
    print(json.dumps(result, indent=2))
    print(f"box build: {'AddressSanitizer' if sanitized else 'no sanitizer'}; {overruns} of {periods} periods "
          f"overran (longest lag {lag} periods); kernel dropped {dropped} frames; "
          + ("zero-drop checks applied" if kept_deadline else
             "zero-drop checks skipped (the box did not keep its deadline): drops and overruns must be "
             "counted, flagged and reported"))
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        return 1
    print("scopekin-box on vcan0: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
