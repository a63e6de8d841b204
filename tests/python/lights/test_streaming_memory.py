"""Memory of the light-rig readers, measured as the peak resident memory a
fresh Python process gains while it reads (Linux: the peak is reset
through /proc/self/clear_refs, then read as VmHWM): a fisheye or
mirror-ball file streams in a few bands instead of sitting whole in memory,
and a long sequence needs no more than a short one (each frame is read,
turned into lights and dropped). The maps' values are checked against the
whole-image path in tests/cpp/lights/map_reader_test.cpp."""

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import _penumbra

from conftest import ADDON_DIR

# Reads in a fresh interpreter, so the peak is this read's own; prints JSON.
MEASURE = """
import json, sys
sys.path.insert(0, {addon!r})
import _penumbra
def reset_peak():
    # Else the peak of importing numpy and the module would hide the read's.
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
def peak_mb():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmHWM")) / 1024
out = {{}}
{body}
print(json.dumps(out))
"""


def measure(body):
    code = MEASURE.format(addon=ADDON_DIR, body=body)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def round_sky(side, projection):
    """A smooth sky with a bright spot inside the image circle, black outside."""
    y, x = np.mgrid[0:side, 0:side].astype(np.float32) + 0.5
    r = np.hypot(x - side / 2, y - side / 2) / (side / 2)
    image = np.stack([0.2 + 0.5 * (1 - r), 0.3 + 0.4 * (1 - r), 0.6 + 0.3 * (1 - r)], axis=-1).astype(np.float32)
    image[r > 1] = 0
    image[(np.abs(x - side * 0.3) < side * 0.02) & (np.abs(y - side * 0.4) < side * 0.02)] = 50.0
    if projection == "mirror_ball":
        image[..., 2] += 0.1 * (x / side)  # not symmetric: both halves of the ball differ
    return image


def write_sequence(folder, image, frames):
    """`frames` copies of one half-float EXR (ZIP), numbered from 1; returns the first."""
    os.makedirs(folder, exist_ok=True)
    first = os.path.join(folder, "sky_0001.exr")
    _penumbra.image.write_exr(first, image, half=True)
    for i in range(2, frames + 1):
        shutil.copy(first, os.path.join(folder, f"sky_{i:04d}.exr"))
    return first


@pytest.mark.parametrize("projection", ["fisheye", "mirror_ball"])
def test_a_large_fisheye_or_mirror_ball_file_streams_in_a_fraction_of_its_size(tmp_path, projection):
    side = 2048
    path = write_sequence(str(tmp_path / "large"), round_sky(side, projection), 1)
    small = write_sequence(str(tmp_path / "small"), round_sky(64, projection), 1)
    decoded_mb = side * side * 3 * 4 / 2 ** 20  # 48 MiB as float RGB
    out = measure(f"""
# A small read first: loading OpenImageIO's EXR reader and starting the
# threads costs ~20 MiB once, which is not the frame's.
_penumbra.lights.read_map({small!r}, mapping={projection!r}, max_width=16, band_bytes=1 << 10)
reset_peak()
before = peak_mb()
m = _penumbra.lights.read_map({path!r}, mapping={projection!r}, max_width=256, band_bytes=1 << 20)
out.update(growth=peak_mb() - before, streamed=m["streamed"], bands=m["bands"],
           buffer_bytes=m["buffer_bytes"], shape=list(m["pixels"].shape))
""")
    assert out["streamed"] and out["bands"] > 10, out
    assert out["shape"][1] == 256
    # Read whole, the frame and its RGB copy would add 96 MiB; streamed in
    # 1 MiB bands the process grows by ~7 MiB (measured 6.5 and 7.1).
    assert out["buffer_bytes"] < 0.1 * decoded_mb * 2 ** 20, out
    assert out["growth"] < 0.25 * decoded_mb, out


def test_a_long_fisheye_sequence_needs_no_more_memory_than_a_short_one(tmp_path):
    side = 1536
    first = write_sequence(str(tmp_path / "seq"), round_sky(side, "fisheye"), 10)
    growth = {}
    for frames in (2, 10):
        out = measure(f"""
source = _penumbra.lights.open_source({first!r})
_penumbra.lights.RigBuilder(count=16, mapping="fisheye", max_width=256).add_frame_from(source, 0)  # warm up
builder = _penumbra.lights.RigBuilder(count=16, mapping="fisheye", max_width=256)
reset_peak()
before = peak_mb()
for i in range({frames}):
    builder.add_frame_from(source, i)
rig = builder.finish()
out.update(growth=peak_mb() - before, frames=len(rig["power"]))
""")
        assert out["frames"] == frames
        growth[frames] = out["growth"]
    # Each frame is read in bands and dropped: eight frames more add
    # nothing (one frame held would be 27 MiB of float RGB).
    assert growth[10] - growth[2] < 6.0, growth
