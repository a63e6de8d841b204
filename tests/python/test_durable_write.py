"""Every file Penumbra publishes is written durably (core/common/durable_file.hpp):
the finished temporary is fsynced, renamed over the target, then the folder is
fsynced. The steps are observed through _penumbra.testing's recording hook for
each kind of file: a pose model, a farm piece (a training set, as
scripts/visibility_bake_farm.py saves it), lookup images, and the rig JSON and
the colour map's backups, which the add-on writes through
_penumbra.write_file_durably and _penumbra.replace_file_durably."""

import json
import os

import numpy as np
import pytest

import _penumbra as p
from visibility_sphere_scenes import bake


@pytest.fixture
def steps():
    """Records the test's durable-write steps; calling it returns them and stops recording."""
    p.testing.record_durable_steps()
    yield p.testing.recorded_durable_steps
    p.testing.recorded_durable_steps()
    p.testing.inject_fsync_failure(p.testing.FsyncFailure.NONE)


def assert_published_durably(steps, path):
    """fsync of a temporary beside `path`, its rename over `path`, fsync of the folder; nothing else."""
    assert len(steps) == 3, steps
    assert steps[1].startswith("rename ") and steps[1].endswith(" -> " + path), steps
    temporary = steps[1][len("rename "):-len(" -> " + path)]
    assert temporary != path and os.path.dirname(temporary) == os.path.dirname(path)
    assert steps == [f"fsync file {temporary}", f"rename {temporary} -> {path}",
                     f"fsync folder {os.path.dirname(path)}"]
    assert os.listdir(os.path.dirname(path)) == [os.path.basename(path)]  # no temporary left


def test_a_pose_model_is_fsynced_renamed_then_its_folder_fsynced(tmp_path, steps):
    model, _ = p.visibility.fit_model(bake(np.linspace(0.0, np.pi / 2, 8), rays=16),
                                      [(True, True), (True, False)], lobes=1)
    path = str(tmp_path / "body.pzh")
    model.save(path)
    assert_published_durably(steps(), path)
    assert p.visibility.PoseModel.load(path).joints == ["arm"]


def test_a_farm_piece_is_fsynced_renamed_then_its_folder_fsynced(tmp_path, steps):
    piece = bake([0.0], rays=16)
    path = str(tmp_path / "body_001.pvis")
    piece.save(path)  # what scripts/visibility_bake_farm.py's bake command does with --out
    assert_published_durably(steps(), path)
    assert p.visibility.TrainingSet.load(path).frame_numbers == [0.0]


@pytest.mark.parametrize("kind", ["exr", "png"])
def test_a_lookup_image_is_fsynced_renamed_then_its_folder_fsynced(tmp_path, steps, kind):
    pixels = np.linspace(0.0, 1.0, 4 * 2 * 3, dtype=np.float32).reshape(2, 4, 3)
    path = str(tmp_path / f"lookup.{kind}")
    if kind == "exr":  # as the colour map's operator writes its lookup, and its optional PNG
        p.image.write_exr(path, pixels, half=False, colorspace="Non-Color")
    else:
        p.image.write_png16(path, pixels, colorspace="Non-Color")
    assert_published_durably(steps(), path)


def test_a_rig_json_is_fsynced_renamed_then_its_folder_fsynced(tmp_path, steps):
    # lights/operators.py publishes the rig's JSON text this way once the rig is in the scene.
    path = str(tmp_path / "penumbra_light_rig.json")
    p.write_file_durably(path, json.dumps({"format": "penumbra-light-rig", "version": 1}).encode())
    assert_published_durably(steps(), path)
    assert json.load(open(path))["format"] == "penumbra-light-rig"


def test_a_colormap_backup_and_its_restore_are_fsynced_and_their_folder_too(tmp_path, steps):
    # colormap/operators.py's _LookupFiles moves an overwritten lookup aside and back.
    path, backup = str(tmp_path / "lookup.exr"), str(tmp_path / "lookup.exr.penumbra-backup")
    open(path, "wb").write(b"old lookup")
    p.replace_file_durably(path, backup)
    p.replace_file_durably(backup, path)
    folder = str(tmp_path)
    assert steps() == [f"fsync file {path}", f"rename {path} -> {backup}", f"fsync folder {folder}",
                       f"fsync file {backup}", f"rename {backup} -> {path}", f"fsync folder {folder}"]
    assert open(path, "rb").read() == b"old lookup" and os.listdir(folder) == ["lookup.exr"]


def test_a_failed_fsync_is_an_os_error_and_leaves_the_old_file_without_a_temporary(tmp_path, steps):
    path = str(tmp_path / "penumbra_light_rig.json")
    open(path, "wb").write(b"old rig")
    p.testing.inject_fsync_failure(p.testing.FsyncFailure.FILE)
    with pytest.raises(OSError, match="unchanged"):
        p.write_file_durably(path, b"new rig")
    assert open(path, "rb").read() == b"old rig" and os.listdir(tmp_path) == ["penumbra_light_rig.json"]
    taken = steps()
    assert len(taken) == 1 and taken[0].startswith("fsync file "), taken  # never renamed


def test_a_failed_folder_fsync_is_an_os_error_after_the_rename(tmp_path, steps):
    path = str(tmp_path / "body.pvis")
    p.testing.inject_fsync_failure(p.testing.FsyncFailure.FOLDER)
    with pytest.raises(p.IoError, match="power cut"):
        bake([0.0], rays=16).save(path)
    assert os.listdir(tmp_path) == ["body.pvis"]
    assert steps()[-1] == f"fsync folder {tmp_path}"
