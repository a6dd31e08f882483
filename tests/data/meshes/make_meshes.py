#!/usr/bin/env python3
"""Writes the mesh files under tests/data/meshes/ (the committed copies are its output).

Only the standard library is used, so the files do not depend on rtwall or OpenMesh code:
a reader bug cannot be hidden by a writer with the same bug. Run it from anywhere:

    python3 tests/data/meshes/make_meshes.py

Good files hold a box or a tetrahedron with known counts and bounds (see mesh tests).
Bad files each break one rule; their names say which.
"""
import math
import os
import random
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

# Box [0,1] x [0,2] x [0,3]: different extents per axis, so swapped axes show up in bounds.
BOX_V = [(x, y, z) for z in (0.0, 3.0) for y in (0.0, 2.0) for x in (0.0, 1.0)]  # index = x + 2y + 4z
BOX_QUADS = [  # counter-clockwise seen from outside
    (0, 4, 6, 2),  # -x
    (1, 3, 7, 5),  # +x
    (0, 1, 5, 4),  # -y
    (2, 6, 7, 3),  # +y
    (0, 2, 3, 1),  # -z
    (4, 5, 7, 6),  # +z
]

# Tetrahedron at the origin, outward winding.
TET_V = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


BOX_N = [unit((x - 0.5, y - 1.0, z - 1.5)) for (x, y, z) in BOX_V]
TET_N = [unit((x - 0.25, y - 0.25, z - 0.25)) for (x, y, z) in TET_V]


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(HERE, name), mode, newline="" if mode == "w" else None) as f:
        f.write(data)


def fmt(x):
    return "%g" % x


# ---------------------------------------------------------------------------------------- OBJ


def obj_box(normals=False):
    lines = ["# box [0,1]x[0,2]x[0,3] as quads", "mtllib does_not_exist.mtl", "o box"]
    lines += ["v %s %s %s" % tuple(map(fmt, v)) for v in BOX_V]
    if normals:
        lines += ["vn %.7f %.7f %.7f" % n for n in BOX_N]
    lines += ["usemtl nothing", "s off"]
    for q in BOX_QUADS:
        if normals:
            lines.append("f " + " ".join("%d//%d" % (i + 1, i + 1) for i in q))
        else:
            lines.append("f " + " ".join(str(i + 1) for i in q) + "  # quad")
    return "\n".join(lines) + "\n"


def obj_tet_negative():
    # Each face follows the vertices it uses and names them relative to the end.
    lines = ["# tetrahedron with negative (relative) indices"]
    lines += ["v %s %s %s" % tuple(map(fmt, v)) for v in TET_V[:3]]
    lines.append("f -3 -1 -2")  # 0 2 1
    lines.append("v %s %s %s" % tuple(map(fmt, TET_V[3])))
    lines += ["f -4 -3 -1", "f -4 -1 -2", "f -3 -2 -1"]  # 0 1 3, 0 3 2, 1 2 3
    return "\r\n".join(lines) + "\r\n"  # Windows line ends on purpose


def obj_tet(faces, extra_vertex_line=None):
    lines = ["v %s %s %s" % tuple(map(fmt, v)) for v in TET_V]
    if extra_vertex_line:
        lines.append(extra_vertex_line)
    lines += ["f " + f for f in faces]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------- OFF


def off_box(normals=False):
    lines = ["NOFF" if normals else "OFF", "# vertices faces edges", "8 6 12"]
    for v, n in zip(BOX_V, BOX_N):
        coords = list(map(fmt, v)) + (["%.7f" % c for c in n] if normals else [])
        lines.append(" ".join(coords))
    lines += ["4 " + " ".join(map(str, q)) for q in BOX_QUADS]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------- PLY


def ply_tet_header(form, comment, after_faces=()):
    """The header of a tetrahedron with float positions and int indices: `form` ascii or binary,
    one comment line, and what follows the face indices."""
    return ["ply", "format %s 1.0" % form, comment, "element vertex 4", "property float x", "property float y",
            "property float z", "element face 4", "property list uchar int vertex_indices", *after_faces, "end_header"]


def ply_tet_ascii():
    lines = ply_tet_header("ascii", "comment tetrahedron")
    lines += ["%s %s %s" % tuple(map(fmt, v)) for v in TET_V]
    lines += ["3 %d %d %d" % f for f in TET_F]
    return "\n".join(lines) + "\n"


def ply_tet_binary(big_endian):
    e = ">" if big_endian else "<"
    if big_endian:
        # Doubles, int list counts and an element after the faces that the reader skips.
        header = [
            "ply",
            "format binary_big_endian 1.0",
            "element vertex 4",
            "property double x",
            "property double y",
            "property double z",
            "element face 4",
            "property list int uint vertex_indices",
            "element extra 1",
            "property uchar flag",
            "end_header",
        ]
        body = b"".join(struct.pack(e + "3d", *v) for v in TET_V)
        body += b"".join(struct.pack(e + "i3I", 3, *f) for f in TET_F)
        body += b"\x01"
    else:
        # Normals and colours, a face colour, and a comment right before end_header (the
        # reader's binary offset logic trips over that unless the header is normalised).
        header = [
            "ply",
            "format binary_little_endian 1.0",
            "obj_info generated by make_meshes.py",
            "element vertex 4",
            "property float x",
            "property float y",
            "property float z",
            "property float nx",
            "property float ny",
            "property float nz",
            "property uchar red",
            "property uchar green",
            "property uchar blue",
            "element face 4",
            "property list uchar int vertex_indices",
            "property uchar red",
            "comment the data follows",
            "end_header",
        ]
        body = b"".join(struct.pack(e + "6f3B", *(v + n + (200, 100, 50))) for v, n in zip(TET_V, TET_N))
        body += b"".join(struct.pack(e + "B3iB", 3, *(f + (7,))) for f in TET_F)
    return ("\n".join(header) + "\n").encode() + body


def ply_tet_texcoords(binary):
    """MeshLab-style per-corner texture coordinates: a face list besides the vertex indices."""
    header = ply_tet_header("binary_little_endian" if binary else "ascii", "comment TextureFile tet.png",
                            ["property list uchar float texcoord", "property int texnumber", "element material 1",
                             "property list uchar uchar name"])
    uv = [0.25, 0.5, 0.75, 0.5, 0.5, 1.0]
    if not binary:
        body = "".join("%s %s %s\n" % tuple(map(fmt, v)) for v in TET_V)
        body += "".join("3 %d %d %d 6 %s 0\n" % (f + (" ".join(map(fmt, uv)),)) for f in TET_F)
        body += "3 97 98 99\n"
        return "\n".join(header) + "\n" + body
    body = b"".join(struct.pack("<3f", *v) for v in TET_V)
    body += b"".join(struct.pack("<B3iB6fi", 3, *(f + (6,) + tuple(uv) + (0,))) for f in TET_F)
    body += struct.pack("<4B", 3, 97, 98, 99)
    return ("\n".join(header) + "\n").encode() + body


# ---------------------------------------------------------------------------------------- STL


def tri_normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    w = [c[i] - a[i] for i in range(3)]
    return unit((u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]))


def stl_tet_ascii():
    # The solid's name contains "outer", which the reader would take for a loop.
    out = ["solid outer_tetrahedron"]
    for f in TET_F:
        a, b, c = (TET_V[i] for i in f)
        out.append("  facet normal %g %g %g" % tri_normal(a, b, c))
        out.append("    outer loop")
        for p in (a, b, c):
            out.append("      vertex %s %s %s" % tuple(map(fmt, p)))
        out.append("    endloop")
        out.append("  endfacet")
    out.append("endsolid outer_tetrahedron")
    return "\n".join(out) + "\n"


def stl_tet_binary(header=b"solid binary tetrahedron (the header may start with solid)"):
    data = header.ljust(80, b" ") + struct.pack("<I", len(TET_F))
    for f in TET_F:
        a, b, c = (TET_V[i] for i in f)
        data += struct.pack("<12fH", *(tri_normal(a, b, c) + a + b + c), 0)
    return data


# ---------------------------------------------------------------------------------------- OM


def om_chunk(entity, type_, bits=0, dim=0, is_float=0, is_signed=0, name=0):
    v = (name << 1) | (entity << 2) | (type_ << 5) | (is_signed << 9) | (is_float << 10) | (dim << 11) | (bits << 14)
    return struct.pack("<H", v)


OM_VERTEX, OM_MESH, OM_FACE, OM_EDGE, OM_HALFEDGE, OM_SENTINEL = 0, 1, 2, 4, 6, 7
OM_POS, OM_NORMAL, OM_TEXCOORD, OM_STATUS, OM_COLOR, OM_CUSTOM, OM_TOPOLOGY = 0, 1, 2, 3, 4, 6, 7


def om_name(text):
    return bytes([len(text)]) + text.encode()


def om_custom(entity, name, type_name, payload):
    """A named custom property as OpenMesh 9 writes it (format 2.2 names the C++ type)."""
    return om_chunk(entity, OM_CUSTOM, name=1) + om_name(name) + om_name(type_name) + struct.pack("<I", len(payload)) + payload


def om_tet_v22(rich=False):
    """OpenMesh 9's own format: faces as halfedge loops. `rich` adds the chunks OpenMesh writes
    for colours, texture coordinates, status bits and persistent custom properties."""
    edges, halfedge_of = [], {}
    for f in TET_F:
        for k in range(3):
            a, b = f[k], f[(k + 1) % 3]
            if (a, b) not in halfedge_of:
                halfedge_of[(a, b)] = 2 * len(edges)
                halfedge_of[(b, a)] = 2 * len(edges) + 1
                edges.append((a, b))
    nh = 2 * len(edges)
    to_vertex, next_, face_of = [0] * nh, [-1] * nh, [-1] * nh
    for (a, b), h in halfedge_of.items():
        to_vertex[h] = b
    for fi, f in enumerate(TET_F):
        hs = [halfedge_of[(f[k], f[(k + 1) % 3])] for k in range(3)]
        for k in range(3):
            next_[hs[k]] = hs[(k + 1) % 3]
            face_of[hs[k]] = fi
    data = b"OM" + b"T" + bytes([(2 << 5) | 2]) + struct.pack("<3I", len(TET_V), len(TET_F), len(edges))
    data += om_chunk(OM_VERTEX, OM_POS, bits=0, dim=2, is_float=1, is_signed=1)
    data += b"".join(struct.pack("<3f", *v) for v in TET_V)
    data += om_chunk(OM_VERTEX, OM_NORMAL, bits=0, dim=2, is_float=1, is_signed=1)
    data += b"".join(struct.pack("<3f", *n) for n in TET_N)
    if rich:
        data += om_chunk(OM_VERTEX, OM_COLOR, dim=2) + bytes([200, 100, 50] * len(TET_V))
        data += om_chunk(OM_VERTEX, OM_TEXCOORD, dim=1, is_float=1, is_signed=1) + struct.pack("<8f", *([0.5] * 8))
        data += om_chunk(OM_HALFEDGE, OM_TEXCOORD, dim=1, is_float=1, is_signed=1) + struct.pack("<2f", 0.25, 0.75) * nh
    data += om_chunk(OM_HALFEDGE, OM_TOPOLOGY, bits=2)
    for e in range(len(edges)):
        h0, h1 = 2 * e, 2 * e + 1
        data += struct.pack("<6i", next_[h0], to_vertex[h0], face_of[h0], next_[h1], to_vertex[h1], face_of[h1])
    data += om_chunk(OM_VERTEX, OM_TOPOLOGY, bits=2)
    outgoing = {}
    for (a, b), h in halfedge_of.items():
        outgoing.setdefault(a, h)
    data += b"".join(struct.pack("<i", outgoing[v]) for v in range(len(TET_V)))
    data += om_chunk(OM_FACE, OM_TOPOLOGY, bits=2)
    data += b"".join(struct.pack("<i", halfedge_of[(f[0], f[1])]) for f in TET_F)
    if rich:
        data += om_chunk(OM_FACE, OM_NORMAL, dim=2, is_float=1, is_signed=1) + struct.pack("<3f", 0, 0, 1) * len(TET_F)
        data += om_chunk(OM_FACE, OM_COLOR, dim=2) + bytes([1, 2, 3] * len(TET_F))
        for entity, count in ((OM_VERTEX, len(TET_V)), (OM_EDGE, len(edges)), (OM_HALFEDGE, nh), (OM_FACE, len(TET_F))):
            data += om_chunk(entity, OM_STATUS) + struct.pack("<I", 0) * count
        data += om_custom(OM_VERTEX, "weight", "float", struct.pack("<4f", 1, 2, 3, 4))
        data += om_custom(OM_FACE, "label", "int32_t", struct.pack("<4i", 7, 8, 9, 10))
        data += om_custom(OM_MESH, "scale", "double", struct.pack("<d", 2.5))
    data += om_chunk(OM_SENTINEL, 0)
    return data


def om_box_v12():
    """The format before 2.0: polygonal faces as vertex index lists (here quads)."""
    data = b"OM" + b"P" + bytes([(1 << 5) | 2]) + struct.pack("<3I", len(BOX_V), len(BOX_QUADS), 12)
    data += om_chunk(OM_VERTEX, OM_POS, bits=0, dim=2, is_float=1, is_signed=1)
    data += b"".join(struct.pack("<3f", *v) for v in BOX_V)
    data += om_chunk(OM_FACE, OM_TOPOLOGY, bits=2)
    data += b"".join(struct.pack("<H4I", 4, *q) for q in BOX_QUADS)
    data += om_chunk(OM_SENTINEL, 0)
    return data


# ---------------------------------------------------------------------------------------- main


def main():
    # Good files.
    write("box_quads.obj", obj_box())
    write("box_normals.obj", obj_box(normals=True))
    write("tet_negative_indices.obj", obj_tet_negative())
    write("box_quads.off", off_box())
    write("box_normals.off", off_box(normals=True))
    write("tet_ascii.ply", ply_tet_ascii())
    write("tet_binary_le.ply", ply_tet_binary(big_endian=False))
    write("tet_binary_be.ply", ply_tet_binary(big_endian=True))
    write("tet_texcoords_ascii.ply", ply_tet_texcoords(binary=False))
    write("tet_texcoords_le.ply", ply_tet_texcoords(binary=True))
    write("tet_ascii.stl", stl_tet_ascii())
    write("tet_binary.stl", stl_tet_binary())
    write("tet.om", om_tet_v22())
    write("tet_rich.om", om_tet_v22(rich=True))
    write("box_v1.om", om_box_v12())

    # Bad files, one broken rule each.
    good_stl = stl_tet_binary(header=b"binary tetrahedron")
    write("bad_truncated_binary.stl", good_stl[:-20])
    write("bad_count_ffffffff.stl", good_stl[:80] + struct.pack("<I", 0xFFFFFFFF) + good_stl[84:134])
    write("bad_huge_vertex_count.ply", ply_tet_ascii().replace("element vertex 4", "element vertex 4000000000"))
    good_ply = ply_tet_binary(big_endian=False)
    write("bad_truncated_binary.ply", good_ply[:-9])
    write("bad_float_list_count.ply", ply_tet_ascii().replace("list uchar int", "list float int"))
    write("bad_no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n")
    write("bad_nan.ply", ply_tet_ascii().replace("\n1 0 0\n", "\n1 nan 0\n"))
    nan_ply = bytearray(ply_tet_binary(big_endian=False))
    first_vertex = nan_ply.index(b"end_header\n") + len(b"end_header\n")
    nan_ply[first_vertex + 4 : first_vertex + 8] = struct.pack("<f", math.inf)  # vertex 0's y
    write("bad_inf_binary.ply", bytes(nan_ply))
    write("bad_index_out_of_range.obj", obj_tet(["1 3 2", "1 2 9", "1 4 3", "2 3 4"]))
    write("bad_negative_index_out_of_range.obj", obj_tet(["1 3 2", "-1 -2 -9", "1 4 3", "2 3 4"]))
    write("bad_index_zero.obj", obj_tet(["0 2 1", "1 2 4", "1 4 3", "2 3 4"]))
    write("bad_nan.obj", obj_tet(["1 3 2", "1 2 5", "1 5 3", "2 3 5"], extra_vertex_line="v 0.5 nan 0.5"))
    write("bad_inf.obj", obj_tet(["1 3 2", "1 2 5", "1 5 3", "2 3 5"], extra_vertex_line="v inf 0 0"))
    write("bad_count_too_large.off", off_box().replace("8 6 12", "8 60000 12"))
    write("bad_index_out_of_range.off", off_box().replace("4 4 5 7 6", "4 4 5 8 6"))
    write("bad_empty.obj", "")
    rng = random.Random(1234)
    garbage = bytes(rng.randrange(256) for _ in range(3000))
    for ext in ("ply", "stl", "om", "obj", "off"):
        write("bad_garbage." + ext, garbage)
    good_om = om_tet_v22()
    write("bad_truncated.om", good_om[:60])
    write("bad_huge_counts.om", good_om[:4] + struct.pack("<3I", 0x7FFFFFFF, 0x7FFFFFFF, 0x3FFFFFFF) + good_om[16:])
    write("bad_ply_content.obj", ply_tet_ascii())


if __name__ == "__main__":
    main()
