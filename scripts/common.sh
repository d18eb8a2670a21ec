# Shared by the README's commands: install what is missing (Debian 12), configure and build.
# Idempotent: installs nothing that is present, and the build is incremental.
set -euo pipefail

PEAKCAST_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${PEAKCAST_BUILD_DIR:-$PEAKCAST_ROOT/build}

# Build and run-time packages (Debian 12 names).
PEAKCAST_PACKAGES=(
  build-essential cmake pkg-config git
  libgtest-dev libgmock-dev
  libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev
  libopenimageio-dev libturbojpeg0-dev libboost1.74-dev
  nlohmann-json3-dev libglm-dev libcli11-dev libspdlog-dev zlib1g-dev
  python3 python3-jsonschema python3-websockets python3-pil
)
# Only the test command needs these (browser tests: Debian's chromium + playwright-core).
PEAKCAST_TEST_PACKAGES=(chromium nodejs python3-vtk9 xvfb xauth)

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
  if [[ ! -d $PEAKCAST_ROOT/tests/browser/node_modules/playwright-core ]]; then
    (cd "$PEAKCAST_ROOT/tests/browser" && npm install --no-audit --no-fund --silent)
  fi
}

build_peakcast() {
  local type=${1:-Release}
  if [[ ! -f $BUILD_DIR/CMakeCache.txt ]]; then
    cmake -S "$PEAKCAST_ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$type"
  fi
  cmake --build "$BUILD_DIR" -j"$(nproc)"
}
