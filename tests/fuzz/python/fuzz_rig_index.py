"""Atheris harness: the light index a rig's sun carries, read back from the .blend.

A light rig is written into the .blend as suns, each with a custom property
`penumbra_light_index`; every rebuild reads it back to reuse the suns
(addon/penumbra/lights/rig_index.py `light_index`, called by
rig_objects.write_rig). A .blend is outside data: the property may hold any
value a custom property can (int, float, string, bool, array, group).
Contract checked: light_index returns an int >= 0 or None, and raises nothing.

Input: a type byte, then the value (FuzzedDataProvider). Run by `make fuzz`;
replayed by tests/fuzz/python/test_replay.py.
"""

import importlib.util
import os
import sys

import atheris

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def _load():
    path = os.path.join(ROOT, "addon", "penumbra", "lights", "rig_index.py")  # the package imports bpy
    spec = importlib.util.spec_from_file_location("penumbra_rig_index", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


rig_index = _load()


def value_from(data):
    """A value of any kind a Blender custom property holds, from fuzz bytes."""
    fdp = atheris.FuzzedDataProvider(data)
    kind = fdp.ConsumeIntInRange(0, 7)
    if kind == 0:
        return fdp.ConsumeInt(fdp.ConsumeIntInRange(1, 64))  # any size, any sign
    if kind == 1:
        return fdp.ConsumeFloat()  # NaN and infinities included
    if kind == 2:
        return fdp.ConsumeUnicode(fdp.ConsumeIntInRange(0, 40))
    if kind == 3:
        return fdp.ConsumeBool()
    if kind == 4:
        return [fdp.ConsumeInt(4) for _ in range(fdp.ConsumeIntInRange(0, 4))]  # an IDPropertyArray
    if kind == 5:
        return {"value": fdp.ConsumeInt(4)}  # an IDPropertyGroup
    if kind == 6:
        return fdp.ConsumeBytes(fdp.ConsumeIntInRange(0, 16))
    return None


def TestOneInput(data):
    index = rig_index.light_index(value_from(data))
    assert index is None or (type(index) is int and index >= 0), index


def main():
    atheris.instrument_func(rig_index.light_index)
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
