#!/usr/bin/env bash
# Installs every build and test dependency from Debian packages, fetches the test corpus, and builds
# the release preset. Idempotent, and quiet when everything is already in place.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

packages=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  clang-14 libclang-rt-14-dev           # the fuzz preset (libFuzzer)
  libfmt-dev nlohmann-json3-dev libcli11-dev libtinygltf-dev libstb-dev
  libeigen3-dev libtbb-dev zlib1g-dev
  libmeshoptimizer-dev libdraco-dev      # compressed glTF input (EXT_meshopt_compression, KHR_draco_mesh_compression)
  gltfpack draco                         # the tests' independent producers of such files
  libgtest-dev libgmock-dev libbenchmark-dev
  libassimp-dev                          # bench/io: the peer loader
  libcgal-dev libopenmesh-dev            # bench/peers: the simplifiers we measure against
  gnuplot-nox                            # bench plots (rate-distortion)
  nodejs                                 # gltf-validator (Khronos) in the tests; npm ships with it
  time                                   # /usr/bin/time -v for peak memory in benchmarks
  # lodkit render: headless EGL + OpenGL 4.5 on Mesa's llvmpipe, the libepoxy GL loader (it dlopens
  # libGL.so.1 for the GL entry points), FreeType and DejaVu for labels
  libegl-dev libegl-mesa0 libgl1-mesa-dri libgl1 libepoxy-dev libfreetype-dev fonts-dejavu-core
)
# Debian's nodejs comes without npm (NodeSource's bundles it): ask for Debian's npm only when absent.
command -v npm >/dev/null || packages+=(npm)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq >/dev/null
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/tmp/lodkit-apt.log 2>&1 ||
    { cat /tmp/lodkit-apt.log >&2; exit 1; }
fi

scripts/fetch-corpus.sh

# The glTF tests' Node.js tools (npm registry), each at its lockfile's versions; skipped quietly
# when npm is absent (the tests that need them then skip): Khronos' glTF validator, and a second
# glTF reader (glTF-Transform with Google's draco3dgltf and meshoptimizer's decoders, and two viewers'
# loaders: three.js's GLTFLoader and Babylon.js's). Again when the lockfile is newer than the installed tree.
for tool in gltf-validator gltf-loader; do
  installed="tests/$tool/node_modules/.package-lock.json"
  if command -v npm >/dev/null && { [ ! -f "$installed" ] || [ "tests/$tool/package-lock.json" -nt "$installed" ]; }; then
    echo "setup: installing $tool (npm)"
    npm ci --prefix "tests/$tool" --silent --no-audit --no-fund >/dev/null
  fi
done

# LODKIT_SETUP_BENCH=0 (CI) leaves the peer benchmarks out of a new build: CGAL makes them the
# slowest part to compile, and no test needs them.
configure=(--preset release)
[ "${LODKIT_SETUP_BENCH:-1}" = 0 ] && configure+=(-DLODKIT_BUILD_BENCH=OFF)
if [ ! -f build/release/build.ninja ]; then
  cmake "${configure[@]}" >/tmp/lodkit-configure.log 2>&1 || { cat /tmp/lodkit-configure.log >&2; exit 1; }
fi
# Quiet when nothing is to be done; the full log on failure.
if ! cmake --build --preset release >/tmp/lodkit-build.log 2>&1; then
  cat /tmp/lodkit-build.log >&2
  exit 1
fi
grep -q "no work to do" /tmp/lodkit-build.log || echo "setup: built build/release"
