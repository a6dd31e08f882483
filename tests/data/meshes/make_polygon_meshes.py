#!/usr/bin/env python3
"""Writes the polygon test files (issue 15): polygons.{obj,off,vtk,vtp,vtu,wrl},
polygons_ascii.ply, polygons_le.ply, ring.obj (the ring face alone, for the render test) and
blender_247.ply.

Each polygons.* file holds the same nine faces, one per shape, the way CAD exporters write
them: a ring as one keyhole face (LightWave's concave_polygon.obj: round the outer circle, across
a bridge, round the inner circle the other way, back across the bridge, so two corners appear
twice), a star, a square with a bridged square hole, an L with repeated corners and corners on
straight sides, a nearly collinear zigzag sliver, a square with a zero-width spike, a convex
hexagon, a degenerate face (every corner on a line) and one whose boundary crosses itself. The
shapes and where they lie are defined again in tests/mesh/polygon_shapes.h, which the tests
check against; only the standard library is used here, so a reader bug cannot hide behind a
writer with the same bug. Within a face every distinct point is one vertex, so repeated
corners repeat vertex indices.

blender_247.ply is the tetrahedron with the header line Blender 2.47's PLY exporter writes
("Created by Blender3D 247 - www.blender.org, source file: ..."), which is no PLY keyword.

Run from anywhere: python3 tests/data/meshes/make_polygon_meshes.py
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def keyhole_ring(n, m, outer, inner, start):
    top = math.pi / 2
    c = [(outer * math.cos(top + 2 * math.pi * (i % n) / n), outer * math.sin(top + 2 * math.pi * (i % n) / n)) for i in range(n + 1)]
    c += [(inner * math.cos(top - 2 * math.pi * (i % m) / m), inner * math.sin(top - 2 * math.pi * (i % m) / m)) for i in range(m + 1)]
    return [c[(k + start) % len(c)] for k in range(len(c))]


def star(k, outer, inner):
    out = []
    for i in range(2 * k):
        a, r = math.pi / 2 + math.pi * i / k, (inner if i % 2 else outer)
        out.append((r * math.cos(a), r * math.sin(a)))
    return out


SHAPES = [
    keyhole_ring(32, 32, 1.0, 0.9, 5),
    star(5, 1.0, 0.4),
    [(-1, 0), (-1, -1), (1, -1), (1, 1), (-1, 1), (-1, 0), (-0.5, 0), (-0.5, 0.5), (0.5, 0.5), (0.5, -0.5), (-0.5, -0.5), (-0.5, 0)],
    [(-1, -1), (0, -1), (0, -1), (1, -1), (1, 0), (0.5, 0), (0, 0), (0, 1), (-1, 1), (-1, 1), (-1, 0)],
    [(-1, 0), (1, 0)] + [(1 - i / 20.0, 0.002 + (0.0002 if i % 2 else 0.0)) for i in range(41)],
    [(-0.5, -0.5), (0.5, -0.5), (0.5, 0), (0.9, 0), (0.5, 0), (0.5, 0.5), (-0.5, 0.5)],
    [(math.cos(math.pi * i / 3), math.sin(math.pi * i / 3)) for i in range(6)],
    [(-1, 0), (0, 0), (1, 0), (0.5, 0)],
    [(-1, -1), (1, 1), (1, -1), (-1, 0.5)],
]


def place(k, p):
    """Shape k's plane: the ring in x = -1.25, the star tilted 20 degrees about y through z = 1, the rest in z = k."""
    u, v = p
    if k == 0:
        return (-1.25, u, v)
    if k == 1:
        t = math.radians(20)
        return (u * math.cos(t), v, 1 + u * math.sin(t))
    return (u, v, float(k))


def mesh(shapes=None):
    """Vertices (3D) and faces (zero-based indices, repeats kept) of the given shapes (all by default)."""
    vertices, faces = [], []
    for k, shape in enumerate(SHAPES):
        if shapes is not None and k not in shapes:
            continue
        index = {}
        face = []
        for p in shape:
            if p not in index:
                index[p] = len(vertices)
                vertices.append(place(k, p))
            face.append(index[p])
        faces.append(face)
    return vertices, faces


def num(x):
    return repr(float(x))


def write(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def obj(vertices, faces):
    lines = ["# polygon test shapes (make_polygon_meshes.py)"]
    lines += ["v %s %s %s" % tuple(map(num, v)) for v in vertices]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    return "\n".join(lines) + "\n"


def off(vertices, faces):
    lines = ["OFF", "%d %d 0" % (len(vertices), len(faces))]
    lines += ["%s %s %s" % tuple(map(num, v)) for v in vertices]
    lines += [" ".join(map(str, [len(f)] + f)) for f in faces]
    return "\n".join(lines) + "\n"


def ply_header(encoding, vertices, faces, extra=()):
    return ["ply", "format %s 1.0" % encoding, *extra, "element vertex %d" % len(vertices), "property float x",
            "property float y", "property float z", "element face %d" % len(faces),
            "property list uchar int vertex_indices", "end_header"]


def ply_ascii(vertices, faces, extra=()):
    lines = ply_header("ascii", vertices, faces, extra)
    lines += ["%s %s %s" % tuple(map(num, v)) for v in vertices]
    lines += [" ".join(map(str, [len(f)] + f)) for f in faces]
    return "\n".join(lines) + "\n"


def ply_le(vertices, faces):
    out = ("\n".join(ply_header("binary_little_endian", vertices, faces)) + "\n").encode()
    for v in vertices:
        out += struct.pack("<3f", *v)
    for f in faces:
        out += struct.pack("<B%di" % len(f), len(f), *f)
    return out


def vtk_legacy(vertices, faces):
    lines = ["# vtk DataFile Version 4.2", "polygon test shapes", "ASCII", "DATASET POLYDATA",
             "POINTS %d double" % len(vertices)]
    lines += ["%s %s %s" % tuple(map(num, v)) for v in vertices]
    lines.append("POLYGONS %d %d" % (len(faces), sum(len(f) + 1 for f in faces)))
    lines += [" ".join(map(str, [len(f)] + f)) for f in faces]
    return "\n".join(lines) + "\n"


def xml_arrays(vertices, faces):
    points = " ".join("%s %s %s" % tuple(map(num, v)) for v in vertices)
    connectivity = " ".join(str(i) for f in faces for i in f)
    offsets, at = [], 0
    for f in faces:
        at += len(f)
        offsets.append(str(at))
    return points, connectivity, " ".join(offsets)


def vtp(vertices, faces):
    points, connectivity, offsets = xml_arrays(vertices, faces)
    return ('<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">\n'
            '  <PolyData>\n'
            '    <Piece NumberOfPoints="%d" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="%d">\n'
            '      <Points>\n'
            '        <DataArray type="Float64" NumberOfComponents="3" format="ascii">%s</DataArray>\n'
            '      </Points>\n'
            '      <Polys>\n'
            '        <DataArray type="Int64" Name="connectivity" format="ascii">%s</DataArray>\n'
            '        <DataArray type="Int64" Name="offsets" format="ascii">%s</DataArray>\n'
            '      </Polys>\n'
            '    </Piece>\n'
            '  </PolyData>\n'
            '</VTKFile>\n') % (len(vertices), len(faces), points, connectivity, offsets)


def vtu(vertices, faces):
    points, connectivity, offsets = xml_arrays(vertices, faces)
    types = " ".join("7" for _ in faces)  # VTK_POLYGON
    return ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">\n'
            '  <UnstructuredGrid>\n'
            '    <Piece NumberOfPoints="%d" NumberOfCells="%d">\n'
            '      <Points>\n'
            '        <DataArray type="Float64" NumberOfComponents="3" format="ascii">%s</DataArray>\n'
            '      </Points>\n'
            '      <Cells>\n'
            '        <DataArray type="Int64" Name="connectivity" format="ascii">%s</DataArray>\n'
            '        <DataArray type="Int64" Name="offsets" format="ascii">%s</DataArray>\n'
            '        <DataArray type="UInt8" Name="types" format="ascii">%s</DataArray>\n'
            '      </Cells>\n'
            '    </Piece>\n'
            '  </UnstructuredGrid>\n'
            '</VTKFile>\n') % (len(vertices), len(faces), points, connectivity, offsets, types)


def wrl(vertices, faces):
    points = ",\n        ".join("%s %s %s" % tuple(map(num, v)) for v in vertices)
    index = ",\n      ".join(", ".join(map(str, f)) + ", -1" for f in faces)
    return ("#VRML V2.0 utf8\n# polygon test shapes (make_polygon_meshes.py); convex FALSE, as CAD exporters write it\n"
            "Shape {\n  geometry IndexedFaceSet {\n    convex FALSE\n    solid FALSE\n"
            "    coord Coordinate {\n      point [\n        %s\n      ]\n    }\n"
            "    coordIndex [\n      %s\n    ]\n  }\n}\n") % (points, index)


def main():
    vertices, faces = mesh()
    write("polygons.obj", obj(vertices, faces))
    write("polygons.off", off(vertices, faces))
    write("polygons_ascii.ply", ply_ascii(vertices, faces))
    write("polygons_le.ply", ply_le(vertices, faces))
    write("polygons.vtk", vtk_legacy(vertices, faces))
    write("polygons.vtp", vtp(vertices, faces))
    write("polygons.vtu", vtu(vertices, faces))
    write("polygons.wrl", wrl(vertices, faces))
    write("ring.obj", obj(*mesh([0])))

    tet_v = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    tet_f = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    blender = "Created by Blender3D 247 - www.blender.org, source file: 'tet.blend'"
    write("blender_247.ply", ply_ascii(tet_v, tet_f, extra=(blender,)).replace("list uchar int", "list uchar uint"))


if __name__ == "__main__":
    main()
