#!/usr/bin/env python3
"""Writes a dyncal CSV log as a ROS 2 bag of sensor_msgs/msg/JointState, for the tests.

An independent writer: MCAP from its specification (https://mcap.dev/spec, records, chunks with
CRC-32, zstd or lz4 frame compression, message indexes, a summary), rosbag2's SQLite3 schema
(Humble), metadata.yaml, CDR from the OMG XCDR1 rules. It shares no code with dyncal's reader.

The bag holds, besides the arm's messages on --topic:
- the arm's joints in a shuffled order with an extra joint ('gripper_finger'), so that the reader
  must match by name;
- every 50th message a gripper-only JointState on the same topic (no arm joint: to be skipped);
- a /diagnostics topic of another type;
- header stamps at an epoch of 1.7e9 s, log times 100-160 us after them (a recorder's latency),
  in the order sent.
Also writes reference.csv: the CSV with t as a reader must compute it from the integer stamps,
(stamp - first stamp) * 1e-9, so that a bag and the CSV give bit-identical logs.

usage: write_ros2_bag.py CSV OUT_DIR --storage mcap|sqlite3 [--chunk-compression zstd|lz4|none]
       [--file-compression none|file|message] [--topic /joint_states] [--joint-prefix joint_]
"""
import argparse
import csv
import os
import random
import sqlite3
import struct
import zlib

EPOCH_NS = 1_700_000_000_123_456_789
JOINT_STATE = "sensor_msgs/msg/JointState"


class Cdr:
    """Little-endian CDR; alignment counts from after the 4-byte encapsulation header."""

    def __init__(self):
        self.b = bytearray()

    def align(self, n):
        while len(self.b) % n:
            self.b.append(0)

    def u32(self, v):
        self.align(4)
        self.b += struct.pack("<I", v)

    def i32(self, v):
        self.align(4)
        self.b += struct.pack("<i", v)

    def string(self, s):
        data = s.encode() + b"\0"
        self.u32(len(data))
        self.b += data

    def doubles(self, v):
        self.u32(len(v))
        if v:
            self.align(8)
        for x in v:
            self.b += struct.pack("<d", x)

    def bytes(self):
        return b"\x00\x01\x00\x00" + bytes(self.b)


def joint_state(stamp_ns, names, pos, vel, eff):
    c = Cdr()
    c.i32(stamp_ns // 1_000_000_000)
    c.u32(stamp_ns % 1_000_000_000)
    c.string("base_link")
    c.u32(len(names))
    for n in names:
        c.string(n)
    c.doubles(pos)
    c.doubles(vel)
    c.doubles(eff)
    return c.bytes()


def diagnostic(stamp_ns):
    c = Cdr()
    c.i32(stamp_ns // 1_000_000_000)
    c.u32(stamp_ns % 1_000_000_000)
    c.string("")
    c.u32(0)
    return c.bytes()


def read_log(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head = [h.strip() for h in rows[0]]
    data = [[float(x) for x in r] for r in rows[1:]]
    n = sum(1 for h in head if h.startswith("q") and h[1:].isdigit())
    col = {h: i for i, h in enumerate(head)}
    has_qd = "qd1" in col
    return head, data, n, col, has_qd


def messages(args):
    """(topic, log_time_ns, data) in recording order, and the reference CSV's rows."""
    head, data, n, col, has_qd = read_log(args.csv)
    rng = random.Random(7)
    arm = [f"{args.joint_prefix}{j}" for j in range(1, n + 1)]
    out, reference = [], []
    first = None
    last_log = 0
    for k, row in enumerate(data):
        stamp = EPOCH_NS + round(row[col["t"]] * 1e9)
        first = stamp if first is None else first
        order = list(range(n)) + [n]
        rng.shuffle(order)
        names = [arm[i] if i < n else "gripper_finger" for i in order]
        pos = [row[col[f"q{i + 1}"]] if i < n else 0.01 for i in order]
        vel = [row[col[f"qd{i + 1}"]] if i < n else 0.0 for i in order] if has_qd else []
        eff = [row[col[f"tau{i + 1}"]] if i < n else 0.5 for i in order]
        # Received in order (a FIFO), each at least 1 us after the one before.
        log_time = max(last_log + 1000, stamp + rng.randrange(100_000, 160_000))
        out.append((args.topic, log_time, joint_state(stamp, names, pos, vel, eff)))
        last_log = log_time
        if k % 50 == 25:
            out.append((args.topic, last_log + 1000, joint_state(stamp + 1, ["gripper_finger"], [0.01], [], [0.5])))
            out.append(("/diagnostics", last_log + 2000, diagnostic(stamp)))
            last_log += 2000
        ref = list(row)
        ref[col["t"]] = (stamp - first) * 1e-9
        reference.append(ref)
    return head, out, reference


def topics_of(args):
    return [(args.topic, JOINT_STATE), ("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray")]


# ---------------------------------------------------------------- MCAP
def rec(op, body):
    return struct.pack("<BQ", op, len(body)) + body


def mstr(s):
    b = s.encode()
    return struct.pack("<I", len(b)) + b


def write_mcap(path, args, msgs):
    import lz4.frame
    import zstandard

    out = bytearray(b"\x89MCAP0\r\n")
    out += rec(0x01, mstr("ros2") + mstr("dyncal tests/tools/write_ros2_bag.py"))
    schemas, channels = b"", b""
    for i, (topic, typ) in enumerate(topics_of(args), start=1):
        schemas += rec(0x03, struct.pack("<H", i) + mstr(typ) + mstr("ros2msg") + struct.pack("<I", 0))
        meta = mstr("offered_qos_profiles") + mstr("")
        channels += rec(0x04, struct.pack("<HH", i, i) + mstr(topic) + mstr("cdr") + struct.pack("<I", len(meta)) + meta)
    channel_of = {t: i for i, (t, _) in enumerate(topics_of(args), start=1)}
    chunk_indexes = []
    seq = 0
    at = 0
    first_chunk = True
    while at < len(msgs):
        records = bytearray(schemas + channels) if first_chunk else bytearray()
        first_chunk = False
        index = {}
        start = end = None
        while at < len(msgs) and len(records) < 256 * 1024:
            topic, log_time, data = msgs[at]
            ch = channel_of[topic]
            index.setdefault(ch, []).append((log_time, len(records)))
            records += rec(0x05, struct.pack("<HIQQ", ch, seq, log_time, log_time) + data)
            seq += 1
            start = log_time if start is None else min(start, log_time)
            end = log_time if end is None else max(end, log_time)
            at += 1
        if args.chunk_compression == "zstd":
            stored, name = zstandard.ZstdCompressor().compress(bytes(records)), "zstd"
        elif args.chunk_compression == "lz4":
            stored, name = lz4.frame.compress(bytes(records)), "lz4"
        else:
            stored, name = bytes(records), ""
        chunk_start = len(out)
        body = struct.pack("<QQQI", start, end, len(records), zlib.crc32(records)) + mstr(name)
        body += struct.pack("<Q", len(stored)) + stored
        out += rec(0x06, body)
        index_start = len(out)
        for ch, entries in sorted(index.items()):
            pairs = b"".join(struct.pack("<QQ", t, o) for t, o in entries)
            out += rec(0x07, struct.pack("<H", ch) + struct.pack("<I", len(pairs)) + pairs)
        chunk_indexes.append((start, end, chunk_start, 9 + len(body), index_start, len(out) - index_start,
                              len(stored), len(records), name))
    out += rec(0x0F, struct.pack("<I", zlib.crc32(out)))
    summary_start = len(out)
    out += schemas + channels
    for s, e, cs, cl, ist, il, comp, unc, name in chunk_indexes:
        out += rec(0x08, struct.pack("<QQQQ", s, e, cs, cl) + struct.pack("<I", 0) + struct.pack("<Q", il) + mstr(name)
                   + struct.pack("<QQ", comp, unc))
    out += rec(0x02, struct.pack("<QQI", summary_start, 0, 0))
    out += b"\x89MCAP0\r\n"
    with open(path, "wb") as f:
        f.write(out)


# ---------------------------------------------------------------- SQLite3 (rosbag2 Humble schema)
def write_db3(path, args, msgs, compress):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.executescript("""
        CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
        CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
        CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                            serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
        CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,
                              data BLOB NOT NULL);
        CREATE INDEX timestamp_idx ON messages (timestamp ASC);
        INSERT INTO schema VALUES (3, 'humble');
    """)
    ids = {}
    for i, (topic, typ) in enumerate(topics_of(args), start=1):
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (i, topic, typ))
        ids[topic] = i
    db.executemany("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                   ((ids[t], lt, compress(d)) for t, lt, d in msgs))
    db.commit()
    db.close()


def metadata_yaml(storage, files, msgs, fmt, mode):
    start = min(m[1] for m in msgs)
    dur = max(m[1] for m in msgs) - start
    lines = ["rosbag2_bagfile_information:", "  version: 5", f"  storage_identifier: {storage}",
             "  duration:", f"    nanoseconds: {dur}", "  starting_time:", f"    nanoseconds_since_epoch: {start}",
             f"  message_count: {len(msgs)}", "  topics_with_message_count: []",
             f"  compression_format: \"{fmt}\"", f"  compression_mode: \"{mode}\"", "  relative_file_paths:"]
    lines += [f"    - {f}" for f in files]
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser()
    p.add_argument("csv")
    p.add_argument("out_dir")
    p.add_argument("--storage", choices=["mcap", "sqlite3"], required=True)
    p.add_argument("--chunk-compression", choices=["zstd", "lz4", "none"], default="zstd")
    p.add_argument("--file-compression", choices=["none", "file", "message"], default="none")
    p.add_argument("--topic", default="/joint_states")
    p.add_argument("--joint-prefix", default="joint_")
    args = p.parse_args()
    import zstandard

    os.makedirs(args.out_dir, exist_ok=True)
    head, msgs, reference = messages(args)
    name = "bag_0." + ("mcap" if args.storage == "mcap" else "db3")
    path = os.path.join(args.out_dir, name)
    compress = zstandard.ZstdCompressor().compress if args.file_compression == "message" else (lambda d: d)
    if args.storage == "mcap":
        if args.file_compression == "message":
            msgs = [(t, lt, compress(d)) for t, lt, d in msgs]
        write_mcap(path, args, msgs)
    else:
        write_db3(path, args, msgs, compress)
    if args.file_compression == "file":
        with open(path, "rb") as f:
            data = f.read()
        os.remove(path)
        name += ".zstd"
        with open(os.path.join(args.out_dir, name), "wb") as f:
            f.write(zstandard.ZstdCompressor().compress(data))
    fmt, mode = ("zstd", args.file_compression.upper()) if args.file_compression != "none" else ("", "")
    with open(os.path.join(args.out_dir, "metadata.yaml"), "w") as f:
        f.write(metadata_yaml(args.storage, [name], msgs, fmt, mode))
    with open(os.path.join(args.out_dir, "reference.csv"), "w") as f:
        f.write(",".join(head) + "\n")
        for row in reference:
            f.write(",".join(repr(x) for x in row) + "\n")


if __name__ == "__main__":
    main()
