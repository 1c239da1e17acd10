#!/usr/bin/env python3
"""Generates the malformed input files of tests/data/bad (one defect each).

Run from anywhere: python3 tests/data/bad/make_bad.py. Every file written here has a test in
tests/io/bad_files_test.cpp that checks the exact location and reason of its error message.
"""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def write(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


XYZ_HEADER = "property float x\nproperty float y\nproperty float z\n"


def ascii_ply(body_header, body):
    return "ply\nformat ascii 1.0\n" + body_header + "end_header\n" + body


def binary_ply(body_header, body, fmt="binary_little_endian"):
    return ("ply\nformat %s 1.0\n" % fmt + body_header + "end_header\n").encode() + body


def floats(*v, endian="<"):
    return struct.pack(endian + "%df" % len(v), *v)


write("empty.ply", "")
write("not_ply.ply", "hello world\nformat ascii 1.0\n")
write("unknown_format.ply", "ply\nformat binary_middle_endian 1.0\nelement vertex 0\n" + XYZ_HEADER + "end_header\n")
write("missing_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + XYZ_HEADER + "0 0 0\n")
write("negative_count.ply", ascii_ply("element vertex -5\n" + XYZ_HEADER, ""))
write("non_numeric_count.ply", ascii_ply("element vertex lots\n" + XYZ_HEADER, ""))
write("unsupported_type.ply", ascii_ply("element vertex 1\nproperty int64 x\nproperty float y\nproperty float z\n", "0 0 0\n"))
write("float_list_count.ply", ascii_ply("element vertex 3\n" + XYZ_HEADER + "element face 1\nproperty list float int vertex_indices\n",
                                        "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))
write("missing_x.ply", ascii_ply("element vertex 1\nproperty float y\nproperty float z\n", "0 0\n"))
write("partial_normals.ply", ascii_ply("element vertex 1\n" + XYZ_HEADER + "property float nx\nproperty float ny\n", "0 0 0 1 0\n"))
write("property_before_element.ply", ascii_ply("property float x\nelement vertex 0\n", ""))
write("unknown_keyword.ply", ascii_ply("element vertex 0\n" + XYZ_HEADER + "vertex 3\n", ""))
write("duplicate_property.ply", ascii_ply("element vertex 0\n" + XYZ_HEADER + "property float x\n", ""))
write("no_vertex_element.ply", ascii_ply("element thing 1\nproperty float a\n", "1\n"))
write("segment_missing_x1.ply", ascii_ply("element vertex 0\n" + XYZ_HEADER +
                                          "element segment 1\nproperty float x0\nproperty float y0\nproperty float z0\n"
                                          "property float y1\nproperty float z1\n", "0 0 0 1 1\n"))
# Binary body 10 vertices announced, 5.5 present.
write("truncated_binary.ply", binary_ply("element vertex 10\n" + XYZ_HEADER, floats(*([1.0] * 16)) + b"\0\0"))
write("absurd_count.ply", binary_ply("element vertex 4000000000\n" + XYZ_HEADER, floats(1, 2, 3)))
write("absurd_count_ascii.ply", ascii_ply("element vertex 999999999999\n" + XYZ_HEADER, "0 0 0\n"))
# A face list claiming 2^32 - 16 indices.
write("absurd_list_length.ply",
      binary_ply("element vertex 3\n" + XYZ_HEADER + "element face 1\nproperty list uint int vertex_indices\n",
                 floats(0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<I", 0xFFFFFFF0) + struct.pack("<3i", 0, 1, 2)))
write("non_numeric_token.ply", ascii_ply("element vertex 2\n" + XYZ_HEADER, "0 0 0\n1 abc 3\n"))
write("nan_coordinate.ply", ascii_ply("element vertex 2\n" + XYZ_HEADER, "0 0 0\nnan 0 0\n"))
write("inf_coordinate_binary.ply", binary_ply("element vertex 3\n" + XYZ_HEADER,
                                              floats(0, 0, 0, 1, 1, 1, 2, 2, float("inf"), endian=">"), "binary_big_endian"))
write("face_index_out_of_range.ply", ascii_ply("element vertex 3\n" + XYZ_HEADER + "element face 2\nproperty list uchar int vertex_indices\n",
                                               "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n"))
write("negative_face_index.ply", binary_ply("element vertex 3\n" + XYZ_HEADER + "element face 1\nproperty list uchar int vertex_indices\n",
                                            floats(0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, -1, 2)))
write("face_two_vertices.ply", ascii_ply("element vertex 3\n" + XYZ_HEADER + "element face 1\nproperty list uchar int vertex_indices\n",
                                         "0 0 0\n1 0 0\n0 1 0\n2 0 1\n"))
write("too_few_values.ply", ascii_ply("element vertex 2\n" + XYZ_HEADER, "0 0 0\n1 2\n"))
write("too_many_values.ply", ascii_ply("element vertex 2\n" + XYZ_HEADER, "0 0 0 0\n1 2 3\n"))
write("wrong_count_extra_data.ply", ascii_ply("element vertex 2\n" + XYZ_HEADER, "0 0 0\n1 1 1\n2 2 2\n"))
write("wrong_count_binary_extra.ply", binary_ply("element vertex 1\n" + XYZ_HEADER, floats(0, 0, 0, 1, 1, 1)))
write("file_ends_early_ascii.ply", ascii_ply("element vertex 4\n" + XYZ_HEADER, "0 0 0\n1 1 1\n"))
write("int_out_of_range.ply", ascii_ply("element vertex 1\n" + XYZ_HEADER + "property uchar red\nproperty uchar green\nproperty uchar blue\n",
                                        "0 0 0 300 0 0\n"))
write("negative_list_length.ply", ascii_ply("element vertex 3\n" + XYZ_HEADER + "element face 1\nproperty list char int vertex_indices\n",
                                            "0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n"))
write("texcoord_count_mismatch.ply",
      ascii_ply("element vertex 3\n" + XYZ_HEADER + "element face 1\nproperty list uchar int vertex_indices\n"
                "property list uchar float texcoord\n", "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 4 0 0 1 0\n"))
write("missing_texture.ply", "ply\nformat ascii 1.0\ncomment TextureFile nothere.png\nelement vertex 3\n" + XYZ_HEADER +
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
write("non_numeric.xyz", "# a comment\n0 0 0\n1 2 x\n")
write("wrong_columns.xyz", "0 0 0\n1 2 3 4\n")
write("empty.xyz", "# only a comment\n\n")
write("face_out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
write("model.stl", "solid nothing\nendsolid\n")
os.makedirs(os.path.join(HERE, "directory.ply"), exist_ok=True)
write(os.path.join("directory.ply", ".gitkeep"), "")
