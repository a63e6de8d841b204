#!/usr/bin/env bash
# Installs everything Penumbra needs on a Debian 12 machine, and nothing twice:
# Debian packages only when one is missing, each virtual environment only when
# its requirements file changed, the PyPI libraries only when missing from
# .deps. Safe to run on every `make`.
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian: Blender 3.4, the libraries the core builds against, test tools.
DEBIAN_PACKAGES=(
  blender                 # Blender 3.4: the first Blender the add-on supports (Python 3.11)
  libembree-dev           # ray casting for the visibility baker (copied into the package)
  libtbb-dev              # oneTBB: Embree's scheduler and the core's one parallel helper
  libeigen3-dev           # linear algebra (header-only)
  libhwy-dev              # Google Highway: run-time SIMD dispatch of the run-time shading (copied into the package)
  libimath-dev libfmt-dev # headers OpenImageIO's public headers include (header-only use)
  libgtest-dev            # C++ unit tests
  cmake g++ make pkg-config binutils  # the build; readelf checks the packages' dependencies
  ffmpeg                  # makes the test videos (decoding uses the ffmpeg the package ships)
  xvfb xauth              # a display for Blender's GPU and EEVEE work in tests and the demo, and the
                          # real window examples/panel_screenshot.py photographs the sidebar in
  python3-venv            # the virtual environments below
  python3-pytest python3-numpy  # pytest and numpy inside Debian's Blender (it runs the system Python)
  assimp-testmodels       # CMU motion capture (BVH) that drives examples/scenes/visibility_humanoid.py, the realistic test character
  clang-14 libclang-rt-14-dev   # libFuzzer harnesses of tests/fuzz (make fuzz; docs/reliability.md)
  llvm-14                 # llvm-symbolizer-14: source lines in the fuzzers' reports
)
missing=()
for pkg in "${DEBIAN_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "install_deps: installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# A Python of version $1 (3.10, 3.13): $PENUMBRA_PYTHON3XY, python3.X on PATH, or pyenv's.
find_python() {
  local version=$1 var="PENUMBRA_PYTHON${1//./}" candidate
  for candidate in "${!var:-}" "$(command -v "python$version" || true)" \
      "$(ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$version".*/bin/python"$version" 2>/dev/null | sort -V | tail -n 1)"; do
    if [ -n "$candidate" ] && "$candidate" -c "import sys, venv; sys.exit(sys.version_info[:2] != tuple(map(int, '$version'.split('.'))))" 2>/dev/null; then
      echo "$candidate"
      return
    fi
  done
  echo "install_deps: Python $version is needed (Blender $2 runs it) but was not found." >&2
  echo "  Install it (pyenv install $version, or your distribution's python$version with venv and headers)," >&2
  echo "  or point $var at its interpreter: $var=/path/to/python$version make ..." >&2
  exit 1
}

# make_venv FOLDER PYTHON [REQUIREMENTS]: a venv, refreshed when the requirements change.
make_venv() {
  local folder=$1 python=$2 requirements=${3:-}
  if [ ! -x "$folder/bin/python" ]; then
    echo "install_deps: creating $folder with $("$python" --version)"
    "$python" -m venv "$folder"
  fi
  if [ -n "$requirements" ] && ! cmp -s "$requirements" "$folder/.penumbra-requirements"; then
    echo "install_deps: installing $requirements into $folder"
    "$folder/bin/python" -m pip install -q --upgrade pip
    "$folder/bin/python" -m pip install -q -r "$requirements"
    cp "$requirements" "$folder/.penumbra-requirements"
  fi
}

# .venv: Python 3.11 (Debian's Blender 3.4 and bpy 4.5 run it), the build tools.
make_venv .venv "${PENUMBRA_PYTHON:-python3}" requirements.txt
# .venv313: bpy 5.2 (Blender 5.1+ run Python 3.13); its interpreter builds the cp313 module.
make_venv .venv313 "$(find_python 3.13 "5.1+")" requirements-bpy52.txt
# .venv310: only an interpreter and headers, for the cp310 module of official Blender 3.x builds.
make_venv .venv310 "$(find_python 3.10 "3.x (official builds)")"

# OpenImageIO, OpenColorIO and ffmpeg from PyPI, pinned (scripts/native_deps.py).
.venv/bin/python scripts/native_deps.py
