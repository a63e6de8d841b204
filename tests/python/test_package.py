"""The two zips in dist/ (make package) are self-contained: every ELF file in
them, the module, the libraries beside it and the ffmpeg program, finds each
library it needs inside the package, through its own RPATH/RUNPATH, or in
the manylinux allow-list (PEP 600: glibc's libraries, libstdc++, libgcc_s,
libz, libGL and the X11/GLib set). Checked here with readelf, independently
of the auditwheel run that made them. Every version the packages carry is
the source tree's."""

import glob
import io
import os
import re
import subprocess
import sys
import tomllib
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUDGET_BYTES = 100 * 1000 * 1000
# glibc 2.34, what auditwheel tags (manylinux_2_34): RHEL/Rocky 9, Ubuntu 22.04, Debian 12.
OLDEST_GLIBC = (2, 34)

ALLOWED = {
    "libc.so.6", "libm.so.6", "libdl.so.2", "librt.so.1", "libpthread.so.0", "libutil.so.1",
    "libnsl.so.1", "libresolv.so.2", "ld-linux-x86-64.so.2", "libstdc++.so.6", "libgcc_s.so.1",
    "libz.so.1", "libGL.so.1", "libX11.so.6", "libXext.so.6", "libXrender.so.1", "libICE.so.6",
    "libSM.so.6", "libgobject-2.0.so.0", "libgthread-2.0.so.0", "libglib-2.0.so.0",
}


def zips():
    found = sorted(glob.glob(os.path.join(ROOT, "dist", "penumbra-*.zip")))
    assert [os.path.basename(z).rsplit("-", 1)[1] for z in found] == ["legacy.zip", "linux_x64.zip"], \
        f"make package writes the extension and the legacy zip into dist/: {found}"
    return found


def unpack(zip_path, dest):
    """The zip as a user's Blender would lay it out: wheels unpacked into one
    site-packages folder, as Blender's extension installer does."""
    with zipfile.ZipFile(zip_path) as z:
        z.extractall(dest)
    site = os.path.join(dest, "site-packages")
    for wheel in glob.glob(os.path.join(dest, "wheels", "*.whl")):
        with zipfile.ZipFile(wheel) as z:
            z.extractall(site)
    return dest


def elf_files(tree):
    for folder, _, files in os.walk(tree):
        for name in files:
            path = os.path.join(folder, name)
            with open(path, "rb") as f:
                if f.read(4) == b"\x7fELF":
                    yield path


def dynamic_section(path):
    out = subprocess.run(["readelf", "-d", "-W", path], capture_output=True, text=True, check=True).stdout
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", out)
    paths = re.findall(r"\((?:RPATH|RUNPATH)\)\s+Library r(?:un)?path: \[(.+?)\]", out)
    search = [p.replace("$ORIGIN", os.path.dirname(path)) for entry in paths for p in entry.split(":")]
    return needed, search


def glibc_needed(path):
    out = subprocess.run(["readelf", "-V", "-W", path], capture_output=True, text=True, check=True).stdout
    versions = [tuple(map(int, v.split("."))) for v in re.findall(r"Name: GLIBC_([0-9.]+)", out)]
    return max(versions, default=(0, 0))


@pytest.mark.parametrize("kind", ["legacy", "linux_x64"])
def test_every_shared_object_finds_its_libraries_inside_the_package_or_the_allow_list(kind, tmp_path):
    zip_path = [z for z in zips() if z.endswith(f"-{kind}.zip")][0]
    tree = unpack(zip_path, str(tmp_path))
    objects = list(elf_files(tree))
    names = {os.path.basename(p) for p in objects}
    assert any(n.startswith("_penumbra.cpython-") for n in names) and "libtbb" in " ".join(names), names
    problems = []
    for path in objects:
        needed, search = dynamic_section(path)
        for library in needed:
            if library in ALLOWED:
                continue
            if not any(os.path.isfile(os.path.join(folder, library)) for folder in search):
                problems.append(f"{os.path.relpath(path, tree)} needs {library}, found neither in the "
                                f"package (RPATH {search}) nor in the allow-list")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("kind", ["legacy", "linux_x64"])
def test_each_zip_fits_the_size_budget_and_the_oldest_glibc(kind, tmp_path):
    zip_path = [z for z in zips() if z.endswith(f"-{kind}.zip")][0]
    assert os.path.getsize(zip_path) <= BUDGET_BYTES, f"{zip_path}: {os.path.getsize(zip_path) / 1e6:.1f} MB"
    tree = unpack(zip_path, str(tmp_path))
    newest = max(glibc_needed(p) for p in elf_files(tree))
    assert newest <= OLDEST_GLIBC, f"the package needs glibc {newest}, newer than the documented {OLDEST_GLIBC}"


def test_the_extension_lists_the_wheels_it_carries_and_runs_3_11_and_3_13(tmp_path):
    import tomllib
    zip_path = [z for z in zips() if z.endswith("-linux_x64.zip")][0]
    with zipfile.ZipFile(zip_path) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        carried = {n for n in z.namelist() if n.startswith("wheels/")}
    assert manifest["platforms"] == ["linux-x64"]
    assert {w.lstrip("./") for w in manifest["wheels"]} == carried
    ours = [w for w in carried if "penumbra_core" in w]
    assert len(ours) == 1 and "-cp311.cp313-" in ours[0] and "manylinux_2_34_x86_64" in ours[0], ours
    # imageio-ffmpeg's wheel is PyPI's, byte for byte (Blender's rule for bundled wheels).
    pinned = glob.glob(os.path.join(ROOT, ".deps", "imageio-ffmpeg-*", "imageio_ffmpeg-*.whl"))[0]
    with zipfile.ZipFile(zip_path) as z, open(pinned, "rb") as f:
        assert z.read("wheels/" + os.path.basename(pinned)) == f.read()


def bl_info_version(text):
    return ".".join(re.search(r'"version":\s*\((\d+),\s*(\d+),\s*(\d+)\)', text).groups())


def versions_in_zip(zip_path):
    """{where: version}: the zip's file name, its manifest and bl_info, and
    each penumbra_core wheel's file name and METADATA."""
    name = os.path.basename(zip_path)
    found = {name: name.split("-")[1]}
    with zipfile.ZipFile(zip_path) as z:
        for member in z.namelist():
            if member.split("/")[-1] == "blender_manifest.toml":
                found[f"{name}: {member}"] = tomllib.loads(z.read(member).decode())["version"]
            elif member in ("__init__.py", "penumbra/__init__.py"):
                found[f"{name}: {member} bl_info"] = bl_info_version(z.read(member).decode())
            elif re.fullmatch(r"wheels/penumbra_core-.*\.whl", member):
                found[f"{name}: {member}"] = member.split("-")[1]
                with zipfile.ZipFile(io.BytesIO(z.read(member))) as wheel:
                    metadata = [n for n in wheel.namelist() if n.endswith(".dist-info/METADATA")][0]
                    found[f"{name}: {member} METADATA"] = re.search(
                        r"^Version: (\S+)$", wheel.read(metadata).decode(), re.MULTILINE).group(1)
    return found


def module_version(folder):
    """_penumbra.__version__ of the module in `folder`, imported as Blender
    would (this Python is 3.11, whose module both zips carry)."""
    code = "import sys; sys.path.insert(0, sys.argv[1]); import _penumbra; print(_penumbra.__version__)"
    return subprocess.run([sys.executable, "-c", code, folder], capture_output=True, text=True,
                          check=True).stdout.strip()


def test_every_version_in_the_packages_is_the_source_tree_s(tmp_path):
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        found = {"CMakeLists.txt": re.search(r"project\(penumbra VERSION ([0-9.]+)", f.read()).group(1)}
    for zip_path in zips():
        kind = os.path.basename(zip_path).rsplit("-", 1)[1][:-len(".zip")]
        found.update(versions_in_zip(zip_path))
        tree = unpack(zip_path, str(tmp_path / kind))
        found[f"{kind}: _penumbra.__version__"] = module_version(
            os.path.join(tree, "penumbra") if kind == "legacy" else os.path.join(tree, "site-packages"))
    # Zip names, manifests, bl_infos, the extension's wheel name and METADATA, two modules, CMake.
    assert len(found) == 11 and len(set(found.values())) == 1, found


def test_the_version_reader_sees_a_zip_that_disagrees(tmp_path):
    wheel = io.BytesIO()
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr("penumbra_core-0.2.0.dist-info/METADATA", "Name: penumbra_core\nVersion: 0.2.0\n")
    zip_path = tmp_path / "penumbra-0.2.0-linux_x64.zip"
    with zipfile.ZipFile(zip_path, "w") as z:
        z.writestr("blender_manifest.toml", 'version = "0.2.1"\n')
        z.writestr("__init__.py", 'bl_info = {"version": (0, 2, 0)}\n')
        z.writestr("wheels/penumbra_core-0.3.0-cp311.cp313-cp311.cp313-manylinux_2_34_x86_64.whl", wheel.getvalue())
    assert versions_in_zip(str(zip_path)) == {
        "penumbra-0.2.0-linux_x64.zip": "0.2.0",
        "penumbra-0.2.0-linux_x64.zip: blender_manifest.toml": "0.2.1",
        "penumbra-0.2.0-linux_x64.zip: __init__.py bl_info": "0.2.0",
        "penumbra-0.2.0-linux_x64.zip: wheels/penumbra_core-0.3.0-cp311.cp313-cp311.cp313-manylinux_2_34_x86_64.whl":
            "0.3.0",
        "penumbra-0.2.0-linux_x64.zip: wheels/penumbra_core-0.3.0-cp311.cp313-cp311.cp313-manylinux_2_34_x86_64.whl "
        "METADATA": "0.2.0"}


def test_the_packager_refuses_a_module_or_a_wheel_of_another_version(tmp_path):
    import importlib.util
    spec = importlib.util.spec_from_file_location("package_script", os.path.join(ROOT, "scripts", "package.py"))
    package = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(package)
    (tmp_path / "_penumbra.py").write_text('__version__ = "0.0.1"\n')
    with pytest.raises(SystemExit, match=r"_penumbra.__version__ \(0.0.1\)"):
        package.version_of_addon(str(tmp_path))
    wheel = tmp_path / "penumbra_core-0.0.2-cp311-cp311-linux_x86_64.whl"
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr("penumbra_core-0.0.2.dist-info/METADATA", "Name: penumbra_core\nVersion: 0.0.3\n")
    with pytest.raises(SystemExit, match=r"\(file name\) \(0.0.2\).*\(METADATA\) \(0.0.3\)"):
        package.agreed_version({"the add-on": "0.2.0", **package.wheel_versions(str(wheel))})
