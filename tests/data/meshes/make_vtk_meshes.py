#!/usr/bin/python3
"""Writes the VTK test meshes with VTK's own writers (python3-vtk9), so the importer is tested
on files as VTK produces them. The box is [0,1]x[0,2]x[0,3] (12 triangles, 8 points); the
strip file is the same box's 6 faces as 6 triangle strips of 4 points; the far box is the same
box moved to (148376, 1234, -223423) in double precision. Bad files are written by hand."""
import os
import vtk

HERE = os.path.dirname(os.path.abspath(__file__))


def box_points(offset=(0.0, 0.0, 0.0), double=False):
    pts = vtk.vtkPoints()
    if double:
        pts.SetDataTypeToDouble()
    for i in range(8):
        pts.InsertNextPoint(offset[0] + (i & 1) * 1.0, offset[1] + ((i >> 1) & 1) * 2.0, offset[2] + ((i >> 2) & 1) * 3.0)
    return pts


QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]


def box_polydata(offset=(0.0, 0.0, 0.0), double=False, normals=False):
    pd = vtk.vtkPolyData()
    pd.SetPoints(box_points(offset, double))
    polys = vtk.vtkCellArray()
    for q in QUADS:
        polys.InsertNextCell(4, q)
    pd.SetPolys(polys)
    # A line and a vertex cell, which the importer skips and counts.
    lines = vtk.vtkCellArray()
    lines.InsertNextCell(2, (0, 7))
    pd.SetLines(lines)
    if normals:
        n = vtk.vtkFloatArray()
        n.SetNumberOfComponents(3)
        n.SetName("Normals")
        for i in range(8):
            x, y, z = ((i & 1) * 2 - 1, ((i >> 1) & 1) * 2 - 1, ((i >> 2) & 1) * 2 - 1)
            n.InsertNextTuple3(x, y, z)
        pd.GetPointData().SetNormals(n)
    # Point data the renderer does not use (dropped on import).
    s = vtk.vtkFloatArray()
    s.SetName("temperature")
    for i in range(8):
        s.InsertNextValue(20.0 + i)
    pd.GetPointData().AddArray(s)
    return pd


def box_strips():
    pd = vtk.vtkPolyData()
    pd.SetPoints(box_points())
    strips = vtk.vtkCellArray()
    for a, b, c, d in QUADS:
        # Quad a b c d as the strip a b d c: triangles (a,b,d) and (b,c,d) after the flip.
        strips.InsertNextCell(4, (a, b, d, c))
    pd.SetStrips(strips)
    return pd


def hex_grid():
    ug = vtk.vtkUnstructuredGrid()
    ug.SetPoints(box_points())
    h = vtk.vtkHexahedron()
    for k, v in enumerate((0, 1, 3, 2, 4, 5, 7, 6)):
        h.GetPointIds().SetId(k, v)
    ug.InsertNextCell(h.GetCellType(), h.GetPointIds())
    return ug


def legacy(name, data, binary):
    w = vtk.vtkPolyDataWriter() if isinstance(data, vtk.vtkPolyData) else vtk.vtkUnstructuredGridWriter()
    w.SetFileName(os.path.join(HERE, name))
    w.SetInputData(data)
    w.SetFileVersion(42)
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    w.Write()


def xml(name, data, mode, compressor=None):
    w = vtk.vtkXMLPolyDataWriter() if isinstance(data, vtk.vtkPolyData) else vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(os.path.join(HERE, name))
    w.SetInputData(data)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary, "appended": w.SetDataModeToAppended}[mode]()
    if mode == "appended":
        w.EncodeAppendedDataOff()
    if compressor == "zlib":
        w.SetCompressorTypeToZLib()
    elif compressor == "lz4":
        w.SetCompressorTypeToLZ4()
    else:
        w.SetCompressorTypeToNone()
    w.Write()


def write(name, text):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(text if isinstance(text, bytes) else text.encode())


def main():
    legacy("box_ascii.vtk", box_polydata(normals=True), False)
    legacy("box_binary.vtk", box_polydata(), True)
    legacy("box_strips.vtk", box_strips(), False)
    legacy("box_hex_ascii.vtk", hex_grid(), False)
    xml("box_ascii.vtp", box_polydata(normals=True), "ascii")
    xml("box_base64.vtp", box_polydata(), "binary")
    xml("box_raw.vtp", box_polydata(), "appended")
    xml("box_zlib.vtp", box_polydata(), "binary", "zlib")
    xml("box_lz4.vtp", box_polydata(), "appended", "lz4")
    xml("box_hex_zlib.vtu", hex_grid(), "binary", "zlib")
    xml("box_hex_ascii.vtu", hex_grid(), "ascii")
    xml("box_far.vtp", box_polydata((148376.0, 1234.0, -223423.0), double=True), "binary")

    head = "# vtk DataFile Version 4.2\nbad\nASCII\nDATASET POLYDATA\n"
    write("bad_points_huge.vtk", head + "POINTS 4000000000 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n")
    write("bad_index_out_of_range.vtk", head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 7\n")
    write("bad_index_negative.vtk", head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 -1 2\n")
    write("bad_nan.vtk", head + "POINTS 3 float\n0 0 0 nan 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n")
    write("bad_truncated_ascii.vtk", head + "POINTS 3 float\n0 0 0 1 0\n")
    write("bad_structured.vtk", "# vtk DataFile Version 4.2\nbad\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 100000 100000 100000\n")
    write("bad_not_vtk.vtk", "solid this is not vtk\n")
    with open(os.path.join(HERE, "box_binary.vtk"), "rb") as f:
        data = f.read()
    write("bad_truncated_binary.vtk", data[: data.find(b"POLYGONS") + 30])
    write("bad_points_huge.vtp", '<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">\n'
          '<PolyData><Piece NumberOfPoints="4000000000" NumberOfPolys="1"><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>'
          '<Polys><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2</DataArray><DataArray type="Int32" Name="offsets" format="ascii">3</DataArray></Polys>'
          '</Piece></PolyData></VTKFile>\n')
    write("bad_index.vtp", '<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">\n'
          '<PolyData><Piece NumberOfPoints="3" NumberOfPolys="1"><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>'
          '<Polys><DataArray type="Int32" Name="connectivity" format="ascii">0 1 9</DataArray><DataArray type="Int32" Name="offsets" format="ascii">3</DataArray></Polys>'
          '</Piece></PolyData></VTKFile>\n')
    write("bad_garbage.vtp", '<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1"><PolyData><Piece NumberOfPoints="3"><Points>&&&<<\n')


if __name__ == "__main__":
    main()
