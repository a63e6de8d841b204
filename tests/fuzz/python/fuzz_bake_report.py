"""Atheris harness: the visibility bake report the add-on reads back.

A bake stores its summary as JSON on the object (`penumbra_visibility.report`,
a string property saved in the .blend) and the panel reads it back on every
redraw: addon/penumbra/visibility/report.py `summary_lines`. A .blend is
outside data, so the string may be anything. Contract checked: for any
string, summary_lines returns a list of strings and raises nothing (an
exception in a panel's draw breaks the panel on every redraw).

Input: the report's bytes, decoded as UTF-8 with surrogate escapes (what a
.blend holding invalid UTF-8 gives). Run: `make fuzz` (atheris, libFuzzer
options on the command line); replayed by tests/fuzz/python/test_replay.py.
"""

import importlib.util
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def _load_report_module():
    # Loaded from its file: the add-on package itself imports bpy.
    path = os.path.join(ROOT, "addon", "penumbra", "visibility", "report.py")
    spec = importlib.util.spec_from_file_location("penumbra_visibility_report", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


report = _load_report_module()


def TestOneInput(data):
    text = data.decode("utf-8", "surrogateescape")
    lines = report.summary_lines(text)
    assert isinstance(lines, list) and all(isinstance(line, str) for line in lines), lines


def main():
    import atheris

    for function in (report.summary_lines, report._field, report._number):
        atheris.instrument_func(function)
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
