#!/usr/bin/env python3
"""Import time and stored bytes of flat glTF exports against their size, with and without
congruent-shape detection (issue 29): writes docs/congruence_import.png and prints the figures
as JSON.

Each file (tools/gltf_testgen.py --flat-parts N) holds N parts of 3 shapes, every part a mesh
with accessors of its own and its vertices placed in the world. `rtwall info --json` loads it
with detection (the default) and with --no-congruence, alternately, RUNS times each; the medians
of its load_seconds are charted, with the unique meshes and mesh bytes each way.

  /usr/bin/python3 tools/congruence_chart.py [--rtwall build/tools/rtwall] [--sizes 100,1000,10000,30000]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def info(rtwall, path, detect):
    cmd = [rtwall, "info", "--json", path] + ([] if detect else ["--no-congruence"])
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rtwall", default=os.path.join(HERE, "..", "build", "tools", "rtwall"))
    p.add_argument("--sizes", default="100,1000,10000,30000")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--chart", default=os.path.join(HERE, "..", "docs", "congruence_import.png"))
    args = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in [int(x) for x in args.sizes.split(",")]:
            subprocess.run([sys.executable, os.path.join(HERE, "gltf_testgen.py"), "--out", tmp, "--flat-parts", str(n)], check=True)
            path = os.path.join(tmp, "flat%d.glb" % n)
            on, off = [], []
            for _ in range(args.runs):
                a = info(args.rtwall, path, True)
                b = info(args.rtwall, path, False)
                on.append(a["load_seconds"])
                off.append(b["load_seconds"])
            rows.append({"parts": n, "load_s_detect": statistics.median(on), "load_s_no_detect": statistics.median(off),
                         "meshes_detect": a["meshes"], "meshes_no_detect": b["meshes"], "congruent_meshes": a["congruent_meshes"],
                         "mesh_bytes_detect": a["mesh_bytes"], "mesh_bytes_no_detect": b["mesh_bytes"]})
            os.remove(path)
    print(json.dumps(rows, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (t, m) = plt.subplots(1, 2, figsize=(10, 4))
    parts = [r["parts"] for r in rows]
    t.loglog(parts, [r["load_s_no_detect"] for r in rows], "o-", label="without detection")
    t.loglog(parts, [r["load_s_detect"] for r in rows], "s-", label="with detection")
    t.set_xlabel("parts (each a mesh of its own in the file)")
    t.set_ylabel("rtwall info load time, s (median of %d)" % args.runs)
    t.legend()
    t.grid(True, which="both", alpha=0.3)
    m.loglog(parts, [r["mesh_bytes_no_detect"] / 1e6 for r in rows], "o-", label="without detection")
    m.loglog(parts, [r["mesh_bytes_detect"] / 1e6 for r in rows], "s-", label="with detection (3 meshes)")
    m.set_xlabel("parts")
    m.set_ylabel("stored mesh bytes, MB")
    m.legend()
    m.grid(True, which="both", alpha=0.3)
    fig.suptitle("Flat glTF export of 3 shapes: congruent-shape detection (issue 29)")
    fig.tight_layout()
    fig.savefig(args.chart, dpi=90)


if __name__ == "__main__":
    main()
