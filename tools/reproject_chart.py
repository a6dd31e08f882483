#!/usr/bin/env python3
"""Charts `rtwall bench reproject --json` (issue 27): PSNR and FLIP of the shown image against a
true render, against head speed, one line per render rate, warped (solid) and stale (dashed),
one row of panels per scene. Writes the chart and prints the tables docs/latency.md quotes (the
grid, the guard bands, the failure cases). Several result files (e.g. the grid and a guard-band
run) are merged.

    build/tools/rtwall bench reproject --json --guard-bands 0 --images docs > out/reproject.json
    tools/reproject_chart.py docs/reprojection_quality.png out/reproject.json [more.json ...]
"""
import json
import sys


def load(paths):
    rows, cases = [], {}
    for path in paths:
        with open(path) as f:
            result = json.load(f)
        if result.get("benchmark") != "reproject" or "rows" not in result:
            sys.exit(f"{path}: not a result of rtwall bench reproject --json")
        rows += result["rows"]
        cases.update(result.get("failure_cases", {}))
    # A configuration measured in two files (the same seed gives the same figures): once.
    seen, unique = set(), []
    for r in rows:
        key = (r["scene"], r["speed_m_s"], r["render_fps"], r["warped"], r["guard_band"], r["width"], r["height"])
        if key not in seen:
            seen.add(key)
            unique.append(r)
    return unique, cases


def plain(rows):
    """The rows without a guard band: the grid of speeds x rates, warped and stale."""
    return [r for r in rows if r["guard_band"] == 0]


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = plain(rows)
    scenes = sorted({r["scene"] for r in rows})
    rates = sorted({r["render_fps"] for r in rows})
    fig, axes = plt.subplots(len(scenes), 2, figsize=(12, 4.2 * len(scenes)), squeeze=False)
    for s, scene in enumerate(scenes):
        psnr, flip = axes[s]
        for i, fps in enumerate(rates):
            for warped in (True, False):
                rs = sorted((r for r in rows if r["scene"] == scene and r["render_fps"] == fps and r["warped"] == warped),
                            key=lambda r: r["speed_m_s"])
                if not rs:
                    continue
                v = [r["speed_m_s"] for r in rs]
                style = dict(color=f"C{i}", ls="-" if warped else "--", marker="o" if warped else "x")
                name = f"{fps:g} fps, {'warped' if warped else 'stale (no warp)'}"
                psnr.plot(v, [r["psnr_db"]["median"] for r in rs], label=name, **style)
                psnr.fill_between(v, [r["psnr_db"]["p95"] for r in rs], [r["psnr_db"]["median"] for r in rs],
                                  color=f"C{i}", alpha=0.08)
                flip.plot(v, [r["flip"]["median"] for r in rs], label=name, **style)
                flip.fill_between(v, [r["flip"]["median"] for r in rs], [r["flip"]["p95"] for r in rs], color=f"C{i}",
                                  alpha=0.08)
        w, h, hz = rows[0]["width"], rows[0]["height"], rows[0]["display_hz"]
        psnr.set_ylabel("PSNR against the true render, dB\n(median; band to the worst 5 %)")
        flip.set_ylabel("mean FLIP against the true render\n(median; band to the worst 5 %)")
        psnr.set_title(f"{scene}: PSNR of the shown frame ({w}x{h}, {hz:g} Hz display)")
        flip.set_title(f"{scene}: FLIP of the shown frame (lower is better)")
        for ax in (psnr, flip):
            ax.set_xscale("log")
            ax.set_xticks([0.1, 0.25, 0.5, 1.0])
            ax.set_xticklabels(["0.1", "0.25", "0.5", "1"])
            ax.set_xlabel("head speed, m/s")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=80, facecolor="white")
    plt.close(fig)


def grid_table(rows):
    rows = plain(rows)
    print("| scene | head m/s | render fps | warped PSNR dB, median / worst 5 % | stale PSNR dB | warped FLIP, median / worst 5 % "
          "| stale FLIP | holes, median / worst 5 % |")
    print("|---|---|---|---|---|---|---|---|")
    key = lambda r: (r["scene"], r["speed_m_s"], r["render_fps"])
    stale = {key(r): r for r in rows if not r["warped"]}
    for r in sorted((r for r in rows if r["warped"]), key=key):
        s = stale.get(key(r))
        st = (f"{s['psnr_db']['median']:.1f} / {s['psnr_db']['p95']:.1f}", f"{s['flip']['median']:.3f} / {s['flip']['p95']:.3f}") if s else ("-", "-")
        print(f"| {r['scene']} | {r['speed_m_s']:g} | {r['render_fps']:g} | {r['psnr_db']['median']:.1f} / {r['psnr_db']['p95']:.1f} "
              f"| {st[0]} | {r['flip']['median']:.3f} / {r['flip']['p95']:.3f} | {st[1]} "
              f"| {100 * r['holes']['median']:.2f} % / {100 * r['holes']['p95']:.2f} % |")


def guard_table(rows):
    warped = [r for r in rows if r["warped"]]
    key = lambda r: (r["scene"], r["speed_m_s"], r["render_fps"])
    banded = {key(r) for r in warped if r["guard_band"] > 0}
    if not banded:
        return
    print("\n| scene | head m/s | render fps | guard band | pixels rendered | PSNR dB, median | edge PSNR dB, median / worst 5 % "
          "| edge FLIP, median / worst 5 % | holes, median |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in sorted((r for r in warped if key(r) in banded), key=lambda r: (key(r), r["guard_band"])):
        print(f"| {r['scene']} | {r['speed_m_s']:g} | {r['render_fps']:g} | {100 * r['guard_band']:g} % "
              f"| {100 * r['rendered_pixels']:.1f} % | {r['psnr_db']['median']:.1f} "
              f"| {r['edge_psnr_db']['median']:.1f} / {r['edge_psnr_db']['p95']:.1f} "
              f"| {r['edge_flip']['median']:.4f} / {r['edge_flip']['p95']:.4f} | {100 * r['holes']['median']:.2f} % |")


def case_table(cases):
    if not cases:
        return
    print("\n| case | head m/s | render fps | frame age | holes | warped PSNR dB / FLIP | stale PSNR dB / FLIP "
          "| where it fails | there: warped PSNR dB / FLIP | there: stale |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, c in cases.items():
        w, s = c["warped"], c["stale"]
        print(f"| {name} | {c['speed_m_s']:g} | {c['render_fps']:g} | {c['age_ms']:.0f} ms | {100 * c['holes']:.1f} % "
              f"| {w['psnr_db']:.1f} / {w['flip']:.3f} | {s['psnr_db']:.1f} / {s['flip']:.3f} | {c['marked']} "
              f"| {w['marked_psnr_db']:.1f} / {w['marked_flip']:.3f} | {s['marked_psnr_db']:.1f} / {s['marked_flip']:.3f} |")


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: reproject_chart.py OUT.png RESULT.json [RESULT.json ...]")
    rows, cases = load(sys.argv[2:])
    chart(rows, sys.argv[1])
    grid_table(rows)
    guard_table(rows)
    case_table(cases)


if __name__ == "__main__":
    main()
