#!/usr/bin/env python3
"""Writes a set of the light-rig tool's test data into a folder (the maker
itself is bench/helpers/test_videos.py):

    .venv/bin/python scripts/lights_make_test_videos.py out/light_videos"""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
from bench.helpers.test_videos import (crossfade_frames, exposure_frames, flicker_frames, load_world,  # noqa: E402
                                       noisy, rotation_frames, sky, sun_disc, write_sequence, write_video)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "light_videos")
    forest, sunset = load_world("forest", 256), load_world("sunset", 256)
    write_sequence(os.path.join(out, "rotation"), rotation_frames(forest, 48, 2.0))
    write_sequence(os.path.join(out, "crossfade"), crossfade_frames(forest, sunset, 48))
    write_sequence(os.path.join(out, "exposure"), exposure_frames(forest, 48, 3.0))
    write_sequence(os.path.join(out, "flicker"), noisy(flicker_frames(forest, 48, 21.0)))
    write_video(os.path.join(out, "rotation.mov"), rotation_frames(forest, 24, 2.0))
    write_sequence(os.path.join(out, "synthetic"), [sky(128, 256), sun_disc(128, 256, (1, 1, 1), 0.05, 1e4),
                                                    sun_disc(128, 256, (1, 1, 1), 0.05, 1e4, 0.5)], stem="map_")
    print(f"wrote test data under {out}")


if __name__ == "__main__":
    main()
