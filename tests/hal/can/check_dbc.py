#!/usr/bin/python3
"""Checks the box's typed CAN encoders/decoders against firmware/protocol/scopekin.dbc.

Usage: check_dbc.py <protocol_codec_tool> <scopekin.dbc>

The DBC is read with canmatrix (Debian: python3-canmatrix; run with Debian's /usr/bin/python3).
The C++ side is tests/hal/can/protocol_codec_tool (JSON lines on stdin/stdout), which runs the
TYPED codecs protocol::encode(const T&) / protocol::decode(frame, T&) through the message structs.

(a) Layouts: message_layouts() == the DBC: names, ids (standard), lengths, and for every signal
    its start bit, length, signedness, factor (the C++ num/den equals the DBC's decimal factor
    exactly), offset 0, little-endian, integer (not float), not multiplexed.  Nothing missing on
    either side; the tool's hand-written field mapping covers every message and signal.
(b) Vectors (seeded, deterministic): for every message, random raw values for all signals, plus
    for every signal its extremes (raw min, raw max, 0, 1, -1 if signed), one value per bit
    position (1 << k, and -(1 << k) if signed), and for Q16.16-carried signals the raws either side
    of Q16.16's range (±32768 in physical units).  For each vector:
      1. canmatrix encodes the raw values -> bytes; the C++ DECODER's result on those bytes must be
         the expected one ("ok", or "out_of_range" for an undefined enumeration value = a raw value
         without an entry in the signal's VAL_ table, or a physical value beyond Q16.16), and on ok
         every field must equal the DBC's physical value raw * factor:
           - integer/flag/enum fields: exactly;
           - Q16.16 fields: EXACTLY the correctly rounded Q16.16 value, i.e. raw * factor * 2^16
             rounded to nearest with ties away from zero (the firmware's rounding rule,
             can_signal.hpp).  So the tolerance against the real number raw * factor is half a
             Q16.16 LSB, 2^-17 = 7.6e-6 in the signal's unit, and no more: 0.005, 0.1, 0.01, 0.0001
             and 0.001 are not binary fractions, so the nearest Q16.16 value is the best any
             decoder into Q16.16 can do; the decoder must do exactly that, with no extra rounding
             error.  (No ties occur: the factors' denominators have the prime factor 5.)
         On a refusal the decoder must leave its output untouched.
      2. The C++ ENCODER, given the physical values (Q16.16 fields = llround(value * 2^16), which
         is the correctly rounded Q16.16 value since no tie occurs and a double carries 52 bits),
         must produce exactly canmatrix's bytes, id, length, a standard data frame, zero padding.
         Where a physical value does not fit Q16.16 (InsertionRoll's Insertion beyond ±32768 mm),
         the struct holds Q16.16's limit and the expected raw is that limit's, rounded as the
         encoder does (its documented saturation).
      3. canmatrix's decode of the C++ bytes gives back the raw values and raw * factor.
(c) Refusals: every wrong length 0..8 -> bad_length; extended, remote and error frames ->
    not_data; the other messages' ids and unknown ids -> wrong_id; every undefined enumeration
    value (BoxState 4..15, ContactForceLevel 3, CounterIndex 17..255: read from the DBC's VAL_
    tables) -> out_of_range.  Each refusal must leave the output untouched.

Prints a summary; exits 1 on any mismatch, naming message, signal, value and both results.
"""

import json
import logging
import random
import subprocess
import sys
from decimal import Decimal
from fractions import Fraction

# canmatrix logs a warning per optional format it cannot load (arxml, xls, ...): not our business.
logging.basicConfig(level=logging.ERROR)
logging.getLogger("canmatrix").setLevel(logging.ERROR)

try:
    import canmatrix
    import canmatrix.formats
except ImportError as error:  # pragma: no cover - configure already checked
    sys.exit(f"check_dbc.py: cannot import canmatrix ({error}); install the Debian package "
             "python3-canmatrix and run with /usr/bin/python3")

SEED = "scopekin-dbc-check-1"
RANDOM_VECTORS_PER_MESSAGE = 400
Q16_ONE = 1 << 16
INT32_MIN = -(1 << 31)
INT32_MAX = (1 << 31) - 1
MAX_REPORTED_PER_KIND = 5

# The brief's list of undefined enumeration values; the check derives them from the VAL_ tables
# and also asserts that this list is among them (so a DBC edit cannot silently drop one).
EXPECTED_UNDEFINED = {
    ("BoxStatus", "BoxState"): range(4, 16),
    ("Alarms", "ContactForceLevel"): range(3, 4),
    ("BoxCounters", "CounterIndex"): range(17, 256),
}


class Mismatches:
    """Collects mismatches; prints the first few of each kind (the text before the first ':')."""

    def __init__(self):
        self.items = []
        self.per_kind = {}
        self.hidden = 0

    def add(self, text):
        self.items.append(text)
        kind = text.split(":", 1)[0]
        self.per_kind[kind] = self.per_kind.get(kind, 0) + 1
        if self.per_kind[kind] <= MAX_REPORTED_PER_KIND:
            print("MISMATCH: " + text, file=sys.stderr)
        else:
            self.hidden += 1


class Tool:
    """The C++ codec tool, one JSON request/answer per line."""

    def __init__(self, path):
        self.process = subprocess.Popen([path], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        text=True, bufsize=1)
        self.requests = 0

    def __call__(self, request):
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError(f"codec tool ended (exit {self.process.poll()}) on {request}")
        self.requests += 1
        return json.loads(line)

    def close(self):
        self.process.stdin.close()
        return self.process.wait(timeout=30)


def round_half_away(value):
    """Nearest integer of a Fraction, ties away from zero (the firmware's rule)."""
    magnitude = abs(value)
    rounded = int(magnitude + Fraction(1, 2))  # floor(|v| + 1/2)
    return rounded if value >= 0 else -rounded


def raw_range(signal):
    if signal.is_signed:
        return -(1 << (signal.size - 1)), (1 << (signal.size - 1)) - 1
    return 0, (1 << signal.size) - 1


def factor_of(signal):
    return Fraction(str(signal.factor))


def is_q16(signal):
    """Signals carried as Q16.16 in the structs: every scaled one (factor != 1)."""
    return factor_of(signal) != 1


def q16_of(raw, signal):
    """Correctly rounded Q16.16 raw value of raw * factor (may lie outside int32)."""
    return round_half_away(raw * factor_of(signal) * Q16_ONE)


def defined_values(signal):
    """The VAL_ table's values, or None if the signal has none (every raw value is defined)."""
    return {int(key) for key in signal.values} if signal.values else None


def hex_bytes(data):
    return bytes(data).hex().upper()


def check_layouts(db, layouts, bad):
    dbc_frames = {frame.name: frame for frame in db.frames}
    cpp = {message["name"]: message for message in layouts["messages"]}
    signals_checked = 0
    for name in sorted(set(dbc_frames) - set(cpp)):
        bad.add(f"layouts: message {name} is in the DBC but not in message_layouts()")
    for name in sorted(set(cpp) - set(dbc_frames)):
        bad.add(f"layouts: message {name} is in message_layouts() but not in the DBC")
    mapped = {entry["name"]: entry["id"] for entry in layouts["mapped"]}
    if mapped != {name: message["id"] for name, message in cpp.items()}:
        bad.add(f"layouts: the tool maps {mapped}, message_layouts() has "
                f"{ {name: message['id'] for name, message in cpp.items()} }")
    ids = [message["id"] for message in layouts["messages"]]
    if ids != sorted(ids):
        bad.add(f"layouts: message_layouts() is not in identifier order: {ids}")
    for name in sorted(set(dbc_frames) & set(cpp)):
        frame, message = dbc_frames[name], cpp[name]
        if frame.arbitration_id.extended:
            bad.add(f"layouts: {name}: the DBC declares an extended (29-bit) id")
        if frame.arbitration_id.id != message["id"]:
            bad.add(f"layouts: {name}: id DBC 0x{frame.arbitration_id.id:X}, C++ 0x{message['id']:X}")
        if frame.size != message["length"]:
            bad.add(f"layouts: {name}: length DBC {frame.size}, C++ {message['length']}")
        if frame.is_multiplexed or frame.is_complex_multiplexed:
            bad.add(f"layouts: {name}: the DBC frame is multiplexed (the codecs are not)")
        dbc_signals = {signal.name: signal for signal in frame.signals}
        cpp_signals = {signal["name"]: signal for signal in message["signals"]}
        for signal_name in sorted(set(dbc_signals) - set(cpp_signals)):
            bad.add(f"layouts: {name}.{signal_name} is in the DBC but not in message_layouts()")
        for signal_name in sorted(set(cpp_signals) - set(dbc_signals)):
            bad.add(f"layouts: {name}.{signal_name} is in message_layouts() but not in the DBC")
        used = {}
        for signal_name in sorted(set(dbc_signals) & set(cpp_signals)):
            signals_checked += 1
            s, c = dbc_signals[signal_name], cpp_signals[signal_name]
            where = f"layouts: {name}.{signal_name}"
            start = s.get_startbit(bit_numbering=1, start_little=True)
            if not s.is_little_endian:
                bad.add(f"{where}: the DBC signal is big-endian (@0); the codecs are little-endian")
            if s.is_float:
                bad.add(f"{where}: the DBC signal is a float; the codecs are integer")
            if start != c["start_bit"]:
                bad.add(f"{where}: start bit DBC {start}, C++ {c['start_bit']}")
            if s.size != c["bit_length"]:
                bad.add(f"{where}: length DBC {s.size}, C++ {c['bit_length']}")
            if bool(s.is_signed) != c["signed"]:
                bad.add(f"{where}: signed DBC {bool(s.is_signed)}, C++ {c['signed']}")
            cpp_factor = Fraction(c["factor_num"], c["factor_den"])
            if factor_of(s) != cpp_factor:
                bad.add(f"{where}: factor DBC {s.factor}, C++ {c['factor_num']}/{c['factor_den']}")
            if Decimal(str(s.offset)) != 0:
                bad.add(f"{where}: offset DBC {s.offset}, C++ 0 (the codecs have no offset)")
            if s.multiplex is not None:
                bad.add(f"{where}: the DBC signal is multiplexed")
            for bit in range(start, start + s.size):
                if bit >= 8 * frame.size:
                    bad.add(f"{where}: bit {bit} lies beyond the frame's {frame.size} bytes")
                    break
                if bit in used:
                    bad.add(f"{where}: bit {bit} overlaps {used[bit]}")
                used[bit] = signal_name
    return signals_checked


def special_raws(signal):
    """Extremes, small values, every bit position, and Q16.16's range limits if relevant."""
    low, high = raw_range(signal)
    values = {low, high, 0, 1}
    if signal.is_signed:
        values.add(-1)
    for bit in range(signal.size):
        values.add(1 << bit)
        values.add(-(1 << bit))
        values.add(high ^ (1 << bit) if not signal.is_signed else (1 << bit) - 1)
    if is_q16(signal):
        factor = factor_of(signal)
        for limit in (Fraction(INT32_MAX, Q16_ONE), Fraction(INT32_MIN, Q16_ONE)):
            centre = int(limit / factor)
            values.update(range(centre - 2, centre + 3))
    return sorted(value for value in values if low <= value <= high)


def random_raw(rng, signal):
    low, high = raw_range(signal)
    choice = rng.random()
    if choice < 0.6:
        return rng.randint(low, high)
    if choice < 0.8:  # small magnitudes, where most real traffic is
        return max(low, min(high, rng.randint(-300, 300)))
    bits = rng.randint(1, signal.size)  # every magnitude scale
    value = rng.getrandbits(bits)
    if signal.is_signed and rng.random() < 0.5:
        value = -value
    return max(low, min(high, value))


def expected_decode(frame, raws):
    """The decoder's expected result for these raw values, and why if not ok."""
    for signal in frame.signals:
        raw = raws[signal.name]
        defined = defined_values(signal)
        if defined is not None and raw not in defined:
            return "out_of_range", f"{signal.name}={raw} has no VAL_ entry"
        if is_q16(signal) and not INT32_MIN <= q16_of(raw, signal) <= INT32_MAX:
            return "out_of_range", f"{signal.name}={raw} * {signal.factor} is beyond Q16.16"
    return "ok", ""


def physical_for_tool(signal, raw):
    """What the tool receives: a double for Q16.16 fields, the integer otherwise."""
    if is_q16(signal):
        return float(raw * factor_of(signal))
    return raw


def encoder_raw(signal, raw):
    """The raw value the C++ encoder must write for the DBC raw `raw` (saturation aside, equal)."""
    if not is_q16(signal):
        return raw, False
    q = q16_of(raw, signal)
    if INT32_MIN <= q <= INT32_MAX:
        return raw, False
    q = max(INT32_MIN, min(INT32_MAX, q))  # the struct holds Q16.16's limit
    factor = factor_of(signal)
    return round_half_away(Fraction(q, Q16_ONE) / factor), True


def check_vector(tool, frame, raws, bad, counts):
    name = frame.name
    shown = ", ".join(f"{s.name}={raws[s.name]}" + (f" (= {float(raws[s.name] * factor_of(s))!r}"
                                                     f"{' ' + s.unit if s.unit else ''})"
                                                     if is_q16(s) else "")
                      for s in frame.signals)
    dbc_bytes = bytes(frame.encode(dict(raws)))
    if len(dbc_bytes) != frame.size:
        bad.add(f"{name}: canmatrix encoded {len(dbc_bytes)} bytes for [{shown}]")
        return
    counts["vectors"] += 1

    # 1. the C++ decoder on canmatrix's bytes
    answer = tool({"cmd": "decode", "message": name, "data": hex_bytes(dbc_bytes)})
    counts["decodes"] += 1
    want, why = expected_decode(frame, raws)
    if "error" in answer:
        bad.add(f"{name}: tool error on decode of {hex_bytes(dbc_bytes)}: {answer['error']}")
        return
    if answer["result"] != want:
        bad.add(f"{name}: decode of {hex_bytes(dbc_bytes)} [{shown}]: C++ {answer['result']}, "
                f"expected {want} {why}".rstrip())
    elif want == "ok":
        values = answer["values"]
        if set(values) != set(raws):
            bad.add(f"{name}: decoded signals {sorted(values)} != DBC signals {sorted(raws)}")
        for signal in frame.signals:
            if signal.name not in values:
                continue
            raw, got = raws[signal.name], values[signal.name]
            exact = raw * factor_of(signal)
            if is_q16(signal):
                if not isinstance(got, float):
                    bad.add(f"{name}.{signal.name}: the tool maps a scaled signal to an integer field")
                    continue
                want_q = q16_of(raw, signal)
                got_q = Fraction(got) * Q16_ONE
                if got_q != want_q:
                    bad.add(f"{name}.{signal.name}: raw {raw} (DBC {float(exact)!r}): C++ decoded "
                            f"{got!r} (Q16.16 raw {got_q}), expected Q16.16 raw {want_q} "
                            f"= {want_q / Q16_ONE!r}")
            else:
                if not isinstance(got, int) or got != raw:
                    bad.add(f"{name}.{signal.name}: raw {raw}: C++ decoded {got!r}, DBC {exact}")
    elif not answer["untouched"]:
        bad.add(f"{name}: decode of {hex_bytes(dbc_bytes)} refused ({answer['result']}) but "
                "changed its output")

    # 2. the C++ encoder on the physical values
    values = {signal.name: physical_for_tool(signal, raws[signal.name]) for signal in frame.signals}
    answer = tool({"cmd": "encode", "message": name, "values": values})
    counts["encodes"] += 1
    if "error" in answer:
        bad.add(f"{name}: tool error on encode of [{shown}]: {answer['error']}")
        return
    expected_raws, saturated = {}, []
    for signal in frame.signals:
        expected_raws[signal.name], clipped = encoder_raw(signal, raws[signal.name])
        if clipped:
            saturated.append(signal.name)
    expected_bytes = bytes(frame.encode(expected_raws))
    cpp_bytes = bytes.fromhex(answer["data"])
    if cpp_bytes != expected_bytes:
        diff = []
        decoded = frame.decode(cpp_bytes) if len(cpp_bytes) == frame.size else {}
        for signal in frame.signals:
            got = decoded[signal.name].raw_value if signal.name in decoded else "?"
            if got != expected_raws[signal.name]:
                diff.append(f"{signal.name}: value {values[signal.name]!r}, C++ raw {got}, "
                            f"canmatrix raw {expected_raws[signal.name]}")
        bad.add(f"{name}: encode [{shown}]: C++ bytes {answer['data']}, canmatrix bytes "
                f"{hex_bytes(expected_bytes)} ({'; '.join(diff) or 'length differs'})")
    if (answer["id"] != frame.arbitration_id.id or answer["length"] != frame.size
            or answer["extended"] or answer["remote"] or answer["error_frame"] or not answer["tail_zero"]):
        bad.add(f"{name}: encode [{shown}]: frame id 0x{answer['id']:X} length {answer['length']} "
                f"extended {answer['extended']} remote {answer['remote']} error {answer['error_frame']} "
                f"zero padding {answer['tail_zero']}; expected id 0x{frame.arbitration_id.id:X} "
                f"length {frame.size}, a standard data frame")
    if sorted(answer["saturated"]) != sorted(saturated):
        bad.add(f"{name}: encode [{shown}]: Q16.16 saturation of {answer['saturated']}, "
                f"expected {saturated}")

    # 3. canmatrix's decode of the C++ bytes
    if len(cpp_bytes) == frame.size:
        decoded = frame.decode(cpp_bytes)
        for signal in frame.signals:
            got = decoded[signal.name]
            want_raw = expected_raws[signal.name]
            if got.raw_value != want_raw or Fraction(str(got.phys_value)) != want_raw * factor_of(signal):
                bad.add(f"{name}.{signal.name}: canmatrix decodes the C++ bytes {answer['data']} "
                        f"as raw {got.raw_value} = {got.phys_value}, expected raw {want_raw} "
                        f"= {float(want_raw * factor_of(signal))!r}")


def check_refusal(tool, name, request, want, bad, counts, what):
    answer = tool(dict(request, cmd="decode", message=name))
    counts["refusals"] += 1
    if "error" in answer:
        bad.add(f"{name}: tool error on {what}: {answer['error']}")
    elif answer["result"] != want:
        bad.add(f"{name}: {what}: C++ {answer['result']}, expected {want}")
    elif want != "ok" and not answer["untouched"]:
        bad.add(f"{name}: {what}: refused ({want}) but the output was changed")


def check_refusals(tool, db, rng, bad, counts):
    ids = {frame.arbitration_id.id for frame in db.frames}
    undefined_seen = set()
    for frame in db.frames:
        name = frame.name
        raws = {}
        for signal in frame.signals:
            defined = defined_values(signal)
            raws[signal.name] = min(defined) if defined else random_raw(rng, signal)
        for signal in frame.signals:  # a vector the decoder accepts, as the base of the refusals
            if is_q16(signal):
                raws[signal.name] = rng.randint(-100, 100) if signal.is_signed else rng.randint(0, 100)
        good = bytes(frame.encode(raws))
        good_hex = hex_bytes(good)
        check_refusal(tool, name, {"data": good_hex}, "ok", bad, counts, f"base frame {good_hex}")
        for length in range(0, 9):
            if length != frame.size:
                data = (good + bytes(8))[:length]
                check_refusal(tool, name, {"data": hex_bytes(data)}, "bad_length", bad, counts,
                              f"length {length} ({hex_bytes(data)})")
        for flag in ("extended", "remote", "error_frame"):
            check_refusal(tool, name, {"data": good_hex, flag: True}, "not_data", bad, counts,
                          f"{flag} frame with id 0x{frame.arbitration_id.id:X}")
        for other in sorted(ids - {frame.arbitration_id.id}) + [0x000, 0x10F, 0x112, 0x7FF]:
            check_refusal(tool, name, {"data": good_hex, "id": other}, "wrong_id", bad, counts,
                          f"standard frame with id 0x{other:X}")
        for signal in frame.signals:
            defined = defined_values(signal)
            if defined is None:
                continue
            low, high = raw_range(signal)
            for value in range(low, high + 1):
                if value in defined:
                    continue
                undefined_seen.add((name, signal.name, value))
                data = hex_bytes(frame.encode(dict(raws, **{signal.name: value})))
                check_refusal(tool, name, {"data": data}, "out_of_range", bad, counts,
                              f"undefined {signal.name} {value} ({data})")
    for (name, signal_name), values in EXPECTED_UNDEFINED.items():
        missing = [value for value in values if (name, signal_name, value) not in undefined_seen]
        if missing:
            bad.add(f"{name}.{signal_name}: the DBC's VAL_ table defines {missing}, which the "
                    "protocol treats as undefined")


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    tool_path, dbc_path = argv[1], argv[2]
    db = canmatrix.formats.loadp_flat(dbc_path)
    tool = Tool(tool_path)
    bad = Mismatches()
    counts = {"vectors": 0, "decodes": 0, "encodes": 0, "refusals": 0}

    layouts = tool({"cmd": "layouts"})
    signals = check_layouts(db, layouts, bad)
    cpp_names = {message["name"] for message in layouts["messages"]}

    for frame in sorted(db.frames, key=lambda f: f.arbitration_id.id):
        if frame.name not in cpp_names:
            continue  # reported by check_layouts
        rng = random.Random(f"{SEED}:{frame.name}")
        vectors = []
        for signal in frame.signals:
            for raw in special_raws(signal):
                raws = {s.name: random_raw(rng, s) for s in frame.signals}
                raws[signal.name] = raw
                vectors.append(raws)
        for extreme in (0, 1):
            vectors.append({s.name: raw_range(s)[extreme] for s in frame.signals})
        vectors.append({s.name: 0 for s in frame.signals})
        for _ in range(RANDOM_VECTORS_PER_MESSAGE):
            vectors.append({s.name: random_raw(rng, s) for s in frame.signals})
        for raws in vectors:
            check_vector(tool, frame, raws, bad, counts)

    check_refusals(tool, db, random.Random(f"{SEED}:refusals"), bad, counts)
    status = tool.close()
    if status != 0:
        bad.add(f"the codec tool exited with status {status}")

    print(f"check_dbc: {len(db.frames)} messages, {signals} signals, {counts['vectors']} vectors "
          f"({counts['decodes']} decodes, {counts['encodes']} encodes checked against canmatrix), "
          f"{counts['refusals']} refusals; {len(bad.items)} mismatches")
    if bad.items:
        if bad.hidden:
            print(f"({bad.hidden} more mismatches not shown: at most {MAX_REPORTED_PER_KIND} "
                  "per message/signal)", file=sys.stderr)
        return 1
    print("check_dbc: every encoder and decoder matches scopekin.dbc as read by canmatrix")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
