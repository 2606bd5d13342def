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

import random
import re
import shutil
import struct
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DBC = ROOT / "firmware" / "protocol" / "scopekin.dbc"
CORPUS = HERE / "corpus"


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


if __name__ == "__main__":
    main()
