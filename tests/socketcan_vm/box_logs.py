"""Readers shared by check_box_run.py and check_box_faults.py: what scopekin-box and its peers
left in the VM test's /out folder.

* read_candump: candump -L logs (plain or .gz), and the DROPCOUNT lines candump -d writes into
  them (frames the observer lost);
* decode_box_frames: the box's frames decoded with python3-canmatrix from scopekin.dbc;
* FaultLog: scopekin-box --fault-log (one row per change of the fault state), with period_at():
  the period released at or after a CLOCK_MONOTONIC time; longest_lag_periods(), and
  check_flags_account(): every drop and overrun flagged;
* read_marks: the guest script's marks (NAME -> CLOCK_MONOTONIC µs).
"""
import csv
import gzip
import math
import re

FORCE_ID, ENCODER_ID = 0x110, 0x111
STATUS_ID, ESTIMATE_ID, SUMMARY_ID, ALARMS_ID, COUNTERS_ID, EVIDENCE_ID, STATION_ID = (
    0x180, 0x181, 0x182, 0x183, 0x184, 0x185, 0x190)

# BoxStatus.DriverFaults (firmware/messages/box_faults.hpp)
DRIVER_FORCE_STALE, DRIVER_ENCODER_STALE = 1 << 0, 1 << 1
DRIVER_COUNTER_GAP, DRIVER_BUS_OFF = 1 << 6, 1 << 8
DRIVER_RECEIVE_DROPPED, DRIVER_SEND_FAILED = 1 << 9, 1 << 10
DRIVER_SERIAL_FRAMING, DRIVER_TRACKER_STALE, DRIVER_PERIOD_OVERRUN = 1 << 11, 1 << 12, 1 << 13
DRIVER_RECEIVE_BACKLOG = 1 << 14
DRIVER_STALE = DRIVER_FORCE_STALE | DRIVER_ENCODER_STALE | DRIVER_TRACKER_STALE
# BoxStatus.TrackerFaults
TRACKER_STALE, TRACKER_FRAMING, TRACKER_LINK = 1 << 0, 1 << 6, 1 << 7
# BoxStatus.KineticFaults (kinetics::FaultFlag): the four stale bits
KINETIC_INSERTION_STALE, KINETIC_FORCE_STALE = 1 << 0, 1 << 3
KINETIC_TORQUE_STALE, KINETIC_ROLL_STALE = 1 << 5, 1 << 7
KINETIC_STALE = (KINETIC_INSERTION_STALE | KINETIC_FORCE_STALE | KINETIC_TORQUE_STALE
                 | KINETIC_ROLL_STALE)
# ... and the force cell lost: stale 20 periods in a row (protocol 1.4)
KINETIC_FORCE_BLIND = 1 << 14
# kinetics::Config::force_blind_after_steps, the box's default: the force cell is reported lost in
# the 20th stale period in a row.
FORCE_BLIND_AFTER_PERIODS = 20
# BoxCounters.CounterIndex (protocol::BoxCounterIndex)
COUNTER_INDEX = {"can_received": 0, "can_dropped": 1, "can_error_frames": 2, "can_bus_off": 3,
                 "can_send_failures": 4, "serial_frames": 10, "period_overruns": 13}
CAN_STATE_BUS_OFF = 3

_DROPCOUNT = re.compile(r"DROPCOUNT: dropped (\d+) CAN frame")


def read_candump(path):
    """Returns (frames, observer_drops): frames as (stamp_s, id, extended, data bytes), in the
    order of the file; observer_drops = frames candump itself lost (its -d DROPCOUNT lines)."""
    frames = []
    drops = 0
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as log:
        for number, line in enumerate(log, 1):
            parts = line.split()
            if not parts:
                continue
            dropped = _DROPCOUNT.search(line)
            if dropped:
                drops += int(dropped.group(1))
                continue
            if len(parts) != 3 or "#" not in parts[2]:
                raise SystemExit(f"{path}:{number}: not a candump log line: {line!r}")
            stamp = float(parts[0].strip("()"))
            ident, data = parts[2].split("#", 1)
            frames.append((stamp, int(ident, 16), len(ident) == 8,
                           bytes.fromhex(data.replace(".", ""))))
    return frames, drops


def decode_box_frames(db, frames, failures):
    """The box's frames (0x180..0x190, standard ids) decoded: (index in frames, id, values)."""
    import canmatrix
    decoded = []
    for index, (_, ident, extended, data) in enumerate(frames):
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
        decoded.append((index, ident, values))
    return decoded


class FaultLog:
    """scopekin-box --fault-log rows (dicts with int fields) and the period of a time."""

    def __init__(self, path, period_us):
        self.period_us = period_us
        with open(path) as f:
            self.rows = []
            for row in csv.DictReader(f):
                parsed = {}
                for key, value in row.items():
                    parsed[key] = value if key in ("box_state", "can_state") else int(value, 0)
                self.rows.append(parsed)
        if not self.rows:
            raise SystemExit(f"{path}: no rows")

    @classmethod
    def from_rows(cls, log, rows):
        """A FaultLog of some of `log`'s rows (for longest_lag_periods over a window)."""
        part = cls.__new__(cls)
        part.period_us = log.period_us
        part.rows = list(rows)
        return part

    def period_at(self, monotonic_us):
        """The first period released at or after `monotonic_us`.  Exact: between two rows the
        periods are one period apart (an overrun writes a row)."""
        before = [r for r in self.rows if r["monotonic_us"] <= monotonic_us]
        if not before:
            return self.rows[0]["period"]
        row = before[-1]
        return row["period"] + math.ceil((monotonic_us - row["monotonic_us"]) / self.period_us)

    def rows_between(self, first_us, last_us):
        return [r for r in self.rows if first_us <= r["monotonic_us"] <= last_us]

    def state_at(self, period):
        """The row in force in `period` (the last row at or before it)."""
        current = None
        for row in self.rows:
            if row["period"] > period:
                break
            current = row
        return current


def read_marks(path):
    marks = {}
    with open(path) as f:
        for line in f:
            name, value = line.split()
            marks[name] = int(value)
    return marks


def bit_runs(log, column, bit, last_period):
    """The runs of periods (first, last) in which `bit` of `column` is set, by the fault log (a row
    is written at each change, so between two rows the state is the first row's; the last row's
    state lasts to `last_period`)."""
    runs, first = [], None
    for row in log.rows:
        if row[column] & bit and first is None:
            first = row["period"]
        elif not row[column] & bit and first is not None:
            runs.append((first, row["period"] - 1))
            first = None
    if first is not None:
        runs.append((first, last_period))
    return runs


def longest_lag_periods(log):
    """The longest stretch the box fell behind its schedule, in periods: the overruns counted in
    consecutive periods, summed (a period that overran writes a row)."""
    longest = current = 0
    previous = None
    for row in log.rows:
        grew = previous is not None and row["period_overruns"] > previous["period_overruns"]
        if grew:
            step = row["period_overruns"] - previous["period_overruns"]
            current = current + step if row["period"] == previous["period"] + 1 else step
            longest = max(longest, current)
        else:
            current = 0
        previous = row
    return longest


def check_flags_account(log, expect):
    """Every drop and every overrun the box counted was flagged in a period (the fault log's
    counts and bits): the count grows from one row to the next only if the bit is set in one of
    them (drops: in the periods between two rows the state is the first row's), resp. in the
    second (an overrun always writes a row)."""
    for a, b in zip(log.rows, log.rows[1:]):
        if b["can_dropped"] > a["can_dropped"]:
            expect((a["driver_faults"] | b["driver_faults"]) & DRIVER_RECEIVE_DROPPED,
                   f"{b['can_dropped'] - a['can_dropped']} frames dropped between periods "
                   f"{a['period']} and {b['period']} without kBoxFaultReceiveDropped")
        if b["period_overruns"] > a["period_overruns"]:
            expect(b["driver_faults"] & DRIVER_PERIOD_OVERRUN,
                   f"overrun in period {b['period']} without kBoxFaultPeriodOverrun")
        if b["driver_faults"] & DRIVER_PERIOD_OVERRUN:
            expect(b["period_overruns"] > a["period_overruns"],
                   f"period {b['period']} flagged an overrun that was not counted")
