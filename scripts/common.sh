# Shared by the README's commands: install what is missing (Debian 12), configure and build.
# Idempotent: installs nothing that is present, and the build is incremental.
set -euo pipefail

PEAKCAST_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${PEAKCAST_BUILD_DIR:-$PEAKCAST_ROOT/build}

# What compiling peakcast needs (Debian 12 names); the container's build stage installs just these.
PEAKCAST_BUILD_PACKAGES=(
  build-essential cmake pkg-config ccache
  libgtest-dev libgmock-dev
  libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev
  libopenimageio-dev libturbojpeg0-dev libboost1.74-dev
  nlohmann-json3-dev libglm-dev libcli11-dev libspdlog-dev zlib1g-dev libhwy-dev
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libblosc-dev libzstd-dev libbz2-dev
  libgdcm-dev libzip-dev
)
# What the built server needs at run time and nothing more: the container's runtime stage
# (docker/Dockerfile). The container test checks the binary finds every library in that image.
PEAKCAST_RUNTIME_PACKAGES=(
  libepoxy0 libegl1 libopengl0 libegl-mesa0 libgl1-mesa-dri libopenimageio2.4 libturbojpeg0
  libspdlog1.10 libfmt9 zlib1g libhwy1
  libavcodec59 libavformat59 libavutil57 libswscale6 libblosc1 libzstd1 libbz2-1.0 libgdcm3.0 libzip4
)
# The README's commands: building plus the scripts' own tools.
PEAKCAST_PACKAGES=("${PEAKCAST_BUILD_PACKAGES[@]}" git python3 python3-jsonschema python3-websockets python3-pil)
# Only the test command needs these (browser tests: Debian's chromium + playwright-core;
# clang-format: the unit label's format check; the container label: buildah and debootstrap;
# manifests: python3-yaml; the mpi label: OpenMPI and IceT from ParaView's packages;
# python3-zarr reads and writes the OME-Zarr the tests check; python3-dask: a dask array the
# client's chunked upload sends; python3-pydicom writes the DICOM
# series the tests read, libgdcm-tools' gdcmconv compresses them to JPEG, JPEG-LS and JPEG 2000).
PEAKCAST_TEST_PACKAGES=(chromium nodejs python3-vtk9 xvfb xauth clang clang-format libclang-rt-14-dev
  buildah debootstrap python3-yaml python3-pytest python3-numpy python3-venv python3-zarr python3-dask python3-pydicom libgdcm-tools
  libopenmpi-dev openmpi-bin paraview-dev)
# paraview-dev brings IceT (the mpi label). --no-install-recommends matters for it: with
# recommends it pulls python3-paraview, which removes python3-vtk9.

install_packages() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [[ ${#missing[@]} -eq 0 ]] && return 0
  local sudo=()
  if [[ $(id -u) -ne 0 ]]; then
    if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
      sudo=(sudo)
    else
      echo "peakcast: these Debian packages are missing: ${missing[*]}" >&2
      echo "peakcast: run as root, or install them: sudo apt-get install ${missing[*]}" >&2
      exit 1
    fi
  fi
  echo "peakcast: installing ${missing[*]}"
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# Node tools for the browser tests: Debian's node may be missing; npm packages from the registry.
install_node_modules() {
  # Debian's nodejs ships npm separately; some images' nodejs brings its own (and conflicts with it).
  command -v npm >/dev/null || install_packages npm
  if [[ ! -d $PEAKCAST_ROOT/tests/browser/node_modules/playwright-core || ! -d $PEAKCAST_ROOT/tests/browser/node_modules/axe-core ]]; then
    (cd "$PEAKCAST_ROOT/tests/browser" && npm install --no-audit --no-fund --silent)
  fi
}

# ccache when present: rebuilds on the same machine (CI after a session, sanitizer and fuzz build
# directories sharing sources, a second checkout of the same commit) reuse objects. The settings
# are exported when this file is sourced, so the builds see them (an export inside $(...) is lost).
# CCACHE_NOHASHDIR: debug builds (-g) would otherwise hash the build folder into every key.
# CCACHE_COMPILERCHECK=content: the container's build stage (docker/build-image.sh lends it this
# cache) has the same Debian compiler with another mtime, which the default check would count.
# Exported whether or not ccache is there yet: the install step may bring it later.
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PEAKCAST_ROOT} CCACHE_NOHASHDIR=1 CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache} \
  CCACHE_MAXSIZE=${CCACHE_MAXSIZE:-10G} CCACHE_COMPILERCHECK=${CCACHE_COMPILERCHECK:-content}
peakcast_ccache_flags() {
  if command -v ccache >/dev/null; then
    echo "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache"
  fi
}

# build_peakcast TYPE [DIR [extra cmake args...]]: configure once, then build incrementally;
# PEAKCAST_TARGETS (e.g. "peakcast_label_unit peakcast_label_net") limits what is built.
build_peakcast() {
  local type=${1:-Release} dir=${2:-$BUILD_DIR}
  shift 2 || shift $#
  if [[ ! -f $dir/CMakeCache.txt ]]; then
    cmake -S "$PEAKCAST_ROOT" -B "$dir" -DCMAKE_BUILD_TYPE="$type" $(peakcast_ccache_flags) "$@"
  fi
  local targets=()
  for t in ${PEAKCAST_TARGETS:-}; do targets+=(--target "$t"); done
  # ccache keys hold the locale (it changes the compiler's messages): one locale for every build,
  # so that the container's build stage (no LANG) finds what the host's build cached.
  LANG=C.UTF-8 LC_ALL=C.UTF-8 LC_CTYPE=C.UTF-8 LC_MESSAGES=C.UTF-8 cmake --build "$dir" -j"$(nproc)" "${targets[@]}"
}
