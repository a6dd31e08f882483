#!/usr/bin/python3
"""Charts of `rtwall bench denoise --json` (issue 28) for docs/shading.md.

    tools/denoise_chart.py OUT_DIR BENCH.json [BENCH.json ...] [--images DIR]

Writes OUT_DIR/denoise-front.png: per scene, moving-camera PSNR against frames per second, one
point per setting (denoise mode x GI samples) and image size, the Pareto front of each size drawn; and, with
--images (the bench's --images folder), OUT_DIR/denoise-CASE.png strips (off | temporal | svgf |
converged reference) for every set of images the folder holds.
"""
import argparse
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

MARKERS = {"off": "o", "temporal": "s", "svgf": "^"}


def front(points):
    """The points no other point beats in both fps and PSNR, by fps."""
    out = []
    for p in sorted(points, key=lambda p: -p[0]):
        if not out or p[1] > out[-1][1]:
            out.append(p)
    return out


def chart(rows, path):
    """One panel per scene: moving PSNR against fps, a front per image size."""
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.5 * len(scenes), 4.5), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        mine = [r for r in rows if r["scene"] == scene and not r["still"]]
        for w, h in sorted({(r["width"], r["height"]) for r in mine}):
            pts = []
            for r in mine:
                if (r["width"], r["height"]) != (w, h):
                    continue
                pts.append((r["fps"], r["psnr_db"]))
                ax.scatter(r["fps"], r["psnr_db"], marker=MARKERS.get(r["denoise"], "x"), s=50)
                ax.annotate(f'{r["denoise"]} {r["gi_spp"]}spp', (r["fps"], r["psnr_db"]), textcoords="offset points",
                            xytext=(4, 3), fontsize=7)
            f = front(pts)
            ax.plot([p[0] for p in f], [p[1] for p in f], "-", alpha=0.5, label=f"{w}x{h}: front")
        ax.axhline(30, color="grey", ls=":", lw=1)
        ax.set_xscale("log")
        ax.set_xlabel("frames per second (render + denoise, this 2-core PC, no cluster)")
        ax.set_ylabel("PSNR of the moving camera's frames, dB")
        ax.set_title(f"{scene}: o off, s temporal, ^ svgf; dotted: the 30 dB target", fontsize=10)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def strips(images, out):
    groups = {}
    for f in sorted(images.glob("denoise_*_reference.png")):
        stem = f.name[: -len("_reference.png")]
        groups[stem] = f
    for stem, ref in groups.items():
        tiles = []
        for mode in ("off", "temporal", "svgf"):
            cands = sorted(images.glob(f"{stem}_{mode}_1spp.png"))
            if cands:
                tiles.append(mpimg.imread(cands[0])[:, :, :3])
        if not tiles:
            continue
        tiles.append(mpimg.imread(ref)[:, :, :3])
        strip = np.concatenate(tiles, axis=1)
        name = stem[len("denoise_"):]
        mpimg.imsave(out / f"denoise-{name}.png", strip)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("json", nargs="+")
    ap.add_argument("--images")
    a = ap.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for j in a.json:
        rows += json.load(open(j))["rows"]
    if not rows:
        sys.exit("denoise_chart: no rows")
    chart(rows, out / "denoise-front.png")
    if a.images:
        strips(pathlib.Path(a.images), out)


if __name__ == "__main__":
    main()
