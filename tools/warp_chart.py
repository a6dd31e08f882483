#!/usr/bin/env python3
"""Charts `rtwall bench warp --json` (issue 30): PSNR and FLIP against a supersampled direct
render, for direct per-pixel rays and for the rasteriser's post-warp, against the arc of the
curved screen (the warp's strength). Writes the PNG and prints the table docs/mpcdi.md quotes.

    build/tools/rtwall bench warp --json > out/warp.json
    tools/warp_chart.py out/warp.json docs/mpcdi_warp.png
"""
import json
import sys

METHODS = [("direct", "direct: 1 ray a pixel through the warp", "C0", "-", "o"),
           ("direct_ss2", "direct, 2x2 rays a pixel", "C0", "--", "s"),
           ("post", "post-warp: flat render of the projector's pixels, resampled", "C3", "-", "o"),
           ("post_2x", "post-warp: flat render of 2x2 as many pixels, resampled", "C3", "--", "s")]


def table(result):
    lines = ["| arc | " + " | ".join(m[0] + " PSNR / FLIP / s" for m in METHODS) + " |",
             "| --- |" + " --- |" * len(METHODS)]
    for r in result["rows"]:
        cells = ["%.2f dB / %.4f / %.3f" % (r[m]["psnr_db"], r[m]["flip"], r[m]["frame_s"]) for m, *_ in METHODS]
        lines.append("| %g deg | " % r["span_deg"] + " | ".join(cells) + " |")
    return "\n".join(lines)


def chart(result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = result["rows"]
    arcs = [r["span_deg"] for r in rows]
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.8))
    for key, label, colour, ls, marker in METHODS:
        a.plot(arcs, [r[key]["psnr_db"] for r in rows], color=colour, ls=ls, marker=marker, label=label)
        b.plot(arcs, [r[key]["flip"] for r in rows], color=colour, ls=ls, marker=marker, label=label)
    a.set_ylabel("PSNR against the reference, dB (higher is better)")
    b.set_ylabel("mean FLIP against the reference (lower is better)")
    for ax in (a, b):
        ax.set_xlabel("arc of the cylindrical screen, degrees (0: flat)")
        ax.grid(alpha=0.3)
    a.set_title("%dx%d projector, reference: %dx%d rays a pixel" % (result["width"], result["height"],
                                                                     result["reference_supersample"], result["reference_supersample"]))
    b.set_title(result["scene"])
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: warp_chart.py RESULT.json OUT.png")
    with open(sys.argv[1]) as f:
        result = json.load(f)
    chart(result, sys.argv[2])
    print(table(result))
