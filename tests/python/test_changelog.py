"""CHANGELOG.md keeps up with the add-on's version and with what a user
upgrading must know. The rules, checked on the repository's files and shown
failing on fabricated ones:

1. Shape (Keep a Changelog 1.1.0): every `## ` heading is `[Unreleased]` or
   `[X.Y.Z] - YYYY-MM-DD`; `[Unreleased]` appears at most once, first;
   versions go newest first, each once.
2. The newest section is `[Unreleased]` or the section of the manifest's
   version (addon/penumbra/blender_manifest.toml), and it has content (at
   least one bullet under a `###` heading). So an `[Unreleased]` heading
   with nothing under it fails: leave it out until the first change lands.
3. The manifest's version has its own section with content: once released,
   and as soon as the manifest is raised to the next version (the entry then
   moves from `[Unreleased]` to it). No section is newer than it.
4. The manifest's version is not older than the newest release recorded in
   docs/release-formats.json, and every recorded release has a section.
5. Each file-format constant (`model_format_version` in core/,
   `NOISE_FILTER_VERSION` in addon/penumbra/colormap/, the rig JSON's
   `"version"` in addon/penumbra/lights/; each found by searching for its
   definition) and each setting's default (`_penumbra.settings_spec()`) is
   compared with the newest recorded release. One that differs, is new or is
   gone needs a bullet in the newest section's `### Upgrading` naming it as
   docs/release-formats.json keys it (a whole word; backticks and case
   ignored). A line elsewhere, or in an older section, does not count.

Releasing X.Y.Z, then: raise the manifest, bl_info and CMake to X.Y.Z
(scripts/package.py refuses a mismatch), turn `## [Unreleased]` into
`## [X.Y.Z] - YYYY-MM-DD`, and record X.Y.Z's values in
docs/release-formats.json (from then on, changes are compared with X.Y.Z).
"""

import json
import os
import re
import tomllib

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
UNRELEASED = "Unreleased"
HEADING = re.compile(r"^## \[(?P<name>[^\]]+)\](?P<rest>.*)$")
VERSION = re.compile(r"\d+\.\d+\.\d+")
DATED = re.compile(r" - \d{4}-\d{2}-\d{2}$")

# Where each format constant is defined: (folder, file suffixes, definition).
# A definition whose value is a name (RIG_VERSION) is resolved in the same folder.
FORMAT_DEFINITIONS = {
    "model_format_version": ("core", (".hpp", ".cpp"), r"\bmodel_format_version\s*=\s*(\w+)\s*;"),
    "rig JSON version": ("addon/penumbra/lights", (".py",),
                         r"\"format\":\s*\"penumbra-light-rig\"[^}]*?\"version\":\s*(\w+)"),
    "NOISE_FILTER_VERSION": ("addon/penumbra/colormap", (".py",), r"^NOISE_FILTER_VERSION\s*=\s*(\w+)"),
}


def version_key(version):
    return tuple(int(part) for part in version.split("."))


# ---- reading ----------------------------------------------------------------

def sections(text):
    """[(name, heading rest, {subsection: [bullet text]})] in file order;
    bullets wrapped over several lines are joined."""
    found = []
    subsection = bullets = None
    for line in text.splitlines():
        heading = HEADING.match(line)
        if heading:
            found.append((heading["name"], heading["rest"], {}))
            subsection = bullets = None
        elif found and line.startswith("### "):
            subsection = line[4:].strip()
            bullets = found[-1][2].setdefault(subsection, [])
        elif bullets is not None and line.startswith("- "):
            bullets.append(line[2:].strip())
        elif bullets and line.startswith("  ") and line.strip():
            bullets[-1] += " " + line.strip()
    return found


def manifest_version(root=ROOT):
    with open(os.path.join(root, "addon", "penumbra", "blender_manifest.toml"), "rb") as f:
        return tomllib.load(f)["version"]


def releases(root=ROOT):
    with open(os.path.join(root, "docs", "release-formats.json")) as f:
        return json.load(f)["releases"]


def _matches(root, folder, suffixes, pattern):
    hits = []
    for where, dirs, files in os.walk(os.path.join(root, folder)):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for name in sorted(files):
            if name.endswith(suffixes):
                path = os.path.join(where, name)
                with open(path, encoding="utf-8") as f:
                    hits += [(os.path.relpath(path, root), m.group(1))
                             for m in re.finditer(pattern, f.read(), re.MULTILINE)]
    return hits


def format_constant(name, root=ROOT, definitions=FORMAT_DEFINITIONS):
    """The value of format constant `name`, from its one definition in the tree."""
    folder, suffixes, pattern = definitions[name]
    hits = _matches(root, folder, suffixes, pattern)
    assert len(hits) == 1, f"{name}: expected one definition under {folder}/, found {hits or 'none'}"
    value = hits[0][1]
    if not value.isdigit():
        named = _matches(root, folder, suffixes, rf"^\s*{re.escape(value)}\s*=\s*(\d+)\b")
        assert len(named) == 1, f"{name} is {value}: expected one definition of it under {folder}/, found {named}"
        value = named[0][1]
    return int(value)


def current_values(root=ROOT):
    import _penumbra
    return ({name: format_constant(name, root) for name in FORMAT_DEFINITIONS},
            {name: spec["default"] for name, spec in _penumbra.settings_spec().items()})


# ---- the rules ----------------------------------------------------------------

def shape_problems(found):
    problems, versions = [], []
    for index, (name, rest, _) in enumerate(found):
        if name == UNRELEASED:
            if index != 0 or rest.strip():
                problems.append("[Unreleased] must be the first section, its heading '## [Unreleased]' alone")
        elif not VERSION.fullmatch(name) or not DATED.fullmatch(rest):
            problems.append(f"'## [{name}]{rest}': a version's heading is '## [X.Y.Z] - YYYY-MM-DD'")
        else:
            versions.append(version_key(name))
    if versions != sorted(set(versions), reverse=True):
        problems.append(f"versions must go newest first, each once: {['.'.join(map(str, v)) for v in versions]}")
    return problems


def version_problems(found, manifest, recorded):
    names = [name for name, _, _ in found]
    has_content = {name: any(body.values()) for name, _, body in found}
    problems = []
    if not found:
        return ["CHANGELOG.md has no '## [...]' section"]
    if names[0] not in (UNRELEASED, manifest):
        problems.append(f"the newest section is [{names[0]}]; it must be [Unreleased] or the manifest's "
                        f"version [{manifest}]")
    elif not has_content[names[0]]:
        problems.append(f"the newest section [{names[0]}] is empty")
    if not has_content.get(manifest):
        problems.append(f"the manifest's version {manifest} has no section with content")
    newer = [n for n in names if VERSION.fullmatch(n) and version_key(n) > version_key(manifest)]
    if newer:
        problems.append(f"sections newer than the manifest's version {manifest}: {newer}")
    last = max(recorded, key=version_key)
    if version_key(manifest) < version_key(last):
        problems.append(f"the manifest's version {manifest} is older than the last release {last}")
    problems += [f"the recorded release {v} has no section" for v in recorded if v not in names]
    return problems


def upgrading_problems(found, recorded, formats, defaults):
    """An Upgrading bullet in the newest section for each value that differs
    from the newest recorded release."""
    last = recorded[max(recorded, key=version_key)]
    changed = []
    for now, then in ((formats, last["formats"]), (defaults, last["settings_defaults"])):
        for name in sorted(set(now) | set(then)):
            if _normalised(now.get(name)) != _normalised(then.get(name)):
                changed.append((name, then.get(name), now.get(name)))
    bullets = found[0][2].get("Upgrading", []) if found else []
    said = [b.replace("`", "").lower() for b in bullets]
    return [f"{name} was {then} in {max(recorded, key=version_key)} and is {now} now: the newest section's "
            f"'### Upgrading' needs a line naming {name}"
            for name, then, now in changed if not any(_names(b, name) for b in said)]


def _names(bullet, name):
    """Whether `bullet` names `name` as a whole word (lights.count is not lights.count_max)."""
    return re.search(rf"(?<![\w.]){re.escape(name.lower())}(?![\w.])", bullet) is not None


def _normalised(value):
    return list(value) if isinstance(value, tuple) else value


def changelog_problems(text, manifest, recorded, formats, defaults):
    found = sections(text)
    return (shape_problems(found) + version_problems(found, manifest, recorded)
            + upgrading_problems(found, recorded, formats, defaults))


# ---- the repository ---------------------------------------------------------------

def test_the_changelog_covers_the_manifest_version_and_every_format_or_default_change():
    with open(os.path.join(ROOT, "CHANGELOG.md"), encoding="utf-8") as f:
        text = f.read()
    formats, defaults = current_values()
    problems = changelog_problems(text, manifest_version(), releases(), formats, defaults)
    assert not problems, "CHANGELOG.md:\n" + "\n".join(problems)


# ---- the rules failing on fabricated input -------------------------------------------

RECORDED = {"0.2.0": {"formats": {"model_format_version": 2, "NOISE_FILTER_VERSION": 4},
                      "settings_defaults": {"lights.count": 64, "visibility.transmission": [0.5, 0.5, 0.5]}}}
FORMATS = {"model_format_version": 2, "NOISE_FILTER_VERSION": 4}
DEFAULTS = {"lights.count": 64, "visibility.transmission": (0.5, 0.5, 0.5)}
RELEASED = "## [0.2.0] - 2026-11-26\n\n### Added\n- The three tools.\n"
UNRELEASED_ENTRY = "## [Unreleased]\n\n### Fixed\n- A durable write,\n  wrapped.\n\n"


def problems_of(text, manifest="0.2.0", formats=FORMATS, defaults=DEFAULTS, recorded=RECORDED):
    return changelog_problems(text, manifest, recorded, formats, defaults)


def test_a_changelog_that_follows_the_rules_passes():
    assert problems_of(UNRELEASED_ENTRY + RELEASED) == []
    assert problems_of(RELEASED) == []
    assert problems_of("## [0.3.0] - 2027-01-10\n\n### Added\n- More.\n\n" + RELEASED, manifest="0.3.0") == []


@pytest.mark.parametrize("text, manifest, expected", [
    ("# Changelog\n", "0.2.0", "no '## [...]' section"),
    ("## [Unreleased]\n\n" + RELEASED, "0.2.0", "newest section [Unreleased] is empty"),
    ("## [Unreleased]\n\n### Added\n\n" + RELEASED, "0.2.0", "newest section [Unreleased] is empty"),
    ("## [0.2.0] - 2026-11-26\n\n### Added\n", "0.2.0", "newest section [0.2.0] is empty"),
    (UNRELEASED_ENTRY + RELEASED, "0.3.0", "0.3.0 has no section with content"),
    (RELEASED, "0.3.0", "the newest section is [0.2.0]"),
    ("## [0.3.0] - 2027-01-10\n\n- x\n\n" + RELEASED, "0.2.0", "newer than the manifest's version"),
    (UNRELEASED_ENTRY, "0.2.0", "the recorded release 0.2.0 has no section"),
    (UNRELEASED_ENTRY + RELEASED, "0.1.0", "older than the last release 0.2.0"),
    (RELEASED + "\n" + UNRELEASED_ENTRY, "0.2.0", "[Unreleased] must be the first section"),
    ("## [0.2.0]\n\n### Added\n- x\n", "0.2.0", "'## [X.Y.Z] - YYYY-MM-DD'"),
    ("## [0.2.0] - 2026-11-26\n- x\n## [0.3.0] - 2027-01-01\n- y\n", "0.3.0", "newest first"),
])
def test_a_missing_empty_or_misplaced_section_fails(text, manifest, expected):
    assert any(expected in p for p in problems_of(text, manifest=manifest)), problems_of(text, manifest=manifest)


def test_a_changed_format_constant_needs_an_upgrading_line_naming_it():
    raised = dict(FORMATS, NOISE_FILTER_VERSION=5)
    failing = problems_of(UNRELEASED_ENTRY + RELEASED, formats=raised)
    assert len(failing) == 1 and "NOISE_FILTER_VERSION was 4" in failing[0], failing
    elsewhere = UNRELEASED_ENTRY + "### Changed\n- NOISE_FILTER_VERSION is 5.\n\n" + RELEASED
    assert problems_of(elsewhere, formats=raised) != [], "only an Upgrading line counts"
    in_the_old_section = (UNRELEASED_ENTRY + "## [0.2.0] - 2026-11-26\n\n### Upgrading\n"
                          "- `NOISE_FILTER_VERSION` is 5.\n")
    assert problems_of(in_the_old_section, formats=raised) != [], "only the newest section counts"
    named = UNRELEASED_ENTRY + "### Upgrading\n- The colour map's\n  `noise_filter_version` is now 5: re-bake.\n\n"
    assert problems_of(named + RELEASED, formats=raised) == []


def test_a_changed_new_or_removed_default_needs_an_upgrading_line_naming_it():
    for defaults, name in ((dict(DEFAULTS, **{"lights.count": 32}), "lights.count"),
                           (dict(DEFAULTS, **{"visibility.transmission": (0.5, 0.5, 0.4)}), "visibility.transmission"),
                           (dict(DEFAULTS, **{"lights.new_setting": 1}), "lights.new_setting"),
                           ({"lights.count": 64}, "visibility.transmission")):
        failing = problems_of(UNRELEASED_ENTRY + RELEASED, defaults=defaults)
        assert len(failing) == 1 and failing[0].startswith(name), failing
        named = UNRELEASED_ENTRY + f"### Upgrading\n- `{name}` changed.\n\n" + RELEASED
        assert problems_of(named, defaults=defaults) == []
        longer = UNRELEASED_ENTRY + f"### Upgrading\n- `{name}_max` changed.\n\n" + RELEASED
        assert problems_of(longer, defaults=defaults) != [], "a longer name is another setting"


def _tree(tmp_path, files):
    for path, text in files.items():
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text(text)
    return tmp_path


def test_each_format_constant_is_found_by_its_definition_wherever_it_moves(tmp_path):
    root = _tree(tmp_path, {
        "core/visibility/model_file.hpp": "constexpr std::uint32_t model_format_version = 3;\n",
        "core/visibility/model_file.cpp": "write_file(path, magic, model_format_version, bytes);\n",
        "addon/penumbra/colormap/filter_version.py": "NOISE_FILTER_VERSION = 6\n",
        "addon/penumbra/colormap/node_groups.py": "from .filter_version import NOISE_FILTER_VERSION\n",
        "addon/penumbra/lights/rig_json.py": "RIG_VERSION = 2\n",
        "addon/penumbra/lights/operators.py": 'doc = {\n    "format": "penumbra-light-rig",\n'
                                              '    "version": RIG_VERSION,\n}\n'})
    assert {name: format_constant(name, str(root)) for name in FORMAT_DEFINITIONS} == \
        {"model_format_version": 3, "NOISE_FILTER_VERSION": 6, "rig JSON version": 2}


@pytest.mark.parametrize("files", [
    {"addon/penumbra/colormap/a.py": "NOISE_FILTER_VERSION = 4\n", "addon/penumbra/colormap/b.py": "NOISE_FILTER_VERSION = 5\n"},
    {"addon/penumbra/colormap/a.py": "from .b import NOISE_FILTER_VERSION\n"},
])
def test_a_constant_defined_twice_or_nowhere_fails(tmp_path, files):
    with pytest.raises(AssertionError, match="expected one definition"):
        format_constant("NOISE_FILTER_VERSION", str(_tree(tmp_path, files)))
