"""Scripts the benchmarks run inside Blender, each in a fresh process
(`blender -b --python FILE -- ARGS`, or `.venv/bin/python FILE ARGS` for the
bpy module), printing what they measure; a package only so that one script
(or a test's check) can import another's harness."""
