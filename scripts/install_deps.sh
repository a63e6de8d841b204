#!/usr/bin/env bash
# Installs everything Penumbra needs on a Debian 12 machine, and nothing twice:
# Debian packages only when one is missing, the .venv only when its
# requirements file changed. Safe to run on every `make`.
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian: Blender 3.4, the C++ libraries, tools used by tests and the demo.
DEBIAN_PACKAGES=(
  blender                 # Blender 3.4: the add-on's first target, and its Python 3.11
  libopenimageio-dev      # image and video I/O (EXR, HDR, PNG, TIFF, ffmpeg reader)
  openimageio-tools       # oiiotool/iinfo: inspect outputs by hand
  libopencolorio-dev      # colour management (Blender's own OCIO config)
  libembree-dev           # ray casting for the visibility baker
  libeigen3-dev           # linear algebra
  libgtest-dev            # C++ unit tests
  pybind11-dev            # the _penumbra Python module
  cmake g++ make pkg-config  # the build
  ffmpeg                  # makes the test videos that OpenImageIO's ffmpeg reader decodes
  python3-venv            # the .venv below
  python3-pytest python3-numpy  # pytest and numpy inside Debian's Blender (it runs the system Python)
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

# PyPI, in .venv: bpy 4.5 LTS (Blender as a module), numpy < 2, pytest, mpmath.
PYTHON="${PENUMBRA_PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
  echo "install_deps: creating .venv with $($PYTHON --version)"
  "$PYTHON" -m venv .venv
fi
stamp=.venv/.penumbra-requirements
if ! cmp -s requirements.txt "$stamp"; then
  echo "install_deps: installing requirements.txt into .venv"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -r requirements.txt
  cp requirements.txt "$stamp"
fi
