#!/usr/bin/env python3
"""Seeds for tests/hal/serial/fuzz_em_tracker_framer.cpp (the EM-tracker framer's fuzzer).

Writes fuzz_corpus/em_tracker_framer/*.bin next to this script (the corpus folder holds seeds only).  Each seed is one control byte (chunking of
the fuzzer: bit 7 = oversized chunks) followed by a wire stream per
firmware/protocol/em_tracker/em_tracker_serial.md.  The frames are encoded here independently of
the C++ encoder (CRC-16/CCITT-FALSE = binascii.crc_hqx with init 0xFFFF), so the seeds also
cross-check the spec.  Deterministic: rerunning gives the same bytes.

    python3 tests/hal/serial/make_em_tracker_framer_seeds.py
"""
import binascii
import pathlib
import random
import struct

SYNC = b"\xA5\x5A"
POSE, TIP_FORCE = 0x01, 0x02


def frame(msg_type: int, payload: bytes, length: int | None = None) -> bytes:
    body = bytes([msg_type, len(payload) if length is None else length]) + payload
    return SYNC + body + struct.pack("<H", binascii.crc_hqx(body, 0xFFFF))


def pose(time_us: int, sensor: int, pos_um, quat_q14, status: int = 0) -> bytes:
    return frame(POSE, struct.pack("<IBB3i4h", time_us, sensor, status, *pos_um, *quat_q14))


def tip_force(time_us: int, force_mn, status: int = 0) -> bytes:
    return frame(TIP_FORCE, struct.pack("<IB3h", time_us, status, *force_mn))


SPEC_POSE = pose(1_000_000, 0, (12_345, -6_789, 250_000), (11585, 0, 0, 11585))
SPEC_FORCE = tip_force(1_000_250, (-150, 40, 2_500))
# The spec's worked examples (§5), byte for byte.
assert SPEC_POSE.hex(" ").upper() == (
    "A5 5A 01 1A 40 42 0F 00 00 00 39 30 00 00 7B E5 FF FF 90 D0 03 00 41 2D 00 00 00 00 41 2D CB 4B")
assert SPEC_FORCE.hex(" ").upper() == "A5 5A 02 0B 3A 43 0F 00 00 6A FF 28 00 C4 09 87 60"


def corrupt(data: bytes, index: int) -> bytes:
    return data[:index] + bytes([data[index] ^ 0x5A]) + data[index + 1:]


def main() -> None:
    rng = random.Random(5)
    out = pathlib.Path(__file__).resolve().parent / "fuzz_corpus" / "em_tracker_framer"
    out.mkdir(parents=True, exist_ok=True)
    noise = bytes([0x00, 0xA5, 0xA5, 0x11, 0x5A, 0xA5, 0x5A, 0xFF, 0xA5, 0x13])

    long_stream = b""
    for i in range(40):
        long_stream += pose((4_294_000_000 + i * 33_000) % 2**32, i % 4,
                            (rng.randint(-900_000, 900_000), rng.randint(-900_000, 900_000),
                             rng.randint(-900_000, 900_000)), (8192, 8192, -8192, 8192))
        if i % 5 == 0:
            long_stream += tip_force(i * 33_000, (0, 0, rng.randint(-20_000, 20_000)))
        if i % 3 == 0:
            long_stream += bytes(rng.choice([0xA5, 0x5A, rng.randrange(256)]) for _ in range(rng.randint(1, 20)))

    seeds = {
        "spec_pose": b"\x00" + SPEC_POSE,
        "spec_tip_force": b"\x05" + SPEC_FORCE,
        "garbage_between_frames": b"\x11" + noise + SPEC_POSE + noise + SPEC_FORCE + noise,
        "bad_crc_then_valid": b"\x22" + corrupt(SPEC_POSE, 31) + SPEC_POSE + corrupt(SPEC_FORCE, 9) + SPEC_FORCE,
        "fake_sync_huge_length": b"\x80" + SYNC + b"\x01\xFF" + SPEC_POSE + SYNC + b"\x02\xC8" + SPEC_FORCE,
        "unknown_type_and_bad_length": b"\x33" + frame(0x03, bytes(26)) + frame(POSE, bytes(11)) + SPEC_FORCE,
        "truncated_then_valid": b"\x44" + SPEC_POSE[:20] + SPEC_POSE + SPEC_FORCE[:5] + SPEC_FORCE,
        "frame_inside_corrupted_frame": b"\x06" + corrupt(frame(POSE, bytes(4) + SPEC_FORCE + bytes(5)), 30),
        "long_mixed_stream_oversized_chunks": b"\xC1" + long_stream,
        "sync_rich_noise": b"\x07" + bytes(rng.choice([0xA5, 0x5A, 0x01, 0x02, 0x1A, 0x0B]) for _ in range(300)),
    }
    for name, data in seeds.items():
        (out / f"{name}.bin").write_bytes(data)
    print(f"{len(seeds)} seeds in {out}")


if __name__ == "__main__":
    main()
