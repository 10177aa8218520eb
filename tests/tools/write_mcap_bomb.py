#!/usr/bin/env python3
"""Writes a valid MCAP file whose one zstd chunk decompresses to --expands-to bytes (zeros inside one
JointState message on /joint_states): its stated size and CRC-32 are right, so only a reader that
bounds what it decompresses by the file's size refuses it before allocating it (issue 67).

usage: write_mcap_bomb.py OUT --expands-to BYTES
"""
import argparse
import struct
import zlib

import zstandard


def rec(op, body):
    return struct.pack("<BQ", op, len(body)) + body


def mstr(s):
    b = s.encode()
    return struct.pack("<I", len(b)) + b


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--expands-to", type=int, required=True)
    a = p.parse_args()
    schema = rec(0x03, struct.pack("<H", 1) + mstr("sensor_msgs/msg/JointState") + mstr("ros2msg") + struct.pack("<I", 0))
    meta = mstr("offered_qos_profiles") + mstr("")
    channel = rec(0x04, struct.pack("<HH", 1, 1) + mstr("/joint_states") + mstr("cdr") + struct.pack("<I", len(meta)) + meta)
    head = schema + channel
    data_len = a.expands_to - len(head) - 9 - 22
    message_head = struct.pack("<BQ", 0x05, 22 + data_len) + struct.pack("<HIQQ", 1, 0, 1, 1)
    records_len = len(head) + len(message_head) + data_len
    crc = zlib.crc32(head + message_head)
    comp = zstandard.ZstdCompressor(level=3).compressobj()
    stored = bytearray(comp.compress(head + message_head))
    block = bytes(1 << 24)
    left = data_len
    while left > 0:
        n = min(left, len(block))
        chunk = block if n == len(block) else bytes(n)
        crc = zlib.crc32(chunk, crc)
        stored += comp.compress(chunk)
        left -= n
    stored += comp.flush()
    out = bytearray(b"\x89MCAP0\r\n")
    out += rec(0x01, mstr("ros2") + mstr("dyncal tests/tools/write_mcap_bomb.py"))
    body = struct.pack("<QQQI", 1, 1, records_len, crc) + mstr("zstd") + struct.pack("<Q", len(stored)) + bytes(stored)
    out += rec(0x06, body)
    out += rec(0x0F, struct.pack("<I", zlib.crc32(out)))
    out += rec(0x02, struct.pack("<QQI", 0, 0, 0))
    out += b"\x89MCAP0\r\n"
    with open(a.out, "wb") as f:
        f.write(out)


if __name__ == "__main__":
    main()
