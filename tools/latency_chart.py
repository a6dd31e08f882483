#!/usr/bin/env python3
"""Charts `rtwall bench latency --json` (issue 18): motion-to-photon latency against frame rate,
and the head error at display time against frame rate, for mono/stereo x async off/on x
prediction off/on. Writes docs/latency.png and prints the table docs/latency.md quotes.

    build/tools/rtwall bench latency --json > out/latency.json
    tools/latency_chart.py out/latency.json docs/latency.png
"""
import json
import sys


def label(r):
    return (f"{'stereo' if r['stereo'] else 'mono'}, {'async' if r['async'] else 'sync'}, "
            f"{'prediction' if r['prediction_ms'] > 0 else 'no prediction'}")


def series(rows):
    out = {}
    for r in rows:
        out.setdefault(label(r), []).append(r)
    for v in out.values():
        v.sort(key=lambda r: r["fps"])
    return out


def chart(result, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = result["rows"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 5))
    styles = {}
    for i, (name, rs) in enumerate(sorted(series(rows).items())):
        colour = f"C{i // 2}"
        ls = "-" if "no prediction" in name else "--"
        marker = "o" if "mono" in name else "s"
        styles[name] = (colour, ls, marker)
        fps = [r["fps"] for r in rs]
        # Per frame: the newest datagram it was made with to its presentation (the target's
        # measure); thin: every datagram, waiting for the frame in progress included.
        a.plot(fps, [r["frame_latency_ms_median"] for r in rs], ls=ls, marker=marker, color=colour, label=name)
        a.fill_between(fps, [r["frame_latency_ms_median"] for r in rs], [r["frame_latency_ms_p95"] for r in rs], color=colour,
                       alpha=0.08)
        a.plot(fps, [r["latency_ms_median"] for r in rs], ls=":", lw=0.8, marker=marker, ms=3, color=colour)
        b.plot(fps, [r["error_mm_median"] for r in rs], ls=ls, marker=marker, color=colour, label=name)
    # The async-off target: one frame time plus the slack.
    xs = sorted({r["fps"] for r in rows})
    if xs:
        lo, hi = min(xs) * 0.9, max(xs) * 1.1
        grid = [lo + (hi - lo) * k / 50 for k in range(51)]
        a.plot(grid, [1e3 / f + result["target_slack_ms"] for f in grid], color="red", ls=":", lw=1,
               label=f"target (sync): frame time + {result['target_slack_ms']:.0f} ms")
    b.axhline(result["target_error_mm"], color="red", ls=":", lw=1, label=f"target: {result['target_error_mm']:.0f} mm")
    a.set_xlabel("frames/s (median, presented)")
    a.set_ylabel("newest datagram to presented frame, ms (median; band to p95)\n"
                 "dotted: every datagram to the first frame using it (median)")
    a.set_title("Motion-to-photon latency")
    b.set_xlabel("frames/s (median, presented)")
    b.set_ylabel(f"head position error at display, mm (median), head at {result['head_speed_m_s']} m/s")
    b.set_title("Pose error at display time")
    for ax in (a, b):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90, facecolor="white")
    plt.close(fig)


def table(result):
    print("| configuration | image | fps | newest datagram to display, median / p95 (ms) | frames over target | "
          "every datagram, median / p95 (ms) | head error median / p95 (mm) | frames over 5 mm |")
    print("|---|---|---|---|---|---|---|---|")
    for r in result["rows"]:
        pred = f", predict {r['prediction_ms']:.1f} ms" if r["prediction_ms"] > 0 else ""
        print(f"| {'stereo' if r['stereo'] else 'mono'} {'async' if r['async'] else 'sync'}{pred} | {r['width']}x{r['height']} "
              f"| {r['fps']:.1f} | {r['frame_latency_ms_median']:.1f} / {r['frame_latency_ms_p95']:.1f} "
              f"| {100 * r['frame_latency_over_target']:.0f}% over {r['latency_target_ms']:.1f} ms "
              f"| {r['latency_ms_median']:.1f} / {r['latency_ms_p95']:.1f} "
              f"| {r['error_mm_median']:.1f} / {r['error_mm_p95']:.1f} | {100 * r['error_over_target']:.0f}% |")


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: latency_chart.py RESULT.json OUT.png")
    with open(sys.argv[1]) as f:
        result = json.load(f)
    if result.get("benchmark") != "latency" or not result.get("rows"):
        sys.exit(f"{sys.argv[1]}: not a result of rtwall bench latency --json")
    chart(result, sys.argv[2])
    table(result)


if __name__ == "__main__":
    main()
