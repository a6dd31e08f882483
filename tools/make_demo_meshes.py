#!/usr/bin/env python3
"""Writes the demo scene's mesh files (configs/meshes/) with the standard library only, so the
demo exercises the real import path. Run once; the output is committed."""
import math
import struct
import sys
from pathlib import Path


def torus_knot(p, q, segments, sides, tube):
    def curve(t):
        r = 0.5 * (2.0 + math.cos(q * t))
        return (r * math.cos(p * t), 0.5 * math.sin(q * t), r * math.sin(p * t))

    verts, norms, tris = [], [], []
    for i in range(segments):
        t = 2 * math.pi * i / segments
        c0, c1 = curve(t), curve(t + 1e-3)
        tangent = [b - a for a, b in zip(c0, c1)]
        ln = math.sqrt(sum(x * x for x in tangent))
        tangent = [x / ln for x in tangent]
        up = (0.0, 1.0, 0.0)
        n = [tangent[1] * up[2] - tangent[2] * up[1], tangent[2] * up[0] - tangent[0] * up[2],
             tangent[0] * up[1] - tangent[1] * up[0]]
        ln = math.sqrt(sum(x * x for x in n))
        n = [x / ln for x in n]
        b = [tangent[1] * n[2] - tangent[2] * n[1], tangent[2] * n[0] - tangent[0] * n[2],
             tangent[0] * n[1] - tangent[1] * n[0]]
        for j in range(sides):
            a = 2 * math.pi * j / sides
            d = [math.cos(a) * n[k] + math.sin(a) * b[k] for k in range(3)]
            verts.append(tuple(c0[k] + tube * d[k] for k in range(3)))
            norms.append(tuple(d))
    for i in range(segments):
        for j in range(sides):
            a = i * sides + j
            b_ = ((i + 1) % segments) * sides + j
            c = ((i + 1) % segments) * sides + (j + 1) % sides
            d = i * sides + (j + 1) % sides
            tris.append((a, b_, c))
            tris.append((a, c, d))
    return verts, norms, tris


def write_ply_binary(path, verts, norms, tris):
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment rtwall demo mesh\n"
        f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        for v, n in zip(verts, norms):
            f.write(struct.pack("<6f", *v, *n))
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "configs" / "meshes")
    out.mkdir(parents=True, exist_ok=True)
    v, n, t = torus_knot(3, 2, 360, 24, 0.28)
    write_ply_binary(out / "knot.ply", v, n, t)
    print(f"wrote {out / 'knot.ply'}: {len(v)} vertices, {len(t)} triangles")


if __name__ == "__main__":
    main()
