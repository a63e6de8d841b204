"""Reading the one line a script run inside Blender hands back
(`RESULT {json}`, as blender_result.report prints it), free of bpy so that
the process that started Blender (a benchmark driver, a test) can import it."""

import json

PREFIX = "RESULT "


def results(text):
    """Every `RESULT {json}` line of a Blender's output, parsed, in order."""
    return [json.loads(line[len(PREFIX):]) for line in text.splitlines() if line.startswith(PREFIX)]


def last_result(text):
    """The last result in a Blender's output, or None when it printed none
    (it crashed, or was stopped before the end)."""
    found = results(text)
    return found[-1] if found else None


def only_result(proc, exit_zero=False, tail=4000):
    """The one result of a finished process (subprocess.run with text
    output). Anything else, or a non-zero exit when `exit_zero`, raises
    RuntimeError with the exit code and the end of both streams: what a
    failed run has to say is there."""
    found = results(proc.stdout)
    if len(found) != 1 or (exit_zero and proc.returncode != 0):
        raise RuntimeError(f"{len(found)} results, exit {proc.returncode}\n"
                           f"{proc.stdout[-tail:]}\n{proc.stderr[-tail:]}")
    return found[0]
