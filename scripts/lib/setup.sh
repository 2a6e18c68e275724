# Shared set-up for scripts/test, scripts/demo and scripts/bench: installs any missing Debian
# packages (non-interactive, idempotent, quiet when all are present) and configures + builds.
# Source it; it defines gesweep_install_deps and gesweep_build.

GESWEEP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"

# Debian packages the build, the tests and the scripts need. Keep in step with docs/dependencies.md.
GESWEEP_PACKAGES=(
  build-essential cmake ninja-build pkg-config git ccache
  libeigen3-dev libboost-dev libboost-math-dev libhdf5-dev hdf5-tools libtbb-dev
  libtomlplusplus-dev nlohmann-json3-dev libcli11-dev libgtest-dev libbenchmark-dev
  libslicot-dev liblapack-dev libblas-dev gfortran libgfortran5 libre2-dev
  libopenmpi-dev openmpi-bin
  libxsimd-dev  # engine/simulation: the SIMD lanes of batched time responses (lanes.h)
  libdeflate-dev  # engine/archive: the faster deflate encoder ([output] deflate_encoder = "libdeflate")
  clang-format clang-tidy  # tests/layout: the formatting check (hygiene.clang_format) and the tidy check
  python3 python3-numpy python3-scipy python3-h5py python3-matplotlib python3-jsonschema
  pybind11-dev python3-pybind11 python3-dev  # engine/python: the module gesweep (docs/python.md)
  python3-xarray python3-h5netcdf python3-pandas python3-pytest netcdf-bin  # its API and tests/python
  chromium  # headless, for tests/report: the report page loads and shows every figure
  python3-nbclient python3-ipykernel  # tests/notebook: the tour notebook runs (jupyter-notebook to open it)
)

gesweep_install_deps() {
  local missing=()
  local p
  for p in "$@" "${GESWEEP_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "gesweep: installing missing Debian packages: ${missing[*]}" >&2
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq >/dev/null
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# gesweep_build BUILD_DIR [extra cmake args...]: configure (once) and build with all cores.
# Compiles go through ccache when it is there (it is in GESWEEP_PACKAGES): a second build of the same
# sources, in this clone or another one of the same machine, takes the objects from its cache
# (CCACHE_BASEDIR makes the cache independent of where the clone is; docs/reliability.md §6).
gesweep_build() {
  local dir="$1"; shift
  local generator=()
  command -v ninja >/dev/null && generator=(-G Ninja)
  if command -v ccache >/dev/null; then
    export CMAKE_CXX_COMPILER_LAUNCHER=ccache CMAKE_C_COMPILER_LAUNCHER=ccache
    export CCACHE_BASEDIR="$GESWEEP_ROOT" CCACHE_NOHASHDIR=1
  fi
  if [ ! -f "$dir/CMakeCache.txt" ]; then
    cmake -S "$GESWEEP_ROOT" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
  else
    cmake -S "$GESWEEP_ROOT" -B "$dir" "$@" >/dev/null
  fi
  cmake --build "$dir" -j "$(nproc)"
}

# The python the scripts use: Debian's, which has numpy, scipy, h5py and matplotlib.
GESWEEP_PYTHON=/usr/bin/python3
