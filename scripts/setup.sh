#!/usr/bin/env bash
# One-command set-up on a fresh Debian 12 machine (run as root, or with sudo available):
#   scripts/setup.sh run    install what is missing, build, run the main job on the sample in data/
#   scripts/setup.sh test   install what is missing, build, run the tests
# Idempotent: installed packages and an existing build are reused.
set -euo pipefail

mode="${1:-run}"
case "$mode" in run | test) ;; *) echo "usage: $0 run|test" >&2; exit 2 ;; esac
cd "$(dirname "$0")/.."

# Debian packages the build needs (see README.md, "Dependencies", for why each is there).
packages=(
  build-essential cmake ccache pkg-config
  libgdal-dev gdal-bin
  libcgal-dev libeigen3-dev libgmp-dev libmpfr-dev libboost-dev
  libopencv-core-dev libopencv-imgproc-dev
  libglpk-dev coinor-libcbc-dev
  libtomlplusplus-dev nlohmann-json3-dev libproj-dev
  libjemalloc-dev
  libgtest-dev
)

# The tests validate CityJSON output with ajv-cli from the npm registry: they need node and npm.
if [ "$mode" = test ] && ! command -v npm >/dev/null 2>&1; then packages+=(nodejs npm); fi
# The tests also run every fuzz harness briefly: clang 14 with libFuzzer and the sanitizer runtimes.
if [ "$mode" = test ]; then packages+=(clang libclang-rt-14-dev); fi
# The tests render report.html in headless Chromium (a screenshot, no console errors).
if [ "$mode" = test ]; then packages+=(chromium); fi
# The Slurm test starts a private single-node cluster (../shared/SLURM.md): the daemons and clients only.
if [ "$mode" = test ]; then packages+=(slurmctld slurmd slurm-client); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j "$jobs"

if [ "$mode" = run ]; then
  # The main job: every footprint of the sample block (two AHN3 tiles, NAP heights) reconstructed into
  # city3d_out/, with the GeoPackage and 3D Tiles a 3DBAG user loads.
  set -x
  ./build/city3d reconstruct data/delft_sample_1.las data/delft_sample_2.las \
    --footprints data/delft_sample_footprints.gpkg --id-field gml_id --crs EPSG:7415 --gpkg --3dtiles \
    -j "$jobs" --output city3d_out
  head -n 5 city3d_out/report.csv
else
  if [ ! -x build/tools/node_modules/.bin/ajv ] || [ ! -f build/tools/node_modules/gltf-validator/package.json ]; then
    echo "setup: installing ajv-cli (CityJSON schemas) and gltf-validator (the 3D Tiles' glTF) into build/tools"
    npm install --prefix build/tools --no-audit --no-fund --silent ajv-cli@5.0.0 ajv-formats@2.1.1 \
      gltf-validator@2.0.0-dev.3.10
  fi
  # CesiumJS draws the tileset in the tests: only its prebuilt Build/Cesium, from the package's
  # tarball (npm pack: no dependencies, no install scripts), unpacked into build/tools/cesium.
  if [ ! -f build/tools/cesium/Cesium.js ]; then
    echo "setup: unpacking CesiumJS (npm cesium 1.145.0, 23 MB) into build/tools/cesium"
    tmp="$(mktemp -d)"
    (cd "$tmp" && npm pack --silent cesium@1.145.0 > /dev/null)
    mkdir -p build/tools/cesium
    tar -xzf "$tmp"/cesium-1.145.0.tgz -C build/tools/cesium --strip-components=3 package/Build/Cesium
    rm -rf "$tmp"
  fi
  ctest --test-dir build --output-on-failure -j "$jobs"
  # A short run of every fuzz harness (fuzz/README.md; bench/fuzz.sh runs them for an hour).
  fuzz/run.sh 15 "$jobs"
fi
