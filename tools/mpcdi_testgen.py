#!/usr/bin/env python3
"""Writes MPCDI calibration files (.mpcdi) for rtwall's warped screens, with the standard library only.

It is a second, independent MPCDI writer (rtwall reads .mpcdi with libzip, pugixml and libpng),
so the tests read files rtwall's own code did not make, written the way calibration tools
write them: a zip of mpcdi.xml, PFM geometry warps (rows bottom to top, little-endian) and PNG
blend maps (8-bit grey alpha with gamma 2.2 embedded, 8-bit grey beta).

  python3 tools/mpcdi_testgen.py cylinder OUT.mpcdi [--res 320x240] [--grid WxH] [--overlap 0.15] [--wall OUT.toml]
                                   [--unit m|dm|cm|mm] [--declare UNIT]
      a cylindrical screen section (radius 3 m, 120 degrees, 2.4 m high, axis vertical through
      (0, y, 3), its middle at z = 0) lit by three overlapping projectors, profile a3 (points in
      metres, wall coordinates); each projector's image bends ("smile") so that its top and
      bottom corners land off the screen (NaN samples); alpha maps blend the overlaps to one in
      linear light, beta maps lift the black of single-projector parts to the overlaps'.
      --wall also writes the wall config that uses it: three screens side by side in the wall
      image, each framed by its projector's chord of the cylinder, the viewer on the axis.
  python3 tools/mpcdi_testgen.py identity OUT.mpcdi --buffer ID=WxH [--buffer ...] [--shift DX,DY]
      profile 2d: one buffer per screen, a warp of one sample per pixel that maps each pixel to
      its own centre (shifted by whole pixels with --shift), no blend maps.
  python3 tools/mpcdi_testgen.py malformed DIR
      broken files, each with one thing wrong (the names say what), and good.mpcdi beside them.
  python3 tools/mpcdi_testgen.py fuzz-seeds DIR
      the seed corpus of tests/fuzz/fuzz_mpcdi.cpp (its first byte: 0 archive, 1 parts, 2 PFM).
"""
import argparse
import io
import math
import os
import struct
import sys
import zipfile
import zlib

NAN = float("nan")

# ---- the parts --------------------------------------------------------------------------------


def pfm(width, height, samples, header=None):
    """A three-component PFM; samples[j][i] is (x, y, z) of row j from the TOP. Rows are written
    bottom to top, as the format says; scale -1: little-endian."""
    out = bytearray((header or "PF\n%d %d\n-1.0\n" % (width, height)).encode("ascii"))
    for j in reversed(range(height)):
        row = samples[j]
        for i in range(width):
            out += struct.pack("<3f", *row[i])
    return bytes(out)


def png_grey(width, height, values, bits=8, channels=1):
    """A grey (channels 1) or RGB (channels 3) PNG from values in [0, 1] (row-major, top row
    first, `channels` values a pixel), 8 or 16 bits a value."""
    top = (1 << bits) - 1
    raw = bytearray()
    for j in range(height):
        raw.append(0)
        for i in range(width * channels):
            v = max(0, min(top, int(round(values[j * width * channels + i] * top))))
            raw += struct.pack(">H", v) if bits == 16 else bytes([v])

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    colour_type = 2 if channels == 3 else 0
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bits, colour_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


def png_blank(width, height):
    """A black grey PNG, written row by row (a big one compresses to almost nothing)."""
    comp = zlib.compressobj(9)
    row = bytes(width + 1)
    data = b"".join(comp.compress(row) for _ in range(height)) + comp.flush()

    def chunk(tag, payload):
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)) +
            chunk(b"IDAT", data) + chunk(b"IEND", b""))


def archive(entries):
    """A zip of (name, bytes), deflated, as calibration tools write them."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries:
            z.writestr(name, data)
    return buf.getvalue()


def xml(profile, buffers, level=2, file_sets=True, unit="m", alpha_depth=(1, 8), beta_depth=(1, 8), alpha_gamma=2.2,
        frusta=None):
    """buffers: [(buffer id, w, h, [(region id, w, h, warp path, alpha path or None, beta path or None)])];
    the maps' (componentDepth, bitDepth) and the alpha maps' gammaEmbedded; frusta: region id ->
    (yaw, pitch, roll, leftAngle, rightAngle, upAngle, downAngle), degrees (profile 3d)."""
    lines = ['<?xml version="1.0" encoding="utf-8"?>',
             '<MPCDI profile="%s" geometry="%d" color="1" version="2.0">' % (profile, level), "  <display>"]
    sets = []
    for bid, bw, bh, regions in buffers:
        lines.append('    <buffer id="%s" Xresolution="%d" Yresolution="%d">' % (bid, bw, bh))
        for rid, rw, rh, warp, alpha, beta in regions:
            region = '      <region id="%s" Xresolution="%d" Yresolution="%d" x="0" y="0" xsize="1" ysize="1"' % (rid, rw, rh)
            if frusta and rid in frusta:
                names = ("yaw", "pitch", "roll", "leftAngle", "rightAngle", "upAngle", "downAngle")
                lines += [region + ">", "        <frustum>" + "".join("<%s>%.12g</%s>" % (n, v, n) for n, v in zip(names, frusta[rid])) +
                          "</frustum>", "      </region>"]
            else:
                lines.append(region + "/>")
            s = ['    <fileset region="%s">' % rid]
            if warp:
                unit_xml = "<geometricUnit>%s</geometricUnit>" % unit if profile != "2d" else ""
                s.append("      <geometryWarpFile><path>%s</path>%s<interpolation>linear</interpolation>"
                         "<originOf3DData>idealEyePoint</originOf3DData></geometryWarpFile>" % (warp, unit_xml))
            if alpha:
                s.append("      <alphaMap><path>%s</path><componentDepth>%d</componentDepth><bitDepth>%d</bitDepth>"
                         "<gammaEmbedded>%g</gammaEmbedded></alphaMap>" % ((alpha,) + tuple(alpha_depth) + (alpha_gamma,)))
            if beta:
                s.append("      <betaMap><path>%s</path><componentDepth>%d</componentDepth><bitDepth>%d</bitDepth></betaMap>" %
                         ((beta,) + tuple(beta_depth)))
            s.append("    </fileset>")
            sets += s
        lines.append("    </buffer>")
    lines.append("  </display>")
    if file_sets:
        lines += ["  <files>"] + sets + ["  </files>"]
    lines.append("</MPCDI>")
    return ("\n".join(lines) + "\n").encode("utf-8")


# ---- the cylinder -------------------------------------------------------------------------------

RADIUS, SPAN_DEG, HEIGHT, AXIS_Z = 3.0, 120.0, 2.4, 3.0


def cylinder_point(theta, y):
    """The screen point at angle theta (radians, 0 in the middle, positive to the right) and height y."""
    return (RADIUS * math.sin(theta), y, AXIS_Z - RADIUS * math.cos(theta))


def projector_ranges(overlap):
    """Each projector's angle range (radians): three equal parts of the span, overlapping by
    `overlap` of a projector's width."""
    span = math.radians(SPAN_DEG)
    width = span / (3 - 2 * overlap)
    step = width * (1 - overlap)
    return [(-span / 2 + k * step, -span / 2 + k * step + width) for k in range(3)]


def projector_map(k, u, v, overlap):
    """Projector k's pixel at (u, v) in [0, 1] from the top left: (theta, y) on the screen, or None
    off it. The image covers the angle range horizontally and 1.08 x the height, bent by a smile
    (the middle of a row lower than its ends), so corners fall off the screen."""
    t0, t1 = projector_ranges(overlap)[k]
    theta = t0 + (t1 - t0) * u
    y = HEIGHT * 1.08 * (0.5 - v) - 0.12 * (u - 0.5) ** 2 * HEIGHT + 0.0075 * HEIGHT
    if abs(y) > HEIGHT / 2:
        return None
    return theta, y


def blend_weight(k, theta, overlap):
    """Projector k's share of the light at angle theta: a smooth ramp across each overlap, the
    shares of all projectors summing to one (linear light)."""
    ranges = projector_ranges(overlap)
    t0, t1 = ranges[k]
    if theta < t0 or theta > t1:
        return 0.0

    def ramp(x):  # 0 -> 1 smoothly over [0, 1]
        x = max(0.0, min(1.0, x))
        return x * x * (3 - 2 * x)

    w = 1.0
    if k > 0:  # the overlap with the projector to the left
        lo, hi = t0, ranges[k - 1][1]
        if theta < hi:
            w = ramp((theta - lo) / (hi - lo))
    if k < 2:  # with the one to the right
        lo, hi = ranges[k + 1][0], t1
        if theta > lo:
            w = 1 - ramp((theta - lo) / (hi - lo))
    return w


UNITS = {"m": 1.0, "dm": 10.0, "cm": 100.0, "mm": 1000.0}


# Profile 3d: each projector's frustum from the eye point on the cylinder's axis (the wall's
# viewer), turned by these pitch and roll besides its yaw, so that every turn is exercised.
FRUSTUM_PITCH, FRUSTUM_ROLL = 2.0, 1.5


def turned(v, yaw, pitch, roll):
    """v turned by Ry(-yaw) Rx(pitch) Rz(-roll) (degrees): positive yaw turns right, positive
    pitch up, positive roll lowers the right side (SGCT's reading, Christie's description)."""
    x, y, z = v
    r = math.radians(-roll)
    x, y = math.cos(r) * x - math.sin(r) * y, math.sin(r) * x + math.cos(r) * y
    p = math.radians(pitch)
    y, z = math.cos(p) * y - math.sin(p) * z, math.sin(p) * y + math.cos(p) * z
    a = math.radians(-yaw)
    return (math.cos(a) * x + math.sin(a) * z, y, -math.sin(a) * x + math.cos(a) * z)


def unturned(v, yaw, pitch, roll):
    """The inverse of turned(): the same turns undone in the reverse order."""
    x, y, z = v
    a = math.radians(yaw)
    x, z = math.cos(a) * x + math.sin(a) * z, -math.sin(a) * x + math.cos(a) * z
    p = math.radians(-pitch)
    y, z = math.cos(p) * y - math.sin(p) * z, math.sin(p) * y + math.cos(p) * z
    r = math.radians(roll)
    return (math.cos(r) * x - math.sin(r) * y, math.sin(r) * x + math.cos(r) * y, z)


def frustum_samples(k, overlap, points):
    """Projector k's points (rows of (x, y, z) in metres, or NaN) as frustum coordinates (u, v, 0)
    seen from the eye point (0, 0, AXIS_Z), and its frustum (yaw, pitch, roll, left, right, up,
    down): yawed to the middle of its angle range, the angles enclosing its points with 2% to spare."""
    yaw = math.degrees(sum(projector_ranges(overlap)[k]) / 2)
    tans = []
    for row in points:
        out = []
        for p in row:
            if math.isnan(p[0]):
                out.append(None)
                continue
            x, y, z = unturned((p[0], p[1], p[2] - AXIS_Z), yaw, FRUSTUM_PITCH, FRUSTUM_ROLL)
            out.append((x / -z, y / -z))
        tans.append(out)
    flat = [t for row in tans for t in row if t]
    lo_x, hi_x = min(t[0] for t in flat), max(t[0] for t in flat)
    lo_y, hi_y = min(t[1] for t in flat), max(t[1] for t in flat)
    pad_x, pad_y = 0.02 * (hi_x - lo_x), 0.02 * (hi_y - lo_y)
    lo_x, hi_x, lo_y, hi_y = lo_x - pad_x, hi_x + pad_x, lo_y - pad_y, hi_y + pad_y
    samples = [[(NAN, NAN, NAN) if t is None else ((t[0] - lo_x) / (hi_x - lo_x), (t[1] - lo_y) / (hi_y - lo_y), 0.0)
                for t in row] for row in tans]
    angles = tuple(math.degrees(math.atan(v)) for v in (lo_x, hi_x, hi_y, lo_y))
    return samples, (yaw, FRUSTUM_PITCH, FRUSTUM_ROLL) + angles



def cylinder(res, grid, overlap, unit="m", declared=None, profile="a3"):
    """The archive; points in `unit` (mm: 1000 per metre), declared as `declared` (default: the
    same). Profile 3d: the same projector pixels as frustum coordinates seen from the viewer."""
    per_metre = UNITS[unit]
    w, h = res
    gw, gh = grid
    buffers, entries, frusta = [], [], {}
    for k in range(3):
        samples = []
        for j in range(gh):
            row = []
            for i in range(gw):
                m = projector_map(k, (i + 0.5) / gw, (j + 0.5) / gh, overlap)
                row.append((NAN, NAN, NAN) if m is None else tuple(c * per_metre for c in cylinder_point(*m)))
            samples.append(row)
        if profile == "3d":
            samples, frusta["proj%d_region" % k] = frustum_samples(k, overlap, [[tuple(c / per_metre for c in p) for p in row]
                                                                       for row in samples])
        alpha, beta = [], []
        for j in range(h):
            for i in range(w):
                m = projector_map(k, (i + 0.5) / w, (j + 0.5) / h, overlap)
                if m is None:
                    alpha.append(0.0)
                    beta.append(0.0)
                    continue
                share = blend_weight(k, m[0], overlap)
                alpha.append(share ** (1 / 2.2))  # gammaEmbedded 2.2
                beta.append(0.02 if share >= 1.0 else 0.0)
        pid = "proj%d" % k
        entries += [(pid + "_warp.pfm", pfm(gw, gh, samples)), (pid + "_alpha.png", png_grey(w, h, alpha)),
                    (pid + "_beta.png", png_grey(w, h, beta))]
        buffers.append((pid, w, h, [(pid + "_region", w, h, pid + "_warp.pfm", pid + "_alpha.png", pid + "_beta.png")]))
    return archive([("mpcdi.xml", xml(profile, buffers, unit=declared or unit, frusta=frusta))] + entries)


def cylinder_wall(res, overlap, mpcdi_name, buffers=None, grid=None):
    """The wall config of the cylinder: one screen per projector, framed by the chord rectangle of
    its angle range; [warp] maps buffer projK to screen projK."""
    w, h = res
    f = lambda p: "[%.9g, %.9g, %.9g]" % p
    out = ["# A cylindrical screen section (radius %g m, %g degrees, %g m high) lit by three overlapping" % (RADIUS, SPAN_DEG, HEIGHT),
           "# projectors, calibrated by an MPCDI file (profile a3) that tools/mpcdi_testgen.py writes:",
           "#   python3 tools/mpcdi_testgen.py cylinder %s --res %dx%d%s --wall THIS.toml"
           % (mpcdi_name, w, h, " --grid %dx%d" % grid if grid and tuple(grid) != tuple(res) else ""),
           "# Each projector is a screen of the wall image (side by side), framed by the chord of its part",
           "# of the cylinder; every projector pixel's ray goes from the eye through the surface point the",
           "# calibration gives it ([warp], docs/mpcdi.md).",
           "[wall]", 'name = "curved-3-projectors"', "width = %d" % (3 * w), "height = %d" % h, "",
           "[stereo]", 'mode = "none"', "viewer = [0.0, 0.0, %g]  # on the cylinder's axis, at its middle height" % AXIS_Z,
           "lower_left = %s" % f(cylinder_point(-math.radians(SPAN_DEG) / 2, -HEIGHT / 2)),
           "lower_right = %s" % f(cylinder_point(math.radians(SPAN_DEG) / 2, -HEIGHT / 2)),
           "upper_left = %s" % f(cylinder_point(-math.radians(SPAN_DEG) / 2, HEIGHT / 2)), ""]
    for k, (t0, t1) in enumerate(projector_ranges(overlap)):
        out += ["[[screen]]", 'name = "proj%d"' % k, "viewport = [%d, 0, %d, %d]" % (k * w, w, h),
                "lower_left = %s" % f(cylinder_point(t0, -HEIGHT / 2)), "lower_right = %s" % f(cylinder_point(t1, -HEIGHT / 2)),
                "upper_left = %s" % f(cylinder_point(t0, HEIGHT / 2)), ""]
    mapping = buffers or {"proj%d" % k: "proj%d" % k for k in range(3)}
    out += ["[warp]", 'mpcdi = "%s"' % mpcdi_name,
            "buffers = { %s }" % ", ".join('%s = "%s"' % (b, sc) for b, sc in mapping.items()), ""]
    return "\n".join(out)


# ---- identity 2d --------------------------------------------------------------------------------


def identity_samples(w, h, dx=0, dy=0):
    """Each pixel to its own centre (u right, v up from the lower left), shifted by whole pixels."""
    return [[((i + dx + 0.5) / w, 1 - (j + dy + 0.5) / h, 0.0) for i in range(w)] for j in range(h)]


def identity(buffers, shift):
    dx, dy = shift
    xmlbufs, entries = [], []
    for bid, (w, h) in buffers:
        entries.append((bid + ".pfm", pfm(w, h, identity_samples(w, h, dx, dy))))
        xmlbufs.append((bid, w, h, [(bid + "_region", w, h, bid + ".pfm", None, None)]))
    return archive([("mpcdi.xml", xml("2d", xmlbufs))] + entries)


def map_values(w, h, channels, kind):
    """Distinct values for each pixel and channel: what `depths` writes and the test expects."""
    n = w * h * channels
    if kind == "alpha":
        return [((k * 997 + 13) % 65536) / 65535 for k in range(n)]
    return [(k % 23) / 22 for k in range(n)]


def depths(alpha_depth, beta_depth, w=6, h=4):
    """A 2D identity calibration of one region whose alpha and beta maps have the given
    (componentDepth, bitDepth): 16-bit and RGB maps as writers other than ours export them."""
    entries = [("r.pfm", pfm(w, h, identity_samples(w, h)))]
    for name, (channels, bits) in (("alpha", alpha_depth), ("beta", beta_depth)):
        entries.append(("r_%s.png" % name, png_grey(w, h, map_values(w, h, channels, name), bits, channels)))
    bufs = [("p", w, h, [("r", w, h, "r.pfm", "r_alpha.png", "r_beta.png")])]
    return archive([("mpcdi.xml", xml("2d", bufs, alpha_depth=alpha_depth, beta_depth=beta_depth, alpha_gamma=1.0))] + entries)


# ---- malformed ----------------------------------------------------------------------------------


def malformed(out):
    """One file per fault; the file name says what is wrong."""
    w, h = 8, 6
    good_warp = pfm(w, h, identity_samples(w, h))
    one = [("p0", w, h, [("r0", w, h, "r0.pfm", "r0_alpha.png", None)])]
    good_xml = xml("2d", one)
    alpha = png_grey(w, h, [1.0] * (w * h))
    good = archive([("mpcdi.xml", good_xml), ("r0.pfm", good_warp), ("r0_alpha.png", alpha)])
    files = {
        "good.mpcdi": good,
        "truncated-zip.mpcdi": good[: len(good) // 2],
        "not-a-zip.mpcdi": b"this is not a zip archive at all\n" * 4,
        "no-mpcdi-xml.mpcdi": archive([("calibration.xml", good_xml), ("r0.pfm", good_warp)]),
        "missing-warp.mpcdi": archive([("mpcdi.xml", good_xml), ("r0_alpha.png", alpha)]),
        "no-geometry-warp.mpcdi": archive([("mpcdi.xml", xml("2d", [("p0", w, h, [("r0", w, h, None, None, None)])]))]),
        "pfm-short.mpcdi": archive([("mpcdi.xml", good_xml), ("r0.pfm", good_warp[:-12]), ("r0_alpha.png", alpha)]),
        "pfm-huge-header.mpcdi": archive([("mpcdi.xml", good_xml),
                                          ("r0.pfm", b"PF\n16384 16384\n-1.0\n" + good_warp[-w * h * 12:]),
                                          ("r0_alpha.png", alpha)]),
        "pfm-infinite.mpcdi": archive([("mpcdi.xml", good_xml),
                                       ("r0.pfm", pfm(w, h, [[(math.inf if (i, j) == (3, 2) else 0.5, 0.5, 0.0)
                                                              for i in range(w)] for j in range(h)])),
                                       ("r0_alpha.png", alpha)]),
        "all-nan.mpcdi": archive([("mpcdi.xml", good_xml), ("r0.pfm", pfm(w, h, [[(NAN, NAN, NAN)] * w] * h)),
                                  ("r0_alpha.png", alpha)]),
        "alpha-wrong-size.mpcdi": archive([("mpcdi.xml", good_xml), ("r0.pfm", good_warp),
                                           ("r0_alpha.png", png_grey(w + 1, h, [1.0] * ((w + 1) * h)))]),
        "unknown-profile.mpcdi": archive([("mpcdi.xml", good_xml.replace(b'profile="2d"', b'profile="4d"')),
                                          ("r0.pfm", good_warp), ("r0_alpha.png", alpha)]),
        "bad-xml.mpcdi": archive([("mpcdi.xml", good_xml[:-20]), ("r0.pfm", good_warp), ("r0_alpha.png", alpha)]),
        "alpha-huge.mpcdi": archive([("mpcdi.xml", xml("2d", [("p0", 8200, 8192, [("r0", 8200, 8192, "r0.pfm", "r0_alpha.png", None)])])),
                                     ("r0.pfm", good_warp), ("r0_alpha.png", png_blank(8200, 8192))]),
        "pfm-one-component.mpcdi": archive([("mpcdi.xml", good_xml), ("r0.pfm", b"Pf\n8 6\n-1.0\n" + bytes(w * h * 4)),
                                            ("r0_alpha.png", alpha)]),
        "3d-no-frustum.mpcdi": archive([("mpcdi.xml", xml("3d", one)), ("r0.pfm", good_warp), ("r0_alpha.png", alpha)]),
        "3d-no-left-angle.mpcdi": archive([("mpcdi.xml", xml("3d", one, frusta={"r0": (0, 0, 0, -20, 20, 15, -15)})
                                            .replace(b"<leftAngle>-20</leftAngle>", b"")),
                                           ("r0.pfm", good_warp), ("r0_alpha.png", alpha)]),
        "3d-empty-frustum.mpcdi": archive([("mpcdi.xml", xml("3d", one, frusta={"r0": (0, 0, 0, 20, -20, 15, -15)})),
                                           ("r0.pfm", good_warp), ("r0_alpha.png", alpha)]),
    }
    os.makedirs(out, exist_ok=True)
    for name, data in files.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)


def fuzz_seeds(out):
    """Small valid inputs of each of fuzz_mpcdi's three kinds."""
    os.makedirs(out, exist_ok=True)
    w, h = 4, 3
    warp = pfm(w, h, identity_samples(w, h))
    alpha = png_grey(w, h, [0.5] * (w * h))
    one = [("p0", w, h, [("r0", w, h, "r0.pfm", "r0_alpha.png", "r0_beta.png")])]
    text = xml("2d", one)
    seeds = {
        "archive-2d": b"\x00" + archive([("mpcdi.xml", text), ("r0.pfm", warp), ("r0_alpha.png", alpha),
                                          ("r0_beta.png", alpha)]),
        "archive-a3": b"\x00" + cylinder((8, 6), (4, 3), 0.15),
        "parts-2d": b"\x01" + text + b"\x00\x00" + warp + b"\x00\x00" + alpha + b"\x00\x00" + alpha,
        "archive-3d": b"\x00" + cylinder((8, 6), (4, 3), 0.15, profile="3d"),
        "parts-a3": b"\x01" + xml("a3", one) + b"\x00\x00" + pfm(2, 2, [[(0.0, 1.0, 2.0), (NAN, NAN, NAN)]] * 2),
        "pfm": b"\x02" + warp,
    }
    for name, data in seeds.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)


def size(text):
    w, _, h = text.partition("x")
    return int(w), int(h)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="what", required=True)
    c = sub.add_parser("cylinder")
    c.add_argument("out")
    c.add_argument("--res", type=size, default=(320, 240))
    c.add_argument("--grid", type=size, default=None, help="warp samples (default: one per pixel)")
    c.add_argument("--overlap", type=float, default=0.15)
    c.add_argument("--wall", default=None, help="also write the wall config that uses it")
    c.add_argument("--unit", choices=sorted(UNITS), default="m", help="the warp's points in this unit")
    c.add_argument("--declare", choices=sorted(UNITS), default=None, help="declare this unit instead (a faulty export)")
    c.add_argument("--profile", choices=["a3", "3d", "sl"], default="a3",
                   help="a3, sl: surface points; 3d: the same pixels as coordinates in each projector's frustum from the viewer")
    i = sub.add_parser("identity")
    i.add_argument("out")
    i.add_argument("--buffer", action="append", required=True, help="ID=WxH")
    i.add_argument("--shift", default="0,0")
    m = sub.add_parser("malformed")
    m.add_argument("out")
    d = sub.add_parser("depths", help="one region whose blend maps have the given component and bit depths")
    d.add_argument("out")
    d.add_argument("--alpha", type=size, default=(1, 16), help="COMPONENTSxBITS (1x16: 16-bit grey)")
    d.add_argument("--beta", type=size, default=(3, 8), help="COMPONENTSxBITS (3x8: 8-bit RGB)")
    d.add_argument("--res", type=size, default=(6, 4), help="the region's (and buffer's) pixels, WxH")
    fz = sub.add_parser("fuzz-seeds")
    fz.add_argument("out")
    a = p.parse_args()
    if a.what == "cylinder":
        data = cylinder(a.res, a.grid or a.res, a.overlap, a.unit, a.declare, a.profile)
        if a.wall:
            rel = os.path.relpath(os.path.abspath(a.out), os.path.dirname(os.path.abspath(a.wall)))
            with open(a.wall, "w") as f:
                f.write(cylinder_wall(a.res, a.overlap, rel, grid=a.grid))
    elif a.what == "identity":
        bufs = []
        for b in a.buffer:
            bid, _, wh = b.partition("=")
            bufs.append((bid, size(wh)))
        dx, dy = (int(v) for v in a.shift.split(","))
        data = identity(bufs, (dx, dy))
    elif a.what == "depths":
        data = depths(a.alpha, a.beta, *a.res)
    elif a.what == "fuzz-seeds":
        fuzz_seeds(a.out)
        return
    else:
        malformed(a.out)
        return
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    sys.exit(main())
