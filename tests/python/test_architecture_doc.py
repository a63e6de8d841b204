"""docs/architecture.md names real code: every path in its data-flow tables
exists, every C++ function is defined in the file cited for it, every
add-on function and operator exists, every `_penumbra` name is in the
built module (tests/architecture_doc.py). The checks are first shown to
report a misspelt or renamed name, and a cited function that is not called
(tests/blender/test_architecture_calls.py runs the tools)."""

import os
import sys

import numpy as np
import pytest

import _penumbra

sys.path.append(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/: architecture_doc
import architecture_doc as doc  # noqa: E402

HEADER = "### `visibility`\n\n| step | operator | add-on | `_penumbra` | core |\n|---|---|---|---|---|\n"


@pytest.fixture(scope="module")
def rows():
    rows, problems = doc.load()
    assert not problems, "\n".join(problems)
    return rows


def one_row(cells):
    rows, problems = doc.parse(HEADER + "| a step | " + " | ".join(cells) + " |\n")
    assert not problems, problems
    assert len(rows) == 1
    return rows


# ---- the doc as it is ---------------------------------------------------------

def test_each_tool_has_a_step_table_that_cites_penumbra_functions(rows):
    for tool in ("visibility", "lights", "colormap"):
        steps = [r for r in rows if r.tool == tool and r.kind == "step"]
        assert steps and any(r.penumbra for r in steps), tool
        assert all(r.operators and r.addon for r in steps), tool


def test_every_cited_path_exists(rows):
    with open(doc.DOC, encoding="utf-8") as f:
        text = f.read()
    assert not doc.missing_paths(rows) + doc.missing_cited_paths(text)


def test_every_cited_cpp_function_is_defined_in_its_file(rows):
    assert sum(len(r.core) for r in rows) > 50
    assert not doc.undefined_cpp(rows)


def test_every_cited_addon_function_and_operator_exists(rows):
    assert not doc.undefined_addon(rows) + doc.unknown_operators(rows)


def test_every_cited_penumbra_name_is_in_the_built_module(rows):
    assert not doc.unknown_penumbra(rows, _penumbra)


# ---- the checks catch what they are for ----------------------------------------

def test_a_renamed_name_in_any_column_is_reported(rows):
    with open(doc.DOC, encoding="utf-8") as f:
        text = f.read()
    renames = {"`core/visibility/mesh_frames.cpp:topology_hash,": "`core/visibility/mesh_frames.cpp:mesh_hash,",
               "`visibility/bake.py:fit_model`": "`visibility/bake.py:fit_pose`",
               "`_penumbra.visibility.PoseModel.shade_frame`": "`_penumbra.visibility.PoseModel.shade_frames`",
               "`penumbra.bake_colormap_lut`": "`penumbra.bake_colormap`",
               "`core/lights/rig.cpp:preview_image`": "`core/lights/rigs.cpp:preview_image`"}
    for old, new in renames.items():
        assert old in text, old
        text = text.replace(old, new)
    renamed, problems = doc.parse(text)
    assert not problems
    reported = "\n".join(doc.missing_paths(renamed) + doc.undefined_cpp(renamed) + doc.undefined_addon(renamed) +
                         doc.unknown_operators(renamed) + doc.unknown_penumbra(renamed, _penumbra))
    for name in ("mesh_hash is not defined in core/visibility/mesh_frames.cpp",
                 "fit_pose is not defined in addon/penumbra/visibility/bake.py",
                 "_penumbra.visibility.PoseModel.shade_frames is not in the built _penumbra",
                 "`penumbra.bake_colormap` is no operator", "no file core/lights/rigs.cpp"):
        assert name in reported, name


def test_a_function_renamed_in_the_code_is_reported(tmp_path):
    (tmp_path / "core").mkdir()
    (tmp_path / "core" / "ramp.cpp").write_text("namespace p {\nint ramp_table(int n) {\n    return n;\n}\n}\n")
    row = one_row(["—", "—", "—", "`core/ramp.cpp:ramp_to_table`"])
    assert doc.undefined_cpp(row, root=str(tmp_path)) == \
        [f"{row[0].where()}: ramp_to_table is not defined in core/ramp.cpp"]


@pytest.mark.parametrize("source", [
    "int f(int x);\n",                                  # a declaration
    "void g() {\n    f(1);\n}\n",                       # a call
    "int x = f(2);\n",                                   # a call at namespace scope
    "struct S {\n    int f(int x) { return x; }\n};\n",  # a member defined in its class
    "void S::f(int x) {\n}\n",                          # another class's f
    "// int f(int x) {\n/* int f(int x) { */\n",        # comments
])
def test_a_declaration_a_call_or_another_scope_is_not_a_definition(source):
    assert not doc.cpp_defines(source, "f")


@pytest.mark.parametrize("source, name", [
    ("int f(int x) {\n    return x;\n}\n", "f"),
    ("template <typename T>\nT f(const T& x) {\n    return x;\n}\n", "f"),
    ("std::vector<int> S::f(int x) const noexcept {\n    return {};\n}\n", "S::f"),
    ("S::S(int x)\n    : x_(x) {}\n", "S::S"),
    ("S::~S() = default;\n", "S::~S"),
    ("auto f() -> int { return 1; }\n", "f"),
])
def test_definitions_are_found(source, name):
    assert doc.cpp_defines(source, name)


def test_a_cell_with_prose_or_a_wrong_shape_is_reported():
    row = "| s | `penumbra.x` and more | `bake.py` | `penumbra.sh.rotate` | `core/a.cpp:f` |\n"
    _, problems = doc.parse(HEADER + row)
    text = "\n".join(problems)
    assert "operator cell is neither" in text
    assert "`bake.py` is not `path:name" in text
    assert "`penumbra.sh.rotate` is not a dotted _penumbra name" in text


def test_a_cited_function_or_class_that_is_not_called_is_reported():
    cited = ["_penumbra.visibility.topology_hash", "_penumbra.visibility.mesh_diagnostics",
             "_penumbra.visibility.ShadingMesh", "_penumbra.visibility.TrainingSet",
             "_penumbra.visibility.PoseModel.load"]
    row = one_row(["—", "—", ", ".join(f"`{n}`" for n in cited), "—"])
    classes = doc.cited_classes(row, _penumbra)
    init = _penumbra.visibility.ShadingMesh.__dict__["__init__"]
    sizes, loops = np.array([3]), np.array([0, 1, 2])
    with doc.CallRecorder(_penumbra, classes) as recorder:
        _penumbra.visibility.topology_hash(3, sizes, loops)
        _penumbra.visibility.ShadingMesh(3, sizes, loops)
    assert _penumbra.visibility.ShadingMesh.__dict__["__init__"] is init  # the pass-through is gone
    assert doc.uncalled(row, _penumbra, recorder.called) == [
        f"{row[0].where()}: {name} was not called" for name in cited[1:2] + cited[3:]]
    # An `also` row is not required to be called.
    row[0].kind = "also"
    assert doc.uncalled(row, _penumbra, recorder.called) == []
