#!/usr/bin/env python3
"""Converts an X Window Dump (xwd -root, TrueColor, 24/32 bits per pixel) to PNG with the standard
library only, and fails on a screenshot that shows nothing (one colour: an empty display).
Usage: xwd_to_png.py IN.xwd OUT.png"""
import struct
import sys
import zlib


def read_xwd(path):
    data = open(path, "rb").read()
    fields = struct.unpack(">25I", data[:100])
    header_size, version, pixmap_format = fields[0], fields[1], fields[2]
    width, height, byte_order = fields[4], fields[5], fields[7]
    bits_per_pixel, bytes_per_line = fields[11], fields[12]
    masks = fields[14:17]
    ncolors = fields[19]
    if version != 7 or pixmap_format != 2 or bits_per_pixel not in (24, 32):
        sys.exit(f"{path}: unsupported xwd (version {version}, format {pixmap_format}, {bits_per_pixel} bpp)")
    offset = header_size + 12 * ncolors
    step = bits_per_pixel // 8
    endian = "little" if byte_order == 0 else "big"
    shifts = [(m & -m).bit_length() - 1 for m in masks]
    rows = []
    for y in range(height):
        line = data[offset + y * bytes_per_line: offset + y * bytes_per_line + width * step]
        row = bytearray()
        for x in range(0, len(line), step):
            pixel = int.from_bytes(line[x:x + step], endian)
            row += bytes(((pixel & m) >> s) & 0xFF for m, s in zip(masks, shifts))
        rows.append(bytes(row))
    return width, height, rows


def write_png(path, width, height, rows):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    raw = b"".join(b"\x00" + row for row in rows)
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    with open(path, "wb") as out:
        out.write(png)


def main():
    width, height, rows = read_xwd(sys.argv[1])
    colours = {row[i:i + 3] for row in rows[::8] for i in range(0, len(row), 24)}
    write_png(sys.argv[2], width, height, rows)
    print(f"{sys.argv[2]}: {width}x{height}, {len(colours)} colours sampled")
    if len(colours) < 4:
        sys.exit(f"{sys.argv[1]}: the screenshot is (nearly) one colour: nothing is shown")


if __name__ == "__main__":
    main()
