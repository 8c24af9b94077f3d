#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets (fuzz/corpus/<target>/), standard library only.

Small valid files of every encoding each reader supports (a few hundred bytes to a few KB),
plus a few near-misses; the points are a deterministic synthetic helix, no third-party data.
Run from anywhere: python3 fuzz/make_seeds.py
"""
import math
import pathlib
import struct
import zlib

ROOT = pathlib.Path(__file__).resolve().parent / "corpus"


def points(n, offset=0.0):
    """n points on a helix, with one NaN point when n > 8 (readers drop and count it)."""
    out = []
    for i in range(n):
        t = 0.3 * i
        out.append((math.cos(t) + offset, math.sin(t), 0.05 * i))
    if n > 8:
        out[5] = (float("nan"), 1.0, 2.0)
    return out


def lzf_compress(data):
    """A small greedy LZF compressor (literal runs and back references, as liblzf decodes)."""
    out = bytearray()
    literal = bytearray()

    def flush():
        while literal:
            run = literal[:32]
            out.append(len(run) - 1)
            out.extend(run)
            del literal[:32]

    i = 0
    while i < len(data):
        best_len, best_off = 0, 0
        for j in range(max(0, i - 8192), i):
            length = 0
            while i + length < len(data) and length < 264 and data[j + length] == data[i + length]:
                length += 1
            if length > best_len:
                best_len, best_off = length, i - j - 1
        if best_len >= 3:
            flush()
            code = best_len - 2
            if code < 7:
                out.append((code << 5) | (best_off >> 8))
            else:
                out.append((7 << 5) | (best_off >> 8))
                out.append(code - 7)
            out.append(best_off & 0xFF)
            i += best_len
        else:
            literal.append(data[i])
            i += 1
    flush()
    return bytes(out)


def write(target, name, data):
    folder = ROOT / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(data if isinstance(data, bytes) else data.encode())


def fmt(v):
    return repr(float(v)) if not math.isnan(v) else "nan"


def pcd_header(fields, sizes, types, counts, n, data):
    return (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
        f"FIELDS {' '.join(fields)}\nSIZE {' '.join(map(str, sizes))}\n"
        f"TYPE {' '.join(types)}\nCOUNT {' '.join(map(str, counts))}\n"
        f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n"
    )


def pcd_seeds():
    pts = points(12)
    text = pcd_header(["x", "y", "z", "intensity"], [4] * 4, "FFFF", [1] * 4, 12, "ascii")
    text += "".join(f"{fmt(x)} {fmt(y)} {fmt(z)} {i}\n" for i, (x, y, z) in enumerate(pts))
    write("fuzz_pcd", "ascii.pcd", text)
    # COUNT > 1 before the coordinates, v0.5 COLUMNS spelling, organised (HEIGHT 2).
    text = "VERSION .5\nCOLUMNS n x y z\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 3 1 1 1\n"
    text += "WIDTH 3\nHEIGHT 2\nPOINTS 6\nDATA ascii\n"
    text += "".join(f"0 0 1 {fmt(x)} {fmt(y)} {fmt(z)}\n" for x, y, z in points(6))
    write("fuzz_pcd", "ascii_count.pcd", text)
    # binary: x y z float, rgb uint32, a double field
    body = b"".join(struct.pack("<fffId", x, y, z, 0xFF8000, 0.5 * i)
                    for i, (x, y, z) in enumerate(pts))
    header = pcd_header(["x", "y", "z", "rgb", "t"], [4, 4, 4, 4, 8], "FFFUF", [1] * 5, 12, "binary")
    write("fuzz_pcd", "binary.pcd", header.encode() + body)
    # binary with 8-byte coordinates and an int16 field between them
    body = b"".join(struct.pack("<dhdd", x, 7, y, z) for x, y, z in pts)
    header = pcd_header(["x", "ring", "y", "z"], [8, 2, 8, 8], "FIFF", [1] * 4, 12, "binary")
    write("fuzz_pcd", "binary_double.pcd", header.encode() + body)
    # binary_compressed: structure of arrays (all x, then all y, ...), LZF
    n = 24
    pts = points(n)
    columns = [struct.pack(f"<{n}f", *(p[a] for p in pts)) for a in range(3)]
    columns.append(struct.pack(f"<{n}f", *([1.0] * n)))
    raw = b"".join(columns)
    packed = lzf_compress(raw)
    header = pcd_header(["x", "y", "z", "intensity"], [4] * 4, "FFFF", [1] * 4, n,
                        "binary_compressed")
    write("fuzz_pcd", "binary_compressed.pcd",
          header.encode() + struct.pack("<II", len(packed), len(raw)) + packed)
    header = pcd_header(["x", "y", "z"], [4] * 3, "FFF", [1] * 3, 0, "binary_compressed")
    write("fuzz_pcd", "binary_compressed_empty.pcd", header.encode() + struct.pack("<II", 0, 0))


def ply_header(encoding, n, coordinate="float", faces=0):
    text = f"ply\nformat {encoding} 1.0\ncomment seed\nelement vertex {n}\n"
    text += f"property {coordinate} x\nproperty {coordinate} y\nproperty {coordinate} z\n"
    text += "property uchar red\nproperty ushort label\n"
    if faces:
        text += f"element face {faces}\nproperty list uchar int vertex_indices\n"
    return text + "end_header\n"


def ply_seeds():
    pts = points(10)
    text = ply_header("ascii", 10, faces=2)
    text += "".join(f"{fmt(x)} {fmt(y)} {fmt(z)} 255 {i}\n" for i, (x, y, z) in enumerate(pts))
    text += "3 0 1 2\n3 2 3 4\n"
    write("fuzz_ply", "ascii.ply", text)
    for order, name in (("<", "binary_little_endian"), (">", "binary_big_endian")):
        body = b"".join(struct.pack(order + "fffBH", x, y, z, 200, i)
                        for i, (x, y, z) in enumerate(pts))
        body += struct.pack(order + "Biii", 3, 0, 1, 2) + struct.pack(order + "Biii", 3, 2, 3, 4)
        write("fuzz_ply", f"{name}.ply", ply_header(name, 10, faces=2).encode() + body)
        body = b"".join(struct.pack(order + "dddBH", x, y, z, 1, 2) for x, y, z in pts)
        write("fuzz_ply", f"{name}_double.ply", ply_header(name, 10, "double").encode() + body)
    # an element before the vertices, int8/int16/int32 names
    text = ("ply\nformat ascii 1.0\nobj_info x\nelement camera 1\nproperty int8 a\n"
            "property int16 b\nproperty list uint8 float32 k\nelement vertex 3\n"
            "property float32 x\nproperty float32 y\nproperty float32 z\nend_header\n"
            "1 2 2 0.5 0.25\n0 0 0\n1 0 0\n0 1 0\n")
    write("fuzz_ply", "ascii_camera.ply", text)


def raw_seeds():
    pts = [p for p in points(16)]
    write("fuzz_kitti_bin", "scan.bin",
          b"".join(struct.pack("<ffff", x, y, z, 0.25) for x, y, z in pts))
    write("fuzz_kitti_bin", "one.bin", struct.pack("<ffff", 1, 2, 3, 0))
    write("fuzz_f32", "cloud.f32", b"".join(struct.pack("<fff", *p) for p in pts))
    write("fuzz_f32", "one.f32", struct.pack("<fff", 1, 2, 3))


def xyz_seeds():
    pts = points(12)
    write("fuzz_xyz", "spaces.xyz", "".join(f"{fmt(x)} {fmt(y)} {fmt(z)}\n" for x, y, z in pts))
    write("fuzz_xyz", "header.csv",
          "intensity,x,y,z\n" + "".join(f"7,{fmt(x)},{fmt(y)},{fmt(z)}\n" for x, y, z in pts))
    write("fuzz_xyz", "tabs.txt",
          "# comment\n" + "".join(f"{x:.6e}\t{y:.6e};{z:.6e}\r\n" for x, y, z in pts[:6]))
    write("fuzz_xyz", "extra_columns.txt", "1 2 3 4 5\n-1.5 +2e3 .25 0 0\ninf 1 1 1 1\n")


def vtk_seeds():
    pts = points(9)
    text = "# vtk DataFile Version 3.0\nseed\nASCII\nDATASET POLYDATA\nPOINTS 9 float\n"
    text += "".join(f"{fmt(x)} {fmt(y)} {fmt(z)}\n" for x, y, z in pts)
    text += "VERTICES 1 10\n9 0 1 2 3 4 5 6 7 8\n"
    write("fuzz_vtk", "float.vtk", text)
    text = "# vtk DataFile Version 2.0\nseed\nascii\nDATASET POLYDATA\nPOINTS 4 double\n"
    text += " ".join(f"{v:.17g}" for p in points(4) for v in p) + "\n"
    write("fuzz_vtk", "double.vtk", text)


def transform_seeds():
    write("fuzz_transform", "identity_3x4.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n")
    c, s = math.cos(0.3), math.sin(0.3)
    write("fuzz_transform", "rotation_4x4.txt",
          f"# T_reference_source\n{c:.17g} {-s:.17g} 0 1.5\n{s:.17g} {c:.17g} 0 -2\n"
          "0 0 1 0.25\n0 0 0 1\n")
    write("fuzz_transform", "six_digits.txt",
          f"[{c:.6f}, {-s:.6f}, 0, 1e3;\n {s:.6f}, {c:.6f}, 0, +2;\n 0, 0, 1, -3.5e-2]\n")
    write("fuzz_transform", "kitti_line.txt", "1 0 0 0 0 1 0 0 0 0 1 0 # one line\r\n")


def pairs_seeds():
    write("fuzz_pairs", "pairs.txt",
          "# source reference T_reference_source (3x4, row-major)\n\n"
          "scans/000001.bin scans/000000.bin 1 0 0 0.5 0 1 0 0 0 0 1 0\n"
          "   # an indented comment\n"
          "a.pcd ../b.ply 0 -1 0 1  1 0 0 2  0 0 1 3\r\n"
          "/abs/c.xyz d.vtk 1 0 0 0 0 1 0 0 0 0 1 0")


def png(width, height, samples, bit_depth=16, colour_type=0, interlace=0):
    """A PNG of row-major samples (big endian when 16-bit), filter type 0 on every row."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    per_pixel = len(samples) // (width * height)
    fmt = ">%dH" if bit_depth == 16 else ">%dB"
    row = width * per_pixel
    raw = b"".join(b"\0" + struct.pack(fmt % row, *samples[v * row:(v + 1) * row]) for v in range(height))
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, interlace)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))


def depth_png_seeds():
    # A tilted plane in millimetres with holes (0) and a 65535 sentinel, 16 x 12 pixels.
    depth = [0 if (u * v) % 7 == 3 else 1200 + 15 * u + 9 * v for v in range(12) for u in range(16)]
    depth[5] = 65535
    write("fuzz_depth_png", "plane16.png", png(16, 12, depth))
    write("fuzz_depth_png", "one16.png", png(1, 1, [1000]))
    write("fuzz_depth_png", "eight_bit.png", png(4, 3, [100] * 12, bit_depth=8))
    write("fuzz_depth_png", "rgb16.png", png(2, 2, [1000] * 12, colour_type=2))


if __name__ == "__main__":
    depth_png_seeds()
    pcd_seeds()
    ply_seeds()
    raw_seeds()
    xyz_seeds()
    vtk_seeds()
    transform_seeds()
    pairs_seeds()
