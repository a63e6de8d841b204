"""The rig JSON has a documented schema per `version` (issue 28), and the
files the real 0.2.0 wrote (tests/data/upgrade/0.2.0/, from bpy 4.5 and 5.2)
validate against theirs. What today's operator writes is validated in
tests/python/test_demo.py, on the demo's rigs from all three Blenders."""

import copy
import glob
import json
import os

import jsonschema
import pytest

from tests import rig_json_schema
from tests.python.test_changelog import format_constant

ROOT = rig_json_schema.ROOT
OLD_RIGS = sorted(glob.glob(os.path.join(ROOT, "tests", "data", "upgrade", "0.2.0", "*", "rig.json")))


def old_rig():
    with open(OLD_RIGS[0]) as f:
        return json.load(f)


def test_every_version_up_to_todays_has_a_valid_schema_that_names_it():
    current = format_constant("rig JSON version")
    for version in range(1, current + 1):
        schema = rig_json_schema.schema(version)
        jsonschema.Draft202012Validator.check_schema(schema)
        assert schema["properties"]["version"] == {"const": version}


@pytest.mark.parametrize("path", OLD_RIGS, ids=lambda p: os.path.basename(os.path.dirname(p)))
def test_a_rig_written_by_0_2_0_validates_against_its_version(path):
    assert len(OLD_RIGS) == 2
    with open(path) as f:
        doc = json.load(f)
    assert doc["version"] == 1 and len(doc["frames"]) > 1
    rig_json_schema.validate(doc)


def _drop_frames(doc):
    del doc["frames"]


def _unknown_version(doc):
    doc["version"] = 99


def _negative_power(doc):
    doc["frames"][0]["lights"][0]["rgb"][1] = -0.5


def _undocumented_field(doc):
    doc["exposure"] = 1.0


def _light_without_direction(doc):
    del doc["frames"][1]["lights"][0]["direction"]


def _two_component_direction(doc):
    doc["frames"][0]["lights"][0]["direction"] = [0.0, 1.0]


def _other_format(doc):
    doc["format"] = "light-rig"


@pytest.mark.parametrize("break_it", [_drop_frames, _unknown_version, _negative_power, _undocumented_field,
                                      _light_without_direction, _two_component_direction, _other_format],
                         ids=lambda f: f.__name__.strip("_"))
def test_the_schema_rejects_a_broken_rig(break_it):
    doc = copy.deepcopy(old_rig())
    break_it(doc)
    with pytest.raises(jsonschema.ValidationError):
        rig_json_schema.validate(doc)
