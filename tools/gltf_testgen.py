#!/usr/bin/env python3
"""Writes small glTF 2.0 assemblies for rtwall's importer tests, with the standard library only.

It is a second, independent glTF writer (rtwall reads glTF through tinygltf), so the tests read
files that rtwall's own code did not make. One assembly, written three ways that must import
alike:
  embedded.gltf   buffers and the texture as data: URIs
  binary.glb      one GLB file: the buffer in the BIN chunk, the texture in a buffer view
  external.gltf   external.bin and checker.png beside it
The assembly: a textured box mesh placed by three nodes (one under a scaled parent, one by a
matrix) and four times more by EXT_mesh_gpu_instancing; a quad with vertex colours (normalised
unsigned bytes); a glass pane (KHR_materials_transmission and KHR_materials_ior), without an
index accessor; a mesh of two primitives, a metal triangle strip and a triangle without a
material. Unique meshes: 5 (one per primitive); instances: 11; nodes: 9.
Beside them: shared_accessors.glb (21 glTF meshes, 20 of them over one box's accessors) and
copied_accessors.glb (the same, each box with accessors of its own): see shared(); alpha.glb
(glTF's alpha modes and doubleSided): see alpha_assembly(); congruent.glb (a flat export of
congruent shapes and near misses): see congruent().

With --malformed it also writes broken files, each with one thing wrong (the names say what).

  python3 tools/gltf_testgen.py --out DIR [--malformed]
  python3 tools/gltf_testgen.py --out DIR --grid N   # a large file for timing: an N x N x N grid of boxes
  python3 tools/gltf_testgen.py --out DIR --flat-parts N  # a flat export of N parts of 3 shapes (timing)
"""
import argparse
import base64
import json
import math
import random
import os
import struct
import zlib


def png(width, height, pixels, channels=3):
    """An 8-bit RGB (channels 3) or RGBA (channels 4) PNG, filter 0 on every row."""
    row = width * channels
    raw = b"".join(b"\x00" + pixels[y * row:(y + 1) * row] for y in range(height))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    colour_type = {3: 2, 4: 6}[channels]
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def checker_png():
    n = 8
    rgb = bytearray()
    for y in range(n):
        for x in range(n):
            rgb += bytes((230, 30, 30)) if (x + y) % 2 else bytes((240, 240, 240))
    return png(n, n, bytes(rgb))


FLOAT, UBYTE, USHORT = 5126, 5121, 5123


class Builder:
    def __init__(self):
        self.blob = bytearray()
        self.views = []
        self.accessors = []

    def view(self, data, target=None):
        while len(self.blob) % 4:
            self.blob.append(0)
        v = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        if target:
            v["target"] = target
        self.blob += data
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, fmt_type, values, components, component_type=FLOAT, normalized=False, target=None):
        code = {FLOAT: "f", UBYTE: "B", USHORT: "H"}[component_type]
        flat = [c for v in values for c in (v if isinstance(v, (list, tuple)) else (v,))]
        data = struct.pack("<%d%s" % (len(flat), code), *flat)
        a = {"bufferView": self.view(data, target), "componentType": component_type, "count": len(values),
             "type": fmt_type}
        if normalized:
            a["normalized"] = True
        if fmt_type == "VEC3" and component_type == FLOAT:
            a["min"] = [min(v[i] for v in values) for i in range(3)]
            a["max"] = [max(v[i] for v in values) for i in range(3)]
        self.accessors.append(a)
        return len(self.accessors) - 1


def box_geometry():
    """24 vertices (4 per face, outward normals, UVs) and 36 indices, counter-clockwise from outside."""
    pos, nrm, uv, idx = [], [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
            base = len(pos)
            for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = sign * 0.5
                p[u_axis] = a * 0.5
                p[v_axis] = b * 0.5 * sign
                pos.append(p)
                nrm.append(list(n))
                uv.append([(a + 1) / 2, (b + 1) / 2])
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, uv, idx


def quat_y(degrees):
    h = math.radians(degrees) / 2
    return [0.0, math.sin(h), 0.0, math.cos(h)]


def assembly(image_mode):
    """The glTF JSON and its binary buffer. image_mode: 'uri' (filled in by the caller) or 'view'."""
    b = Builder()
    pos, nrm, uv, idx = box_geometry()
    box = {"attributes": {"POSITION": b.accessor("VEC3", pos, 3, target=34962),
                          "NORMAL": b.accessor("VEC3", nrm, 3, target=34962),
                          "TEXCOORD_0": b.accessor("VEC2", uv, 2, target=34962)},
           "indices": b.accessor("SCALAR", idx, 1, USHORT, target=34963), "material": 0}
    quad_pos = [[-0.5, 0.0, 0.5], [0.5, 0.0, 0.5], [0.5, 0.0, -0.5], [-0.5, 0.0, -0.5]]
    quad_col = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 255, 255]]
    colours = {"attributes": {"POSITION": b.accessor("VEC3", quad_pos, 3),
                              "COLOR_0": b.accessor("VEC4", quad_col, 4, UBYTE, normalized=True)},
               "indices": b.accessor("SCALAR", [0, 1, 2, 0, 2, 3], 1, UBYTE), "material": 1}
    pane_pos = [[-0.6, -0.4, 0.0], [0.6, -0.4, 0.0], [0.6, 0.4, 0.0], [-0.6, -0.4, 0.0], [0.6, 0.4, 0.0], [-0.6, 0.4, 0.0]]
    pane = {"attributes": {"POSITION": b.accessor("VEC3", pane_pos, 3)}, "material": 2}
    strip_pos = [[0.0, 0.0, 0.0], [0.0, 0.3, 0.0], [1.0, 0.0, 0.0], [1.0, 0.3, 0.0], [2.0, 0.0, 0.0], [2.0, 0.3, 0.0]]
    strip = {"attributes": {"POSITION": b.accessor("VEC3", strip_pos, 3)}, "mode": 5, "material": 3}
    plain = {"attributes": {"POSITION": b.accessor("VEC3", [[0, 0.5, 0], [0.5, 0.5, 0], [0, 1.0, 0]], 3)}}
    bolts_t = b.accessor("VEC3", [[-1.5, 0.1, 1.5], [1.5, 0.1, 1.5], [1.5, 0.1, -1.5], [-1.5, 0.1, -1.5]], 3)
    bolts_s = b.accessor("VEC3", [[0.2, 0.2, 0.2]] * 4, 3)

    doc = {
        "asset": {"version": "2.0", "generator": "rtwall tools/gltf_testgen.py"},
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "EXT_mesh_gpu_instancing"],
        "scene": 0,
        "scenes": [{"name": "review", "nodes": [0]}],
        "nodes": [
            {"name": "root", "children": [1, 2, 3, 4, 5, 6, 8]},
            {"name": "box_a", "mesh": 0, "translation": [-2.0, 0.5, 0.0]},
            {"name": "box_b", "mesh": 0, "translation": [2.0, 0.5, 0.0], "rotation": quat_y(45)},
            {"name": "group", "scale": [0.5, 0.5, 0.5], "translation": [0.0, 0.0, -2.0], "children": [7]},
            {"name": "floor_colours", "mesh": 1, "scale": [4.0, 1.0, 4.0]},
            {"name": "window", "mesh": 2, "translation": [0.0, 1.0, 1.5]},
            {"name": "bolts", "mesh": 0,
             "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": bolts_t, "SCALE": bolts_s}}}},
            {"name": "box_c", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1]},
            {"name": "pipes", "mesh": 3, "translation": [-1.0, 2.0, -1.0]},
        ],
        "meshes": [{"name": "box", "primitives": [box]}, {"name": "colour_quad", "primitives": [colours]},
                   {"name": "pane", "primitives": [pane]}, {"name": "pipe", "primitives": [strip, plain]}],
        "materials": [
            {"name": "textured", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                                          "roughnessFactor": 0.5}},
            {"name": "painted", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0}},
            {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 1.0, 0.95, 1.0], "metallicFactor": 0.0,
                                                       "roughnessFactor": 0.0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.45}}},
            {"name": "steel", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.85, 1.0], "metallicFactor": 1.0,
                                                       "roughnessFactor": 0.2}},
        ],
        "textures": [{"source": 0}],
        "images": [{}],
    }
    if image_mode == "view":
        doc["images"][0] = {"bufferView": b.view(checker_png()), "mimeType": "image/png"}
    doc["bufferViews"] = b.views
    doc["accessors"] = b.accessors
    doc["buffers"] = [{"byteLength": len(b.blob)}]
    return doc, bytes(b.blob)


def data_uri(mime, data):
    return "data:%s;base64,%s" % (mime, base64.b64encode(data).decode("ascii"))


def glb(doc, blob):
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    blob = blob + b"\x00" * (-len(blob) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def write(path, data):
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode("utf-8"))


def write_assemblies(out):
    doc, blob = assembly("uri")
    doc["buffers"][0]["uri"] = data_uri("application/octet-stream", blob)
    doc["images"][0] = {"uri": data_uri("image/png", checker_png())}
    write(os.path.join(out, "embedded.gltf"), json.dumps(doc, indent=1))

    doc, blob = assembly("view")
    write(os.path.join(out, "binary.glb"), glb(doc, blob))

    doc, blob = assembly("uri")
    doc["buffers"][0]["uri"] = "external.bin"
    doc["images"][0] = {"uri": "checker.png"}
    write(os.path.join(out, "external.gltf"), json.dumps(doc, indent=1))
    write(os.path.join(out, "external.bin"), blob)
    write(os.path.join(out, "checker.png"), checker_png())

    write(os.path.join(out, "shared_accessors.glb"), shared(False))
    write(os.path.join(out, "copied_accessors.glb"), shared(True))
    write(os.path.join(out, "alpha.glb"), glb(*alpha_assembly()))
    write(os.path.join(out, "congruent.glb"), congruent())


def write_malformed(out):
    """Broken files, each wrong in one way; the importer must name the file and the fault."""
    def embedded():
        doc, blob = assembly("uri")
        doc["buffers"][0]["uri"] = data_uri("application/octet-stream", blob)
        doc["images"][0] = {"uri": data_uri("image/png", checker_png())}
        return doc, blob

    def put(name, doc):
        write(os.path.join(out, name), json.dumps(doc))

    doc, blob = assembly("view")
    whole = glb(doc, blob)
    write(os.path.join(out, "truncated.glb"), whole[:len(whole) // 2])
    write(os.path.join(out, "bad_json.gltf"), '{"asset": {"version": "2.0"}, "nodes": [')

    doc, _ = embedded()
    doc["accessors"][0]["count"] = 1000000  # the box's positions: far more than its buffer view holds
    put("accessor_overflow.gltf", doc)

    doc, blob = embedded()
    doc["bufferViews"][0]["byteLength"] = len(blob) + 64  # the view runs past the end of its buffer
    put("view_outside_buffer.gltf", doc)

    doc, _ = embedded()
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99  # no such accessor
    put("bad_accessor_index.gltf", doc)

    doc, blob = assembly("uri")
    # Index 0 of the colour quad (an unsigned byte) patched to 200, with 4 vertices.
    view = doc["bufferViews"][doc["accessors"][doc["meshes"][1]["primitives"][0]["indices"]]["bufferView"]]
    patched = bytearray(blob)
    patched[view["byteOffset"]] = 200
    doc["buffers"][0]["uri"] = data_uri("application/octet-stream", bytes(patched))
    doc["images"][0] = {"uri": data_uri("image/png", checker_png())}
    put("index_out_of_range.gltf", doc)

    doc, _ = assembly("uri")
    doc["buffers"][0]["uri"] = "missing.bin"
    doc["images"][0] = {"uri": data_uri("image/png", checker_png())}
    put("missing_buffer.gltf", doc)

    doc, _ = embedded()
    doc["accessors"][1]["count"] = 2 ** 31  # a huge count that must be refused, not allocated
    put("huge_count.gltf", doc)

    doc, _ = embedded()
    doc["nodes"][7]["children"] = [3]  # box_c (under group) names group as its child: a cycle
    put("node_cycle.gltf", doc)

    doc, blob = alpha_assembly()
    doc["materials"][1]["alphaMode"] = "SOMETIMES"
    write(os.path.join(out, "bad_alpha_mode.glb"), glb(doc, blob))

    # Zero scales: box_a flat on one axis, and one of the four bolts (EXT_mesh_gpu_instancing)
    # squashed to a point. Legal glTF (exporters hide objects so); nothing can be traced through
    # them: the importer leaves those instances out, one warning line per node.
    doc, blob = assembly("view")
    doc["nodes"][1]["scale"] = [1.0, 0.0, 1.0]
    bolts_s = doc["accessors"][doc["nodes"][6]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"]]
    view = doc["bufferViews"][bolts_s["bufferView"]]
    patched = bytearray(blob)
    at = view.get("byteOffset", 0) + bolts_s.get("byteOffset", 0) + 2 * 12  # the third bolt's scale
    patched[at:at + 12] = struct.pack("<3f", 0.0, 0.0, 0.0)
    write(os.path.join(out, "zero_scale.glb"), glb(doc, bytes(patched)))

    doc, blob = assembly("view")
    # The texture's buffer view runs past the BIN chunk (tinygltf 2.7 itself reads it unchecked).
    doc["bufferViews"][doc["images"][0]["bufferView"]]["byteOffset"] = len(blob) + 100000
    write(os.path.join(out, "image_view_outside_buffer.glb"), glb(doc, blob))


def plate_geometry(nx, nz):
    """A flat plate of nx x nz quads (2 nx nz triangles) in the xz plane, normal +y."""
    pos, nrm, idx = [], [], []
    for j in range(nz + 1):
        for i in range(nx + 1):
            pos.append([-2.0 + 4.0 * i / nx, 0.0, -2.0 + 4.0 * j / nz])
            nrm.append([0.0, 1.0, 0.0])
    for j in range(nz):
        for i in range(nx):
            a = j * (nx + 1) + i
            idx += [a, a + nx + 1, a + 1, a + 1, a + nx + 1, a + nx + 2]
    return pos, nrm, idx


def shared(copies):
    """21 glTF meshes: 20 boxes over the same accessors (as writers that give every copy of a part a
    mesh of its own write them), alternating two materials, and a plate of 320 triangles; one node
    each, and a 22nd node placing box mesh 3 four more times by EXT_mesh_gpu_instancing. Stored:
    2 meshes, 332 unique triangles; instances 25 (608 instanced triangles). With copies=True every
    box mesh has accessors of its own over the same bytes: 21 meshes as far as accessors tell."""
    b = Builder()
    pos, nrm, _, idx = box_geometry()

    def box_primitive():
        return {"attributes": {"POSITION": b.accessor("VEC3", pos, 3), "NORMAL": b.accessor("VEC3", nrm, 3)},
                "indices": b.accessor("SCALAR", idx, 1, USHORT)}

    first = box_primitive()
    meshes = []
    for i in range(20):
        prim = dict(box_primitive() if copies and i else first)
        prim["material"] = i % 2
        meshes.append({"name": "box%02d" % i, "primitives": [prim]})
    ppos, pnrm, pidx = plate_geometry(16, 10)
    meshes.append({"name": "plate", "primitives": [{
        "attributes": {"POSITION": b.accessor("VEC3", ppos, 3), "NORMAL": b.accessor("VEC3", pnrm, 3)},
        "indices": b.accessor("SCALAR", pidx, 1, USHORT), "material": 2}]})
    nodes = [{"name": "plant", "children": list(range(1, 23))}]
    for i in range(20):
        nodes.append({"name": "box node %d" % i, "mesh": i, "rotation": quat_y(9.0 * i),
                      "translation": [-1.6 + 0.8 * (i % 5), 0.25, -1.2 + 0.8 * (i // 5)], "scale": [0.3, 0.3, 0.3]})
    nodes.append({"name": "plate node", "mesh": 20})
    bolts = b.accessor("VEC3", [[-1.8, 0.1, 1.8], [1.8, 0.1, 1.8], [1.8, 0.1, -1.8], [-1.8, 0.1, -1.8]], 3)
    scale = b.accessor("VEC3", [[0.15, 0.15, 0.15]] * 4, 3)
    nodes.append({"name": "bolts", "mesh": 3,
                  "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": bolts, "SCALE": scale}}}})
    doc = {"asset": {"version": "2.0", "generator": "rtwall tools/gltf_testgen.py"},
           "extensionsUsed": ["EXT_mesh_gpu_instancing"], "scene": 0, "scenes": [{"nodes": [0]}], "nodes": nodes,
           "meshes": meshes,
           "materials": [{"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1.0], "metallicFactor": 0.0}},
                         {"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.8, 1.0], "metallicFactor": 0.0}},
                         {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.6, 1.0], "metallicFactor": 0.0}}],
           "bufferViews": b.views, "accessors": b.accessors, "buffers": [{"byteLength": len(b.blob)}]}
    return glb(doc, bytes(b.blob))


def alpha_assembly():
    """Four unit quads at z = 0 facing +z (UVs 0..1 left to right), centred at x = -2.25, -0.75,
    0.75, 2.25, before a green backdrop at z = -1:
      mask    MASK, alphaCutoff 0.4, a red RGBA texture whose left half has alpha 0, right half 255
      blend   BLEND, blue, baseColorFactor alpha 0.5
      faded   MASK, baseColorFactor alpha 0.3 (below the default cutoff 0.5: all hole)
      opaque  OPAQUE, yellow, alpha 0.1 (ignored), doubleSided
    """
    b = Builder()
    quad_uv = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
    quad_idx = [0, 1, 2, 0, 2, 3]
    prims = []
    for i, x in enumerate((-2.25, -0.75, 0.75, 2.25)):
        pos = [[x - 0.5, -0.5, 0.0], [x + 0.5, -0.5, 0.0], [x + 0.5, 0.5, 0.0], [x - 0.5, 0.5, 0.0]]
        prims.append({"attributes": {"POSITION": b.accessor("VEC3", pos, 3),
                                     "NORMAL": b.accessor("VEC3", [[0.0, 0.0, 1.0]] * 4, 3),
                                     "TEXCOORD_0": b.accessor("VEC2", quad_uv, 2)},
                      "indices": b.accessor("SCALAR", quad_idx, 1, UBYTE), "material": i})
    back = [[-6.0, -4.0, -1.0], [6.0, -4.0, -1.0], [6.0, 4.0, -1.0], [-6.0, 4.0, -1.0]]
    prims.append({"attributes": {"POSITION": b.accessor("VEC3", back, 3)},
                  "indices": b.accessor("SCALAR", quad_idx, 1, UBYTE), "material": 4})
    texels = bytearray()
    for y in range(2):
        for x in range(8):
            texels += bytes((230, 20, 20, 0 if x < 4 else 255))
    image = b.view(png(8, 2, bytes(texels), channels=4))

    def pbr(rgba):
        return {"baseColorFactor": rgba, "metallicFactor": 0.0, "roughnessFactor": 1.0}

    doc = {"asset": {"version": "2.0", "generator": "rtwall tools/gltf_testgen.py"}, "scene": 0,
           "scenes": [{"nodes": [0]}], "nodes": [{"name": "stage", "mesh": 0}],
           "meshes": [{"name": "quads", "primitives": prims}],
           "materials": [
               dict(name="mask", alphaMode="MASK", alphaCutoff=0.4,
                    pbrMetallicRoughness=dict(pbr([1.0, 1.0, 1.0, 1.0]), baseColorTexture={"index": 0})),
               dict(name="blend", alphaMode="BLEND", pbrMetallicRoughness=pbr([0.05, 0.05, 0.9, 0.5])),
               dict(name="faded", alphaMode="MASK", pbrMetallicRoughness=pbr([0.9, 0.1, 0.9, 0.3])),
               dict(name="opaque", doubleSided=True, pbrMetallicRoughness=pbr([0.9, 0.8, 0.05, 0.1])),
               dict(name="backdrop", pbrMetallicRoughness=pbr([0.05, 0.7, 0.05, 1.0]))],
           "textures": [{"source": 0}], "images": [{"bufferView": image, "mimeType": "image/png"}],
           "bufferViews": b.views, "accessors": b.accessors, "buffers": [{"byteLength": len(b.blob)}]}
    return doc, bytes(b.blob)


def rotation(axis, degrees):
    """The 3x3 rotation (rows) about a unit axis."""
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z)
    x, y, z = x / n, y / n, z / n
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    t = 1 - c
    return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]


def apply(m, p):
    return [m[0][0] * p[0] + m[0][1] * p[1] + m[0][2] * p[2], m[1][0] * p[0] + m[1][1] * p[1] + m[1][2] * p[2],
            m[2][0] * p[0] + m[2][1] * p[1] + m[2][2] * p[2]]


def cuboid(sx, sy, sz, offset=(0.0, 0.0, 0.0)):
    pos, nrm, _, idx = box_geometry()
    return ([[p[0] * sx + offset[0], p[1] * sy + offset[1], p[2] * sz + offset[2]] for p in pos], nrm, idx)


def prism(sides, radius, height):
    """A closed prism about y, flat-shaded (vertices repeated per face)."""
    pos, nrm, idx = [], [], []
    ring = [(radius * math.cos(2 * math.pi * k / sides), radius * math.sin(2 * math.pi * k / sides)) for k in range(sides)]
    for k in range(sides):
        (x0, z0), (x1, z1) = ring[k], ring[(k + 1) % sides]
        a = math.pi * (2 * k + 1) / sides
        base = len(pos)
        pos += [[x0, -height / 2, z0], [x1, -height / 2, z1], [x1, height / 2, z1], [x0, height / 2, z0]]
        nrm += [[math.cos(a), 0.0, math.sin(a)]] * 4
        idx += [base, base + 2, base + 1, base, base + 3, base + 2]
    for y, ny in ((height / 2, 1.0), (-height / 2, -1.0)):
        base = len(pos)
        pos += [[x, y, z] for (x, z) in ring]
        nrm += [[0.0, ny, 0.0]] * sides
        for k in range(1, sides - 1):
            idx += [base, base + k + 1, base + k] if ny > 0 else [base, base + k, base + k + 1]
    return pos, nrm, idx


def renumbered(shape, seed):
    """The same surface with its vertices and triangles in another order (each triangle started
    at another corner, its winding kept)."""
    pos, nrm, idx = shape
    rng = random.Random(seed)
    order = list(range(len(pos)))
    rng.shuffle(order)  # new vertex k is old vertex order[k]
    new_of = {old: new for new, old in enumerate(order)}
    tris = [[new_of[i] for i in idx[t:t + 3]] for t in range(0, len(idx), 3)]
    rng.shuffle(tris)
    out = []
    for t in tris:
        r = rng.randrange(3)
        out += t[r:] + t[:r]
    return [pos[k] for k in order], [nrm[k] for k in order], out


def congruent():
    """A flat export: 32 meshes, each with accessors of its own and its vertices already placed in
    the world (every node has the identity transform), as meshers and flat CAD exports write them.
    17 are 3 shapes placed by rigid motions: a plate (x4, and once 500 units out), a bolt (x8), an
    L bracket (x4). 3 are
    near misses that must stay apart: the plate scaled by 1.001, a bolt with one vertex moved by
    1e-3, the bracket mirrored. 3 are a non-planar quad folded along one diagonal, the other, and
    the first again, turned and moved. 5 are renumbered (vertex and triangle order shuffled):
    two bolts and a bracket, found; a bolt with a vertex moved, kept apart; a mirrored bracket,
    found as a copy of the other mirror image. 4 are true mirror images (wound outward) and a
    chiral corner: the mirrored bracket is the bracket turned (found), the corner turned is found,
    the corner mirrored is not. Unique after detection: 11 (3 + 3 + 2 + 1 + 2)."""
    b = Builder()
    plate = cuboid(2.0, 0.2, 1.0)
    bolt = prism(6, 0.15, 0.6)
    bp, bn, bi = cuboid(0.8, 0.1, 0.4, (0.0, -0.25, 0.0))
    up, un, ui = cuboid(0.1, 0.5, 0.4, (-0.35, 0.0, 0.0))
    bracket = (bp + up, bn + un, bi + [i + len(bp) for i in ui])
    placements = []  # (name, shape, rotation, translation, tweak)
    for k in range(4):
        placements.append(("plate %d" % k, plate, rotation((0.2, 1.0, 0.1 * k), 30.0 * k + 7.0), (3.0 * k - 4.5, 0.0, -3.0), None))
    # 500 units out (400, 300), where floats keep ~3e-5: beyond the tolerance relative to the plate (2.3e-5),
    # within the precision the file could store (the tolerance's floor).
    placements.append(("plate far out", plate, rotation((0.0, 1.0, 0.3), 50.0), (400.0, 0.0, 300.0), None))
    for k in range(8):
        placements.append(("bolt %d" % k, bolt, rotation((1.0, 0.3 * k, 0.5), 45.0 * k + 11.0), (1.2 * k - 4.2, 0.8, 0.0), None))
    for k in range(4):
        placements.append(("bracket %d" % k, bracket, rotation((0.0, 1.0, 0.0), 90.0 * k + 15.0), (3.0 * k - 4.5, 0.3, 3.0), None))
    placements.append(("plate scaled 1.001", plate, rotation((0.0, 1.0, 0.0), 10.0), (0.0, 0.0, -6.0), "scale"))
    placements.append(("bolt with a vertex moved", bolt, rotation((1.0, 0.0, 0.0), 20.0), (2.0, 0.8, -6.0), "vertex"))
    placements.append(("bracket mirrored", bracket, rotation((0.0, 1.0, 0.0), 40.0), (4.0, 0.3, -6.0), "mirror"))
    # Copies numbered otherwise (another writer's vertex and triangle order): found without a
    # given correspondence; a renumbered near miss stays apart, a renumbered mirror image is
    # congruent to the other mirror image only.
    placements.append(("bolt renumbered 1", renumbered(bolt, 1), rotation((0.3, 1.0, 0.2), 33.0), (-4.0, 0.8, 6.0), None))
    placements.append(("bolt renumbered 2", renumbered(bolt, 2), rotation((1.0, 0.0, 0.4), 71.0), (-2.5, 0.8, 6.0), None))
    placements.append(("bracket renumbered", renumbered(bracket, 3), rotation((0.0, 1.0, 0.2), 123.0), (-1.0, 0.3, 6.0), None))
    placements.append(("bolt renumbered, vertex moved", renumbered(bolt, 4), rotation((0.0, 0.0, 1.0), 12.0), (0.5, 0.8, 6.0), "vertex"))
    placements.append(("bracket renumbered mirrored", renumbered(bracket, 5), rotation((0.0, 1.0, 0.0), 200.0), (2.0, 0.3, 6.0), "mirror"))
    # Mirror images wound outward (a true mirror, as a CAD mirror makes it): the L bracket has a
    # plane of symmetry, so its mirror image is the bracket turned and is found; a corner of
    # three arms of different lengths has none (it is chiral): its mirror image stays apart,
    # while a turned copy of it is found.
    ap, an, ai = cuboid(0.6, 0.05, 0.05, (0.6, 0.0, 0.0))
    bp2, bn2, bi2 = cuboid(0.05, 0.4, 0.05, (0.0, 0.4, 0.0))
    cp, cn, ci = cuboid(0.05, 0.05, 0.25, (0.0, 0.0, 0.25))
    corner = (ap + bp2 + cp, an + bn2 + cn, ai + [i + len(ap) for i in bi2] + [i + len(ap) + len(bp2) for i in ci])
    placements.append(("bracket mirrored outward", bracket, rotation((0.0, 1.0, 0.0), 70.0), (4.0, 0.3, 7.5), "mirror out"))
    placements.append(("corner", corner, rotation((0.0, 1.0, 0.0), 0.0), (-6.0, 0.5, -8.0), None))
    placements.append(("corner turned", corner, rotation((1.0, 1.0, 0.0), 80.0), (-4.0, 0.5, -8.0), None))
    placements.append(("corner mirrored", corner, rotation((0.0, 1.0, 0.0), 30.0), (-2.0, 0.5, -8.0), "mirror out"))
    # The same four vertices of a non-planar quad folded along one diagonal or the other: other
    # surfaces, never merged; a moved copy of the first fold is.
    fold = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.3, 1.0], [0.0, 0.0, 1.0]]
    fold_n = [[0.0, 1.0, 0.0]] * 4
    placements.append(("fold a", (fold, fold_n, [0, 2, 1, 0, 3, 2]), rotation((0.0, 1.0, 0.0), 0.0), (-6.0, 0.0, 5.0), None))
    placements.append(("fold b", (fold, fold_n, [0, 3, 1, 1, 3, 2]), rotation((0.0, 1.0, 0.0), 0.0), (-6.0, 0.0, 5.0), None))
    placements.append(("fold a moved", (fold, fold_n, [0, 2, 1, 0, 3, 2]), rotation((0.0, 1.0, 0.0), 25.0), (-4.0, 0.0, 5.0), None))
    meshes, nodes = [], []
    for name, (pos, nrm, idx), rot, move, tweak in placements:
        pos = [list(p) for p in pos]
        nrm = [list(n) for n in nrm]
        if tweak == "scale":
            pos = [[1.001 * c for c in p] for p in pos]
        elif tweak == "vertex":
            pos[0] = [pos[0][0] + 1e-3, pos[0][1], pos[0][2]]
        elif tweak in ("mirror", "mirror out"):
            pos = [[-p[0], p[1], p[2]] for p in pos]
            nrm = [[-n[0], n[1], n[2]] for n in nrm]
            if tweak == "mirror out":  # the winding turned too, so that the faces still face out
                idx = [i for t in range(0, len(idx), 3) for i in (idx[t], idx[t + 2], idx[t + 1])]
        world = [[a + t for a, t in zip(apply(rot, p), move)] for p in pos]
        normals = [apply(rot, n) for n in nrm]
        prim = {"attributes": {"POSITION": b.accessor("VEC3", world, 3), "NORMAL": b.accessor("VEC3", normals, 3)},
                "indices": b.accessor("SCALAR", idx, 1, USHORT), "material": 0 if name.startswith("plate") else 1}
        meshes.append({"name": name, "primitives": [prim]})
        nodes.append({"name": name, "mesh": len(meshes) - 1})
    doc = {"asset": {"version": "2.0", "generator": "rtwall tools/gltf_testgen.py"}, "scene": 0,
           "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
           "materials": [{"name": "steel", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.65, 1.0], "metallicFactor": 0.0}},
                         {"name": "brass", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.2, 1.0], "metallicFactor": 0.0}}],
           "bufferViews": b.views, "accessors": b.accessors, "buffers": [{"byteLength": len(b.blob)}]}
    return glb(doc, bytes(b.blob))


def flat_parts(n):
    """n parts of 3 shapes (plate, bolt, bracket), each a mesh with accessors of its own and its
    vertices placed in the world: a flat export for timing congruent-shape detection."""
    b = Builder()
    plate = cuboid(2.0, 0.2, 1.0)
    bolt = prism(8, 0.15, 0.6)
    bp, bn, bi = cuboid(0.8, 0.1, 0.4, (0.0, -0.25, 0.0))
    up, un, ui = cuboid(0.1, 0.5, 0.4, (-0.35, 0.0, 0.0))
    shapes = [plate, bolt, (bp + up, bn + un, bi + [i + len(bp) for i in ui])]
    side = max(1, int(math.ceil(math.sqrt(n))))
    meshes, nodes = [], []
    for k in range(n):
        pos, nrm, idx = shapes[k % 3]
        rot = rotation((0.3, 1.0, 0.2 * (k % 7)), 13.0 * k)
        move = (3.0 * (k % side), 0.0, 3.0 * (k // side))
        world = [[a + t for a, t in zip(apply(rot, p), move)] for p in pos]
        prim = {"attributes": {"POSITION": b.accessor("VEC3", world, 3), "NORMAL": b.accessor("VEC3", [apply(rot, q) for q in nrm], 3)},
                "indices": b.accessor("SCALAR", idx, 1, USHORT)}
        meshes.append({"name": "part %d" % k, "primitives": [prim]})
        nodes.append({"name": "part %d" % k, "mesh": k})
    doc = {"asset": {"version": "2.0", "generator": "rtwall tools/gltf_testgen.py"}, "scene": 0,
           "scenes": [{"nodes": list(range(n))}], "nodes": nodes, "meshes": meshes,
           "bufferViews": b.views, "accessors": b.accessors, "buffers": [{"byteLength": len(b.blob)}]}
    return glb(doc, bytes(b.blob))


def write_grid(out, n):
    """An n^3 grid of one box mesh (one node each), for import timing."""
    b = Builder()
    pos, nrm, uv, idx = box_geometry()
    prim = {"attributes": {"POSITION": b.accessor("VEC3", pos, 3), "NORMAL": b.accessor("VEC3", nrm, 3)},
            "indices": b.accessor("SCALAR", idx, 1, USHORT)}
    nodes = [{"name": "grid", "children": list(range(1, n ** 3 + 1))}]
    for i in range(n ** 3):
        x, y, z = i % n, (i // n) % n, i // (n * n)
        nodes.append({"name": "box %d" % i, "mesh": 0, "translation": [1.5 * x, 1.5 * y, 1.5 * z]})
    doc = {"asset": {"version": "2.0", "generator": "rtwall tools/gltf_testgen.py"}, "scene": 0,
           "scenes": [{"nodes": [0]}], "nodes": nodes, "meshes": [{"name": "box", "primitives": [prim]}],
           "bufferViews": b.views, "accessors": b.accessors, "buffers": [{"byteLength": len(b.blob)}]}
    write(os.path.join(out, "grid%d.glb" % n), glb(doc, bytes(b.blob)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True, help="directory to write into (created)")
    p.add_argument("--malformed", action="store_true", help="also write the broken files")
    p.add_argument("--grid", type=int, default=0, help="write gridN.glb: N^3 instances of one box")
    p.add_argument("--flat-parts", type=int, default=0, help="write flatN.glb: N parts of 3 shapes, each a mesh of its own")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.flat_parts:
        write(os.path.join(args.out, "flat%d.glb" % args.flat_parts), flat_parts(args.flat_parts))
        return
    if args.grid:
        write_grid(args.out, args.grid)
        return
    write_assemblies(args.out)
    if args.malformed:
        write_malformed(args.out)


if __name__ == "__main__":
    main()
