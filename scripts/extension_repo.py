"""The static extension repository `make package` writes (dist/repo/), and
the repacking that makes a higher version of the same build for the upgrade
tests. Used by scripts/package.py; README.md (Installing) says how a studio
serves the folder and how a user adds it.

A repository is a folder holding the extension zip and the `index.json`
Blender's own `extension server-generate` writes from it (the one in the
bpy 5.2 module of .venv313): the listing names the zip by a relative URL, so
the folder works wherever it is served, from a file share (file://) or any
static web server.

Repacking rewrites the version in the zips' manifest, bl_info and wheel
(file name, dist-info folder, METADATA, RECORD) and nothing else: the
compiled core is the same file, so its `_penumbra.__version__` still names
the version CMake compiled it as. package.py checks both honestly: the
source tree agrees on the compiled version, the repacked zip on the new one.
"""

import base64
import glob
import hashlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GENERATOR_PYTHON = os.path.join(ROOT, ".venv313", "bin", "python")
WHEEL_NAME = "penumbra_core"
MANIFEST_VERSION = re.compile(r'^version = "([^"]+)"$', re.MULTILINE)
BL_INFO_VERSION = re.compile(r'("version":\s*)\((\d+),\s*(\d+),\s*(\d+)\)')


def server_generate_tool():
    """Blender's blender_ext.py from the bpy 5.2 module (the newest Blender
    we test writes the listing every older 4.2+ reads)."""
    found = glob.glob(os.path.join(ROOT, ".venv313", "lib", "python3.*", "site-packages", "bpy", "*", "scripts",
                                   "addons_core", "bl_pkg", "cli", "blender_ext.py"))
    if len(found) != 1 or not os.access(GENERATOR_PYTHON, os.X_OK):
        sys.exit(f"package: Blender's blender_ext.py was not found in the bpy 5.2 module of .venv313: {found}")
    return found[0]


def write_repository(extension_zip, repo):
    """`repo` holds this zip alone (a repository lists one version of an
    extension) and its index.json; returns the listing's entry."""
    os.makedirs(repo, exist_ok=True)
    for old in glob.glob(os.path.join(repo, "*.zip")) + glob.glob(os.path.join(repo, "index.json")):
        os.remove(old)
    target = os.path.join(repo, os.path.basename(extension_zip))
    try:
        os.link(extension_zip, target)  # dist/ and dist/repo/: one file, not two
    except OSError:
        shutil.copyfile(extension_zip, target)
    subprocess.run([GENERATOR_PYTHON, server_generate_tool(), "server-generate", "--repo-dir", repo],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(repo, "index.json")) as f:
        entries = json.load(f)["data"]
    if [e["id"] for e in entries] != ["penumbra"]:
        sys.exit(f"package: the repository's index.json lists {entries}, not Penumbra alone")
    return entries[0]


def zip_versions(extension_zip):
    """{where: version} inside an extension zip: its manifest, bl_info and
    our wheel's file name and METADATA."""
    with zipfile.ZipFile(extension_zip) as z:
        manifest = MANIFEST_VERSION.search(z.read("blender_manifest.toml").decode()).group(1)
        bl_info = BL_INFO_VERSION.search(z.read("__init__.py").decode())
        wheel_name = _our_wheel(z.namelist())
        with zipfile.ZipFile(io.BytesIO(z.read(wheel_name))) as wheel:
            metadata = [n for n in wheel.namelist() if n.endswith(".dist-info/METADATA")]
            in_metadata = re.search(r"^Version: (\S+)$", wheel.read(metadata[0]).decode(), re.MULTILINE).group(1)
    return {"blender_manifest.toml": manifest, "bl_info": ".".join(bl_info.groups()[1:]),
            f"{os.path.basename(wheel_name)} (file name)": os.path.basename(wheel_name).split("-")[1],
            f"{os.path.basename(wheel_name)} (METADATA)": in_metadata}


def _our_wheel(names):
    found = [n for n in names if n.startswith(f"wheels/{WHEEL_NAME}-") and n.endswith(".whl")]
    assert len(found) == 1, found
    return found[0]


def repack_extension(source, old, new, target):
    """The extension zip `source` of version `old`, as version `new`."""
    with zipfile.ZipFile(source) as z:
        old_wheel = _our_wheel(z.namelist())
        new_wheel = old_wheel.replace(f"{WHEEL_NAME}-{old}-", f"{WHEEL_NAME}-{new}-")
        changed = {
            "blender_manifest.toml": _versioned_manifest(z.read("blender_manifest.toml").decode(), old, new)
            .replace(os.path.basename(old_wheel), os.path.basename(new_wheel)).encode(),
            "__init__.py": _versioned_bl_info(z.read("__init__.py").decode(), new).encode(),
        }
        _rewrite(z, target, changed, {old_wheel: (new_wheel, _repacked_wheel(z.read(old_wheel), old, new))})


def repack_legacy(source, new, target):
    """The legacy zip `source` as version `new` (its bl_info; the module
    inside has no wheel metadata)."""
    with zipfile.ZipFile(source) as z:
        init = "penumbra/__init__.py"
        _rewrite(z, target, {init: _versioned_bl_info(z.read(init).decode(), new).encode()}, {})


def _versioned_manifest(text, old, new):
    found = MANIFEST_VERSION.search(text)
    assert found and found.group(1) == old, (found, old)
    return text[:found.start(1)] + new + text[found.end(1):]


def _versioned_bl_info(text, new):
    major, minor, patch = new.split(".")
    rewritten, count = BL_INFO_VERSION.subn(rf"\g<1>({major}, {minor}, {patch})", text, count=1)
    assert count == 1
    return rewritten


def _repacked_wheel(data, old, new):
    """The wheel with its dist-info folder, METADATA and RECORD renamed to
    `new`; every other file byte for byte."""
    old_info, new_info = f"{WHEEL_NAME}-{old}.dist-info/", f"{WHEEL_NAME}-{new}.dist-info/"
    out = io.BytesIO()
    record = []
    with zipfile.ZipFile(io.BytesIO(data)) as wheel, zipfile.ZipFile(out, "w") as repacked:
        for info in wheel.infolist():
            name = info.filename.replace(old_info, new_info)
            if name == new_info + "RECORD":
                continue
            content = wheel.read(info)
            if name == new_info + "METADATA":
                content = content.replace(f"\nVersion: {old}\n".encode(), f"\nVersion: {new}\n".encode())
            repacked.writestr(_info_like(info, name), content)
            if not name.endswith("/"):
                digest = base64.urlsafe_b64encode(hashlib.sha256(content).digest()).rstrip(b"=").decode()
                record.append(f"{name},sha256={digest},{len(content)}")
        record.append(f"{new_info}RECORD,,")
        repacked.writestr(new_info + "RECORD", "\n".join(record) + "\n")
    return out.getvalue()


def _info_like(info, name):
    # Stored, not deflated: a repack is a throwaway for the tests, and
    # deflating the libraries again would triple its time.
    copy = zipfile.ZipInfo(name, info.date_time)
    copy.external_attr = info.external_attr
    return copy


def _rewrite(z, target, changed, renamed):
    """A copy of the open zip `z` at `target` with `changed` {name: bytes}
    and `renamed` {old name: (new name, bytes)}."""
    partial = target + ".part"
    with zipfile.ZipFile(partial, "w") as out:
        for info in z.infolist():
            name, content = renamed.get(info.filename, (info.filename, None))
            if content is None:
                content = changed.get(info.filename)
            out.writestr(_info_like(info, name), z.read(info) if content is None else content)
    os.replace(partial, target)
