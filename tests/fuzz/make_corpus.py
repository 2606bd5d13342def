#!/usr/bin/env python3
"""Writes the libFuzzer seed corpora tests/fuzz/corpus/<target>/ (deterministic: same files, same
bytes on every run; the script owns those folders and rewrites them completely).

    python3 tests/fuzz/make_corpus.py            # from the repository root or anywhere

can_decoders       the input layout of fuzz_can_decoders.cpp: [selector][flags|length][data]:
                   valid frames of every message of scopekin.dbc (read here with a minimal
                   parser of its BO_/SG_/VAL_ lines; no canmatrix needed), all-zero and all-ones
                   data, undefined enumeration values, wrong lengths, extended/remote/error
                   frames, unknown identifiers.
candump_parser     candump -L lines: every message, 29-bit ids, error frames, remote frames (with
                   and without a length), '.' separators, CRLF, blank lines, CAN FD, garbage, and
                   the regression inputs of what the fuzzer found.

em_tracker_driver  scripts of fuzz_em_tracker_driver.cpp: poses of every sensor, tip forces, a
                   source going stale and back, every sample fault, closed/failed/short reads, a
                   512-byte receive(), noise, and the framer's seeds as receive() operations.
handle_sensors     scripts of fuzz_handle_sensors.cpp: both sensors at 1 kHz, stale and back,
                   late samples, counter gaps and status, raw frames from the DBC (wrong lengths,
                   flags, foreign ids), a receive clock behind the period clock.
sensor_box         scripts of fuzz_sensor_box.cpp: an advance with EM and tip force samples,
                   silence, no serial port, a foreign-frame flood and a burst beyond the queue, a
                   stall, error frames and bus-off, overruns and clock jumps, serial noise, and
                   the regression input of what the fuzzer found.
recording_reader   recording CSV files (RECORDING.md): every group, CRLF with a byte-order mark,
                   reordered and extra columns, the wire's limits, and refused ones (time going
                   back, a 61 s gap, 1e309, an unknown region, half a group, a 300-digit cell).
strict_json,       the repository's JSON files (model/scenarios, model/problems, model/reduction,
scenario           host_sim/scenarios, tests/model/data, tests/host_sim/cli/data) plus edge cases
                   (nesting 64/65/70 deep, duplicate keys, 1e400, escapes, bad UTF-8, a BOM).
candump_replay     candump logs: a sensor log, a box log (inputs, then the period's outputs),
                   foreign/error/extended/remote frames, blank lines and CRLF, and refused ones
                   (a time stamp going back, a gap over 60 s, a malformed line).

Dictionaries are in tests/fuzz/dict/ (written by hand), except dict/scenario.dict, which this
script writes from the keys model/**/*.cpp reads.

The EM tracker framer's seeds are its author's: tests/hal/serial/fuzz_corpus/em_tracker_framer/
(written by tests/hal/serial/make_em_tracker_framer_seeds.py).
"""

import binascii
import random
import re
import shutil
import struct
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DBC = ROOT / "firmware" / "protocol" / "scopekin.dbc"
CORPUS = HERE / "corpus"
FRAMER_SEEDS = ROOT / "tests" / "hal" / "serial" / "fuzz_corpus" / "em_tracker_framer"


# ---- scopekin.dbc (only what the seeds need) ----------------------------------------------------

class Signal:
    def __init__(self, name, start, size, signed):
        self.name, self.start, self.size, self.signed = name, start, size, signed
        self.values = None  # VAL_ table keys, if any

    def raw_range(self):
        if self.signed:
            return -(1 << (self.size - 1)), (1 << (self.size - 1)) - 1
        return 0, (1 << self.size) - 1


class Message:
    def __init__(self, name, frame_id, length):
        self.name, self.id, self.length, self.signals = name, frame_id, length, []

    def pack(self, raws):
        bits = 0
        for signal in self.signals:
            raw = raws[signal.name] & ((1 << signal.size) - 1)
            bits |= raw << signal.start
        return bits.to_bytes(8, "little")[: self.length]


def read_dbc(path):
    messages, by_id = [], {}
    current = None
    for line in path.read_text().splitlines():
        match = re.match(r"BO_ (\d+) (\w+): (\d+)", line)
        if match:
            current = Message(match[2], int(match[1]), int(match[3]))
            messages.append(current)
            by_id[current.id] = current
            continue
        match = re.match(r"\s+SG_ (\w+) : (\d+)\|(\d+)@1([+-])", line)
        if match and current is not None:
            current.signals.append(Signal(match[1], int(match[2]), int(match[3]), match[4] == "-"))
            continue
        match = re.match(r"VAL_ (\d+) (\w+) (.*);", line)
        if match:
            keys = {int(key) for key in re.findall(r"(\d+) \"", match[3])}
            for signal in by_id[int(match[1])].signals:
                if signal.name == match[2]:
                    signal.values = keys
    return sorted(messages, key=lambda m: m.id)  # the order of message_layouts()


def valid_raws(message, rng):
    raws = {}
    for signal in message.signals:
        if signal.values:
            raws[signal.name] = rng.choice(sorted(signal.values))
        else:
            low, high = signal.raw_range()
            # Small magnitudes: physical values within Q16.16 for every signal (Insertion too).
            raws[signal.name] = rng.randint(max(low, -3000), min(high, 3000))
    return raws


# ---- can_decoders ---------------------------------------------------------------------------------

EXTENDED, REMOTE, ERROR = 0x10, 0x20, 0x40


def can_input(selector, flags, length, data, frame_id=None):
    head = bytes([selector, flags | length])
    if frame_id is not None:
        head += struct.pack("<I", frame_id)
    return head + bytes(data)


def can_decoder_seeds(messages, rng):
    seeds = {}
    for index, message in enumerate(messages):
        name = message.name
        for k in range(2):
            data = message.pack(valid_raws(message, rng))
            seeds[f"{name}_valid{k}"] = can_input(index, 0, message.length, data)
        seeds[f"{name}_zero"] = can_input(index, 0, message.length, bytes(message.length))
        seeds[f"{name}_ones"] = can_input(index, 0, message.length, b"\xff" * message.length)
        good = message.pack(valid_raws(message, rng))
        seeds[f"{name}_short"] = can_input(index, 0, message.length - 1, good[:-1])
        seeds[f"{name}_long"] = can_input(index, 0, 9 + index % 7, good + b"\x00" * 8)
        seeds[f"{name}_extended"] = can_input(index, EXTENDED, message.length, good)
        seeds[f"{name}_remote"] = can_input(index, REMOTE, message.length, b"")
        for signal in message.signals:
            if signal.values is not None and len(signal.values) < (1 << signal.size):
                bad = max(set(range(signal.raw_range()[1] + 1)) - signal.values)
                raws = valid_raws(message, rng)
                raws[signal.name] = bad
                seeds[f"{name}_undefined_{signal.name}"] = can_input(
                    index, 0, message.length, message.pack(raws))
    seeds["error_frame_bus_off"] = can_input(0xC0, ERROR, 8, bytes(8), 0x040)
    seeds["error_frame_controller"] = can_input(0xC0, ERROR, 8, bytes([0, 0x04] + [0] * 6), 0x004)
    seeds["unknown_id_7ff"] = can_input(0xC1, 0, 8, b"\x01\x02\x03\x04\x05\x06\x07\x08", 0x7FF)
    seeds["extended_id_of_box_status"] = can_input(0xC2, EXTENDED, 8, bytes(8), 0x180)
    seeds["extended_id_29bit"] = can_input(0xFF, EXTENDED, 4, b"\xde\xad\xbe\xef", 0x1FFFFFFF)
    seeds["empty"] = b""
    seeds["one_byte"] = b"\x00"
    return seeds


# ---- candump_parser -------------------------------------------------------------------------------

def candump_line(seconds, micros, interface, frame_id, data, extended=False):
    ident = f"{frame_id:08X}" if extended else f"{frame_id:03X}"
    return f"({seconds}.{micros:06d}) {interface} {ident}#{data.hex().upper()}\n".encode()


def candump_seeds(messages, rng):
    seeds = {}
    t = 1700000000
    for k, message in enumerate(messages):
        data = message.pack(valid_raws(message, rng))
        seeds[f"{message.name}"] = candump_line(t + k, 123456 + k, "vcan0", message.id, data)
    box = messages[0]
    good = box.pack(valid_raws(box, rng))
    seeds["extended_29bit"] = candump_line(t, 1, "can0", 0x12345678, b"\xde\xad\xbe\xef", True)
    seeds["error_frame_controller"] = b"(1700000000.124000) vcan0 20000004#0004000000000000\n"
    seeds["error_frame_bus_off"] = b"(1700000000.124001) vcan0 20000040#0000000000000000\n"
    seeds["remote"] = b"(1700000000.124100) vcan0 123#R\n"
    seeds["remote_length"] = b"(1700000000.124100) vcan0 123#R4\n"
    seeds["remote_extended"] = b"(1700000000.124100) vcan0 00000123#r8\n"
    seeds["dots"] = b"(1700000000.200000) vcan0 110#D0.07.00.00.00.02\n"
    seeds["empty_data"] = b"(0.000000) x 7FF#\n"
    seeds["crlf"] = candump_line(t, 5, "can1", box.id, good)[:-1] + b"\r\n"
    seeds["no_newline"] = candump_line(t, 6, "can1", box.id, good)[:-1]
    seeds["trailing_blanks"] = candump_line(t, 7, "can1", box.id, good)[:-1] + b"  \t \n"
    seeds["long_interface"] = candump_line(t, 8, "averylongname15", box.id, good)
    seeds["too_long_interface"] = candump_line(t, 9, "averylongname16x", box.id, good)
    seeds["max_seconds"] = candump_line(999999999999, 999999, "vcan0", box.id, good)
    seeds["blank"] = b"   \t\r\n"
    seeds["fd"] = b"(1700000000.300000) vcan0 123##1112233\n"
    seeds["nine_bytes"] = b"(1700000000.300000) vcan0 123#112233445566778899\n"
    seeds["odd_digits"] = b"(1700000000.300000) vcan0 123#112\n"
    seeds["bad_id_4_digits"] = b"(1700000000.300000) vcan0 1234#11\n"
    seeds["bad_timestamp"] = b"(1700000000.3) vcan0 123#11\n"
    seeds["garbage"] = bytes(rng.randrange(256) for _ in range(40))
    seeds["trailing_garbage"] = b"(1700000000.300000) vcan0 123#11 extra\n"
    # Found by this fuzzer (2 s): a NUL byte inside the interface name was accepted, so the record
    # held "v\x06" plus junk after its terminator and did not survive format -> parse.
    seeds["regression_interface_with_nul"] = (
        b"(1700000000.200000) v\x06\x00n1 110#D0.07.00.00.00.02\n")
    return seeds


# ---- em_tracker_driver ------------------------------------------------------------------------------
# The script of fuzz_em_tracker_driver.cpp: opcode & 7 = 0 raw bytes, 1 pose, 2 tip force,
# 3 service(dt), 4 receive(n bytes), 5 port faults, 6 poll(dt), 7 take flags + pop.

def em_frame(msg_type, payload):
    body = bytes([msg_type, len(payload)]) + payload
    return b"\xa5\x5a" + body + struct.pack("<H", binascii.crc_hqx(body, 0xFFFF))


def em_pose_operands(time_us, sensor, pos_um, quat, status=0):
    # u16 time, shift byte, sensor, status, 3 x (u16 low, u16 high), 4 x u16
    out = struct.pack("<HB", time_us & 0xFFFF, 0) + bytes([sensor, status])
    for value in pos_um:
        out += struct.pack("<I", value & 0xFFFFFFFF)
    for value in quat:
        out += struct.pack("<H", value & 0xFFFF)
    return out


def em_force_operands(time_us, force_mn, status=0):
    out = struct.pack("<HB", time_us & 0xFFFF, 0) + bytes([status])
    for value in force_mn:
        out += struct.pack("<H", value & 0xFFFF)
    return out


def em_service(dt_us, shift=0):
    return bytes([3 | (shift << 3)]) + struct.pack("<H", dt_us)


def em_receive(data):
    assert 1 <= len(data) <= 512
    return b"\x04" + struct.pack("<H", len(data) - 1) + data


def em_driver_seeds(rng):
    seeds = {}
    take = b"\x07"
    pose_ops = b""
    for k in range(4):
        pose_ops += b"\x01" + em_pose_operands(1000 + k, k, (12000, -3000, 250000),
                                                (16384, 0, 0, 0))
    seeds["four_sensors_then_service"] = pose_ops + em_service(5000) + take
    seeds["tip_force_then_service"] = (b"\x02" + em_force_operands(77, (100, -200, 1500))
                                       + em_service(5000) + take)
    # 30 Hz poses of one sensor, then silence until stale (100 ms), then it comes back.
    script = b""
    for k in range(6):
        script += b"\x01" + em_pose_operands(33333 * k, 0, (1000, 2000, 3000), (16384, 0, 0, 0))
        script += em_service(33333) + take
    script += em_service(60000, 1) + take + b"\x06" + struct.pack("<H", 10000)
    script += b"\x01" + em_pose_operands(40000, 0, (1000, 2000, 3000), (16384, 0, 0, 0))
    script += em_service(5000) + take
    seeds["stale_and_recovery"] = script
    seeds["bad_values"] = (
        b"\x01" + em_pose_operands(5, 7, (0, 0, 0), (16384, 0, 0, 0))            # unknown sensor
        + b"\x01" + em_pose_operands(6, 1, (2_000_000, 0, 0), (16384, 0, 0, 0))  # out of range
        + b"\x01" + em_pose_operands(7, 1, (0, 0, 0), (100, 0, 0, 0))            # not unit
        + b"\x01" + em_pose_operands(7, 1, (0, 0, 0), (16384, 0, 0, 0))          # time repeated
        + b"\x01" + em_pose_operands(9, 2, (0, 0, 0), (16384, 0, 0, 0), 2)       # status
        + b"\x02" + em_force_operands(3, (30000, 0, 0))                          # out of range
        + em_service(5000) + take)
    seeds["port_closed_failed_short_reads"] = (
        b"\x45\x00" + em_service(5000) + b"\x4d\x00" + em_service(5000) + b"\x15\x06"
        + b"\x01" + em_pose_operands(1, 3, (5, 5, 5), (16384, 0, 0, 0)) + em_service(5000)
        + b"\x25\x00" + em_service(5000) + take)
    # 16 poses (512 bytes) in one receive(): more than the framer's 256-byte ring.  Regression:
    # the driver counted a buffer overflow (and flagged it) though it lost no byte.
    frames = b""
    for k in range(16):
        payload = struct.pack("<IBB3i4h", 100 + k, k % 4, 0, 1000 * k, -1000 * k, 5000, 16384, 0,
                              0, 0)
        frames += em_frame(0x01, payload)
    seeds["receive_512_bytes"] = em_receive(frames[:512]) + take
    seeds["noise_no_sync"] = (b"\x00\x3f" + bytes(rng.randrange(0x80) for _ in range(64))
                              + em_service(5000) + take)
    # The framer's seeds (its author's hostile streams), as receive() operations.
    for path in sorted(FRAMER_SEEDS.iterdir()):
        data = path.read_bytes()[1:]
        script = b""
        for start in range(0, len(data), 512):
            script += em_receive(data[start:start + 512])
        seeds[f"framer_{path.stem}"] = script + em_service(5000) + take
    seeds["empty"] = b""
    return seeds


# ---- handle_sensors -------------------------------------------------------------------------------
# The script of fuzz_handle_sensors.cpp: opcode & 3 = 0 raw frame, 1 well-formed 0x110 (bit 3
# clear) / 0x111 sample (bit 4: next counter, bit 5: status 0), 2 period (dt), 3 frame time offset.

def hs_raw(frame_id, data, length=None, flags=0):
    """A raw frame: selector bit 7 = id from 2 bytes, bit 6 = flags (1 ext, 2 remote, 4 error)."""
    selector = 0x80 | (0x40 if flags else 0) | (flags << 1)
    length = len(data) if length is None else length
    return bytes([0, selector]) + struct.pack("<H", frame_id) + bytes([length]) + \
        data.ljust(8, b"\x00")[:8]


def hs_sample(ir, first_raw, second_raw, status=0, counter=0, next_counter=True, good=True):
    opcode = 1 | (0x08 if ir else 0) | (0x10 if next_counter else 0) | (0x20 if good else 0)
    return bytes([opcode]) + struct.pack("<iiBB", first_raw, second_raw, status, counter)


def hs_period(dt_us, shift=0):
    return bytes([2 | (shift << 3)]) + struct.pack("<H", dt_us)


def handle_sensor_seeds(messages, rng):
    seeds = {}
    by_name = {m.name: m for m in messages}
    # 1 kHz from both sensors, 5 ms periods: the normal case.
    script = b""
    for period in range(8):
        for k in range(5):
            script += hs_sample(False, (3 + k) << 16, (100 * k) << 16)
            script += hs_sample(True, (300 + period) << 16, k << 12)
            script += b"\x03" + bytes([15])  # next frames ~1 ms later
        script += hs_period(5000)
    seeds["both_sensors_1kHz"] = script
    # Silence: stale after 15 ms, then back.
    seeds["stale_and_back"] = (hs_sample(False, 1 << 16, 0) + hs_period(5000) + hs_period(20000)
                               + hs_sample(False, 2 << 16, 0) + hs_period(5000))
    # A backlog: samples stamped well before the period (read late).
    seeds["late_samples"] = (b"\x0b\xff" + hs_sample(False, 1 << 16, 0)
                             + hs_sample(True, 10 << 16, 0) + hs_period(5000))
    seeds["counter_gap_and_status"] = (hs_sample(False, 0, 0, counter=3, next_counter=False)
                                       + hs_sample(False, 0, 0, counter=9, next_counter=False)
                                       + hs_sample(True, 0, 0, status=1, good=False)
                                       + hs_period(5000))
    # Raw frames from the DBC's layouts: valid, wrong length, out of range, foreign, flags.
    raw = b""
    for name in ("HandleForceTorque", "InsertionRoll"):
        message = by_name[name]
        good = message.pack(valid_raws(message, rng))
        raw += hs_raw(message.id, good)
        raw += hs_raw(message.id, good, length=8)
        raw += hs_raw(message.id, good[:-1])
        raw += hs_raw(message.id, b"\xff" * message.length)
        raw += hs_raw(message.id, good, flags=1)
        raw += hs_raw(message.id, b"", flags=2)
        raw += hs_raw(message.id, good, length=15)
    raw += hs_raw(0x7FF, b"\x01\x02") + hs_raw(0x004, bytes(8), flags=4)
    seeds["raw_frames"] = raw + hs_period(5000)
    seeds["clock_behind"] = b"\x0b\x10" + hs_sample(False, 5 << 16, 0) + hs_period(0)
    seeds["empty"] = b""
    return seeds


# ---- sensor_box ----------------------------------------------------------------------------------
# fuzz_sensor_box.cpp: byte 0 = set-up, then opcode & 7 = 0 raw frame, 1 sample (bit 3: 0x111;
# bit 4: good), 2 serial bytes, 3 EM frame (bit 3: tip force; bit 4: plausible), 4 period (bit 3:
# dt from 2 bytes << bits 4..6; bit 7: overrun), 5 error frame, 6 bus-off, 7 burst.

def sb_sample(ir, first_raw, second_raw):
    return bytes([1 | (0x08 if ir else 0) | 0x10]) + struct.pack("<iiBB", first_raw, second_raw, 0, 0)


def sb_pose(sensor, x_um, y_um, z_um):
    return (bytes([3 | 0x10]) + struct.pack("<H", 33333) + bytes([sensor, 0])
            + struct.pack("<iii", x_um, y_um, z_um) + struct.pack("<hhhh", 16384, 0, 0, 0))


def sb_force(fx, fy, fz):
    return bytes([3 | 0x08 | 0x10]) + struct.pack("<H", 33333) + b"\x00" + struct.pack("<hhh", fx, fy, fz)


PERIOD = b"\x04"


def sb_step(dt_us, shift=0, overrun=False):
    return bytes([4 | 0x08 | (shift << 4) | (0x80 if overrun else 0)]) + struct.pack("<H", dt_us)


def sensor_box_seeds(messages, rng):
    seeds = {}
    # An advance: insertion grows 1 mm per period, force 2 N, 5 frames per sensor per period.
    script = b"\x00"
    for period in range(24):
        for k in range(5):
            script += sb_sample(False, 2 << 16, 50 << 16)
            script += sb_sample(True, (100 << 16) + (period * 5 + k) * (1 << 16) // 5, 0)
        if period % 6 == 0:
            script += sb_pose(0, 10_000, 20_000, 300_000 + 1000 * period)
            script += sb_force(0, 0, 500)
        script += PERIOD
    seeds["advance_24_periods"] = script
    seeds["silence_then_stale"] = b"\x02" + PERIOD * 6 + sb_sample(False, 1 << 16, 0) + PERIOD * 5
    seeds["no_serial"] = b"\x01" + (sb_sample(False, 1 << 16, 0) + sb_sample(True, 200 << 16, 0)
                                    + PERIOD) * 4
    # A flood of foreign frames, a burst beyond the 128 a period reads and beyond the queue.
    seeds["flood_and_backlog"] = (b"\x00" + b"\x07\x0f" + sb_to_burst_sample() + PERIOD * 4
                                  + sb_to_burst_sample() * 3 + PERIOD * 3)
    seeds["stall_then_catch_up"] = (b"\x00" + (sb_sample(False, 1 << 16, 0) * 20)
                                    + sb_step(50000) + PERIOD * 3)
    seeds["error_frames_bus_off"] = (b"\x02" + b"\x05\x40" + PERIOD + b"\x05\x04" + PERIOD
                                     + b"\x06\x01" + PERIOD * 2 + b"\x06\x00" + PERIOD)
    seeds["overruns_and_clock_jumps"] = (b"\x00" + sb_step(5000, 0, True) + sb_step(65535, 7)
                                         + sb_step(0) + PERIOD)
    seeds["serial_noise"] = (b"\x00" + b"\x02\x3f" + bytes(rng.randrange(256) for _ in range(64))
                             + PERIOD + sb_pose(5, 0, 0, 0) + sb_force(30000, 0, 0) + PERIOD)
    raw = b"\x00"
    for name in ("HandleForceTorque", "InsertionRoll"):
        message = next(m for m in messages if m.name == name)
        good = message.pack(valid_raws(message, rng))
        raw += bytes([0, 0x80]) + struct.pack("<H", message.id) + bytes([message.length]) + good.ljust(8, b"\x00")
        raw += bytes([0, 0x80]) + struct.pack("<H", message.id) + bytes([8]) + good.ljust(8, b"\x00")
    raw += bytes([0, 0x80]) + struct.pack("<H", 0x181) + bytes([8]) + bytes(8)
    seeds["raw_frames"] = raw + PERIOD * 2
    seeds["empty"] = b""
    # Found by the fuzzer: a box starting at 530.5 mm with 1 N published a normal force < 0.
    seeds["regression_negative_normal_force"] = bytes.fromhex(
        "01110000010000000000000019008c120200000000000088137cff0cff0000041100041100000100000000"
        "000000190000c800000000000000000000000100000020000000190000c800000000000000000100000000"
        "00000019008c88137cff0c0004")
    return seeds


def sb_to_burst_sample():
    """A burst of the good 0x110 sample frame (opcode bit 3), 20 * 16 copies."""
    return b"\x0f\x0f" + struct.pack("<iiBB", 1 << 16, 0, 0, 0)


# ---- recording_reader ----------------------------------------------------------------------------

EM_PREFIXES = ("em_tip", "em_20cm", "em_handle", "em_sigmoid")
RECORDING_COLUMNS = (["time_s", "handle_force_N", "handle_torque_Nmm", "insertion_mm", "roll_rad"]
                     + [f"{p}_{c}" for p in EM_PREFIXES
                        for c in ("x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz")]
                     + ["tip_force_x_N", "tip_force_y_N", "tip_force_z_N", "region"])


def recording_row(t_us, force=None, insertion=None, em=None, tip=None, region=""):
    cells = [f"{t_us // 1000000}.{t_us % 1000000:06d}"]
    cells += [f"{force[0]:.3f}", f"{force[1]:.1f}"] if force else ["", ""]
    cells += [f"{insertion[0]:.2f}", f"{insertion[1]:.4f}"] if insertion else ["", ""]
    for slot in range(4):
        pose = (em or {}).get(slot)
        if pose:
            cells += [f"{v:.3f}" for v in pose[:3]] + [f"{v:.6f}" for v in pose[3:]]
        else:
            cells += [""] * 7
    cells += [f"{v:.3f}" for v in tip] if tip else ["", "", ""]
    cells.append(region)
    return ",".join(cells)


def recording_seeds():
    header = ",".join(RECORDING_COLUMNS)
    seeds = {}
    rows = []
    for k in range(30):  # 1 kHz handle signals, 30 Hz EM / tip force (every 33rd row)
        t = 1_000_000 + 1000 * k
        em = {0: (10.5, -3.25, 120.0 + k, 1.0, 0.0, 0.0, 0.0),
              2: (0.0, 0.0, 0.0, 0.707107, 0.0, 0.707107, 0.0)} if k % 10 == 0 else None
        tip = (0.0, 0.0, 0.125 * k) if k % 10 == 5 else None
        rows.append(recording_row(t, (2.5 + 0.005 * k, -12.3), (300.0 + 0.5 * k, 0.0123 * k), em,
                                  tip, "sigmoid" if k < 20 else "descending"))
    seeds["rows_all_groups"] = (header + "\n" + "\n".join(rows) + "\n").encode()
    seeds["crlf_bom"] = ("\ufeff" + header + "\r\n" + "\r\n".join(rows[:5]) + "\r\n").encode()
    shuffled = RECORDING_COLUMNS[::-1]
    index = [RECORDING_COLUMNS.index(c) for c in shuffled]
    reordered = [",".join(r.split(",")[i] for i in index) for r in rows[:4]]
    seeds["columns_reordered"] = (",".join(shuffled) + "\n" + "\n".join(reordered) + "\n").encode()
    seeds["extra_columns"] = ("x_note," + header + ",x_truth\n"
                              + "\n".join(f"n{k}," + r + f",{k}" for k, r in enumerate(rows[:5]))
                              + "\n").encode()
    seeds["header_only"] = (header + "\n").encode()
    seeds["empty_rows"] = (header + "\n" + recording_row(0) + "\n" + recording_row(5) + "\n").encode()
    seeds["limits"] = (header + "\n" + recording_row(0, (163.835, -3276.8), (2500.0, -838.8608),
                                                     {3: (1000.0, -1000.0, 1000.0, 0.0, 0.0, 0.0, 1.0)},
                                                     (25.0, -25.0, 0.0)) + "\n").encode()
    seeds["bad_time_backwards"] = (header + "\n" + rows[3] + "\n" + rows[2] + "\n").encode()
    seeds["bad_gap"] = (header + "\n" + recording_row(0) + "\n" + recording_row(61_000_000) + "\n").encode()
    seeds["bad_number_1e309"] = (header + "\n" + rows[0].replace("2.500", "1e309", 1) + "\n").encode()
    seeds["bad_region"] = (header + "\n" + rows[0].replace("sigmoid", "stomach") + "\n").encode()
    seeds["bad_half_group"] = (header + "\n" + rows[0].replace(",-12.3,", ",,", 1) + "\n").encode()
    seeds["bad_unknown_column"] = (header + ",extra\n" + rows[0] + ",1\n").encode()
    seeds["bad_huge_cell"] = (header + "\n" + rows[0].replace("2.500", "9" * 300, 1) + "\n").encode()
    # Found by this fuzzer: an extra cell with a carriage return (or a quote) was accepted, and the
    # writer then refused the row the reader had accepted.
    seeds["regression_extra_cell_with_cr"] = ("x_note," + header + "\n" + "n\rx\x00," + rows[0]
                                              + "\n").encode()
    seeds["empty"] = b""
    return seeds


# ---- strict_json, scenario -------------------------------------------------------------------------

JSON_FILES = sorted(p for folder in ("model/scenarios", "model/problems", "model/reduction",
                                     "host_sim/scenarios", "tests/model/data",
                                     "tests/host_sim/cli/data")
                    for p in (ROOT / folder).glob("*.json"))


def json_seeds(extra):
    seeds = {f"{p.parent.name}_{p.stem}": p.read_bytes() for p in JSON_FILES}
    seeds.update(extra)
    return seeds


STRICT_JSON_EXTRA = {
    "deep_65": b"[" * 65 + b"]" * 65,
    "deep_64": b"[" * 64 + b"]" * 64,
    "duplicate_key": b'{"a": 1, "b": {"c": 2, "c": 3}}',
    "number_1e400": b'{"gravity_mm_per_s2": 1e400}',
    "number_tiny": b'{"x": 1e-400, "y": -0.0, "z": 18446744073709551615, "w": -9223372036854775808}',
    "strings": b'{"s": "\\u00e9\\ud83d\\ude00\\n\\t\\"", "e": ""}',
    "bad_utf8": b'{"s": "\xc3\x28"}',
    "bom": b'\xef\xbb\xbf{"a": [1, 2.5, true, null]}',
    "trailing": b'{"a": 1} x',
    "comment": b'{"a": 1 /* c */}',
    "empty": b"",
}

SCENARIO_EXTRA = {
    "deep_in_number": b'{"colon": "bundled", "gravity_mm_per_s2": ' + b"[" * 70 + b"]" * 70 + b"}",
    "number_1e400": b'{"beam": {}, "gravity_mm_per_s2": 1e400}',
    "duplicate_key": b'{"description": "a", "description": "b"}',
    "empty_object": b"{}",
    # Found by the fuzzer: a beam problem's load on a node past the beam's end was refused
    # without the file's name (BeamProblem.NodeChecksNameTheFile).
    "regression_load_node_past_the_end": (
        b'{"beam": {"straight": {"length_mm": 1000, "elements": 20}, "section": {"EA_N": 1e8, '
        b'"EI_Nmm2": 1e6, "GJ_Nmm2": 1e6, "kappa_GA_N": 1e8}}, '
        b'"loads": [{"node": 21, "force_N": [0, -10, 0]}], "supports": [{"node": 0}]}'),
    # Found by the fuzzer: a bend radius beyond size_t's range of 10 mm pieces (undefined
    # behaviour, then billions of points; ScenarioReader.ColonsTooLongToSampleAreRefused...).
    "regression_bend_radius_4e68": (
        b'{"colon": {"bundled": "single_bend", "lead_mm": 150, "bend_radius_mm": 4e68, '
        b'"bend_angle_deg": 115, "inner_radius_mm": 14, "region": "sigmoid"}, '
        b'"scope": {"model": "cf_q160l", "elements": 60}, "initial_insertion_mm": 50}'),
}


# ---- candump_replay --------------------------------------------------------------------------------

def candump_replay_seeds(messages, rng):
    by_name = {m.name: m for m in messages}
    ft, ir = by_name["HandleForceTorque"], by_name["InsertionRoll"]
    seeds = {}
    t0 = 1_700_000_000_000_000
    lines = []
    for k in range(60):  # a sensor log: 1 kHz both sensors, 60 ms
        t = t0 + 1000 * k
        lines.append(candump_line(t // 1000000, t % 1000000, "vcan0", ft.id, ft.pack(valid_raws(ft, rng))))
        lines.append(candump_line(t // 1000000, t % 1000000 + 500, "vcan0", ir.id, ir.pack(valid_raws(ir, rng))))
    seeds["sensor_log"] = b"".join(lines)
    # A box log: inputs of a period, then the box's outputs stamped with the period's time.
    box = []
    outputs = [m for m in messages if m.id >= 0x180]
    for period in range(6):
        tp = t0 + 5000 * period
        for k in range(5):
            t = tp - 4000 + 1000 * k
            box.append(candump_line(t // 1000000, t % 1000000, "can0", ft.id, ft.pack(valid_raws(ft, rng))))
        for m in sorted(outputs, key=lambda m: (m.id != 0x181, m.id)):
            box.append(candump_line(tp // 1000000, tp % 1000000, "can0", m.id, m.pack(valid_raws(m, rng))))
    seeds["box_log"] = b"".join(box)
    # The force cell falls silent for 150 ms while the encoder goes on: force stale, then (after
    # 20 stale periods) force_blind, KineticFaults bit 14 (regression: the check's mask lacked it).
    lost, lost_rng = lines[:20], random.Random("scopekin-fuzz-force-cell-lost")
    for k in range(10, 160):
        t = t0 + 1000 * k
        lost.append(candump_line(t // 1000000, t % 1000000 + 500, "vcan0", ir.id, ir.pack(valid_raws(ir, lost_rng))))
    seeds["regression_force_cell_lost"] = b"".join(lost)
    seeds["foreign_and_error_frames"] = (
        candump_line(1, 0, "vcan0", 0x120, b"\x01" * 8)
        + b"(1.000100) vcan0 20000004#0004000000000000\n"
        + candump_line(1, 200, "vcan0", 0x1ABCDEF, b"\x02", True)
        + b"(1.000300) vcan0 110#R\n"
        + candump_line(1, 400, "vcan0", ft.id, ft.pack(valid_raws(ft, rng))))
    seeds["bad_backwards"] = lines[5] + lines[3]
    seeds["bad_gap_61s"] = (candump_line(10, 0, "vcan0", ft.id, bytes(6))
                            + candump_line(71, 1, "vcan0", ft.id, bytes(6)))
    seeds["gap_60s"] = (candump_line(10, 0, "vcan0", ft.id, bytes(6))
                        + candump_line(70, 0, "vcan0", ft.id, bytes(6)))
    seeds["blank_lines_crlf"] = b"\r\n" + lines[0][:-1] + b"\r\n\n" + lines[1]
    seeds["bad_line"] = lines[0] + b"(1.5) vcan0 110#00\n"
    seeds["empty"] = b""
    return seeds


def scenario_dictionary():
    """The keys the scenario and model readers know (model/**/*.cpp: allow_only lists and
    JsonObject accessors), the colon regions and a few values: tests/fuzz/dict/scenario.dict."""
    keys = set()
    for path in sorted((ROOT / "model").rglob("*.cpp")):
        text = path.read_text()
        for group in re.findall(r"allow_only\(\{([^}]*)\}", text):
            keys.update(re.findall(r'"([A-Za-z_0-9]+)"', group))
        keys.update(re.findall(r'(?:number|number_or|index|index_or|boolean_or|string|vector3|'
                               r'vector3_or|object|array|raw|has)\("([A-Za-z_0-9]+)"', text))
    lines = ["# fuzz_scenario / fuzz_strict_json: the keys the scenario and model readers know",
             "# (written by make_corpus.py from model/**/*.cpp), regions and JSON tokens"]
    lines += [f'key_{k}="\\"{k}\\":"' for k in sorted(keys)]
    lines += [f'region_{r}="\\"{r}\\""' for r in ("rectum", "sigmoid", "descending", "splenic_flexure",
                                                    "transverse", "hepatic_flexure", "ascending",
                                                    "cecum")]
    lines += ['true="true"', 'false="false"', 'null="null"', 'big="1e400"', 'tiny="1e-400"',
              'negative="-1"', 'zero_point="0.0"', 'u64="18446744073709551616"', 'open="[{"',
              'close="}]"', 'escape="\\\\u0000"']
    (HERE / "dict" / "scenario.dict").write_text("\n".join(lines) + "\n")
    print(f"tests/fuzz/dict/scenario.dict: {len(keys)} keys")


def write(target, seeds):
    folder = CORPUS / target
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    for name, data in sorted(seeds.items()):
        (folder / name).write_bytes(data)
    print(f"{folder.relative_to(ROOT)}: {len(seeds)} files")


def main():
    messages = read_dbc(DBC)
    assert len(messages) == 9, "scopekin.dbc: expected 9 messages"
    write("can_decoders", can_decoder_seeds(messages, random.Random("scopekin-fuzz-can")))
    write("candump_parser", candump_seeds(messages, random.Random("scopekin-fuzz-candump")))
    write("em_tracker_driver", em_driver_seeds(random.Random("scopekin-fuzz-em-driver")))
    write("handle_sensors", handle_sensor_seeds(messages, random.Random("scopekin-fuzz-handle")))
    write("sensor_box", sensor_box_seeds(messages, random.Random("scopekin-fuzz-box")))
    write("recording_reader", recording_seeds())
    write("strict_json", json_seeds(STRICT_JSON_EXTRA))
    write("scenario", json_seeds(SCENARIO_EXTRA))
    write("candump_replay", candump_replay_seeds(messages, random.Random("scopekin-fuzz-replay")))
    scenario_dictionary()


if __name__ == "__main__":
    main()
