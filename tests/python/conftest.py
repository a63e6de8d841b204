"""Puts the built module on sys.path: `import _penumbra` finds
build/addon/penumbra/_penumbra*.so, exactly as a batch script would.
$PENUMBRA_ADDON_DIR names another built add-on folder instead (make
test-sanitize: build-asan/addon/penumbra)."""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ADDON_DIR = os.environ.get("PENUMBRA_ADDON_DIR") or os.path.join(ROOT, "build", "addon", "penumbra")
BLENDER_OCIO = "/usr/share/blender/datafiles/colormanagement/config.ocio"
BLENDER_WORLDS = "/usr/share/blender/datafiles/studiolights/world"

if ADDON_DIR not in sys.path:
    sys.path.insert(0, ADDON_DIR)
if ROOT not in sys.path:
    sys.path.append(ROOT)  # bench.helpers: what the tests share with the benchmarks
# Videos are decoded by the ffmpeg the package ships (the build links it here).
os.environ.setdefault("PENUMBRA_FFMPEG", os.path.join(ADDON_DIR, "bin", "ffmpeg"))
