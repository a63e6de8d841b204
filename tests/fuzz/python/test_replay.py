"""Replays the atheris harnesses' corpora and crashers (tests/fuzz/python/<name>/),
so every input that ever failed stays a regression test (make test-fuzz-python)."""

import glob
import importlib
import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

HARNESSES = sorted(os.path.basename(os.path.dirname(d)) for d in glob.glob(os.path.join(HERE, "*", "corpus")))
CASES = [(name, path) for name in HARNESSES
         for path in sorted(glob.glob(os.path.join(HERE, name, "corpus", "*")) +
                            glob.glob(os.path.join(HERE, name, "crashers", "*")))]


def test_every_harness_has_a_corpus():
    assert HARNESSES == ["bake_report", "rig_index"]
    for name in HARNESSES:
        assert any(case[0] == name for case in CASES), name


@pytest.mark.parametrize("name,path", CASES, ids=[os.path.relpath(p, HERE) for _, p in CASES])
def test_input(name, path):
    harness = importlib.import_module(f"fuzz_{name}")
    with open(path, "rb") as f:
        harness.TestOneInput(f.read())
