#!/usr/bin/python3
"""Speed against accuracy: one command regenerates every figure and docs/speed-accuracy.md.

    tools/speed_accuracy.py [--build build] [--work out/speed] [--quick] [--skip-validation]

Steps (each writes raw JSON under --work/raw/, charts under docs/speed-accuracy/):
  1. reference  converged reference per scene (rtwall reference), cached by a hash of the scene
                file, the meshes it names, the settings and the renderer's sources
  2. sweep      every combination of the swept controls (CONTROLS) per scene: one
                `rtwall bench tiles` per render setting (all codecs share one render); error is
                measured against the reference (after bilinear upscaling), frame time is the
                simulated frame time of the measured tile profile on TOPOLOGY (rtwall simulate)
  3. scaling    frames/s against client count, 1..256, paper-era and modern links
  4. failures   named cases where a method breaks down (FAILURES)
  5. validate   simulated against measured frames/s for what this PC can run (rtwall bench cluster)
  6. docs       the charts and docs/speed-accuracy.md, plus a front per scene for
                `rtwall run --target-fps N --front docs/speed-accuracy/front-SCENE.toml`
  7. tessellation  STEP tessellation tolerance against triangles, memory, import time and image
                error (rtwall bench tessellation); `--only tessellation` runs this step alone and
                rewrites only its section of the page

A control is one entry of rtwall's control table (`rtwall controls --json`): its option and label.
Pruning threshold, GI samples per pixel and volume step go there once the renderer has them.
"""
import argparse
import hashlib
import itertools
import json
import math
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


@dataclass
class Control:
    name: str            # also the key in a front's [point.controls]
    values: list
    args: callable       # value -> `rtwall bench tiles` arguments
    label: callable = str


@dataclass
class Scene:
    name: str
    source: str          # "{work}" stands for --work (scenes written by `rtwall gen`)
    wall: tuple          # the wall's resolution: the reference and every error are at this size
    extra: list = field(default_factory=list)  # arguments for every rtwall call on this scene
    sweep: dict = field(default_factory=dict)  # control name -> the values swept on this scene
    reference: dict = field(default_factory=dict)  # converged settings: control name -> value
    gen: list = field(default_factory=list)    # `rtwall gen` arguments that write the scene first
    # Progressive refinement of a still view (rtwall run's accumulation): these settings, frames
    # averaged; reported as the time to 40 dB when still, beside the per-frame figures.
    accumulate: dict = field(default_factory=dict)
    # Settings swept besides the product of `sweep` (each a full setting): expensive points that
    # only make sense in one combination, e.g. many GI samples at full resolution.
    extra_points: list = field(default_factory=list)
    note: str = ""       # how this scene is swept, for the docs
    scaling: bool = True  # its scaling chart (clients and links): not for a second sweep of one scene


# Every control the sweep can set: read from `rtwall controls --json` (one table, in
# display/src/wall/controls.cpp; `rtwall run --target-fps` applies a front's [point.controls] by
# the same names), with its `rtwall bench tiles` / `rtwall reference` option and label. Which
# values each scene sweeps: SCENES. Codecs are applied to each render (CODECS).
CONTROLS = []
CONTROL = {}


def load_controls(r):
    global CONTROLS, CONTROL

    def fmt(v):
        return f"{v:g}"

    def control(c):
        option, label, names = c["option"], c["label"], c.get("names")
        name = (lambda v: names[int(v)]) if names else (lambda v: label.replace("{}", fmt(v)))
        return Control(c["name"], c["sweep"], lambda v: [option, fmt(v)], name)

    CONTROLS = [control(c) for c in r.run("controls", "--json")["controls"] if c["option"]]
    CONTROL = {c.name: c for c in CONTROLS}


CODECS = ["raw", "lz4", "zstd", "jpeg:50", "jpeg:75", "jpeg:90", "jpeg:95"]
# A front point's codec control: TileCodec numbers (cluster.h) and the JPEG quality.
CODEC_IDS = {"raw": 0, "lz4": 1, "zstd": 2, "jpeg": 3}

GRID = {"tile": [32, 64, 128], "scale": [0.5, 0.75, 1.0], "supersample": [1, 2]}
REFERENCE_SUPERSAMPLE = 8  # 64 samples per pixel where a scene has no stochastic effects
SCENES = [
    Scene("knots", "builtin:knots", (1600, 1200), ["--triangles", "3000000"],
          sweep={"tile": [32, 128], "scale": [0.5, 1.0], "supersample": [1, 2]},
          note="1600x1200, 3 million triangles: the costliest scene per process, so two values per control"),
    Scene("demo", "configs/demo.toml", (800, 600), sweep=GRID),
    # The shading demos cost far more per pixel (GI, glass, a volume): modest walls keep the
    # whole regeneration under 30 minutes on the 2-core PC.
    Scene("office", "{work}/scenes/office/office.toml", (200, 150), gen=["office"],
          sweep={"tile": [32], "scale": [0.5, 1.0], "gi_spp": [1, 4, 16, 64, 256], "volume_step": [0.25, 2.0],
                 "prune": [0.05]},
          extra_points=[{"tile": 32, "scale": 1.0, "gi_spp": n, "volume_step": 0.25, "prune": 0.05} for n in (1024, 2048)] +
          # The denoiser (issue 28), scored as the view the camera arrives at (DENOISE_ORBIT).
          [{"tile": 32, "scale": sc, "gi_spp": n, "volume_step": 0.25, "prune": 0.05, "denoise": d}
           for sc, n, d in [(1.0, 1, 1), (1.0, 4, 1), (1.0, 16, 1), (1.0, 1, 2), (1.0, 2, 2), (1.0, 4, 2), (1.0, 16, 2),
                            (0.5, 1, 2), (0.5, 4, 2)]],
          reference={"supersample": 1, "gi_spp": 16, "volume_step": 0.125, "prune": 0.0005, "frames": 160},
          accumulate={"scale": 1.0, "gi_spp": 16, "volume_step": 0.25, "prune": 0.05, "frames": 128},
          note="200x150 wall (GI, glass, a smoke volume; a quarter of the pixels of the 400x300 wall used before, so "
               "that a converged reference and per-frame sample counts up to 2048 fit the 30 minutes; 1024 and 2048 "
               "at full resolution, volume step 0.25 and prune 0.05 only); reference: "
               "160 frames of 16 GI samples per pixel averaged (2560, sub-pixel positions jittered per frame), volume "
               "step 0.125 voxels, pruning threshold 0.0005; denoised points (temporal at 1, 4, 16 samples, svgf at 1, "
               "2, 4, 16, and svgf at half resolution with 1 and 4) at volume step 0.25, prune 0.05"),
    Scene("headlight", "{work}/scenes/headlight/headlight.toml", (160, 120), gen=["headlight"],
          sweep={"tile": [32], "scale": [1.0], "prune": [0.0005, 0.002, 0.01, 0.05], "supersample": [1, 2, 4]},
          reference={"supersample": 8, "prune": 0.0001},
          note="160x120 wall: paths of up to 32 bounces through glass cost seconds per frame even at this size; "
               "reference 8x8 samples per pixel at pruning threshold 1e-4 (unpruned, the ray tree grows as 2^depth); "
               "no lower render resolution (upscaling never comes near 40 dB here), supersampling instead. The "
               "headlight demo is deterministic (a polished reflector, point and directional lights, per-pixel "
               "roulette seeds), but the reflector's images of the filament (radiance 30, 30 times what the display "
               "shows as white), seen through the bumped lens and the lenslets, are specks far smaller than a pixel "
               "at 160x120: a speck covering 3% of a pixel saturates it. Stratified supersampling converges slowly "
               "on them: unpruned, 2x2 and 4x4 differ from 8x8 by 26.5 and 29.1 dB. Two renders both within 40 dB "
               "of the truth would be within 34 dB of each other, so 4x4 (and every point of 16 samples or fewer) "
               "is not at 40 dB; at 2.6 dB per fourfold samples, 40 dB would take thousands of samples per pixel. "
               "Pruning alone, same samples: 41 dB at the default (docs/shading.md)"),
    Scene("sunflowers", "{work}/scenes/sunflowers/scene.toml", (800, 600),
          gen=["sunflowers", "--instances", "2000", "--trees", "2"],
          sweep={"tile": [32, 128], "scale": [0.5, 1.0], "supersample": [1, 2, 3, 4]},
          note="800x600 wall, a field of 2,000 instanced plants (not the full demo's 112,005, so that each of the "
               "sweep's processes loads it in seconds)"),
    # The demo and the sunflower field again with GI (issue 28): what GI samples and the denoiser
    # buy on a scene of hard surfaces and on foliage, at the office's wall size.
    *[Scene(f"{name}-gi", src, (200, 150),
            sweep={"tile": [32], "scale": [0.5, 1.0], "gi_spp": [1, 4, 16, 64]},
            extra_points=[{"tile": 32, "scale": sc, "gi_spp": n, "denoise": d}
                          for sc, n, d in [(1.0, 1, 1), (1.0, 4, 1), (1.0, 1, 2), (1.0, 2, 2), (1.0, 4, 2), (0.5, 1, 2),
                                           (0.5, 4, 2)]],
            reference={"supersample": 1, "gi_spp": 16, "prune": 0.0005, "frames": 64},
            accumulate={"scale": 1.0, "gi_spp": 4, "frames": 64},
            scaling=False,
            note=f"{what} with GI, 200x150 wall (the office's): GI samples 1 to 64 at full and half resolution, "
                 "temporal at 1 and 4 samples, svgf at 1, 2 and 4 and at half resolution with 1 and 4; reference: 64 "
                 "frames of 16 GI samples per pixel averaged (1024, sub-pixel positions jittered per frame), pruning "
                 "threshold 0.0005")
      for name, src, what in [("demo", "configs/demo.toml", "The demo"),
                              ("sunflowers", "{work}/scenes/sunflowers/scene.toml", "The sunflower field (written by the "
                               "sunflowers scene above)")]],
]


# A denoised point (the denoise control) is the view the camera arrives at after turning this many
# degrees a frame for this many frames (rtwall bench tiles --denoise-orbit/--denoise-frames): its
# filter needs a history. Its frame time: the simulated render, or the master link carrying its
# linear tiles and features if that is slower, plus the filter on the master (this PC's threads).
DENOISE_ORBIT = dict(frames=8, degrees=0.5)
GBIT_BYTES_S = 117e6

# Where the frame time of a sweep point comes from: its measured tile profile on this cluster.
TOPOLOGY = dict(clients=8, threads=2, client_link="1gbit", master_link="1gbit", prefetch=8, latency_ms=0.1)
SCALING_LINKS = {
    "paper-era (100 Mbit/s clients, 1 Gbit/s master)": ("100mbit", "1gbit"),
    "modern (10 Gbit/s clients and master)": ("10gbit", "10gbit"),
}
SCALING_CLIENTS = [1, 2, 4, 8, 16, 32, 64, 128, 256]
SCALING_POINT = dict(tile=64, scale=1.0, supersample=1)
SCALING_CODECS = ["raw", "lz4", "jpeg:90"]


def log(*a):
    print("[speed]", *a, flush=True)


class Runner:
    def __init__(self, build, work, quick):
        self.exe = str(Path(build) / "tools" / "rtwall")
        self.work = Path(work).resolve()
        self.raw = self.work / "raw"
        self.quick = quick
        self.raw.mkdir(parents=True, exist_ok=True)
        if not Path(self.exe).exists():
            sys.exit(f"speed_accuracy: {self.exe} does not exist; build first (tools/bootstrap.sh build)")

    def run(self, *args, parse=True):
        cmd = [self.exe, *map(str, args)]
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"speed_accuracy: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
        return json.loads(p.stdout) if parse else p.stdout


# ---- 1. references ---------------------------------------------------------------------------

def source(r, scene):
    return scene.source.format(work=r.work)


def generate(r, scene):
    """Writes a generated demo scene (rtwall gen) afresh on every run, into a scratch folder, and
    copies over only the files that changed: a scene left from an earlier run of an older
    generator is replaced (it was once kept, and the sweep measured a stale headlight), while
    unchanged files keep their bytes and times, so references and mesh caches stay valid."""
    if not scene.gen:
        return
    dest = Path(source(r, scene)).parent
    scratch = r.work / "gen-scratch" / scene.name
    shutil.rmtree(scratch, ignore_errors=True)
    r.run("gen", *scene.gen, "--out", scratch, parse=False)
    changed = []
    for src in sorted(p for p in scratch.rglob("*") if p.is_file()):
        out = dest / src.relative_to(scratch)
        if not out.exists() or out.read_bytes() != src.read_bytes():
            out.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, out)
            changed.append(str(src.relative_to(scratch)))
    shutil.rmtree(scratch, ignore_errors=True)
    log(f"{scene.name}: rtwall gen {' '.join(scene.gen)}: " +
        (f"{len(changed)} file(s) new or changed ({', '.join(changed[:4])}{', ...' if len(changed) > 4 else ''})"
         if changed else "unchanged"))


def reference_settings(scene):
    return scene.reference or {"supersample": REFERENCE_SUPERSAMPLE}


def scene_hash(r, scene, settings):
    h = hashlib.sha256()
    h.update(json.dumps([scene.source, scene.wall, scene.extra, scene.gen, settings], sort_keys=True).encode())
    if not scene.source.startswith("builtin:"):
        path = ROOT / source(r, scene)
        h.update(path.read_bytes())
        import tomllib
        for mesh in tomllib.loads(path.read_text()).get("mesh", []):
            if "file" in mesh:
                h.update((path.parent / mesh["file"]).read_bytes())
    # The renderer's sources: a change to the engine makes a new reference.
    for src in sorted((ROOT / "engine").rglob("*")):
        if src.is_file():
            h.update(src.read_bytes())
    return h.hexdigest()[:16]


def setting_args(settings):
    return [a for name, v in settings.items()
            for a in (["--frames", str(v)] if name == "frames" else CONTROL[name].args(v))]


def reference(r, scene):
    """The converged reference, cached, and an estimate of its own error (PSNR against the truth),
    kept beside it as JSON: for a path-traced scene from two independent halves of its frames
    (rtwall reference --frames), otherwise a bound: the PSNR between it and the same render with
    half the samples per axis (a quarter of the samples), whose error is larger than its own."""
    settings = reference_settings(scene)
    cache = r.work / "references"
    cache.mkdir(parents=True, exist_ok=True)
    path = cache / f"{scene.name}-{scene_hash(r, scene, settings)}.png"
    meta = path.with_suffix(".json")
    if path.exists() and meta.exists():
        log(f"reference {scene.name}: cached {path}")
        return path
    log(f"reference {scene.name}: rendering with {settings}")
    t0 = time.time()
    common = [source(r, scene), "--width", scene.wall[0], "--height", scene.wall[1], *scene.extra]
    out = r.run("reference", *common, "--out", path, *setting_args(settings), "--json")
    info = {"settings": settings, "seconds": time.time() - t0}
    if "own_psnr_db_estimate" in out:
        info.update(own_psnr_db=out["own_psnr_db_estimate"], own_method="two independent halves of its frames")
    else:
        ss = settings.get("supersample", 1)
        half = cache / f"{scene.name}-{scene_hash(r, scene, settings)}-half.png"
        r.run("reference", *common, "--out", half, *setting_args({**settings, "supersample": max(1, ss // 2)}), "--json")
        cmp = r.run("compare", half, path, "--json")
        info.update(own_psnr_db=cmp["psnr_db"], own_method=f"at least: PSNR against {max(1, ss // 2)}x"
                    f"{max(1, ss // 2)} samples", own_is_bound=True)
    meta.write_text(json.dumps(info, indent=1))
    log(f"reference {scene.name}: {time.time() - t0:.0f} s, own error about {info['own_psnr_db']:.1f} dB PSNR "
        f"({info['own_method']})")
    return path


def reference_info(r, scene):
    settings = reference_settings(scene)
    return json.loads((r.work / "references" / f"{scene.name}-{scene_hash(r, scene, settings)}.json").read_text())


def accumulation(r, scene, ref, points):
    """rtwall run's refinement of a still view: the mean of 1, 2, 4, ... frames at scene.accumulate
    against the reference; the time to 40 dB is frames x the simulated frame time of that setting."""
    if not scene.accumulate:
        return None
    acc = dict(scene.accumulate)
    frames = acc.pop("frames")
    prefix = r.raw / f"accumulate-{scene.name}"
    t0 = time.time()
    # Frames 1, 2, ... as rtwall run renders them: independent of the reference's (from 2^20).
    r.run("reference", source(r, scene), "--width", scene.wall[0], "--height", scene.wall[1], "--out",
          f"{prefix}-all.png", "--first-frame", 1, "--progress-out", prefix,
          *setting_args({"supersample": 1, **{k: v for k, v in acc.items() if k != "scale"}}), "--frames", frames, "--json", *scene.extra)
    match = [p for p in points if all(p.get(k) == v for k, v in acc.items()) and p["codec"] == "raw"]
    frame_s = min(p["frame_s"] for p in match) if match else None
    rows = []
    k = 1
    while k <= frames:
        e = r.run("compare", f"{prefix}-{k}.png", ref, "--json")
        rows.append({"frames": k, "psnr_db": e["psnr_db"], "flip": e["flip"],
                     "seconds": k * frame_s if frame_s else None})
        k *= 2
    log(f"{scene.name}: accumulation of {frames} frames ({time.time() - t0:.0f} s): " +
        ", ".join(f"{x['frames']}: {x['psnr_db']:.1f} dB" for x in rows))
    return {"settings": scene.accumulate, "frame_s": frame_s, "rows": rows}


# ---- 2. sweep ----------------------------------------------------------------------------------

def simulate(r, profile, codec, **kw):
    t = {**TOPOLOGY, **kw}
    clients = t.pop("clients")
    args = ["simulate", "--profile", profile, "--codec", codec, "--clients",
            ",".join(map(str, clients if isinstance(clients, list) else [clients])), "--json"]
    for k, v in t.items():
        if v is True:
            args.append("--" + k.replace("_", "-"))
        elif v is not False and v is not None:
            args += ["--" + k.replace("_", "-"), v]
    return r.run(*args)


def sweep(r, scene, ref):
    controls = [Control(name, values, CONTROL[name].args, CONTROL[name].label) for name, values in scene.sweep.items()]
    if r.quick:
        controls = [Control(c.name, [c.values[-1]], c.args, c.label) for c in controls]
    points = []
    settings = [dict(zip([c.name for c in controls], values)) for values in itertools.product(*[c.values for c in controls])]
    if not r.quick:
        settings += [dict(x) for x in scene.extra_points]
        controls = [Control(name, None, CONTROL[name].args, CONTROL[name].label)
                    for name in dict.fromkeys(k for st in settings for k in st)]
    for setting in settings:
        tag = "-".join(f"{k}{v}" for k, v in setting.items())
        profile = r.raw / f"profile-{scene.name}-{tag}.toml"
        args = ["bench", "tiles", source(r, scene), "--width", scene.wall[0], "--height", scene.wall[1],
                "--codecs", "raw" if setting.get("denoise") else ",".join(CODECS), "--reference", ref,
                "--profile-out", profile, "--json", *scene.extra]
        for c in controls:
            if c.name in setting:
                args += c.args(setting[c.name])
        if setting.get("denoise"):
            args += ["--denoise-frames", DENOISE_ORBIT["frames"], "--denoise-orbit", DENOISE_ORBIT["degrees"]]
        t0 = time.time()
        bench = r.run(*args)
        if setting.get("denoise"):
            # Linear tiles and features travel whatever the codec: one point, scored after the orbit.
            dn = bench["denoised"]
            sim = simulate(r, profile, "raw")["results"][0]
            link_s = dn["bytes_per_frame"] / GBIT_BYTES_S
            frame_s = max(1.0 / sim["fps"], link_s) + dn["filter_ms"] / 1e3
            e = dn["error"]
            points.append({"scene": scene.name, **setting, "codec": "raw", "psnr_db": e["psnr_db"], "ssim": e["ssim"],
                           "flip": e["flip"], "rmse": e["rmse"], "max_error": e["max_error"],
                           "bytes_per_frame": dn["bytes_per_frame"], "render_s_one_thread": bench["render_s_per_frame"][0],
                           "fps": 1.0 / frame_s, "frame_s": frame_s, "filter_ms": dn["filter_ms"],
                           "render_fps": sim["fps"], "link_ceiling_fps": 1.0 / link_s,
                           "master_link_load": min(1.0, link_s / frame_s), "client_utilisation": sim["mean_client_utilisation"]})
            log(f"{scene.name} {tag}: denoised {e['psnr_db']:.1f} dB, filter {dn['filter_ms']:.1f} ms, "
                f"{1.0 / frame_s:.1f} fps ({time.time() - t0:.0f} s)")
            continue
        sims = {}
        for codec in bench["codecs"]:
            sim = simulate(r, profile, codec["codec"])["results"][0]
            sims[codec["codec"]] = sim
            points.append({"scene": scene.name, **setting, "codec": codec["codec"],
                           "psnr_db": codec["error"]["psnr_db"], "ssim": codec["error"]["ssim"],
                           "flip": codec["error"]["flip"],
                           "rmse": codec["error"]["rmse"], "max_error": codec["error"]["max_error"],
                           "bytes_per_frame": codec["bytes_per_frame"],
                           "render_s_one_thread": bench["render_s_per_frame"][0],
                           "fps": sim["fps"], "frame_s": 1.0 / sim["fps"], "link_ceiling_fps": sim["link_ceiling_fps"],
                           "master_link_load": sim["master_link_load"],
                           "client_utilisation": sim["mean_client_utilisation"]})
        log(f"{scene.name} {tag}: render {bench['render_s_per_frame'][0]:.2f} s on one thread, "
            f"{len(bench['codecs'])} codecs ({time.time() - t0:.0f} s)")
    return points


def pareto(points):
    """Points not dominated in (fps up, psnr up), sorted by fps."""
    front = []
    for p in sorted(points, key=lambda p: (-p["fps"], -p["psnr_db"])):
        if not front or p["psnr_db"] > front[-1]["psnr_db"]:
            front.append(p)
    return front


def point_name(p):
    names = [f"{p['codec']}"] + [f"{c.name} {c.label(p[c.name])}" for c in CONTROLS if c.name in p]
    return ", ".join(names)


def write_front(points, path):
    """A front for `rtwall run --target-fps` (TOML, read by tools/rtwall/cmd_run.cpp)."""
    lines = [f"# Measured by tools/speed_accuracy.py: frame time simulated on {TOPOLOGY}, error = RMSE",
             f"# (8-bit levels) against the converged reference. Used by rtwall run --target-fps N --front FILE.",
             f'scene = "{points[0]["scene"]}"', ""]
    front = pareto(points)
    names_denoise = any("denoise" in p for p in front)
    for p in front:
        codec, _, quality = p["codec"].partition(":")
        controls = {c.name: p[c.name] for c in CONTROLS if c.name in p}
        if names_denoise:
            controls.setdefault("denoise", 0)  # the filter off, said: a point without it would keep the last one's
        controls["codec"] = CODEC_IDS[codec]
        if codec == "jpeg":
            controls["jpeg_quality"] = int(quality)
        lines += ["[[point]]", f'name = "{point_name(p)}"', f"frame_s = {p['frame_s']:.6g}",
                  f"error = {p['rmse']:.6g}", f"psnr_db = {p['psnr_db']:.4g}",
                  "controls = { " + ", ".join(f"{k} = {v}" for k, v in controls.items()) + " }", ""]
    path.write_text("\n".join(lines))


# ---- 3. scaling ------------------------------------------------------------------------------

def scaling(r, scene, ref):
    s = SCALING_POINT
    profile = r.raw / f"profile-{scene.name}-scaling.toml"
    r.run("bench", "tiles", source(r, scene), "--width", scene.wall[0], "--height", scene.wall[1], "--tile", s["tile"],
          "--scale", s["scale"], "--supersample", s["supersample"], "--codecs", ",".join(SCALING_CODECS),
          "--profile-out", profile, "--json", *scene.extra)
    out = {}
    for label, (client, master) in SCALING_LINKS.items():
        out[label] = {codec: simulate(r, profile, codec, clients=SCALING_CLIENTS, client_link=client, master_link=master,
                                      threads=2, frames=5)["results"] for codec in SCALING_CODECS}
    # No frame is faster than its slowest tile on one thread: the bound many clients run into.
    import tomllib
    prof = tomllib.loads(profile.read_text())
    out["slowest_tile_s"] = max(prof["frame"][0]["render_s"])
    return out


def saturation(rows, threshold=0.9):
    for row in rows:
        if row["master_link_load"] >= threshold:
            return row["clients"]
    return None


# ---- 4. failure cases --------------------------------------------------------------------------

def failure_jpeg_text(r):
    """JPEG on hard edges and text against the same codec on a rendered image."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    text = r.raw / "text.png"
    fig = plt.figure(figsize=(8, 6), dpi=100)
    fig.patch.set_facecolor("white")
    for i, size in enumerate([6, 8, 10, 14, 20]):
        fig.text(0.03, 0.92 - i * 0.09, f"{size} pt: The quick brown fox 0123456789 ()[]{{}} #%&", fontsize=size)
    ax = fig.add_axes([0.05, 0.05, 0.9, 0.4])
    for k in range(12):
        ax.plot([0, 1], [k / 12, 1 - k / 12], lw=0.8, color="black")
    ax.set_xticks([])
    ax.set_yticks([])
    fig.savefig(text, facecolor="white")
    plt.close(fig)
    diff_dir = r.raw / "text-codecs"
    diff_dir.mkdir(exist_ok=True)
    rows = {"text (hard edges, 1-pixel strokes)": r.run("bench", "codecs", text, "--tile", 64, "--json",
                                                        "--diff-dir", diff_dir)}
    return rows, text, diff_dir


def failure_affinity(r, scene):
    """Affinity when the camera moves fast: per-frame tile costs recorded along orbits."""
    out = []
    degrees = [0, 2, 10, 30] if not r.quick else [0, 30]
    for d in degrees:
        profile = r.raw / f"profile-{scene.name}-orbit{d}.toml"
        r.run("bench", "tiles", scene.source, "--width", 800, "--height", 600, "--tile", 32, "--codecs", "lz4",
              "--frames", 6, "--orbit", d, "--profile-out", profile, "--json", *scene.extra)
        for affinity in (True, False):
            res = simulate(r, profile, "lz4", clients=8, threads=1, frames=12, no_affinity=not affinity,
                           client_link="unlimited", master_link="unlimited")["results"][0]
            out.append({"degrees_per_frame": d, "affinity": affinity, "fps": res["fps"],
                        "stolen_per_frame": res["stolen_per_frame"],
                        "affinity_hit_fraction": res["affinity_hit_fraction"],
                        "utilisation": res["mean_client_utilisation"]})
    return out


def failure_prefetch(r, scene):
    """Prefetch when latency spikes: a spiking message delays everything behind it on its link."""
    profile = r.raw / f"profile-{scene.name}-scaling.toml"
    out = []
    for prob, spike in [(0.0, 0), (0.01, 50), (0.05, 50), (0.05, 200)]:
        for prefetch in [1, 2, 4, 8, 16]:
            res = simulate(r, profile, "lz4", clients=8, threads=2, prefetch=prefetch, frames=20,
                           spike_probability=prob, spike_ms=spike)["results"][0]
            out.append({"spike_probability": prob, "spike_ms": spike, "prefetch": prefetch, "fps": res["fps"],
                        "reissued_per_frame": res["reissued_per_frame"]})
    return out


# ---- 5. validation ---------------------------------------------------------------------------

VALIDATION_REPEATS = 3
VALIDATION_CLIENTS = [1, 2, 3, 4]
VALIDATION_CORES = os.cpu_count() or 2
VALIDATION_SCENE = ["builtin:knots", "--triangles", "200000", "--shading", "eyelight", "--width", "1600",
                    "--height", "1200"]
# Loopback latency, as in `rtwall simulate`'s default (not fitted).
VALIDATION_LATENCY_MS = 0.1
# The master's decode pool on this PC: Master uses hardware threads / 2, 1 to 4.
VALIDATION_DECODE_THREADS = max(1, min(4, VALIDATION_CORES // 2))
VALIDATION_TILE = 64
# The host costs besides rendering are calibrated on another setting than the one validated:
# 32-pixel tiles (4x the results per frame, a quarter of the bytes each), 2 clients, raw and
# LZ4 (the two byte counts separate a per-result from a per-byte cost).
CALIBRATION_TILE = 32
CALIBRATION_CLIENTS = 2
CALIBRATION_CODECS = ["raw", "lz4"]
CALIBRATION_FRAMES = 16


def merge_profiles_median(parts, out):
    """Per tile the median render, encode and decode time of several recordings of one profile (the
    least would be biased low: it picks each tile's luckiest run)."""
    med = lambda xs: sorted(xs)[len(xs) // 2]
    import tomllib
    ps = [tomllib.loads(p.read_text()) for p in parts]
    base = ps[0]
    arr = lambda v: "[ " + ", ".join(repr(x) for x in v) + " ]"
    lines = [f'scene = "{base["scene"]}"', f"width = {base['width']}", f"height = {base['height']}",
             f"tile = {base['tile']}", ""]
    for f in range(len(base["frame"])):
        lines += ["[[frame]]", "render_s = " + arr([med(x) for x in zip(*[p["frame"][f]["render_s"] for p in ps])]), ""]
    for c in range(len(base["codec"])):
        cc = base["codec"][c]
        lines += ["[[codec]]", f'codec = "{cc["codec"]}"', f"jpeg_quality = {cc['jpeg_quality']}",
                  f"jpeg_subsample = {str(cc['jpeg_subsample']).lower()}", f"zstd_level = {cc['zstd_level']}",
                  "bytes = " + arr(cc["bytes"])]
        for key in ("encode_s", "decode_s"):
            lines.append(f"{key} = " + arr([med(x) for x in zip(*[p["codec"][c][key] for p in ps])]))
        lines.append("")
    out.write_text("\n".join(lines))


PROBE_S = 1.0


def available_cores(seconds=PROBE_S):
    """The cores this job gets right now: CPU time that VALIDATION_CORES busy processes, started like
    the benchmark's (same session, so the same autogroup and nice level), obtain per wall second.
    Other jobs' runnable threads are no measure of it: they run at other nice levels and in other
    autogroups, and the kernel shares the cores between groups, not threads."""
    import resource
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    busy = f"import time\nt = time.time()\nwhile time.time() - t < {seconds}: pass"
    procs = [subprocess.Popen([sys.executable, "-c", busy]) for _ in range(VALIDATION_CORES)]
    for p in procs:
        p.wait()
    wall = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return min(float(VALIDATION_CORES), cpu / wall)


def background_threads(samples=20, dt=0.05):
    """Other jobs' runnable threads right now: /proc/stat's procs_running (this reader excluded)."""
    vals = []
    for _ in range(samples):
        for line in Path("/proc/stat").read_text().splitlines():
            if line.startswith("procs_running"):
                vals.append(max(0, int(line.split()[1]) - 1))
        time.sleep(dt)
    vals.sort()
    return vals[len(vals) // 2]


def fit_cost(rows, key):
    """CPU seconds per frame `key` = results x a + bytes x b, from runs with the same tile count and
    different bytes (least squares, a and b clamped at 0): (seconds per result, seconds per byte)."""
    n = len(rows)
    xs = [x["bytes_per_frame"] for x in rows]
    ys = [x["cpu_per_frame"][key] for x in rows]
    tiles = rows[0]["cpu_per_frame"]["tiles"]
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = max(0.0, sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx) if sxx > 0 else 0.0
    a = max(0.0, (my - b * mx) / tiles)
    if a == 0:  # a negative intercept: all of it per byte
        b = my / mx
    return a, b


def calibrate(r):
    """The host costs besides rendering, from the per-thread CPU times of `rtwall bench cluster`
    (cpu_per_frame) on the calibration setting: `rtwall simulate` options."""
    runs = []
    for codec in CALIBRATION_CODECS:
        m = r.run("bench", "cluster", "--tile", CALIBRATION_TILE, "--frames", CALIBRATION_FRAMES, "--render",
                  "--client-counts", CALIBRATION_CLIENTS, "--codec", codec, "--json")["results"][0]
        runs.append(m)
        log(f"calibration {codec}: {m['fps']:.2f} fps, CPU per frame " +
            ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in m["cpu_per_frame"].items() if k.endswith("_s")))
    tiles = runs[0]["cpu_per_frame"]["tiles"]
    ca, cb = fit_cost(runs, "client_non_render_s")
    # The master: ZeroMQ's I/O thread (and the kernel's TCP receive it runs) per result.
    ma, mb = fit_cost(runs, "master_zmq_s")
    # Its network thread: per message (the results and one request per client and frame).
    per_msg = sum(x["cpu_per_frame"]["master_net_s"] for x in runs) / len(runs) / (tiles + CALIBRATION_CLIENTS)
    per_frame = sum(x["cpu_per_frame"].get("master_main_s", 0.0) for x in runs) / len(runs)
    # Render threads sharing the cores run slower than one alone (caches, memory): their CPU per
    # frame in the cluster against the tile profile's render + encode of the same frame.
    profile = r.raw / f"profile-calibration-tile{CALIBRATION_TILE}.toml"
    r.run("bench", "tiles", *VALIDATION_SCENE, "--tile", CALIBRATION_TILE, "--codecs", "lz4", "--profile-out", profile,
          "--json")
    import tomllib
    prof = tomllib.loads(profile.read_text())
    alone = sum(prof["frame"][0]["render_s"]) + sum(prof["codec"][0]["encode_s"])
    in_cluster = [x["cpu_per_frame"]["client_render_s"] for x in runs if x["codec"] == "lz4"][0]
    cal = {"client_us_per_result": 1e6 * ca, "client_ns_per_byte": 1e9 * cb,
           "master_us_per_result": 1e6 * ma, "master_ns_per_byte": 1e9 * mb,
           "master_us_per_message": 1e6 * per_msg, "master_ms_per_frame": 1e3 * per_frame,
           "client_speed": min(1.0, alone / in_cluster), "runs": runs}
    log("calibration: " + ", ".join(f"{k} {v:.3g}" for k, v in cal.items() if k != "runs"))
    return cal


def rows_load(runs):
    return sorted(x["background_threads"] for x in runs)[len(runs) // 2]


def validate(r):
    """Local clients rendering for real on this PC against the simulation of the same frame."""
    tile = VALIDATION_TILE
    cal = calibrate(r)
    profile = r.raw / f"profile-validation-tile{tile}.toml"
    parts = []
    for i in range(VALIDATION_REPEATS):
        part = r.raw / f"profile-validation-tile{tile}-{i}.toml"
        r.run("bench", "tiles", *VALIDATION_SCENE, "--tile", tile, "--codecs", "lz4", "--profile-out", part, "--json")
        parts.append(part)
    merge_profiles_median(parts, profile)
    costs = {k: v for k, v in cal.items() if k != "runs"}

    def sim(clients, cores, load, host_costs=True):
        extra = costs if host_costs else {"master_us_per_message": 28}  # 28 µs: the model before calibration
        return simulate(r, profile, "lz4", clients=clients, threads=1, prefetch=4, client_link="unlimited",
                        master_link="unlimited", latency_ms=VALIDATION_LATENCY_MS,
                        decode_threads=VALIDATION_DECODE_THREADS, host_cores=cores, host_load=load,
                        frames=8, **extra)["results"][0]["fps"]

    rows = []
    for n in VALIDATION_CLIENTS:
        runs = []
        for i in range(VALIDATION_REPEATS):
            before = background_threads()
            cores_before = available_cores()
            m = r.run("bench", "cluster", "--tile", tile, "--frames", 8, "--render", "--client-counts", n,
                      "--json")["results"][0]
            load = (before + background_threads()) / 2
            cores = round((cores_before + available_cores()) / 2, 2)
            runs.append({"measured_fps": m["fps"], "background_threads": load, "available_cores": cores,
                         "simulated_fps": sim(n, cores, 0), "cpu_per_frame": m["cpu_per_frame"]})
        med = lambda k: sorted(x[k] for x in runs)[len(runs) // 2]
        rows.append({"clients": n, "runs": runs, "measured_fps": med("measured_fps"),
                     "simulated_fps": med("simulated_fps"), "background_threads": med("background_threads"),
                     "simulated_fps_no_sharing": sim(n, 0, 0), "simulated_fps_idle_pc": sim(n, VALIDATION_CORES, 0),
                     "available_cores": med("available_cores"),
                     "simulated_fps_without_host_costs": sim(n, med("available_cores"), 0, False),
                     "calibration": costs, "calibration_runs": cal["runs"]})
        log(f"validation: {n} clients: measured {rows[-1]['measured_fps']:.2f} fps, simulated "
            f"{rows[-1]['simulated_fps']:.2f} fps ({rows[-1]['available_cores']} cores available, "
            f"{rows[-1]['background_threads']} other runnable threads)")
    return rows


# ---- 5b. the controller on a real cluster ------------------------------------------------------

TRACE_TARGET_FPS = 5
TRACE_PHASE_S = 20
# The throttle: the fast end of the front must fit with room to spare, the accurate end must not.
TRACE_FAST_POINTS = 2      # the front's fastest points...
TRACE_FAST_SHARE = 2 / 3   # ...need at most this share of the throttled link at the target rate


def trace_rate(front_points, target_fps):
    """The throttle, in kbit/s, computed from the front's MB/frame: the fastest TRACE_FAST_POINTS points
    need TRACE_FAST_SHARE of it at the target frame rate; and which points can hold the target there."""
    front = pareto(front_points)
    need = lambda p: p["bytes_per_frame"] * 8 * target_fps  # bit/s at the target rate
    fast = max(need(p) for p in front[:TRACE_FAST_POINTS])
    kbit = int(math.ceil(fast / TRACE_FAST_SHARE / 1000 / 100) * 100)
    fits = [need(p) <= kbit * 1000 for p in front]
    return kbit, fits, front


def controller_trace(r, front, front_points):
    """rtwall run --target-fps on loopback: clients killed and started, the link throttled (tc tbf)."""
    out = r.raw / "controller-trace"
    shutil.rmtree(out, ignore_errors=True)
    kbit, fits, pts = trace_rate(front_points, TRACE_TARGET_FPS)
    rate = f"{kbit}kbit"
    log(f"controller trace: throttle {rate}; front points that fit it at {TRACE_TARGET_FPS} fps: "
        + ", ".join(f"{i} ({p['bytes_per_frame'] / 1e6:.3f} MB)" for i, (p, f) in enumerate(zip(pts, fits)) if f))
    cmd = ["unshare", "-rn", str(ROOT / "tools" / "controller_trace.sh"), r.exe, str(front), str(TRACE_TARGET_FPS),
           str(out), rate]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env={**os.environ, "PHASE": str(TRACE_PHASE_S)})
    if p.returncode != 0 or not (out / "trace.csv").exists():
        log(f"controller trace failed ({p.returncode}): {p.stderr.strip()[-500:]}")
        return None
    import csv
    frames = list(csv.DictReader((out / "trace.csv").open()))
    events = list(csv.DictReader((out / "events.csv").open()))
    return {"target_fps": TRACE_TARGET_FPS, "rate": rate, "phase_s": TRACE_PHASE_S,
            "front_mb_per_frame": [p["bytes_per_frame"] / 1e6 for p in pts], "front_fits_throttle": fits,
            "frames": [{"frame": int(f["frame"]), "seconds": float(f["seconds"]), "clients": int(f["clients"]),
                        "point_index": int(f["point_index"]), "point": f["point"]} for f in frames],
            "events": [{"frame": int(e["frame"]), "event": e["event"]} for e in events],
            "summary": (out / "run.log").read_text().strip().splitlines()[-1:]}


def trace_chart(docs, trace):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fr = trace["frames"]
    xs = [f["frame"] for f in fr]
    fig, (a, b) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    a.plot(xs, [1 / f["seconds"] for f in fr], "-", lw=0.8, color="C0", label="frames/s (master frame time)")
    a.axhline(trace["target_fps"], color="red", ls="--", lw=1, label=f"target {trace['target_fps']} fps")
    a.set_yscale("log")
    a.set_ylabel("frames/s")
    b.step(xs, [f["point_index"] for f in fr], where="post", color="C1", label="operating point (front index)")
    b.step(xs, [f["clients"] for f in fr], where="post", color="C2", ls=":", label="connected clients")
    b.set_ylabel("front index / clients")
    b.set_xlabel("frame")
    for ax in (a, b):
        for e in trace["events"]:
            ax.axvline(e["frame"], color="grey", lw=0.8)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    for e in trace["events"]:
        a.text(e["frame"], a.get_ylim()[1], " " + e["event"], rotation=90, va="top", fontsize=7)
    fig.tight_layout()
    path = docs / "speed-accuracy-controller-trace.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def trace_summary(trace):
    """Per phase: frames, frames within budget after the first 10, point changes, the final point."""
    fr, ev = trace["frames"], trace["events"]
    budget = 1 / trace["target_fps"]
    rows = []
    for i, e in enumerate(ev[:-1]):
        sel = [f for f in fr if e["frame"] < f["frame"] <= ev[i + 1]["frame"]]
        if not sel:
            continue
        late = sel[10:]
        changes = sum(1 for a, b in zip(sel, sel[1:]) if a["point_index"] != b["point_index"])
        back = next((k for k, f in enumerate(sel) if all(g["seconds"] <= budget for g in sel[k:k + 5])), None)
        rows.append([e["event"], len(sel), "-" if back is None else back,
                     f"{sum(f['seconds'] <= budget for f in late)} of {len(late)}", changes, sel[-1]["point"]])
    return rows


# ---- 6. charts and docs ------------------------------------------------------------------------

def charts(docs, points_by_scene, scaling_by_scene, affinity, prefetch, validation):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = {}
    for scene, points in points_by_scene.items():
        fig, ax = plt.subplots(figsize=(9, 6))
        codecs = sorted({p["codec"] for p in points}, key=CODECS.index)
        cmap = plt.get_cmap("tab10")
        markers = {1.0: "o", 0.75: "s", 0.5: "^"}
        for i, codec in enumerate(codecs):
            for scale, marker in markers.items():
                sel = [p for p in points if p["codec"] == codec and p.get("scale", 1.0) == scale]
                if sel:
                    ax.scatter([p["fps"] for p in sel], [min(p["psnr_db"], 80) for p in sel], s=22, marker=marker,
                               color=cmap(i), alpha=0.75, label=codec if scale == 1.0 else None)
        for d, (marker, colour) in {1: ("D", "C8"), 2: ("*", "C3")}.items():
            sel = [p for p in points if p.get("denoise") == d]
            if sel:
                ax.scatter([p["fps"] for p in sel], [min(p["psnr_db"], 80) for p in sel], s=60, marker=marker,
                           color=colour, label=f"denoise {CONTROL['denoise'].label(d)} (after an orbit)")
        plain = [p for p in points if not p.get("denoise")]
        if len(plain) < len(points):
            front0 = pareto(plain)
            ax.plot([p["fps"] for p in front0], [min(p["psnr_db"], 80) for p in front0], ":", color="grey", lw=1.2,
                    label="Pareto front without the denoiser")
        front = pareto(points)
        ax.plot([p["fps"] for p in front], [min(p["psnr_db"], 80) for p in front], "k-", lw=1.2, label="Pareto front")
        ax.scatter([p["fps"] for p in front], [min(p["psnr_db"], 80) for p in front], s=70, facecolors="none",
                   edgecolors="black")
        ax.axhline(40, color="grey", ls=":", lw=1)
        ax.set_xscale("log")
        ax.set_xlabel(f"frames/s (simulated: {TOPOLOGY['clients']} clients x {TOPOLOGY['threads']} threads of this PC, "
                      f"{TOPOLOGY['client_link']} links)")
        ax.set_ylabel("PSNR against the converged reference, dB")
        ax.set_title(f"{scene}: speed against accuracy (o full, s 3/4, ^ 1/2 resolution)")
        ax.legend(fontsize=8, ncol=2)
        ax.grid(True, which="both", alpha=0.3)
        path = docs / f"speed-accuracy-{scene}.png"
        fig.tight_layout()
        fig.savefig(path, dpi=90)
        plt.close(fig)
        out[f"pareto-{scene}"] = path

    cols = min(3, len(scaling_by_scene))
    rows_n = (len(scaling_by_scene) + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(7 * cols, 5.5 * rows_n), squeeze=False)
    for ax in axes.flat[len(scaling_by_scene):]:
        ax.axis("off")
    for ax, (scene, by_link) in zip(axes.flat, scaling_by_scene.items()):
        by_link = {k: v for k, v in by_link.items() if k != "slowest_tile_s"}
        for j, (label, by_codec) in enumerate(by_link.items()):
            for k, (codec, rows) in enumerate(by_codec.items()):
                c = plt.get_cmap("tab10")(3 * j + k)
                xs = [row["clients"] for row in rows]
                ax.plot(xs, [row["fps"] for row in rows], "o-", color=c, ms=4, label=f"{codec}, {label}")
                ax.plot(xs, [row["link_ceiling_fps"] for row in rows], "--", color=c, lw=1)
                n = saturation(rows)
                if n:
                    sat = next(row for row in rows if row["clients"] == n)
                    ax.annotate(f"link saturated at {n}", (n, sat["fps"]), fontsize=7, xytext=(5, -12),
                                textcoords="offset points", color=c)
        ax.plot(xs, [rows[0]["render_bound_fps"] * x for x in xs], ":", color="grey", lw=1, label="rendering alone")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("clients (2 threads each, this PC's speed)")
        ax.set_ylabel("frames/s (simulated); dashed: link-bound ceiling")
        ax.set_title(f"{scene}: scaling")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    path = docs / "speed-accuracy-scaling.png"
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    out["scaling"] = path

    if validation:
        fig, ax = plt.subplots(figsize=(7, 5))
        xs = [v["clients"] for v in validation]
        for v in validation:
            ax.scatter([v["clients"]] * len(v["runs"]), [x["measured_fps"] for x in v["runs"]], color="C0", s=12, alpha=0.5)
        ax.plot(xs, [v["measured_fps"] for v in validation], "o-", color="C0", label="measured (median; dots: runs)")
        ax.plot(xs, [v["simulated_fps"] for v in validation], "s-", color="C1",
                label="simulated: the cores this job got (measured), host costs calibrated")
        ax.plot(xs, [v["simulated_fps_without_host_costs"] for v in validation], "x-.", color="C4",
                label="simulated: the same without host costs (the model before)")
        ax.plot(xs, [v["simulated_fps_idle_pc"] for v in validation], "^--", color="C2",
                label=f"simulated: {VALIDATION_CORES} shared cores, idle PC, host costs calibrated")
        ax.plot(xs, [v["simulated_fps_no_sharing"] for v in validation], "v:", color="C3",
                label="simulated: one machine per client (old model)")
        ax.set_xticks(xs)
        ax.set_xlabel("local render clients (1 thread each) on this PC")
        ax.set_ylabel("frames/s")
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
        path = docs / "speed-accuracy-validation.png"
        fig.tight_layout()
        fig.savefig(path, dpi=90)
        plt.close(fig)
        out["validation"] = path
    return out


def fmt_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def psnr(v):
    return "inf (lossless)" if v >= 900 else f"{v:.1f}"


def affinity_summary(affinity):
    cost = []
    for d in sorted({a["degrees_per_frame"] for a in affinity}):
        on = next(a for a in affinity if a["degrees_per_frame"] == d and a["affinity"])
        off = next(a for a in affinity if a["degrees_per_frame"] == d and not a["affinity"])
        cost.append((d, on["fps"] / off["fps"] - 1))
    worst = min(cost, key=lambda c: c[1])
    return (f"Measured here: affinity changes frames/s by {', '.join(f'{100 * c:+.0f}% at {d} deg' for d, c in cost)} "
            f"(worst {100 * worst[1]:+.0f}% at {worst[0]} deg/frame). Work stealing absorbs the mismatch, so the "
            "frame rate barely moves; what breaks is the premise: when the image moves by more than a tile per "
            "frame, the tile a client gets back shows other geometry than last frame, so any per-client cache "
            "warmth is gone while the stealing traffic stays.")


def prefetch_summary(prefetch):
    calm = {p["prefetch"]: p["fps"] for p in prefetch if p["spike_probability"] == 0}
    worst = [p for p in prefetch if p["spike_probability"] == max(q["spike_probability"] for q in prefetch)
             and p["spike_ms"] == max(q["spike_ms"] for q in prefetch)]
    parts = ", ".join(f"{100 * p['fps'] / calm[p['prefetch']]:.0f}% at prefetch {p['prefetch']}" for p in worst)
    most = max(prefetch, key=lambda p: p["reissued_per_frame"])
    keep = {p["prefetch"]: p["fps"] / calm[p["prefetch"]] for p in worst}
    best_keep = max(keep, key=keep.get)
    best_abs = max(worst, key=lambda p: p["fps"])
    return (f"With the worst spikes ({worst[0]['spike_probability']:g} of messages, {worst[0]['spike_ms']} ms) "
            f"frames/s falls to {parts} of the spike-free rate: prefetch no longer hides anything, since every "
            "frame waits for some tile stuck behind a spike. In absolute terms prefetch "
            f"{best_abs['prefetch']} is still fastest ({best_abs['fps']:.1f} frames/s); relative to its own "
            f"spike-free rate prefetch {best_keep} loses least. The deeper the prefetch, the more duplicate work: "
            f"stragglers are re-issued, up to {most['reissued_per_frame']:.0f} tiles per frame (prefetch "
            f"{most['prefetch']}, {most['spike_ms']} ms spikes), rendered twice and sent twice.")


def shading_failures(points_by_scene):
    """Pruning on deep glass (headlight) and GI in dark corners (office), from the sweep's points."""
    md = []
    lossless = lambda p: p["codec"] == "lz4" and p.get("scale", 1.0) == 1.0 and p.get("supersample", 1) == 1
    head = sorted((p for p in points_by_scene.get("headlight", []) if lossless(p)), key=lambda p: p["prune"])
    if head:
        md += ["### prune-deep-glass: ray-tree pruning on deep glass", "",
               "Pruning drops a ray once its throughput to the pixel falls below the threshold. In the headlight, "
               "light reaches the eye through a reflector and a structured lens: every glass interface splits a path "
               "in two, each branch carrying a fraction of the light, so after a few interfaces every branch is below "
               "a modest threshold and is dropped, although together they carry most of the lens's light. Headlight at "
               "full resolution, 1x1 samples, lossless (lz4), against the reference (" +
               ", ".join(f"{k} {v:g}" for k, v in reference_settings(next(sc for sc in SCENES if sc.name == "headlight")).items()) +
               f"). PSNR moves little ({head[0]['psnr_db']:.1f} to {head[-1]['psnr_db']:.1f} dB): at 1x1 samples "
               "it is dominated by the sub-pixel specks of the filament's images (the scene's note above; the "
               "sweep's supersampled points show how much of it goes with more samples). FLIP, which looks at what "
               "the eye sees, " + ("does rise" if head[-1]['flip'] > head[0]['flip'] else "does not rise") +
               " with the threshold "
               f"({head[0]['flip']:.3f} at {head[0]['prune']:g} to {head[-1]['flip']:.3f} at {head[-1]['prune']:g}) "
               "while the frame rate grows "
               f"{head[-1]['fps'] / head[0]['fps']:.1f}x" +
               (": pruning buys speed with a loss that a whole-image mean error hides." if head[-1]['flip'] > head[0]['flip']
                else "."), "",
               fmt_table(["prune threshold", "frames/s (simulated)", "PSNR dB", "FLIP", "largest error"],
                         [[f"{p['prune']:g}", f"{p['fps']:.2f}", psnr(p["psnr_db"]), f"{p['flip']:.4f}",
                           p["max_error"]] for p in head]), ""]
    office = [p for p in points_by_scene.get("office", []) if lossless(p)]
    if office:
        step = min(p["volume_step"] for p in office)
        prune = min(p["prune"] for p in office)
        gi = sorted((p for p in office if p["volume_step"] == step and p["prune"] == prune), key=lambda p: p["gi_spp"])
        md += ["### gi-dark-corners: few GI samples in dark corners", "",
               "Indirect light is estimated by random bounces; where little light arrives (corners, under the desk, "
               "behind the plant) most bounces find nothing and a few find a bright surface, so the estimate's "
               "relative noise is largest exactly where the image is dark. PSNR, a mean over the whole image, "
               "barely sees it (dark pixels have small absolute errors); FLIP, which compares in a perceptual "
               "colour space with the eye's contrast sensitivity, weighs the speckle in the dark more. Office at "
               f"full resolution, lossless, volume step {step:g}, prune {prune:g}:", "",
               fmt_table(["GI samples per pixel", "frames/s (simulated)", "PSNR dB", "SSIM", "FLIP", "largest error"],
                         [[p["gi_spp"], f"{p['fps']:.2f}", psnr(p["psnr_db"]), f"{p['ssim']:.4f}", f"{p['flip']:.4f}",
                           p["max_error"]] for p in gi]), ""]
    return md


# ---- 7. STEP tessellation --------------------------------------------------------------------

TESSELLATION_ARGS = ["--linear", "3,1,0.3,0.1,0.03,0.01", "--angular", "1,0.5,0.25,0.1", "--reference-linear", "0.002",
                     "--reference-angular", "0.05", "--width", "800", "--height", "600", "--supersample", "2",
                     "--runs", "3"]
TESSELLATION_BEGIN, TESSELLATION_END = "<!-- tessellation: begin -->", "<!-- tessellation: end -->"


def tessellation(r):
    t0 = time.time()
    res = r.run("bench", "tessellation", "--json", "--dir", r.work / "tessellation", *TESSELLATION_ARGS)
    res["elapsed_s"] = time.time() - t0
    (r.raw / "tessellation.json").write_text(json.dumps(res, indent=1))
    log(f"tessellation: done ({res['elapsed_s'] / 60:.1f} min)")
    return res


def tessellation_chart(docs, tess):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = tess["rows"]
    angulars = sorted({row["angular_deflection"] for row in rows}, reverse=True)
    panels = [("unique triangles", lambda row: row["unique_triangles"], True),
              ("memory, MB (mesh buffers + Embree BVH)", lambda row: (row["geometry_bytes"] + row["embree_bytes"]) / 1e6, True),
              (f"cold import, s (median of {tess['runs']})", lambda row: row["import_s"], True),
              ("RMSE against the reference, 8-bit levels", lambda row: row["rmse"], True),
              ("mean FLIP against the reference", lambda row: row["flip"], True)]
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    cmap = plt.get_cmap("viridis")
    for ax, (label, value, logy) in zip(axes.flat, panels):
        for i, a in enumerate(angulars):
            sel = sorted((row for row in rows if row["angular_deflection"] == a), key=lambda row: row["linear_deflection"])
            ax.plot([row["linear_deflection"] for row in sel], [max(value(row), 1e-4) for row in sel], "o-", ms=4,
                    color=cmap(i / max(1, len(angulars) - 1)), label=f"angular {a:g} rad")
        ax.set_xscale("log")
        ax.invert_xaxis()  # finer to the right
        if logy:
            ax.set_yscale("log")
        ax.set_xlabel("linear deflection, mm (finer to the right)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes.flat[0].legend(fontsize=8)
    ax = axes.flat[5]
    for i, a in enumerate(angulars):
        sel = [row for row in rows if row["angular_deflection"] == a]
        ax.scatter([row["unique_triangles"] for row in sel], [min(row["psnr_db"], 80) for row in sel], s=22,
                   color=cmap(i / max(1, len(angulars) - 1)), label=f"angular {a:g} rad")
    ax.axhline(40, color="grey", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_xlabel("unique triangles")
    ax.set_ylabel("PSNR against the reference, dB")
    ax.grid(True, which="both", alpha=0.3)
    ref = tess["reference"]
    fig.suptitle(f"STEP tessellation: {tess['instances']} part instances of {tess['meshes']} curved parts; reference "
                 f"linear {ref['linear_deflection']:g} mm, angular {ref['angular_deflection']:g} rad "
                 f"({ref['unique_triangles']:,} unique triangles)")
    path = docs / "speed-accuracy-tessellation.png"
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def tessellation_section(path, fig, tess):
    rel = os.path.relpath(fig, path.parent)
    ref, rows = tess["reference"], tess["rows"]
    ok = [row for row in rows if row["psnr_db"] >= 40]
    cheapest = min(ok, key=lambda row: row["unique_triangles"]) if ok else None
    default = next((row for row in rows if row["linear_deflection"] == 0.1 and row["angular_deflection"] == 0.5), None)
    md = [TESSELLATION_BEGIN, "## STEP tessellation: tolerance against triangles, memory, import time and error", "",
          f"`rtwall bench tessellation --json {' '.join(TESSELLATION_ARGS)}` (run by `tools/speed_accuracy.py "
          f"--only tessellation` in {tess.get('elapsed_s', 0) / 60:.1f} min): `rtwall gen step-curved` writes a STEP "
          f"assembly through OpenCASCADE of {tess['instances']} part instances of {tess['meshes']} curved parts (a plate "
          "with every edge filleted, pins with a rounded head, ball knobs, torus rings; millimetres), imported at every "
          "pair of linear deflection (the largest distance between surface and triangles) and angular deflection (the "
          "largest angle between neighbouring triangles; BRepMesh meets both). Import time is a cold import "
          "(OpenCASCADE's transfer and BRepMesh, no assembly cache; the median of "
          f"{tess['runs']}); memory is the mesh buffers (positions, normals, indices) plus Embree's BVHs. Error: the "
          f"same camera and {tess['supersample']}x{tess['supersample']} samples per pixel at {tess['width']}x{tess['height']} "
          f"against the reference tessellation (linear {ref['linear_deflection']:g} mm, angular "
          f"{ref['angular_deflection']:g} rad: {ref['unique_triangles']:,} unique triangles, "
          f"{(ref['geometry_bytes'] + ref['embree_bytes']) / 1e6:.1f} MB, import {ref['import_s']:.2f} s), so the only "
          "difference is the geometry: faceted silhouettes and the flat facets' shading (normals come from the "
          "surface, so shading inside a face is smooth already at coarse settings).", "",
          f"![tessellation]({rel})", ""]
    if cheapest:
        md += [f"**The fewest triangles at 40 dB or better: linear {cheapest['linear_deflection']:g} mm, angular "
               f"{cheapest['angular_deflection']:g} rad** ({cheapest['unique_triangles']:,} unique triangles, "
               f"{cheapest['psnr_db']:.1f} dB, {cheapest['unique_triangles'] / ref['unique_triangles']:.1%} of the "
               "reference's triangles)." + (f" The default (0.1 mm, 0.5 rad): {default['unique_triangles']:,} triangles, "
                                            f"{default['psnr_db']:.1f} dB, FLIP {default['flip']:.4f}." if default else ""), ""]
    md += [fmt_table(["linear mm", "angular rad", "unique triangles", "instanced triangles", "mesh MB", "BVH MB",
                      "bytes / unique triangle", "import s", "RMSE", "PSNR dB", "FLIP"],
                     [[f"{row['linear_deflection']:g}", f"{row['angular_deflection']:g}", f"{row['unique_triangles']:,}",
                       f"{row['instanced_triangles']:,}", f"{row['geometry_bytes'] / 1e6:.2f}",
                       f"{row['embree_bytes'] / 1e6:.2f}",
                       f"{(row['geometry_bytes'] + row['embree_bytes']) / max(1, row['unique_triangles']):.0f}",
                       f"{row['import_s']:.3f}", f"{row['rmse']:.3f}", psnr(row["psnr_db"]), f"{row['flip']:.4f}"]
                      for row in sorted(rows, key=lambda row: (-row["linear_deflection"], -row["angular_deflection"]))]),
           "", TESSELLATION_END, ""]
    return md


def update_tessellation_section(path, section):
    """Replaces the page's tessellation section (or puts it before the automatic operating point)."""
    text = path.read_text()
    block = "\n".join(section)
    if TESSELLATION_BEGIN in text and TESSELLATION_END in text:
        head, rest = text.split(TESSELLATION_BEGIN, 1)
        tail = rest.split(TESSELLATION_END, 1)[1].lstrip("\n")
        text = head + block + tail
    else:
        at = text.index("## Automatic operating point")
        text = text[:at] + block + text[at:]
    path.write_text(text)


def docs_intro(elapsed, args):
    """The title, how the page was made, and how the figures are made (write_docs)."""
    return ["# Speed against accuracy", "",
          "Generated by `tools/speed_accuracy.py` (" + ("quick run" if args.quick else "full run") +
          f", from scratch in {elapsed / 60:.1f} min" + (f" in two parts: {args.prior_s / 60:.1f} min for the references and the sweep, then the rest with --reuse"
           if args.prior_s > 0 else " (page redrawn from its raw results)" if args.reuse else "") +
          f" on the 2-core development machine, load average {getattr(args, 'start_load', 0):.1f} at the start; "
          "absolute render times are noisy, ratios within one run are what to read). Raw results: `out/speed/raw/`. "
          "Regenerate everything with `tools/speed_accuracy.py`.", "",
          "## How the figures are made", "",
          "- **Error**: every frame is compared with a converged reference (" +
          "; ".join(f"{sc.name}: " + ", ".join(f"{k} {v:g}" for k, v in reference_settings(sc).items()) for sc in SCENES) +
          "; lossless, rendered by `rtwall reference`, cached by a hash of "
          "scene, meshes, settings and engine sources) at the wall's resolution, after the codec and after bilinear "
          "upscaling when rendered at a lower resolution. `rtwall compare A.png B.png --json` gives RMSE, PSNR, SSIM "
          "(mean SSIM of luminance with the 11x11 Gaussian window, sigma 1.5, of Wang et al. 2004) and the largest "
          "per-pixel error, and writes a false-colour difference image.",
          "- **Frame time**: each render setting is rendered once tile by tile on one thread (`rtwall bench tiles`), "
          "which records every tile's render time and every codec's size and encode/decode time (a tile profile). "
          "`rtwall simulate` then runs the master's real `TileScheduler` against simulated clients and links fed "
          f"with that profile: {TOPOLOGY['clients']} clients with {TOPOLOGY['threads']} threads of this PC's speed, "
          f"{TOPOLOGY['client_link']} client links, a {TOPOLOGY['master_link']} master uplink, prefetch "
          f"{TOPOLOGY['prefetch']}, {TOPOLOGY['latency_ms']} ms latency. This PC cannot run 8 clients for real; the "
          "simulation is validated below against what it can run.",
          f"- **FLIP**: also reported is the mean LDR-FLIP (Andersson et al. 2020; `rtwall::flipMean`, 67 pixels "
          "per degree): 0 for identical images, 1 for the largest perceivable difference (green against blue). "
          "Unlike PSNR it weighs errors by what the eye sees at that distance: edges and fine detail count, noise "
          "finer than the eye resolves does not.",
          "- **Swept**, per scene (every combination), each render with every codec "
          f"{CODECS}:", ""] + [
          f"  - **{sc.name}** (wall {sc.wall[0]}x{sc.wall[1]}): " +
          ", ".join(f"{k} {v}" for k, v in sc.sweep.items()) + (f". {sc.note}" if sc.note else "")
          for sc in SCENES] + [
          "", "  Controls: `tile` (pixels), `scale` (render resolution, upscaled bilinearly), `supersample` (n x n "
          "samples per pixel), `prune` (ray-tree pruning threshold), `gi_spp` (GI samples per pixel sample), "
          "`volume_step` (ray-march step, voxels). The same names are the controls of a front, which "
          "`rtwall run --target-fps` applies.", ""]


def docs_scenes(rel, figs, points_by_scene, scaling_by_scene, refs, accs):
    """Per scene: its Pareto front, reference and refinement when still; and its row of the headline."""
    md = ["## Speed against accuracy per scene", ""]
    headline = []
    for scene, points in points_by_scene.items():
        md += [f"![{scene}]({rel(figs['pareto-' + scene])})", "", f"Pareto front of **{scene}** (fastest first):", ""]
        front = pareto(points)
        md.append(fmt_table(["settings", "frames/s", "PSNR dB", "SSIM", "FLIP", "largest error", "MB/frame"],
                            [[point_name(p), f"{p['fps']:.1f}", psnr(p["psnr_db"]), f"{p['ssim']:.4f}",
                              f"{p.get('flip', float('nan')):.4f}", p["max_error"], f"{p['bytes_per_frame'] / 1e6:.2f}"]
                             for p in front]))
        ok = [p for p in points if p["psnr_db"] >= 40]
        best = max(ok, key=lambda p: p["fps"]) if ok else None
        sat = saturation(scaling_by_scene[scene][list(SCALING_LINKS)[0]]["raw"]) if scene in scaling_by_scene else None
        top = max(points, key=lambda p: (p["psnr_db"], p["fps"]))
        ref = refs.get(scene)
        own = (("> " if ref.get("own_is_bound") else "about ") + f"{ref['own_psnr_db']:.1f} dB") if ref else "-"
        acc = accs.get(scene)
        still = "-"
        if acc:
            hit = next((x for x in acc["rows"] if x["psnr_db"] >= 40), None)
            last = acc["rows"][-1]
            name = ", ".join(f"{k} {CONTROL[k].label(v)}" for k, v in acc["settings"].items() if k in CONTROL)
            if hit and hit["seconds"] is not None:
                still = f"{hit['seconds']:.1f} s ({hit['frames']} frames of {name} at {1 / acc['frame_s']:.2f} fps)"
            else:
                still = f"not within {last['frames']} frames ({last['psnr_db']:.1f} dB after {last['frames']} of {name})"
        headline.append([scene, f"{best['fps']:.2f} ({point_name(best)})" if best else
                         f"none reaches 40 dB (best {top['psnr_db']:.1f} dB, at {top['fps']:.2f} fps: {point_name(top)})",
                         still, own, str(sat) if sat else "> 256" if scene in scaling_by_scene else "-"])
        md += ["", f"Front for `rtwall run --target-fps N --front docs/speed-accuracy/front-{scene}.toml`.", ""]
        md += denoise_summary(points)
        if ref:
            md += [f"Reference: {', '.join(f'{k} {v:g}' for k, v in ref['settings'].items())}, rendered in "
                   f"{ref['seconds']:.0f} s; its own error: {own} PSNR ({ref['own_method']}).", ""]
        if acc:
            md += [f"Refined while still (`rtwall run` averages the frames of a still view in linear light): the "
                   f"mean of the first N frames at {name} against the reference; time = N x the simulated frame "
                   f"time of that setting ({acc['frame_s'] * 1e3:.0f} ms):" if acc["frame_s"] else "", "",
                   fmt_table(["frames averaged", "PSNR dB", "FLIP", "time when still"],
                             [[x["frames"], psnr(x["psnr_db"]), f"{x['flip']:.4f}",
                               f"{x['seconds']:.1f} s" if x["seconds"] is not None else "-"] for x in acc["rows"]]), ""]
    return md, headline


def denoise_summary(points):
    """What the denoiser moves on a scene whose sweep has denoised points: those points, and the
    issue's moving target (30 dB and FLIP 0.08 at the frame rate of 4 GI samples without it)."""
    dn = [p for p in points if p.get("denoise")]
    if not dn:
        return []
    plain = [p for p in points if not p.get("denoise")]
    md = [f"**The denoiser** (the `denoise` control; each denoised point is the view the camera arrives at after "
          f"turning {DENOISE_ORBIT['degrees']:g} degrees a frame for {DENOISE_ORBIT['frames']} frames, filtered as the "
          "wall filters it; its frame time is the simulated render, or the 1 Gbit/s master link carrying its linear "
          "tiles and features (8 bytes a pixel plus the mode's features) if that is slower, plus the filter on the "
          f"master's {TOPOLOGY['threads']} threads, measured on this PC):", "",
          fmt_table(["settings", "frames/s", "render alone frames/s", "filter ms", "PSNR dB", "FLIP", "MB/frame"],
                    [[point_name(p), f"{p['fps']:.1f}", f"{p['render_fps']:.1f}", f"{p['filter_ms']:.1f}",
                      psnr(p["psnr_db"]), f"{p['flip']:.4f}", f"{p['bytes_per_frame'] / 1e6:.2f}"]
                     for p in sorted(dn, key=lambda p: -p["fps"])]), ""]
    four = [p for p in plain if p.get("gi_spp") == 4 and p.get("scale", 1.0) == 1.0 and p["codec"] == "raw"]
    if four:
        base = max(four, key=lambda p: p["psnr_db"])
        fast = [p for p in points if p["fps"] >= base["fps"]]
        best = max(fast, key=lambda p: p["psnr_db"])
        best0 = max([p for p in fast if not p.get("denoise")], key=lambda p: p["psnr_db"])
        meets = best["psnr_db"] >= 30 and best["flip"] <= 0.08
        md += [f"At the frame rate of 4 GI samples without the denoiser ({point_name(base)}: {base['fps']:.1f} fps, "
               f"{psnr(base['psnr_db'])} dB, FLIP {base['flip']:.4f}) the most accurate point at least as fast is "
               f"**{point_name(best)}: {psnr(best['psnr_db'])} dB, FLIP {best['flip']:.4f} at {best['fps']:.1f} fps** "
               f"(without the denoiser: {point_name(best0)}, {psnr(best0['psnr_db'])} dB). The moving target (30 dB, "
               f"FLIP 0.08 at that rate) is {'met' if meets else 'missed'} here. The dotted line in the chart is the "
               "front without the denoiser.", ""]
    return md


def docs_headline(headline):
    """The headline table and how to read it."""
    return ["## Headline", "",
                   fmt_table(["scene", "frames/s at PSNR >= 40 dB, every frame (simulated, settings)",
                              "accumulated when still: time to 40 dB", "reference's own error (PSNR)",
                              "clients at which the 1 Gbit/s master link saturates (paper-era links, raw RGB8)"],
                             headline),
                   "", "The first column is per frame: every frame at 40 dB or better. The second is a different "
                   "figure: how long a still view takes to refine to 40 dB with `rtwall run`'s accumulation (only "
                   "where a scene path traces, so that frames differ). The reference's own error is estimated from "
                   "two independent halves of its frames where it path traces, else bounded by comparing it with the "
                   "same render at a quarter of its samples; PSNRs against it are trustworthy well below that figure.",
                   ""]


def docs_operating_point(rel, figs, trace):
    """The automatic operating point, and the controller trace on the real cluster."""
    md = ["## Automatic operating point", "",
           "`rtwall run CONFIG --target-fps N --front docs/speed-accuracy/front-SCENE.toml` starts at the most "
           "accurate front point whose frame time fits 1/N, then feeds every measured frame time to an "
           "`OperatingPointController` (rtwall/tune.h). It predicts each point's time as its front time times a "
           "running ratio of measured to front time (a heavier view, fewer clients or a throttled link raise the "
           "ratio for every point), steps to a faster point after 2 frames more than 5% over budget, to a more "
           "accurate one only after 10 frames in which it would fit with 10% headroom, and rests 5 frames after "
           "every change, so noise below (1 + 5%) / (1 - 10%) cannot make it flip. Without `--front` it calibrates "
           "codec x tile size (and two lower resolutions) on the first view. It sets codec and JPEG quality "
           "(`Master::setCodec`, from the next frame), tile size, resolution (frames written upscaled) and samples "
           "per pixel; a front naming any other control is refused with its name. The fronts above come from the "
           "simulated 8-client cluster, so on this 2-core PC the ratio settles far above 1 and the controller "
           "walks down the front to what two local clients can hold.", "",
           "The controller also set pruning threshold, GI samples and volume step when a front names them "
           "(`prune`, `gi_spp`, `volume_step`).", ""]
    md += ["### Holding the target on the real cluster: clients leave and join, the link is throttled", ""]
    if trace:
        md += [f"![controller trace]({rel(figs['trace'])})", "",
               f"`unshare -rn tools/controller_trace.sh build/tools/rtwall docs/speed-accuracy/front-demo.toml "
               f"{trace['target_fps']} OUT {trace['rate']}` (run by this script, {trace['phase_s']} s per phase): "
               "in a private network namespace, `rtwall run configs/run/demo.toml --target-fps "
               f"{trace['target_fps']} --front docs/speed-accuracy/front-demo.toml --trace` with external local "
               "clients (`rtwall client`, 1 thread each): two at the start, one killed with SIGKILL, two more "
               f"started, then the loopback link throttled to {trace['rate']} with tc's token-bucket filter (the "
               "kernel has no sch_netem; loopback's MTU set to 1500 in the namespace, since tbf drops every packet "
               "larger than its bucket and loopback's 64 KiB segments are: with the default MTU a throttled "
               "loopback carries almost nothing, which is why an earlier run at 4mbit held 0 frames) and the "
               "throttle removed. Above: each frame's rate (the master's frame time); below: the front index the "
               "controller chose and the connected clients. Other jobs on the PC make the frame rate noisy on its "
               "own.", "",
               f"The throttle is computed from the front's MB/frame: its {TRACE_FAST_POINTS} fastest points need at "
               f"most {100 * TRACE_FAST_SHARE:.0f}% of it at {trace['target_fps']} fps. Front points (fastest first) "
               "and whether they fit it: " + ", ".join(
                   f"{i}: {mb:.3f} MB ({'fits' if f else 'does not'})"
                   for i, (mb, f) in enumerate(zip(trace.get("front_mb_per_frame", []),
                                                   trace.get("front_fits_throttle", [])))) + ".", "",
               fmt_table(["phase", "frames", "frames until 5 in a row within budget", "within budget after the "
                          "first 10", "point changes", "point at the end"], trace_summary(trace)), "",
               "Run summary: " + " ".join(trace["summary"]), ""]
    else:
        md += ["(Not run: `--skip-validation`, or the run failed; see the log.)", ""]
    md += ["The same, deterministic, in the unit tests (`ControllerInSimulation` in "
           "tests/cluster/controller_simulation_test.cpp): the controller driven by the cluster simulation (the "
           "real `TileScheduler`), 4 clients, then 2, then 8, then the master's link throttled to 40 Mbit/s and "
           "restored; after every event the frame rate is back within the target in at most 12 frames (2 in that "
           "run) and stays there, the point moves one way only within a phase and is settled for the second half.",
           ""]
    return md


def docs_scaling(rel, figs, scaling_by_scene):
    """Simulated scaling to many clients, per scene and link."""
    md = ["## Scaling beyond this machine", "",
           f"![scaling]({rel(figs['scaling'])})", "",
           f"Simulated with the scene's tile profile at tile {SCALING_POINT['tile']}, "
           f"{SCALING_POINT['supersample']}x{SCALING_POINT['supersample']} samples per pixel, full resolution; each "
           "client has 2 threads at this PC's speed. Dashed: the link-bound ceiling (a frame's result bytes over the "
           "master's link, or over all client links together, whichever is lower). Dotted: rendering alone. The "
           "link is 'saturated' from the first client count where the master's link is 90% busy.", ""]
    for scene, by_link in scaling_by_scene.items():
        rows = []
        slowest = by_link["slowest_tile_s"]
        for label, by_codec in by_link.items():
            if label == "slowest_tile_s":
                continue
            for codec, res in by_codec.items():
                n = saturation(res)
                last = res[-1]
                rows.append([label, codec, f"{res[0]['bytes_per_frame'] / 1e6:.2f}",
                             " / ".join(f"{row['fps']:.1f}" for row in res), str(n) if n else "> 256",
                             f"{100 * last['master_link_load']:.0f}% / {100 * last['master_cpu_load']:.0f}% / "
                             f"{100 * last['mean_client_utilisation']:.0f}%"])
        md += [f"**{scene}**, frames/s at {', '.join(map(str, SCALING_CLIENTS))} clients (slowest tile "
               f"{slowest * 1e3:.0f} ms on one thread, so no frame can be faster than {1 / slowest:.0f} frames/s "
               "however many clients):", "",
               fmt_table(["links", "codec", "MB/frame", "frames/s", "link saturated at",
                          "at 256 clients: master link / master CPU / clients busy"], rows), ""]
    return md


def docs_validation(rel, figs, validation):
    """The cluster simulation against real runs on this PC (empty without validation)."""
    if not validation:
        return []
    dev = [v["simulated_fps"] / v["measured_fps"] - 1 for v in validation]
    within = sum(abs(d) <= 0.10 for d in dev)
    spread = max(max(x["measured_fps"] for x in v["runs"]) / min(x["measured_fps"] for x in v["runs"])
                 for v in validation)
    cal = validation[0]["calibration"]
    cal_runs = validation[0].get("calibration_runs", [])
    return ["## Validation: simulated against measured", "",
           f"![validation]({rel(figs['validation'])})", "",
           "`rtwall bench cluster --tile 64 --frames 8 --render --client-counts N` (1600x1200, 200,000-triangle "
           "knots, eye-light shading, local clients with 1 render thread each, loopback, LZ4, prefetch 4), run "
           f"{VALIDATION_REPEATS} times per client count, against `rtwall simulate` on a tile profile of the same "
           f"frame (per tile the median CPU time of {VALIDATION_REPEATS} recordings). The model: the clients' "
           "render threads, their network work, the master's I/O, network and decode threads "
           f"({VALIDATION_DECODE_THREADS} on this PC) and its per-frame work share the cores this job gets under "
           "processor sharing (`--host-cores`). Those cores are measured just before and after each run: the CPU "
           f"time {VALIDATION_CORES} busy processes started the same way obtain per second (other jobs run at "
           "other nice levels and in other autogroups, so counting their runnable threads says little). "
           f"Loopback latency {VALIDATION_LATENCY_MS} ms, not fitted. Tile costs are CPU time after an untimed "
           "warm-up pass, so a profile recorded on a busy PC is not inflated by other jobs.", "",
           "**Host costs besides rendering**, calibrated on another setting than the one validated: "
           f"`rtwall bench cluster --tile {CALIBRATION_TILE} --frames {CALIBRATION_FRAMES} --render --client-counts "
           f"{CALIBRATION_CLIENTS} --codec C` for C in {', '.join(CALIBRATION_CODECS)} (4x the results per frame "
           "of the validated 64-pixel tiles, a quarter of the bytes each). Its `cpu_per_frame` splits each "
           "process's CPU time (user + system, so the kernel's loopback TCP counts where it runs) by thread, from "
           "/proc/PID/task/TID/stat: the clients' render threads (rendering and LZ4 encoding, which the profile "
           "has) against the rest of the clients (network thread, ZeroMQ I/O thread), and the master's ZeroMQ "
           "I/O thread, network thread, decode threads and the rest. Results x a + bytes x b fitted to the two "
           "codecs' figures gives:", "",
           fmt_table(["cost", "measured", "rtwall simulate option"],
                     [[label, f"{cal[key]:.3g} {unit}", f"--{key.replace('_', '-')}"] for key, label, unit in [
                         ("client_us_per_result", "client, per result (network thread, ZeroMQ, TCP send)", "µs"),
                         ("client_ns_per_byte", "client, per result byte", "ns"),
                         ("master_us_per_result", "master's ZeroMQ I/O thread, per result (TCP receive)", "µs"),
                         ("master_ns_per_byte", "master's ZeroMQ I/O thread, per byte", "ns"),
                         ("master_us_per_message", "master's network thread, per message", "µs"),
                         ("master_ms_per_frame", "master, per frame (the caller's thread)", "ms"),
                         ("client_speed", "render threads' speed in the cluster against the profile's (one "
                          "thread alone; LZ4 run)", "x")]]), "",
           f"At {CALIBRATION_TILE}-pixel tiles that is about "
           f"{1e3 * sum(x['cpu_per_frame']['client_non_render_s'] + x['cpu_per_frame']['master_total_s'] for x in cal_runs) / len(cal_runs):.0f} ms "
           "of CPU per frame besides the render threads' "
           f"{1e3 * sum(x['cpu_per_frame']['client_render_s'] for x in cal_runs) / len(cal_runs):.0f} ms: "
           "cheap eye-light tiles cost about as much to ship over loopback as to render, which the model "
           "before this calibration (only 28 µs per message on the master) did not see.", "",
           f"**{within} of {len(dev)} client counts agree within 10%; median deviation "
           f"{100 * sorted(abs(d) for d in dev)[len(dev) // 2]:.0f}%, largest {100 * max(abs(d) for d in dev):.0f}%.** "
           f"The runs of one client count differ by up to {spread:.2f}x in frames/s.", "",
           fmt_table(["clients", "measured fps (runs)", "cores available (runs)", "simulated fps (runs)",
                      "deviation of medians", "simulated without host costs", "deviation without",
                      "simulated, idle PC", "simulated, one machine per client"],
                     [[v["clients"], f"{v['measured_fps']:.2f} (" + ", ".join(f"{x['measured_fps']:.2f}" for x in v["runs"]) + ")",
                       ", ".join(f"{x['available_cores']:g}" for x in v["runs"]),
                       f"{v['simulated_fps']:.2f} (" + ", ".join(f"{x['simulated_fps']:.2f}" for x in v["runs"]) + ")",
                       f"{100 * (v['simulated_fps'] / v['measured_fps'] - 1):+.0f}%",
                       f"{v['simulated_fps_without_host_costs']:.2f}",
                       f"{100 * (v['simulated_fps_without_host_costs'] / v['measured_fps'] - 1):+.0f}%",
                       f"{v['simulated_fps_idle_pc']:.2f}", f"{v['simulated_fps_no_sharing']:.2f}"]
                      for v in validation]), ""]


def docs_failures(rel, figs, text_rows, affinity, prefetch):
    """Where methods break down: JPEG on text, affinity under a fast camera, prefetch under latency spikes."""
    md = ["## Where methods break down", ""]
    md += ["### jpeg-text: JPEG on hard edges and text", "",
           "JPEG quantises 8x8 blocks of cosine frequencies; a rendered image is smooth almost everywhere, but text "
           "and one-pixel lines put their energy into the highest frequencies, which JPEG throws away first, and "
           "ringing appears beside every stroke. Same codec, same quality, 64-pixel tiles:", ""]
    rows = []
    for label, res in text_rows.items():
        for c in res["codecs"]:
            rows.append([label, c["codec"], f"{c['bits_per_pixel']:.2f}", psnr(c["error"]["psnr_db"]),
                         f"{c['error']['ssim']:.4f}", c["error"]["max_error"]])
    md += [fmt_table(["image", "codec", "bit/pixel", "PSNR dB", "SSIM", "largest error"], rows), ""]
    text = next(iter(text_rows.values()))["codecs"]
    by = {c["codec"]: c for c in text}
    if "zstd" in by and "jpeg:75" in by:
        md += [f"On text JPEG fails twice: at quality 75 it needs {by['jpeg:75']['bits_per_pixel']:.2f} bit/pixel, "
               f"{by['jpeg:75']['bits_per_pixel'] / by['zstd']['bits_per_pixel']:.1f}x what lossless zstd needs "
               f"({by['zstd']['bits_per_pixel']:.2f}), and still leaves errors of up to "
               f"{by['jpeg:75']['error']['max_error']} levels beside the strokes. PSNR hides this (the white page "
               "dominates the mean); the largest error and the difference image show it. For text, drawings and "
               "user interfaces on the wall, use a lossless codec.", ""]
    if "text_diff" in figs:
        md += [f"![jpeg q75 on text: false-colour difference, red = 32 levels]({rel(figs['text_diff'])})", ""]
    md += ["### affinity-fast-camera: tile affinity when the camera moves fast", "",
           "Affinity gives each client last frame's tiles first. When the camera orbits quickly, the expensive tiles "
           "move across the screen, the queues no longer match the work, and clients steal from each other at the "
           "end of the frame. Simulated: 8 clients x 1 thread, the knot scene at 800x600 with 32-pixel tiles, "
           "per-tile render times recorded along the orbit, links unlimited. The simulation does not model what "
           "affinity is for (warm caches of a client's part of the scene), so it shows only its cost. " +
           affinity_summary(affinity), "",
           fmt_table(["degrees per frame", "affinity", "frames/s", "stolen tiles per frame", "tiles kept their client",
                      "client utilisation"],
                     [[a["degrees_per_frame"], "on" if a["affinity"] else "off", f"{a['fps']:.2f}",
                       f"{a['stolen_per_frame']:.1f}", f"{100 * a['affinity_hit_fraction']:.0f}%",
                       f"{100 * a['utilisation']:.0f}%"] for a in affinity]), ""]
    md += ["### prefetch-latency-spikes: prefetch when latency spikes", "",
           "Prefetch hides the round trip by keeping several tiles in flight per client. A latency spike on one "
           "link delays every message behind it (TCP keeps order), so the deeper the prefetch, the more tiles wait "
           "behind one spike; tiles are re-issued to other clients only after they count as stragglers (4 median "
           "latencies). Simulated: knot scene, 8 clients x 2 threads, 1 Gbit/s links, 0.1 ms base latency. " +
           prefetch_summary(prefetch), "",
           fmt_table(["spike probability per message", "spike ms", "prefetch", "frames/s", "re-issued tiles per frame"],
                     [[p["spike_probability"], p["spike_ms"], p["prefetch"], f"{p['fps']:.1f}",
                       f"{p['reissued_per_frame']:.1f}"] for p in prefetch]), ""]
    return md


# The page's section on `rtwall bench denoise` (the denoiser on moving and still views of the GI
# scenes, measured on this PC's threads, not by the sweep) is written by hand from that bench's
# runs; a regeneration keeps it as it is.
DENOISE_BEGIN = "<!-- denoise bench: begin (rtwall bench denoise; kept as it is by tools/speed_accuracy.py) -->"
DENOISE_END = "<!-- denoise bench: end -->"


def kept_section(path, begin, end):
    """The block between the markers of the page as it is (with them), or nothing."""
    text = path.read_text() if path.exists() else ""
    if begin not in text or end not in text:
        return []
    return [begin + text.split(begin, 1)[1].split(end, 1)[0] + end, ""]


def write_docs(path, figs, points_by_scene, scaling_by_scene, text_rows, affinity, prefetch, validation, elapsed, args,
               trace=None, refs=None, accs=None, tess=None):
    refs, accs = refs or {}, accs or {}
    kept = kept_section(path, DENOISE_BEGIN, DENOISE_END)
    rel = lambda p: os.path.relpath(p, path.parent)
    md = docs_intro(elapsed, args)
    scenes, headline = docs_scenes(rel, figs, points_by_scene, scaling_by_scene, refs, accs)
    # The headline goes after the title and the line on how the page was made, in place of the
    # intro's own heading (md[4:6]): the figures' description follows it without a heading.
    md = md[:4] + docs_headline(headline) + md[6:] + scenes
    if tess:
        md += tessellation_section(path, figs["tessellation"], tess)
    md += kept
    md += docs_operating_point(rel, figs, trace)
    md += docs_scaling(rel, figs, scaling_by_scene)
    md += docs_validation(rel, figs, validation)
    md += docs_failures(rel, figs, text_rows, affinity, prefetch)
    md += shading_failures(points_by_scene)
    path.write_text("\n".join(md))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=str(ROOT / "build"))
    ap.add_argument("--work", default=str(ROOT / "out" / "speed"))
    ap.add_argument("--docs", default=str(ROOT / "docs"))
    ap.add_argument("--quick", action="store_true", help="one setting per control (a smoke test of the pipeline)")
    ap.add_argument("--skip-validation", action="store_true", help="no real cluster runs")
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the sweep, scaling and failure results of an earlier run in --work; validation runs "
                         "again unless --skip-validation (then its earlier results are reused too)")
    ap.add_argument("--prior-s", type=float, default=0,
                    help="with --reuse after a run that stopped after its sweep: the seconds that run took (the "
                         "page then reports their sum as the regeneration time)")
    ap.add_argument("--only", choices=["tessellation"],
                    help="run this step alone and rewrite only its section of the page (and its chart)")
    args = ap.parse_args()
    args.start_load = os.getloadavg()[0]  # how busy the PC was: the page says so
    t0 = time.time()
    r = Runner(args.build, args.work, args.quick)
    docs = Path(args.docs)
    figdir = docs / "speed-accuracy"
    figdir.mkdir(parents=True, exist_ok=True)
    if args.only == "tessellation":
        tess = tessellation(r)
        page = docs / "speed-accuracy.md"
        update_tessellation_section(page, tessellation_section(page, tessellation_chart(figdir, tess), tess))
        log(f"wrote the tessellation section of {page} in {(time.time() - t0) / 60:.1f} min")
        return
    load_controls(r)

    points_by_scene, scaling_by_scene = {}, {}
    if args.reuse:
        for scene in SCENES:
            points_by_scene[scene.name] = json.loads((r.raw / f"sweep-{scene.name}.json").read_text())
            if scene.scaling:
                scaling_by_scene[scene.name] = json.loads((r.raw / f"scaling-{scene.name}.json").read_text())
    if args.reuse and not (r.raw / "failures.json").exists():
        # An earlier run stopped after the sweep: measure the rest now.
        text_rows, affinity, prefetch, validation, diff_dir = measure_rest(r, args, t0)
    elif args.reuse:
        f = json.loads((r.raw / "failures.json").read_text())
        text_rows, affinity, prefetch = f["jpeg_text"], f["affinity"], f["prefetch"]
        diff_dir = r.raw / "text-codecs"
        if args.skip_validation:
            validation = json.loads((r.raw / "validation.json").read_text())
        else:
            validation = validate(r)
            (r.raw / "validation.json").write_text(json.dumps(validation, indent=1))
    for scene in SCENES if not args.reuse else []:
        generate(r, scene)
        ref = reference(r, scene)
        points = sweep(r, scene, ref)
        points_by_scene[scene.name] = points
        (r.raw / f"sweep-{scene.name}.json").write_text(json.dumps(points, indent=1))
        (r.raw / f"reference-{scene.name}.json").write_text(json.dumps(reference_info(r, scene), indent=1))
        (r.raw / f"accumulate-{scene.name}.json").write_text(json.dumps(accumulation(r, scene, ref, points), indent=1))
        write_front(points, figdir / f"front-{scene.name}.toml")
        if scene.scaling:
            scaling_by_scene[scene.name] = scaling(r, scene, ref)
            (r.raw / f"scaling-{scene.name}.json").write_text(json.dumps(scaling_by_scene[scene.name], indent=1))
        log(f"{scene.name}: done ({(time.time() - t0) / 60:.1f} min)")
    if not args.reuse:
        text_rows, affinity, prefetch, validation, diff_dir = measure_rest(r, args, t0)
    figs = charts(figdir, points_by_scene, scaling_by_scene, affinity, prefetch, validation)
    tess_file = r.raw / "tessellation.json"
    tess = json.loads(tess_file.read_text()) if args.reuse and tess_file.exists() else tessellation(r)
    figs["tessellation"] = tessellation_chart(figdir, tess)
    trace_file = r.raw / "controller-trace.json"
    if args.skip_validation:
        trace = json.loads(trace_file.read_text()) if args.reuse and trace_file.exists() else None
    else:
        trace = controller_trace(r, figdir / "front-demo.toml", points_by_scene["demo"])
        trace_file.write_text(json.dumps(trace, indent=1))
    if trace:
        figs["trace"] = trace_chart(figdir, trace)
    # A crop of the text's false-colour difference at JPEG q75, committed beside the charts.
    from PIL import Image as PILImage  # matplotlib depends on Pillow
    crop = PILImage.open(diff_dir / "jpeg_75_diff.png").crop((0, 0, 560, 200))
    figs["text_diff"] = figdir / "jpeg-text-diff.png"
    crop.save(figs["text_diff"])
    timing = r.raw / "timing.json"
    if args.prior_s > 0:
        elapsed = args.prior_s + time.time() - t0
        timing.write_text(json.dumps({"from_scratch_s": elapsed, "prior_s": args.prior_s}))
    elif args.reuse and timing.exists():
        elapsed = json.loads(timing.read_text())["from_scratch_s"]
        args.prior_s = json.loads(timing.read_text()).get("prior_s", 0)  # for the page's note only
    else:
        elapsed = time.time() - t0
        timing.write_text(json.dumps({"from_scratch_s": elapsed}))
    load = lambda kind: {sc.name: json.loads((r.raw / f"{kind}-{sc.name}.json").read_text()) for sc in SCENES
                         if (r.raw / f"{kind}-{sc.name}.json").exists()}
    accs = {k: v for k, v in load("accumulate").items() if v}
    write_docs(docs / "speed-accuracy.md", figs, points_by_scene, scaling_by_scene, text_rows, affinity, prefetch,
               validation, elapsed, args, trace, refs=load("reference"), accs=accs, tess=tess)
    log(f"wrote {docs / 'speed-accuracy.md'} and {len(figs)} figures in {(time.time() - t0) / 60:.1f} min")


def measure_rest(r, args, t0):
    text_rows, text_png, diff_dir = failure_jpeg_text(r)
    knots = SCENES[0]
    knots_png = r.raw / "knots-frame.png"
    r.run("bench", "tiles", knots.source, "--width", 800, "--height", 600, "--codecs", "lz4", "--save-image", knots_png,
          "--json", *knots.extra)
    text_rows["rendered knots (800x600)"] = r.run("bench", "codecs", knots_png, "--tile", 64, "--json")
    affinity = failure_affinity(r, knots)
    prefetch = failure_prefetch(r, knots)
    (r.raw / "failures.json").write_text(json.dumps({"jpeg_text": text_rows, "affinity": affinity,
                                                     "prefetch": prefetch}, indent=1))
    log(f"failure cases done ({(time.time() - t0) / 60:.1f} min)")
    validation = [] if args.skip_validation else validate(r)
    (r.raw / "validation.json").write_text(json.dumps(validation, indent=1))
    return text_rows, affinity, prefetch, validation, diff_dir


if __name__ == "__main__":
    main()
