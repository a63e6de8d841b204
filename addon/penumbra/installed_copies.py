"""The other installs of Penumbra in this Blender (README: Installing).

- A stale core (native.py asks before it calls into the module). Python
  keeps a compiled module for the life of the process: after an update in a
  running Blender (Get Extensions > Update, or Install Add-on over the old
  legacy zip) the new add-on finds the previous core still loaded, its file
  deleted, replaced or overwritten. The new Python code must not call into
  it (after an overwrite in place it crashes Blender 3.4), so the core counts
  as not loaded and the panel and the operators say: restart Blender. The
  file's identity is recorded on the module when it is first loaded; a core
  loaded by 0.2.0, which kept no record, is judged by /proc/self/maps and
  the process's start time.
- Another enabled copy (register() asks). A user who installed Penumbra
  from disk, then from a repository, has two packages with the same
  operators and settings: the copy being enabled disables the others and
  keeps their preferences (their files stay until the user removes them).
"""

import os
import sys


LOADED_FILE = "_penumbra_loaded_file"   # set on the module object: outlives reloads of the add-on


def stale_core_reason(module):
    """Why the loaded `_penumbra` is not the file now on disk, or None.
    Checked before anything calls into the module: an installer that
    overwrites the file in place (Blender 3.x's Install Add-on does) leaves
    the process running code whose pages now come from the new file."""
    path = getattr(module, "__file__", None)
    if not path:
        return None
    now = _identity(path)
    recorded = getattr(module, LOADED_FILE, None)
    stale = now != tuple(recorded) if recorded is not None else _replaced_since_start(path, now)
    if not stale:
        return None
    return (f"Penumbra was installed or updated while Blender was running, but the compiled core of the copy "
            f"installed before it is still loaded ({path}). Restart Blender to load the new core.")


def remember_loaded_file(module):
    """Records the core's file as it was when first loaded in this process."""
    path = getattr(module, "__file__", None)
    if path and getattr(module, LOADED_FILE, None) is None:
        setattr(module, LOADED_FILE, _identity(path))


def _identity(path):
    try:
        info = os.stat(path)
    except OSError:
        return None
    return (info.st_ino, info.st_mtime_ns, info.st_size)


def _replaced_since_start(path, now):
    """For a core loaded by a version that kept no record (0.2.0): the
    mapped file was deleted or replaced, or written after this process
    started (Linux; elsewhere, no answer)."""
    mapped = _mapped_files().get(os.path.realpath(path))
    if mapped is None:
        return False
    inode, deleted = mapped
    started = _process_start()
    return deleted or now is None or now[0] != inode or (started is not None and now[1] / 1e9 > started + 2)


def _process_start():
    try:
        with open("/proc/self/stat") as f:
            ticks = int(f.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/stat") as f:
            boot = next(int(line.split()[1]) for line in f if line.startswith("btime"))
    except (OSError, ValueError, IndexError, StopIteration):
        return None
    return boot + ticks / os.sysconf("SC_CLK_TCK")


def _mapped_files():
    """{path: (inode, deleted)} of the files this process maps (Linux)."""
    try:
        with open("/proc/self/maps") as f:
            lines = f.read().splitlines()
    except OSError:
        return {}
    found = {}
    for line in lines:
        fields = line.split(maxsplit=5)
        if len(fields) == 6 and fields[5].startswith("/"):
            path = fields[5]
            deleted = path.endswith(" (deleted)")
            found[path[:-len(" (deleted)")] if deleted else path] = (int(fields[4]), deleted)
    return found


def take_over_other_copies(package):
    """Disables every other enabled Penumbra add-on; returns the
    preferences the first one had, {name: value}, to carry over."""
    import addon_utils
    import bpy
    kept = {}
    for addon in list(bpy.context.preferences.addons):
        if addon.module == package or addon.module.rpartition(".")[2] != "penumbra":
            continue
        if not kept and addon.preferences is not None:
            kept = {p.identifier: getattr(addon.preferences, p.identifier) for p in addon.preferences.bl_rna.properties
                    if p.identifier != "rna_type" and not p.is_readonly}
        print(f"Penumbra: {package} takes over from {addon.module}, which is now disabled", file=sys.stderr)
        addon_utils.disable(addon.module, default_set=True)
    return kept


def carry_preferences(package, kept):
    import bpy
    addon = bpy.context.preferences.addons.get(package)
    if addon is None or addon.preferences is None:
        return
    for name, value in kept.items():
        if hasattr(addon.preferences, name):
            setattr(addon.preferences, name, value)
