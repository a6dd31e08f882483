#!/usr/bin/env python3
"""Writes the small files with per-vertex texture coordinates (issue 7) that tests/mesh/uv_test.cpp reads.

Every good file holds the same quad: 4 vertices, 2 triangles wound towards +y, and the texture
coordinates below, exactly representable in float so that every format gives the same bits.
Run from this folder: python3 make_uv_meshes.py
"""
import math
import struct

P = [(0, 0, 0), (2, 0, 0), (2, 0, 1), (0, 0, 1)]
UV = [(0.125, 0.25), (0.875, 0.25), (0.875, 0.75), (0.125, 0.75)]
T = [(0, 2, 1), (0, 3, 2)]


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(name, mode) as f:
        f.write(data)


def ply_ascii(names):
    head = ["ply", "format ascii 1.0", "element vertex 4", "property float x", "property float y", "property float z",
            f"property float {names[0]}", f"property float {names[1]}", "element face 2",
            "property list uchar int vertex_indices", "end_header"]
    body = [f"{p[0]} {p[1]} {p[2]} {t[0]} {t[1]}" for p, t in zip(P, UV)] + [f"3 {a} {b} {c}" for a, b, c in T]
    return "\n".join(head + body) + "\n"


def ply_binary(names, uv=UV):
    head = ["ply", "format binary_little_endian 1.0", "element vertex 4", "property float x", "property float y",
            "property float z", f"property float {names[0]}", f"property float {names[1]}", "element face 2",
            "property list uchar int vertex_indices", "end_header"]
    out = ("\n".join(head) + "\n").encode()
    for p, t in zip(P, uv):
        out += struct.pack("<5f", *p, *t)
    for tri in T:
        out += struct.pack("<B3i", 3, *tri)
    return out


def main():
    write("uv_quad_ascii.ply", ply_ascii(("u", "v")))
    write("uv_quad_st_le.ply", ply_binary(("s", "t")))
    write("uv_quad_texture_uv.ply", ply_ascii(("texture_u", "texture_v")))
    write("bad_uv_nan_le.ply", ply_binary(("u", "v"), [UV[0], (math.nan, 0.25), UV[2], UV[3]]))

    off = ["STOFF", "4 2 0"] + [f"{p[0]} {p[1]} {p[2]} {t[0]} {t[1]}" for p, t in zip(P, UV)] + [f"3 {a} {b} {c}" for a, b, c in T]
    write("uv_quad.off", "\n".join(off) + "\n")

    obj = [f"v {p[0]} {p[1]} {p[2]}" for p in P] + [f"vt {t[0]} {t[1]}" for t in UV]
    obj += [f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}" for a, b, c in T]
    write("uv_quad.obj", "\n".join(obj) + "\n")

    # A seam: vertex 1 (index 0) has vt 1 in the first face and vt 5 in the second, so it is
    # split; vertex 3 (index 2) has vt 3 in both, so it is not. "vt u v w" drops w.
    seam = [f"v {p[0]} {p[1]} {p[2]}" for p in P] + [f"vt {t[0]} {t[1]} 0.5" for t in UV] + ["vt 0.5 0.0625 0.5"]
    seam += ["f 1/1 3/3 2/2", "f 1/5 4/4 3/3"]
    write("uv_seam.obj", "\n".join(seam) + "\n")

    # The same seam with vertex colours and normals: the copy of vertex 1 must carry both.
    colours = ["1 0 0", "0 1 0", "0 0 1", "1 1 0"]
    normals = ["0 1 0", "0 0.6 0.8", "0.6 0.8 0", "0 0.8 0.6"]
    attrs = ["# uv_seam.obj with vertex colours and normals: the seam's copy of vertex 1 must carry both"]
    attrs += [f"v {p[0]} {p[1]} {p[2]} {c}" for p, c in zip(P, colours)] + [f"vt {t[0]} {t[1]}" for t in UV]
    attrs += ["vt 0.5 0.0625"] + [f"vn {n}" for n in normals] + ["f 1/1/1 3/3/3 2/2/2", "f 1/5/1 4/4/4 3/3/3"]
    write("uv_seam_attrs.obj", "\n".join(attrs) + "\n")

    partial = [f"v {p[0]} {p[1]} {p[2]}" for p in P] + [f"vt {t[0]} {t[1]}" for t in UV]
    write("bad_uv_partial_face.obj", "\n".join(partial + ["f 1/1 3/3 2/2", "f 1/1 4 3/3"]) + "\n")
    write("bad_uv_face_without.obj", "\n".join(partial + ["f 1/1 3/3 2/2", "f 1 4 3"]) + "\n")

    vtk = ["# vtk DataFile Version 3.0", "uv quad", "ASCII", "DATASET POLYDATA", "POINTS 4 float"]
    vtk += [f"{p[0]} {p[1]} {p[2]}" for p in P] + ["POLYGONS 2 8"] + [f"3 {a} {b} {c}" for a, b, c in T]
    write("uv_quad.vtk", "\n".join(vtk + ["POINT_DATA 4", "TEXTURE_COORDINATES uv 2 float"] +
                                  [f"{t[0]} {t[1]}" for t in UV]) + "\n")
    # Binary (big-endian), since VTK's ASCII reader cannot spell a NaN.
    nan_vtk = b"# vtk DataFile Version 3.0\nuv quad\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n"
    nan_vtk += b"".join(struct.pack(">3f", *p) for p in P) + b"\nPOLYGONS 2 8\n"
    nan_vtk += b"".join(struct.pack(">4i", 3, *t) for t in T) + b"\nPOINT_DATA 4\nTEXTURE_COORDINATES uv 2 float\n"
    nan_vtk += b"".join(struct.pack(">2f", *t) for t in [UV[0], (math.nan, 0.25), UV[2], UV[3]]) + b"\n"
    write("bad_uv_nan.vtk", nan_vtk)
    write("bad_uv_1d.vtk", "\n".join(vtk + ["POINT_DATA 4", "TEXTURE_COORDINATES uv 1 float", "0 1 2 3"]) + "\n")

    pts = " ".join(f"{c}" for p in P for c in p)
    tc = " ".join(f"{t[0]} {t[1]} 0.5" for t in UV)
    conn = " ".join(str(i) for tri in T for i in tri)
    vtp = f"""<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
  <PolyData>
    <Piece NumberOfPoints="4" NumberOfPolys="2">
      <PointData TCoords="uvw">
        <DataArray type="Float32" Name="uvw" NumberOfComponents="3" format="ascii">{tc}</DataArray>
      </PointData>
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">{pts}</DataArray>
      </Points>
      <Polys>
        <DataArray type="Int32" Name="connectivity" format="ascii">{conn}</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">3 6</DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
"""
    write("uv_quad3.vtp", vtp)
    # Three texture coordinates for four points.
    write("bad_uv_count.vtp", vtp.replace(f'format="ascii">{tc}<', 'format="ascii">0 0 0 1 0 0 1 1 0<'))

    wrl = f"""#VRML V2.0 utf8
Shape {{
  geometry IndexedFaceSet {{
    coord Coordinate {{ point [ {", ".join(f"{p[0]} {p[1]} {p[2]}" for p in P)} ] }}
    coordIndex [ {", ".join(f"{a}, {b}, {c}, -1" for a, b, c in T)} ]
    texCoord TextureCoordinate {{ point [ {", ".join(f"{t[0]} {t[1]}" for t in UV)} ] }}
  }}
}}
"""
    write("uv_quad.wrl", wrl)

    # texCoordIndex: (u, v) per face corner; VTK's importer gives every corner its own point.
    write("uv_texcoordindex.wrl", """#VRML V2.0 utf8
Shape {
  geometry IndexedFaceSet {
    coord Coordinate { point [ 0 0 0, 2 0 0, 2 0 1, 0 0 1 ] }
    coordIndex [ 0, 2, 1, -1, 0, 3, 2, -1 ]
    texCoord TextureCoordinate { point [ 0.5 0.5, 0.125 0.0625, 0.25 0.75, 0.375 1, 1 0.875 ] }
    texCoordIndex [ 4, 3, 2, -1, 1, 0, 3, -1 ]
  }
}
""")


if __name__ == "__main__":
    main()
