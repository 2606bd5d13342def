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
    # 80 poses in one receive(): more than the framer's ring and the sample queue.
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
    assert len(messages) == 8, "scopekin.dbc: expected 8 messages"
    write("can_decoders", can_decoder_seeds(messages, random.Random("scopekin-fuzz-can")))
    write("candump_parser", candump_seeds(messages, random.Random("scopekin-fuzz-candump")))
    write("em_tracker_driver", em_driver_seeds(random.Random("scopekin-fuzz-em-driver")))
    write("handle_sensors", handle_sensor_seeds(messages, random.Random("scopekin-fuzz-handle")))


if __name__ == "__main__":
    main()
