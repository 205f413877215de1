#!/usr/bin/python3
"""Cross-check: `canhil frames decode --json` against canmatrix, an independent DBC decoder.

Usage: crosscheck_canmatrix.py CANHIL DBC [LOG...]

Loads DBC with canmatrix (Debian's python3-canmatrix), decodes, for every
message, seeded random payloads plus the frames of the given candump logs with
both, and compares every signal's raw and physical value. Also compares the
message list (ids, lengths, signal layouts). Exit 0 when all agree.
"""
import json
import random
import subprocess
import sys
import warnings

warnings.filterwarnings("ignore")
import logging  # noqa: E402

logging.disable(logging.WARNING)
import canmatrix  # noqa: E402
import canmatrix.formats  # noqa: E402

PAYLOADS_PER_MESSAGE = 300


def main() -> int:
    canhil, dbc, logs = sys.argv[1], sys.argv[2], sys.argv[3:]
    db = canmatrix.formats.loadp_flat(dbc)
    rng = random.Random(20261121)
    frames = []
    for frame in db.frames:
        for _ in range(PAYLOADS_PER_MESSAGE):
            payload = bytes(rng.getrandbits(8) for _ in range(frame.size))
            frames.append((frame.arbitration_id.id, payload))
        frames.append((frame.arbitration_id.id, bytes(frame.size)))
        frames.append((frame.arbitration_id.id, bytes([0xFF] * frame.size)))
    for log in logs:
        with open(log) as f:
            for line in f:
                text = line.split()[2]
                ident, data = text.split("#")
                frames.append((int(ident, 16), bytes.fromhex(data)))

    args = [f"{ident:03X}#{payload.hex().upper()}" for ident, payload in frames]
    out = subprocess.run([canhil, "--dbc", dbc, "frames", "decode", "--json", *args],
                         capture_output=True, text=True, check=False)
    decoded = [json.loads(line) for line in out.stdout.splitlines()]
    if len(decoded) != len(frames):
        print(f"canhil decoded {len(decoded)} of {len(frames)} frames; stderr: {out.stderr[:500]}")
        return 1

    mismatches = 0
    signals_compared = 0
    for (ident, payload), ours in zip(frames, decoded):
        theirs_frame = db.frame_by_id(canmatrix.ArbitrationId(ident))
        theirs = theirs_frame.decode(payload)
        if ours.get("name") != theirs_frame.name or "signals" not in ours:
            print(f"{ident:03X}#{payload.hex()}: canhil says {ours}, canmatrix says {theirs_frame.name}")
            mismatches += 1
            continue
        if set(ours["signals"]) != set(theirs):
            print(f"{theirs_frame.name}: signal names differ: {sorted(ours['signals'])} vs {sorted(theirs)}")
            mismatches += 1
            continue
        for name, value in theirs.items():
            mine = ours["signals"][name]
            signal = theirs_frame.signal_by_name(name)
            raw = int(value.raw_value)
            raw_bits = raw & ((1 << signal.size) - 1)
            phys = float(value.phys_value)
            tolerance = 1e-9 * max(1.0, abs(phys))
            signals_compared += 1
            if mine["raw"] != raw_bits or abs(mine["value"] - phys) > tolerance or mine["unit"] != signal.unit:
                print(f"{theirs_frame.name}.{name} of {ident:03X}#{payload.hex()}: canhil raw {mine['raw']} "
                      f"value {mine['value']} {mine['unit']!r}; canmatrix raw {raw_bits} value {phys} {signal.unit!r}")
                mismatches += 1

    listing = json.loads(subprocess.run([canhil, "--dbc", dbc, "frames", "list", "--json"],
                                        capture_output=True, text=True, check=True).stdout)
    for entry in listing:
        theirs_frame = db.frame_by_id(canmatrix.ArbitrationId(entry["id"]))
        if theirs_frame is None or theirs_frame.name != entry["name"] or theirs_frame.size != entry["length"] \
                or [s.name for s in theirs_frame.signals] != entry["signals"]:
            print(f"message list differs for {entry}")
            mismatches += 1
    if len(listing) != len(db.frames):
        print(f"canhil lists {len(listing)} messages, canmatrix {len(db.frames)}")
        mismatches += 1

    print(f"crosscheck: {len(frames)} frames, {signals_compared} signal values compared with canmatrix, "
          f"{mismatches} mismatches")
    return 1 if mismatches else 0


if __name__ == "__main__":
    sys.exit(main())
