"""The light index each sun of a rig carries (the custom property
`penumbra_light_index`), read back from the .blend on every rebuild to
reuse the suns. No bpy here: a .blend is outside data, so the value may be
anything; tests/fuzz/python/fuzz_rig_index.py fuzzes it."""


def light_index(value):
    """The slot a sun's stored index names: an int >= 0, or None when the
    value is not one (a damaged or hand-edited .blend). A sun with None is
    not reused: the rebuild replaces it instead of failing."""
    if isinstance(value, bool):  # an int to Python, but never an index the add-on wrote
        return None
    if isinstance(value, float) and value.is_integer():  # not NaN, not infinite
        value = int(value)
    if isinstance(value, int) and value >= 0:
        return value
    return None
