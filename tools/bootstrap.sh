#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine:
#   tools/bootstrap.sh demo [NAME [gen options]]   install what is missing, build, run the master with
#             local clients (NAME: office, headlight, sunflowers, powerplant or step-assembly,
#             generated first; step-assembly: a STEP assembly in configs/demos/step_assembly.toml)
#   tools/bootstrap.sh test   install what is missing, build, run the whole test suite
#   tools/bootstrap.sh deps   only install what is missing
#   tools/bootstrap.sh build  install and build
# Idempotent; works as root or through sudo; says what it does.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
BUILD_DIR=${RTWALL_BUILD_DIR:-build}
JOBS=${RTWALL_JOBS:-$(nproc)}

# Debian packages, found by CMake's find_package.
PACKAGES=(
  cmake ninja-build g++ pkg-config
  libembree-dev        # Embree 3: BVH build and packet traversal
  libopenmesh-dev      # OpenMesh 9: OBJ/OFF/PLY/STL/OM parsers
  libvtk9-dev          # VTK 9: .vtk/.vtp/.vtu/.wrl importers and volume data sets (.vti, legacy .vtk)
  libtomlplusplus-dev  # toml++: scene and wall configs, JSON output
  libcli11-dev         # CLI11: command-line parsing
  libpng-dev           # libpng: PNG images
  libzip-dev           # libzip: MPCDI calibration archives (.mpcdi is a zip)
  zipcmp zipmerge ziptool  # libzip-dev's CMake config names these tools (configure fails without them)
  libpugixml-dev       # pugixml: MPCDI's mpcdi.xml
  libgtest-dev libgmock-dev  # GoogleTest
  libbenchmark-dev     # Google Benchmark
  libzmq3-dev cppzmq-dev  # ZeroMQ: master/client transport
  liblz4-dev libzstd-dev libturbojpeg0-dev  # tile codecs
  libxxhash-dev        # content hashes of meshes and scene states
  clang libclang-rt-14-dev  # libFuzzer with ASan/UBSan for the fuzz targets
  libasio-dev          # standalone Asio (header-only): the tracker's UDP receiver (DTrack)
  libglfw3-dev libgl-dev  # GLFW and OpenGL 3.3: the wall's windows and input
  glslang-dev          # glslang: every wall shader is compiled at `rtwall check` and in the tests
  glslang-tools        # glslangValidator: glslang-dev's CMake targets reference it, but it only Suggests it
  xvfb xauth libgl1-mesa-dri  # gui tests and bench display: Xvfb with Mesa's software OpenGL (llvmpipe)
  iproute2             # ip netns/veth and tc: the fault tests' and tools/netem.sh's own namespaces and links
  nftables             # nft: packet loss in the fault tests' own namespaces (no sch_netem here)
  iptables libnetfilter-queue-dev  # NFQUEUE: netjitter's delay, jitter and reordering in those namespaces
  python3
  python3-matplotlib   # charts of tools/speed_accuracy.py (speed against accuracy)
  libtinygltf-dev      # tinygltf 2.7: glTF 2.0 (.gltf/.glb) parser, the Debian shared library (no implementation TU of ours)
  libcpp-httplib-dev   # cpp-httplib 0.11: the operator console's HTTP/HTTPS server (rtwall run --web), Debian's OpenSSL build
  nlohmann-json3-dev   # nlohmann/json: the console API's request bodies
  chromium chromium-driver python3-selenium  # the console's browser tests: a real headless browser driven by Selenium
  libocct-data-exchange-dev libocct-ocaf-dev libocct-modeling-algorithms-dev  # OpenCASCADE 7.6: STEP/IGES assemblies (XDE), tessellation
)

say() { printf '[bootstrap] %s\n' "$*"; }

install_missing() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    say "all ${#PACKAGES[@]} packages are installed"
    return
  fi
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "bootstrap: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo=(sudo)
  fi
  say "installing: ${missing[*]}"
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
}

build() {
  say "configuring ${BUILD_DIR} (Ninja, RelWithDebInfo)"
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
  say "building with ${JOBS} jobs"
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

case "${1:-}" in
  deps) install_missing ;;
  build) install_missing; build ;;
  demo)
    install_missing; build
    if [ -z "${2:-}" ]; then
      say "running the master with two local render clients on the built-in scene, on the reference wall"
      say "(2x2 projectors, 1600x1200; calibrates, then holds the frame rate: rtwall run)"
      "$BUILD_DIR/tools/rtwall" run --frames 60 --write-every 30 --out out/frames
      say "frames (and, headless, each projector's image of them) are in $(pwd)/out/frames/"
    else
      # A named demo scene: generated (rtwall gen NAME, extra arguments passed on), then run on
      # the cluster path like the default.
      name=$2; shift 2
      dir=$(pwd)/out/$name
      gen=$name
      scene=
      # Demos with a scene file shipped in configs/demos/: the generator writes what it references.
      case $name in
        step-assembly) gen=step; scene=$(pwd)/configs/demos/step_assembly.toml; set -- --instances 700 "$@" ;;
      esac
      say "generating the '$name' scene into $dir (rtwall gen $gen $*)"
      "$BUILD_DIR/tools/rtwall" gen "$gen" --out "$dir" "$@"
      if [ -z "$scene" ]; then
        scene=$dir/scene.toml
        [ -f "$scene" ] || scene=$dir/$name.toml
      fi
      printf 'scene = "%s"\n[image]\nwidth = 800\nheight = 600\n[cluster]\nclients = 2\n[run]\nframes = 10\nwrite_every = 5\nout = "%s/frames"\n' \
        "$scene" "$dir" > "$dir/run.toml"
      say "running the master with two local render clients on $scene (rtwall run $dir/run.toml)"
      "$BUILD_DIR/tools/rtwall" run "$dir/run.toml"
      say "frames are in $dir/frames/"
    fi
    ;;
  test)
    install_missing; build
    # Fuzz targets need clang's libFuzzer: a second, small build of just those, each run briefly.
    say "fuzzing every decoder briefly (clang, libFuzzer, ASan+UBSan)"
    cmake -S . -B "$BUILD_DIR-fuzz" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
      -DRTWALL_FUZZ=ON -DRTWALL_BUILD_BENCHMARKS=OFF >/dev/null
    cmake --build "$BUILD_DIR-fuzz" -j "$JOBS" --target fuzz_targets  # every fuzz_* target (tests/fuzz)
    # A finding is written to tests/fuzz/crashes/CORPUS/ (git shows it); the committed ones there
    # run as the *_regressions tests.
    ctest --test-dir "$BUILD_DIR-fuzz" -L fuzz --output-on-failure --timeout 600
    say "running the test suite"
    ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" --timeout 900
    ;;
  *)
    echo "usage: tools/bootstrap.sh demo|test|deps|build" >&2
    exit 2
    ;;
esac
