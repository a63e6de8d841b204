#!/usr/bin/env python3
"""Fetches the native libraries Penumbra links and ships, from PyPI only, into .deps/.

Why these and not Debian's: the module must load in Blenders on other machines,
so every library it needs travels inside the package (docs/packaging.md).
 - OpenImageIO and OpenColorIO: the shared libraries from their PyPI wheels
   (built on manylinux_2_28, their own dependencies linked in and hidden),
   and the public headers from the sdists of the same versions. The two
   generated headers (oiioversion.h, OpenColorABI.h) are configured by CMake
   from the sdists' templates (cmake/PenumbraNativeDeps.cmake).
 - FFmpeg: the static `ffmpeg` executable of the imageio-ffmpeg wheel. Video
   is decoded in a child process (core/image/video_decoder.cpp), so a decoder
   crash can never take Blender down with it.

Every file is pinned by URL and sha256; nothing is unpacked twice. Usage:
    scripts/native_deps.py [DEST]      (default: .deps next to this folder)
"""

import hashlib
import os
import shutil
import sys
import tarfile
import tempfile
import urllib.request
import zipfile

PYPI = "https://files.pythonhosted.org/packages/"

# name: (version, [(url tail, sha256)])
PINNED = {
    "openimageio": ("3.2.2.0", [
        ("63/86/5e1b046baef1be49cd5ea2239841be45d583acabdfddb1be1c9444b6166f/"
         "openimageio-3.2.2.0-cp311-cp311-manylinux_2_28_x86_64.whl",
         "1133b6a6c04270398c419804e0d293b2bb3ce2d7607a17724cc45f385036b05b"),
        ("c3/7f/7a49e65b7f49f859c213e1d6ce19d32ce568d4ed15385898c2f65314e536/"
         "openimageio-3.2.2.0.tar.gz",
         "d66c829016b4f092c443b7f7896f06d0ab6af02a103d635d1b0b841c14bfd7c1"),
    ]),
    "opencolorio": ("2.6.0", [
        ("39/4b/42b7cce441b4cfadd17f1966eceb3840c6c1fc181903db66e9c3880b71d1/"
         "opencolorio-2.6.0-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl",
         "3df85517096baac44a8d67b6c9514c8b26ad8232ca0d2a3216e405f146da7cf9"),
        ("91/74/daaec42e86464f114bb908753f73e7b4c5b553829c31c8801708865b3c67/"
         "opencolorio-2.6.0.tar.gz",
         "b124f4573e425e17764e64d1fdac51a956e066b905c8a7f8712410b3103d2ef0"),
    ]),
    # Kept whole: the extension bundles this wheel unmodified (Blender's rule).
    "imageio-ffmpeg": ("0.6.0", [
        ("a0/2d/43c8522a2038e9d0e7dbdf3a61195ecc31ca576fb1527a528c877e87d973/"
         "imageio_ffmpeg-0.6.0-py3-none-manylinux2014_x86_64.whl",
         "c7e46fcec401dd990405049d2e2f475e2b397779df2519b544b8aab515195282"),
    ]),
}


def download(url_tail, sha256, folder):
    """The verified file in `folder`, downloaded once."""
    path = os.path.join(folder, url_tail.rsplit("/", 1)[1])
    if os.path.exists(path) and _sha256(path) == sha256:
        return path
    print(f"native_deps: downloading {os.path.basename(path)}", flush=True)
    with urllib.request.urlopen(PYPI + url_tail, timeout=300) as response, \
            tempfile.NamedTemporaryFile(dir=folder, delete=False) as out:
        shutil.copyfileobj(response, out)
    if _sha256(out.name) != sha256:
        os.unlink(out.name)
        sys.exit(f"native_deps: {os.path.basename(path)} does not match its pinned sha256; "
                 "the download was corrupted or the file changed on PyPI")
    os.replace(out.name, path)
    return path


def _sha256(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def extract_members(archive, prefix, dest, rename=None):
    """Members of a wheel (zip) or sdist (tar.gz) under the folder `prefix`,
    into `dest`, with the prefix removed (or the whole name replaced by
    `rename`, for a single file); executable bits kept."""
    os.makedirs(dest, exist_ok=True)
    if archive.endswith(".whl"):
        with zipfile.ZipFile(archive) as z:
            for info in z.infolist():
                if info.filename.startswith(prefix) and not info.is_dir():
                    target = os.path.join(dest, rename or info.filename[len(prefix):])
                    os.makedirs(os.path.dirname(target), exist_ok=True)
                    with z.open(info) as src, open(target, "wb") as out:
                        shutil.copyfileobj(src, out)
                    os.chmod(target, (info.external_attr >> 16) & 0o777 or 0o644)
    else:
        with tarfile.open(archive) as t:
            for member in t.getmembers():
                if member.name.startswith(prefix) and member.isfile():
                    target = os.path.join(dest, member.name[len(prefix):])
                    os.makedirs(os.path.dirname(target), exist_ok=True)
                    with t.extractfile(member) as src, open(target, "wb") as out:
                        shutil.copyfileobj(src, out)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    dest = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, ".deps"))
    downloads = os.path.join(dest, "downloads")
    os.makedirs(downloads, exist_ok=True)
    for name, (version, files) in PINNED.items():
        out = os.path.join(dest, f"{name}-{version}")
        stamp = os.path.join(out, ".complete")
        if os.path.exists(stamp):
            continue
        shutil.rmtree(out, ignore_errors=True)
        paths = [download(tail, sha, downloads) for tail, sha in files]
        if name == "openimageio":
            extract_members(paths[0], "OpenImageIO/lib/", os.path.join(out, "lib"))
            extract_members(paths[1], f"openimageio-{version}/src/include/OpenImageIO/",
                            os.path.join(out, "include", "OpenImageIO"))
        elif name == "opencolorio":
            extract_members(paths[0], "PyOpenColorIO/libOpenColorIO.so", os.path.join(out, "lib"),
                            rename="libOpenColorIO.so")
            extract_members(paths[1], f"opencolorio-{version}/include/OpenColorIO/",
                            os.path.join(out, "include", "OpenColorIO"))
        elif name == "imageio-ffmpeg":
            extract_members(paths[0], "imageio_ffmpeg/binaries/ffmpeg-", os.path.join(out, "bin"), rename="ffmpeg")
            shutil.copy(paths[0], out)  # the wheel itself, bundled unmodified in the extension
        open(stamp, "w").close()
    print(f"native_deps: ready in {dest}")


if __name__ == "__main__":
    main()
