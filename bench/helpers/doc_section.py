"""Replacing a benchmark's section of a page in docs/ and its key in the
benchmark's JSON (written to a temporary name, then renamed), and the
optional lock that keeps two timed
benchmarks from running at once on a shared machine."""

import contextlib
import fcntl
import json
import os


def replace_section(text, marker, section, after=None):
    """`text` with the section starting at `marker` (up to the next "## "
    heading) replaced by `section`; when absent, `section` goes before the
    heading that follows the section starting at `after`, else at the end."""
    if marker in text:
        start = text.index(marker)
        end = text.find("\n## ", start + len(marker))
        end = len(text) if end < 0 else end
        head = text[:start].rstrip("\n")
        return (head + "\n" if head else "") + section + text[end:]
    if after and after in text:
        end = text.find("\n## ", text.index(after) + len(after))
        if end >= 0:
            return text[:end].rstrip("\n") + "\n" + section + text[end:]
    return text.rstrip("\n") + "\n" + section


def write_section(path, marker, section, after=None):
    """replace_section on the file at `path`, written atomically."""
    text = open(path).read() if os.path.exists(path) else ""
    with open(path + ".tmp", "w") as f:
        f.write(replace_section(text, marker, section, after))
    os.replace(path + ".tmp", path)


def write_json(path, value):
    """`value` as indented JSON at `path`, written to a temporary name, then renamed."""
    with open(path + ".tmp", "w") as f:
        json.dump(value, f, indent=1)
    os.replace(path + ".tmp", path)


def update_json(path, key, value):
    """Sets `key` of the JSON object in the file at `path` (a new one when
    absent), written atomically: a section rewritten alone keeps its
    benchmark's other results."""
    stored = {}
    if os.path.exists(path):
        with open(path) as f:
            stored = json.load(f)
    stored[key] = value
    write_json(path, stored)


@contextlib.contextmanager
def locked(path):
    """An exclusive flock on `path` while the block runs; nothing when `path`
    is empty (a machine with one benchmark at a time needs no lock)."""
    if not path:
        yield
        return
    with open(path, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def lock_path(argv):
    """The lock a script was given: `--lock PATH`, else $PENUMBRA_BENCH_LOCK."""
    if "--lock" in argv:
        return argv[argv.index("--lock") + 1]
    return os.environ.get("PENUMBRA_BENCH_LOCK")
