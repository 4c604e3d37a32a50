#!/usr/bin/env python3
"""Writes the small generated seed files of fuzz/corpus (PCD, PLY, PNG, DetectRequest).

Run from anywhere: python3 fuzz/make_seeds.py. The UR, URScript and
configuration seeds are copied or hand-written, not generated here.
"""
import os
import struct
import zlib

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")

# A 3 x 2 organized grid, one no-return (NaN) point.
POINTS = [(-0.1, -0.1, 1.0), (0.0, -0.1, 1.01), (0.1, -0.1, 1.02),
          (-0.1, 0.1, 1.0), (float("nan"),) * 3, (0.1, 0.1, 0.98)]


def write(harness, name, data):
    os.makedirs(os.path.join(ROOT, harness), exist_ok=True)
    with open(os.path.join(ROOT, harness, name), "wb") as f:
        f.write(data)


def pcd_header(fields, sizes, types, width, height, data):
    return ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
            f"FIELDS {' '.join(fields)}\nSIZE {' '.join(map(str, sizes))}\n"
            f"TYPE {' '.join(types)}\nCOUNT {' '.join('1' for _ in fields)}\n"
            f"WIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\n"
            f"POINTS {width * height}\nDATA {data}\n").encode()


def lzf_literal(data):
    """LZF stream of literal runs only (a run of n <= 32 bytes: n - 1, bytes)."""
    out = bytearray()
    for i in range(0, len(data), 32):
        chunk = data[i:i + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)


def pcds():
    ascii_body = "".join(" ".join("nan" if v != v else repr(v) for v in p) + "\n" for p in POINTS)
    write("pcd_fuzzer", "organized_ascii.pcd",
          pcd_header("xyz", [4] * 3, "FFF", 3, 2, "ascii") + ascii_body.encode())
    # Binary, with an rgb field and x, y, z out of order.
    body = b"".join(struct.pack("<fIff", p[2], 0x00FF8000 + i, p[0], p[1])
                    for i, p in enumerate(POINTS))
    write("pcd_fuzzer", "binary_rgb_zxy.pcd",
          pcd_header(["z", "rgb", "x", "y"], [4] * 4, "FUFF", 6, 1, "binary") + body)
    # binary_compressed: fields stored one after another (x x x ... y y y ...).
    soa = b"".join(struct.pack("<6f", *[p[axis] for p in POINTS]) for axis in range(3))
    packed = lzf_literal(soa)
    write("pcd_fuzzer", "compressed.pcd",
          pcd_header("xyz", [4] * 3, "FFF", 3, 2, "binary_compressed") +
          struct.pack("<II", len(packed), len(soa)) + packed)
    # Doubles and a 16-bit integer field.
    body = b"".join(struct.pack("<dddH", *p, 7) for p in POINTS if p[0] == p[0])
    write("pcd_fuzzer", "double_xyz_unorganized.pcd",
          pcd_header(["x", "y", "z", "intensity"], [8, 8, 8, 2], "FFFU", 5, 1, "binary") + body)


def plys():
    valid = [p for p in POINTS if p[0] == p[0]]
    head = ("ply\nformat ascii 1.0\ncomment seed\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n" % len(valid))
    write("ply_fuzzer", "ascii.ply",
          (head + "".join("%r %r %r\n" % p for p in valid)).encode())
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
            "property uchar blue\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n" % len(valid))
    body = b"".join(struct.pack("<fffBBB", *p, 200, 100, 50) for p in valid)
    body += struct.pack("<Biii", 3, 0, 1, 2)
    write("ply_fuzzer", "binary_colour_face.ply", head.encode() + body)
    # Organized: a range grid of 3 x 2 cells, one without a vertex.
    head = ("ply\nformat binary_big_endian 1.0\nobj_info num_cols 3\nobj_info num_rows 2\n"
            "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
            "element range_grid 6\nproperty list uchar int vertex_indices\nend_header\n"
            % len(valid))
    body = b"".join(struct.pack(">fff", *p) for p in valid)
    index = 0
    for p in POINTS:
        if p[0] == p[0]:
            body += struct.pack(">Bi", 1, index)
            index += 1
        else:
            body += struct.pack(">B", 0)
    write("ply_fuzzer", "range_grid_big_endian.ply", head.encode() + body)


def png(width, height, bit_depth, colour_type, rows):
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    raw = b"".join(b"\x00" + row for row in rows)
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def pngs():
    rows = [struct.pack(">4H", *[1000 + 10 * u + 100 * v if (u, v) != (2, 1) else 0
                                 for u in range(4)]) for v in range(3)]
    write("depth_png_fuzzer", "depth16_4x3.png", png(4, 3, 16, 0, rows))
    write("depth_png_fuzzer", "rgb8_3x2.png",
          png(3, 2, 8, 2, [bytes([255, 0, 0, 0, 255, 0, 0, 0, 255])] * 2))
    write("depth_png_fuzzer", "grey8_2x2.png", png(2, 2, 8, 0, [b"\x10\x80", b"\x80\x10"]))


# Protocol buffers' wire format, enough for the DetectRequest seeds (field
# numbers from proto/cornerpose/v1/geometry.proto and perception_service.proto).
def varint(n):
    out = bytearray()
    while True:
        byte = n & 0x7F
        n >>= 7
        out.append(byte | (0x80 if n else 0))
        if not n:
            return bytes(out)


def pb_varint(field, n):
    return varint(field << 3) + varint(n)


def pb_double(field, x):
    return varint(field << 3 | 1) + struct.pack("<d", x)


def pb_bytes(field, data):
    return varint(field << 3 | 2) + varint(len(data)) + data


def box_scene(width, height, fx, cx, cy):
    """Depth in metres of a 0.30 x 0.20 x 0.15 carton on a floor 1.0 m below
    the camera, turned 20 degrees about the view axis and off centre so that
    two of its sides show: every ray is cast against the top face, the four
    sides and the floor."""
    import math
    top, floor, x0, y0 = 0.85, 1.0, 0.06, 0.04
    c, s = math.cos(math.radians(20)), math.sin(math.radians(20))
    depth = []
    for v in range(height):
        for u in range(width):
            # The ray (x, y, 1) in the carton's frame (turned about z).
            rx, ry = (u - cx) / fx, (v - cy) / fx
            x, y = c * rx + s * ry, -s * rx + c * ry
            hits = [floor]
            for t in (top,) + tuple(k / x for k in (x0 - 0.15, x0 + 0.15) if x) + \
                    tuple(k / y for k in (y0 - 0.10, y0 + 0.10) if y):
                if top - 1e-9 <= t <= floor and abs(t * x - x0) <= 0.15 + 1e-9 and \
                        abs(t * y - y0) <= 0.10 + 1e-9:
                    hits.append(t)
            depth.append(min(hits))
    return depth


def intrinsics(width, height, fx, cx, cy):
    return (pb_varint(1, width) + pb_varint(2, height) + pb_double(3, fx) + pb_double(4, fx) +
            pb_double(5, cx) + pb_double(6, cy))


def box_dims(l, b, h):
    return pb_double(1, l) + pb_double(2, b) + pb_double(3, h)


def detect_requests():
    harness = "detect_request_fuzzer"
    w, h, fx = 128, 96, 120.0
    cx, cy = w / 2, h / 2
    depth = box_scene(w, h, fx, cx, cy)
    camera = pb_bytes(4, intrinsics(w, h, fx, cx, cy))
    carton = pb_bytes(5, box_dims(0.30, 0.20, 0.15))
    mm = b"".join(struct.pack("<H", round(z * 1000)) for z in depth)
    image = pb_bytes(1, mm) + pb_varint(2, w) + pb_varint(3, h) + pb_varint(4, 1)
    write(harness, "depth_mm_carton.bin", pb_bytes(2, image) + camera + carton + pb_varint(8, 1))
    metres = b"".join(struct.pack("<f", z) for z in depth)
    image = pb_bytes(1, metres) + pb_varint(2, w) + pb_varint(3, h) + pb_varint(4, 2)
    grey = bytes(200 if z < 0.86 else 150 if z < 0.99 else 90 for z in depth)
    colour = pb_bytes(1, grey) + pb_varint(2, w) + pb_varint(3, h) + pb_varint(4, 2)
    overrides = pb_double(1, 0.02) + pb_double(3, 0.01) + pb_varint(4, 1)
    write(harness, "depth_m_grey_overrides.bin",
          pb_bytes(2, image) + camera + pb_bytes(6, b"carton_s") + pb_bytes(7, overrides) +
          pb_bytes(10, colour))
    # An organized cloud (x, y, z float32 per pixel, NaN for no return) with rgb.
    cw, ch, cfx = 64, 48, 60.0
    points = b""
    rgb = b""
    for i, z in enumerate(box_scene(cw, ch, cfx, cw / 2, ch / 2)):
        u, v = i % cw, i // cw
        p = (float("nan"),) * 3 if (u, v) == (3, 3) else ((u - cw / 2) / cfx * z,
                                                          (v - ch / 2) / cfx * z, z)
        points += struct.pack("<3f", *p)
        rgb += bytes((0xA0, 0x80, 0x60))
    cloud = pb_bytes(1, points) + pb_varint(2, cw) + pb_varint(3, ch) + pb_bytes(4, rgb)
    write(harness, "organized_cloud_rgb.bin", pb_bytes(1, cloud) + carton)
    # Unorganized, laid onto the request's camera.
    cloud = pb_bytes(1, points[: 12 * 200]) + pb_varint(2, 200) + pb_varint(3, 1)
    write(harness, "unorganized_cloud_camera.bin",
          pb_bytes(1, cloud) + pb_bytes(4, intrinsics(cw, ch, cfx, cw / 2, ch / 2)) +
          pb_bytes(6, b"brick"))
    write(harness, "source.bin", pb_bytes(3, b"camera") + carton)


if __name__ == "__main__":
    pcds()
    plys()
    pngs()
    detect_requests()
