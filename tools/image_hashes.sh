#!/usr/bin/env bash
# The SHA-256 of every image a fixed set of headless runs writes: the demo scenes (rtwall render,
# single machine and over local clients), the reference wall, a CAVE, passive stereo, a projector
# pair with blending, bezel-corrected monitors and the two-node wall. A refactor of the display
# side must leave every line of this list unchanged (rendering is deterministic by design).
#
#   tools/image_hashes.sh [BUILD_DIR] > hashes.txt     # then diff against an earlier list
#
# Each line is "SHA256  CASE/FILE", sorted. Runs are small (a few frames at the configs' sizes) so
# the whole list takes a few minutes on 2 cores.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
BUILD=${1:-build}
RTWALL=$(realpath "$BUILD/tools/rtwall")
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
log() { printf '[image_hashes] %s\n' "$*" >&2; }

# Single-machine renders of the demo scenes, and the same scene over two local clients.
gen_and_render() {  # NAME GENERATOR [gen args...]
  local name=$1 gen=$2; shift 2
  "$RTWALL" gen "$gen" --out "$WORK/scenes/$name" "$@" >/dev/null
  local scene=$WORK/scenes/$name/scene.toml
  [ -f "$scene" ] || scene=$WORK/scenes/$name/$name.toml
  mkdir -p "$WORK/img/$name"
  "$RTWALL" render "$scene" --width 320 --height 240 --out "$WORK/img/$name/render.png" >/dev/null
  "$RTWALL" render "$scene" --width 320 --height 240 --clients 2 --out "$WORK/img/$name/clients.png" >/dev/null
}
log "demo scenes"
mkdir -p "$WORK/img/demo"
"$RTWALL" render configs/demo.toml --width 320 --height 240 --out "$WORK/img/demo/render.png" >/dev/null
"$RTWALL" render configs/demo.toml --width 320 --height 240 --clients 2 --out "$WORK/img/demo/clients.png" >/dev/null
"$RTWALL" render configs/demo.toml --width 160 --height 120 --gi --samples 2 --frames 3 --out "$WORK/img/demo/gi3.png" >/dev/null
gen_and_render office office
gen_and_render headlight headlight
gen_and_render sunflowers sunflowers --instances 200 --triangles 2000 --trees 1 --tree-triangles 20000
gen_and_render powerplant powerplant --triangles 200000
"$RTWALL" gen step --instances 70 --out "$WORK/scenes/step" >/dev/null
mkdir -p "$WORK/img/step"
sed "s#\\.\\./\\.\\./out/step-assembly#$WORK/scenes/step#g" configs/demos/step_assembly.toml > "$WORK/scenes/step/demo.toml"
"$RTWALL" render "$WORK/scenes/step/demo.toml" --width 320 --height 240 --out "$WORK/img/step/render.png" >/dev/null

# Wall runs: the master with local clients, headless, every frame's screens written.
wall_run() {  # CASE WALL [run args...]
  local name=$1 wall=$2; shift 2
  log "wall $name"
  "$RTWALL" run configs/run/demo.toml --wall "$wall" --headless --frames 3 --write-every 1 \
    --out "$WORK/img/$name" "$@" >/dev/null 2>"$WORK/$name.err" || { log "$name failed: $(tail -1 "$WORK/$name.err")"; return 1; }
}
wall_run wall-2x2 configs/wall/projectors-2x2.toml
# The CAVE is tracked, so it re-projects by default; with async and the orbit a refresh shows the
# frame for the newest camera, and how many refreshes a frame gets is timing: pinned off here.
wall_run cave configs/wall/cave-3.toml --reproject off
wall_run stereo-passive configs/wall/stereo-passive.toml
wall_run blend configs/wall/projector-pair-blend.toml
wall_run bezels configs/wall/monitors-3x2-bezels.toml
wall_run two-nodes configs/wall/two-nodes-2x2.toml
log "plain run (no wall)"
"$RTWALL" run configs/run/demo.toml --headless --frames 3 --write-every 1 --out "$WORK/img/run" >/dev/null 2>&1

cd "$WORK/img"
find . -type f -name '*.png' -printf '%P\n' | LC_ALL=C sort | xargs -d '\n' sha256sum
