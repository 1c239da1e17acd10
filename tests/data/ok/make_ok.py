#!/usr/bin/env python3
"""Generates the tiny valid files of tests/data/ok (checked by tests/io/ok_files_test.cpp and
used as the seed corpus of the PLY fuzzer). Run: python3 tests/data/ok/make_ok.py"""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def write(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


def png(width, height, rgba_rows):
    def chunk(kind, payload):
        c = struct.pack(">I", len(payload)) + kind + payload
        return c + struct.pack(">I", zlib.crc32(kind + payload) & 0xFFFFFFFF)
    raw = b"".join(b"\0" + bytes(row) for row in rgba_rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


# 2x2 texture: top row red, green; bottom row blue, white.
TEXTURE = png(2, 2, [[255, 0, 0, 255, 0, 255, 0, 255], [0, 0, 255, 255, 255, 255, 255, 255]])

# Three points with every standard attribute and one extra property, ascii.
write("points_ascii.ply", """ply
format ascii 1.0
comment source: hand-written test file
element vertex 3
property float x
property float y
property float z
property float nx
property float ny
property float nz
property uchar red
property uchar green
property uchar blue
property uchar alpha
property float radius
property float k_min
end_header
0 0 0 0 0 1 255 0 0 255 0.5 -1.5
1 0 0 0 0 1 0 255 0 128 0.25 0
0 1 0.5 0 1 0 0 0 255 0 0.125 2.5e-3
""")

# The same positions, big-endian, with mixed scalar types (double x, short y as ints) and a
# list property on the vertex that must be skipped.
be = ("ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty float y\n"
      "property float z\nproperty list uchar int junk\nproperty ushort quality\nend_header\n").encode()
for (x, y, z), junk, q in [((0, 0, 0), [1, 2], 7), ((1, 0, 0), [], 8), ((0, 1, 0.5), [3], 65535)]:
    be += struct.pack(">dff", x, y, z) + struct.pack(">B", len(junk)) + struct.pack(">%di" % len(junk), *junk)
    be += struct.pack(">H", q)
write("points_be.ply", be)

# Little-endian with int8..float64 aliases and an unknown element (with a list) before and after.
le = ("ply\nformat binary_little_endian 1.0\nelement camera 1\nproperty float32 fov\nproperty list uint8 float32 k\n"
      "element vertex 2\nproperty float32 x\nproperty float32 y\nproperty float32 z\nproperty int8 a\n"
      "property uint16 b\nproperty int32 c\nproperty uint32 d\nproperty float64 e\n"
      "element tail 1\nproperty list uint16 int16 ids\nend_header\n").encode()
le += struct.pack("<f", 45.0) + struct.pack("<B2f", 2, 1.0, 2.0)
le += struct.pack("<fffbHiId", 1, 2, 3, -5, 600, -70000, 4000000000, 0.125)
le += struct.pack("<fffbHiId", 4, 5, 6, 5, 0, 70000, 0, -0.5)
le += struct.pack("<H3h", 3, -1, 0, 1)
write("points_le.ply", le)

# A hybrid model: one point and two segments with every segment attribute and provenance.
write("hybrid_segments.ply", """ply
format ascii 1.0
comment TextureFile texture.png
element vertex 1
property float x
property float y
property float z
element segment 2
property float x0
property float y0
property float z0
property float x1
property float y1
property float z1
property float nx
property float ny
property float nz
property float red
property float green
property float blue
property float radius
property float u0
property float v0
property float u1
property float v1
property list uchar uint provenance
end_header
5 5 5
0 0 0 1 0 0 0 0 1 1 0.5 0 0.01 0 0 1 0 3 0 1 2
0 1 0 0 2 0 1 0 0 0 0 1 0.02 0.25 0.25 0.75 0.75 0
""")
write("texture.png", TEXTURE)

# A textured quad mesh (one polygon, fan-triangulated) with MeshLab per-corner texcoords.
write("mesh_texcoords.ply", """ply
format ascii 1.0
comment TextureFile texture.png
comment a unit quad
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
element face 1
property list uchar int vertex_indices
property list uchar float texcoord
end_header
0 0 0 0 0 1
1 0 0 0 0 1
1 1 0 0 0 1
0 1 0 0 0 1
4 0 1 2 3 8 0 0 1 0 1 1 0 1
""")

# The same quad as OBJ with MTL and texture.
write("quad.obj", """# a unit quad
mtllib quad.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl checker
f 1/1/1 2/2/1 3/3/1 4/4/1
""")
write("quad.mtl", "newmtl checker\nKd 1 1 1\nmap_Kd texture.png\n")

write("points.xyz", """# three points with normals
0 0 0 0 0 1
1 0 0 0 0 1

0 1 0.5 0 1 0
""")
