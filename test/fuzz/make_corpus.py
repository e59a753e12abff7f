#!/usr/bin/env python3
"""Seed corpora for the fuzz harnesses, extracted from the golden vectors (test/vectors/*.json).

    python3 test/fuzz/make_corpus.py OUT_DIR     -> OUT_DIR/frame/*, OUT_DIR/session/*

frame:  [accepted payload byte] + wire bytes, for every frames.json wire, streams.json input and
        cobs.json encoding (with a delimiter), at the vector's max_payload and at 32 and 255.
session: raw mode ([0x00|room] + a hub hello wire + one hub->device frame wire), the same in
        structured mode (records built from the vector's type/seq/id/payload), and one seed with every
        hub->device frame in a row in each mode.
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
VECTORS = os.path.join(HERE, "..", "vectors")
HUB_TO_DEVICE = {0x2A, 0x48, 0x4A, 0x52, 0x43, 0x07, 0x15, 0x53}


def load(name):
    with open(os.path.join(VECTORS, name)) as fh:
        return json.load(fh)["vectors"]


def record(v, dt=1):
    payload = bytes.fromhex(v["payload"])
    return bytes((dt, v["type"], v["seq"], v["id"], len(payload))) + payload


def main(out):
    frames = load("frames.json")
    streams = load("streams.json")
    cobs = load("cobs.json")
    seeds = {"frame": [], "session": []}
    for v in frames:
        w = bytes.fromhex(v["wire"])
        for mp in (32, 255):
            seeds["frame"].append(bytes((mp,)) + w)
    for v in streams:
        inp = bytes.fromhex(v["input"])
        for mp in {v.get("max_payload", 255) & 0xFF, 32}:
            seeds["frame"].append(bytes((mp,)) + inp)
    for v in cobs:
        seeds["frame"].append(b"\xff" + bytes.fromhex(v["encoded"]) + b"\x00")

    hellos = [v for v in frames if v["type"] == 0x2A and v["message"].get("flags", 0) & 1 == 0]
    hub_hello = hellos[0]
    to_device = [v for v in frames if v["type"] in HUB_TO_DEVICE and not
                 (v["type"] == 0x2A and v["message"].get("flags", 0) & 1)]
    room = 0x80  # mode byte: room 64 * 4 bytes
    all_raw = bytes((room,)) + b"".join(bytes.fromhex(v["wire"]) for v in [hub_hello] + to_device)
    all_rec = bytes((room | 1,)) + b"".join(record(v) for v in [hub_hello] + to_device)
    seeds["session"] += [all_raw, all_rec]
    for v in to_device:
        seeds["session"].append(bytes((room,)) + bytes.fromhex(hub_hello["wire"]) + bytes.fromhex(v["wire"]))
        seeds["session"].append(bytes((room | 1,)) + record(hub_hello) + record(v) + bytes((0xFF, 1, 3, 0, 0))
                               + record(v, dt=30))
    for v in streams:  # line noise then a hello
        seeds["session"].append(bytes((room,)) + bytes.fromhex(v["input"]) + bytes.fromhex(hub_hello["wire"]))
    for target, items in seeds.items():
        d = os.path.join(out, target)
        os.makedirs(d, exist_ok=True)
        for i, data in enumerate(items):
            with open(os.path.join(d, f"vector-{i:03d}"), "wb") as fh:
                fh.write(data)
        print(f"{target}: {len(items)} seeds in {d}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "build/fuzz/seeds")
