#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
"""Writes a level-3 .pgrid (docs/grid-format.md) that the reader accepts but no picture can show:
    make_bad_grid.py point OUT   every node at the origin (a point, not a surface)
    make_bad_grid.py far OUT     every node at the origin but node (8, 4), at x = 1e300
    make_bad_grid.py owner OUT   as point, with a channel "owner" of 0 but 0.5 at node (8, 4)
    make_bad_grid.py set-owner IN OUT VALUE   IN (with a channel "owner") but VALUE at node (8, 4)
Written by the format's rules (layout, names, checksum), independently of pliant's writer."""
import struct
import sys

MASK = (1 << 64) - 1


def checksum(data):
    h = 0xCBF29CE484222325
    words = len(data) // 8
    for i in range(words):
        (w,) = struct.unpack_from("<Q", data, 8 * i)
        h = ((h ^ w) * 0x100000001B3) & MASK
        h ^= h >> 29
    for b in data[8 * words:]:
        h = ((h ^ b) * 0x100000001B3) & MASK
    h ^= h >> 30
    h = (h * 0xBF58476D1CE4E5B9) & MASK
    h ^= h >> 27
    h = (h * 0x94D049BB133111EB) & MASK
    h ^= h >> 31
    return h


def set_owner(src, out, value):
    """Copies the grid file `src` with its channel "owner" set to `value` at node (8, 4)."""
    with open(src, "rb") as f:
        data = bytearray(f.read())
    _, level, channels = struct.unpack_from("<III", data, 8)
    w = 1 << level
    nx, ny = 2 * w + 1, w + 1
    at = 20
    for _ in range(channels):
        name = bytes(data[at:at + 16]).rstrip(b"\0").decode()
        if name == "owner":
            struct.pack_into("<d", data, at + 16 + 8 * (4 * nx + 8), value)
            break
        at += 16 + 8 * nx * ny
    else:
        sys.exit("no channel owner in " + src)
    struct.pack_into("<Q", data, len(data) - 8, checksum(bytes(data[:-8])))
    with open(out, "wb") as f:
        f.write(data)


def main():
    if sys.argv[1] == "set-owner":
        set_owner(sys.argv[2], sys.argv[3], float(sys.argv[4]))
        return
    kind, out = sys.argv[1], sys.argv[2]
    level = 3
    w = 1 << level
    nx, ny = 2 * w + 1, w + 1
    data = bytearray(b"PLIANTG\0")
    names = ("px", "py", "pz", "owner") if kind == "owner" else ("px", "py", "pz")
    data += struct.pack("<III", 1, level, len(names))
    for name in names:
        values = [0.0] * (nx * ny)
        if kind == "far" and name == "px":
            values[4 * nx + 8] = 1e300  # node (8, 4): inside the grid, no twin
        if name == "owner":
            values[4 * nx + 8] = 0.5
        data += name.encode().ljust(16, b"\0")
        data += struct.pack("<%dd" % len(values), *values)
    data += struct.pack("<Q", checksum(bytes(data)))
    with open(out, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
