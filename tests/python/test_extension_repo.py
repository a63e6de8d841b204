"""The repository `make package` writes (dist/repo/), the repacking the
upgrade tests use (`package.py --repack-as`), and the add-on's test for a
core that an update replaced under a running Blender. The Blenders' own
install and update runs are tests/blender/test_extension_repo.py."""

import base64
import hashlib
import importlib.util
import io
import json
import os
import subprocess
import sys
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DIST = os.path.join(ROOT, "dist")


def load(path, name):
    spec = importlib.util.spec_from_file_location(name, os.path.join(ROOT, path))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


extension_repo = load("scripts/extension_repo.py", "extension_repo_script")


def extension_zip():
    found = [n for n in os.listdir(DIST) if n.endswith("-linux_x64.zip")]
    assert len(found) == 1, f"expected one extension zip in dist/ (make package): {found}"
    return os.path.join(DIST, found[0])


def test_the_repository_lists_the_packaged_zip_by_a_relative_url_and_its_hash():
    with open(os.path.join(DIST, "repo", "index.json")) as f:
        listing = json.load(f)
    (entry,) = listing["data"]
    name = os.path.basename(extension_zip())
    with open(extension_zip(), "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    assert entry["archive_url"] == f"./{name}"   # relative: the folder works wherever it is served
    assert entry["archive_hash"] == f"sha256:{digest}" and entry["version"] == name.split("-")[1]
    assert sorted(os.listdir(os.path.join(DIST, "repo"))) == ["index.json", name]


@pytest.fixture(scope="module")
def repacked(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("repack")
    old = os.path.basename(extension_zip()).split("-")[1]
    new = old.rsplit(".", 1)[0] + "." + str(int(old.rsplit(".", 1)[1]) + 1)
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "package.py"), "--repack-as", new,
                    "--dist", str(tmp), "--repo", str(tmp / "repo")], check=True, capture_output=True)
    return old, new, tmp


def test_a_repack_names_the_new_version_everywhere_but_in_the_compiled_core(repacked):
    old, new, tmp = repacked
    zip_path = tmp / f"penumbra-{new}-linux_x64.zip"
    assert set(extension_repo.zip_versions(str(zip_path)).values()) == {new}
    with open(tmp / "repo" / "index.json") as f:
        assert [e["version"] for e in json.load(f)["data"]] == [new]
    # The compiled core is the packaged one, byte for byte (it says `old`).
    with zipfile.ZipFile(extension_zip()) as before, zipfile.ZipFile(zip_path) as after:
        wheels = [zipfile.ZipFile(io.BytesIO(z.read(extension_repo._our_wheel(z.namelist())))) for z in (before, after)]
        modules = [[n for n in w.namelist() if n.startswith("_penumbra.")] for w in wheels]
        assert modules[0] == modules[1] and modules[0]
        assert all(wheels[0].read(n) == wheels[1].read(n) for n in modules[0])


def test_a_repacked_wheel_s_record_matches_its_files(repacked):
    _, new, tmp = repacked
    with zipfile.ZipFile(tmp / f"penumbra-{new}-linux_x64.zip") as z, \
            zipfile.ZipFile(io.BytesIO(z.read(extension_repo._our_wheel(z.namelist())))) as wheel:
        record = wheel.read(f"penumbra_core-{new}.dist-info/RECORD").decode().splitlines()
        for line in record:
            name, digest, size = line.rsplit(",", 2)
            if digest:
                content = wheel.read(name)
                expected = base64.urlsafe_b64encode(hashlib.sha256(content).digest()).rstrip(b"=").decode()
                assert (digest, int(size)) == (f"sha256={expected}", len(content)), name
        files = {n for n in wheel.namelist() if not n.endswith("/")}
        assert {line.rsplit(",", 2)[0] for line in record} == files


def test_the_repacked_legacy_zip_keeps_its_folder_entry_and_says_the_new_version(repacked):
    _, new, tmp = repacked
    with zipfile.ZipFile(tmp / f"penumbra-{new}-legacy.zip") as z:
        # Blender 3.x removes the old folder before unpacking only when the zip names it.
        assert "penumbra/" in z.namelist()
        init = z.read("penumbra/__init__.py").decode()
    assert f'"version": ({new.replace(".", ", ")})' in init


def test_a_repack_must_raise_the_version(tmp_path):
    old = os.path.basename(extension_zip()).split("-")[1]
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "package.py"), "--repack-as", old,
                           "--dist", str(tmp_path)], capture_output=True, text=True)
    assert proc.returncode != 0 and "is not above the built version" in proc.stderr


class Core:
    """Stands in for the loaded _penumbra: only its file matters here."""

    def __init__(self, path):
        self.__file__ = str(path)


def test_a_core_file_replaced_or_rewritten_after_loading_is_stale(tmp_path):
    copies = load("addon/penumbra/installed_copies.py", "installed_copies_under_test")
    path = tmp_path / "_penumbra.so"
    path.write_bytes(b"old core")
    core = Core(path)
    copies.remember_loaded_file(core)
    assert copies.stale_core_reason(core) is None
    path.write_bytes(b"new core, written in place")
    assert "Restart Blender" in copies.stale_core_reason(core)
    replaced = Core(path)
    copies.remember_loaded_file(replaced)
    os.replace(tmp_path / "_penumbra.so", tmp_path / "moved.so")
    (tmp_path / "_penumbra.so").write_bytes(b"another file at that path")
    assert "Restart Blender" in copies.stale_core_reason(replaced)


def test_a_core_loaded_by_a_version_without_the_record_is_judged_by_its_mapping(tmp_path):
    """0.2.0 loaded the core without recording its file: what the process
    maps, and when the process started, decide."""
    import mmap
    copies = load("addon/penumbra/installed_copies.py", "installed_copies_under_test")
    path = tmp_path / "_penumbra.so"
    path.write_bytes(b"\0" * 4096)
    os.utime(path, (0, 0))   # written before this process started, as an installed core is
    with open(path, "rb") as f:
        mapping = mmap.mmap(f.fileno(), 0, prot=mmap.PROT_READ)
    try:
        assert copies.stale_core_reason(Core(path)) is None
        path.unlink()   # what Blender's installers do with the old files
        path.write_bytes(b"the new core")
        assert "Restart Blender" in copies.stale_core_reason(Core(path))
    finally:
        mapping.close()
